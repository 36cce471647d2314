// SPDX-License-Identifier: MIT
// The measurement side of the sliding-window filter (sfd_msckf.h, core/docs/msckf.md): null-space
// projection of a track (eq. (2)), its chi-square statistic (eq. (3)), the compression of the
// accepted tracks (normal equations, factored once) and the Kalman update from it (eq. (4)).
#include "core_private.hpp"
#include "sfd/sfd_msckf.h"
#include "small_linalg.hpp"

namespace sfd {
namespace {

constexpr int kDim = SFD_MSCKF_DIM;
constexpr int kRows = SFD_MSCKF_TRACK_ROWS;

/// The Givens rotation (c, s) with [c s; -s c]^T-free form: for a pair (a, b) it gives
/// c a + s b = rho, -s a + c b = 0 (rho = hypot(a, b)); (1, 0) when both are zero.
void givens(double a, double b, double *c, double *s) {
    if (!(std::fabs(b) > 0.0)) {  // b is zero: nothing to rotate
        *c = 1.0;
        *s = 0.0;
        return;
    }
    // sqrt(a^2 + b^2) rather than hypot: the whitened entries are far from overflow, and hypot's
    // extra care cost 4 % of a frame (callgrind).
    const double rho = std::sqrt(a * a + b * b);
    *c = a / rho;
    *s = b / rho;
}

/// Rows i and k of a row-major array: (x_i, x_k) <- (c x_i + s x_k, -s x_i + c x_k) over
/// columns [from, to).
template <std::size_t K>
void rotate_rows(double (*M)[K], int i, int k, double c, double s, int from, int to) {
    for (int j = from; j < to; ++j) {
        const double a = M[i][j], b = M[k][j];
        M[i][j] = c * a + s * b;
        M[k][j] = -s * a + c * b;
    }
}

/// Columns i and k of R (R <- R G^T, the other half of G R G^T).
void rotate_cols(double (*M)[kRows], int rows, int i, int k, double c, double s) {
    for (int r = 0; r < rows; ++r) {
        const double a = M[r][i], b = M[r][k];
        M[r][i] = c * a + s * b;
        M[r][k] = -s * a + c * b;
    }
}

/// The columns [lo, hi) outside which every row of H_o is zero (a track's rows touch only the
/// clones it was seen in); lo = hi = 0 when H_o is zero.
void column_span(const sfd_msckf_track_t &t, int m, int *lo, int *hi) {
    int a = t.n, b = 0;
    for (int i = 0; i < m; ++i) {
        for (int j = 0; j < a; ++j) {
            if (std::fabs(t.Hx[i][j]) > 0.0) {
                a = j;
                break;
            }
        }
        for (int j = t.n - 1; j >= b; --j) {
            if (std::fabs(t.Hx[i][j]) > 0.0) {
                b = j + 1;
                break;
            }
        }
    }
    *lo = a < b ? a : 0;
    *hi = a < b ? b : 0;
}

bool track_finite(const sfd_msckf_track_t &t) {
    for (int i = 0; i < t.rows; ++i) {
        if (!all_finite(t.Hx[i], std::size_t(t.n)) || !all_finite(t.Hf[i], 3) ||
            !std::isfinite(t.r[i]) || !all_finite(t.R[i], std::size_t(t.rows))) {
            return false;
        }
    }
    return true;
}

}  // namespace
}  // namespace sfd

using namespace sfd;

extern "C" sfd_status_t sfd_msckf_track_project(sfd_msckf_track_t *t) {
    if (t == nullptr || t->projected != 0 || t->rows < 4 || t->rows > kRows || t->n < 1 ||
        t->n > kDim || !track_finite(*t)) {
        return SFD_ERR_INVAL;
    }
    const int rows = t->rows, n = t->n;
    int lo = 0, hi = 0;  // the rotations mix rows: columns outside H_x's span stay zero
    column_span(*t, rows, &lo, &hi);
    double fro = 0.0;
    for (int i = 0; i < rows; ++i) {
        for (int j = 0; j < 3; ++j) fro += t->Hf[i][j] * t->Hf[i][j];
    }
    fro = std::sqrt(fro);
    // Q^T by Givens rotations, bottom up per column: H_f becomes upper triangular (its first three
    // rows); rows 3.. of the rotated system are N^T times the inputs (N: the last rows - 3 columns
    // of Q, orthonormal and orthogonal to H_f's range).
    for (int j = 0; j < 3; ++j) {
        for (int i = rows - 1; i > j; --i) {
            double c = 1.0, s = 0.0;
            givens(t->Hf[i - 1][j], t->Hf[i][j], &c, &s);
            if (!(std::fabs(s) > 0.0)) continue;
            rotate_rows(t->Hf, i - 1, i, c, s, 0, 3);
            t->Hf[i][j] = 0.0;
            rotate_rows(t->Hx, i - 1, i, c, s, lo, hi);
            const double a = t->r[i - 1], b = t->r[i];
            t->r[i - 1] = c * a + s * b;
            t->r[i] = -s * a + c * b;
            rotate_rows(t->R, i - 1, i, c, s, 0, rows);
            rotate_cols(t->R, rows, i - 1, i, c, s);
        }
    }
    for (int j = 0; j < 3; ++j) {
        if (!(std::fabs(t->Hf[j][j]) > 1e-9 * fro)) return SFD_ERR_NUMERIC;
    }
    // Keep the null-space part: rows and columns 3.. of the rotated system, moved to the top.
    const int m = rows - 3;
    for (int i = 0; i < m; ++i) {
        for (int j = 0; j < n; ++j) t->Hx[i][j] = t->Hx[i + 3][j];
        for (int j = 0; j < 3; ++j) t->Hf[i][j] = 0.0;
        t->r[i] = t->r[i + 3];
        for (int j = 0; j < m; ++j) t->R[i][j] = t->R[i + 3][j + 3];
    }
    for (int i = 0; i < m; ++i) {  // exact symmetry: the two rotation passes round differently
        for (int j = i + 1; j < m; ++j) {
            const double v = 0.5 * (t->R[i][j] + t->R[j][i]);
            t->R[i][j] = v;
            t->R[j][i] = v;
        }
    }
    t->rows = m;
    t->projected = 1;
    return SFD_OK;
}

extern "C" sfd_status_t sfd_msckf_track_gate(const sfd_msckf_track_t *t, const double *P,
                                             double *gamma, int32_t *dof) {
    if (t == nullptr || P == nullptr || gamma == nullptr || dof == nullptr || t->projected != 1 ||
        t->rows < 1 || t->rows > kRows || t->n < 1 || t->n > kDim) {
        return SFD_ERR_INVAL;
    }
    const int m = t->rows;
    int lo = 0, hi = 0;  // H_o P H_o^T over the columns H_o touches
    column_span(*t, m, &lo, &hi);
    double S[kRows][kRows];
    double hp[kDim];
    for (int i = 0; i < m; ++i) {
        // (H_o P)_i, row by row of P (contiguous; each entry sums over k in the same order)
        for (int l = lo; l < hi; ++l) hp[l] = 0.0;
        for (int k = lo; k < hi; ++k) {
            const double h = t->Hx[i][k];
            const double *Pk = P + static_cast<std::ptrdiff_t>(k) * kDim;
            for (int l = lo; l < hi; ++l) hp[l] += h * Pk[l];
        }
        for (int j = 0; j <= i; ++j) {
            double v = 0.0;
            for (int l = lo; l < hi; ++l) v += hp[l] * t->Hx[j][l];
            S[i][j] = v + t->R[i][j];
            S[j][i] = S[i][j];
        }
    }
    double L[kRows][kRows];
    if (!la::cholesky(S, m, L)) return SFD_ERR_NUMERIC;
    double w[kRows];
    la::forward_solve(L, m, t->r, w);
    double g = 0.0;
    for (int i = 0; i < m; ++i) g += w[i] * w[i];
    if (!std::isfinite(g)) return SFD_ERR_NUMERIC;
    *gamma = g;
    *dof = m;
    return SFD_OK;
}

namespace sfd {
namespace {

/// gamma = |w|^2 - |M^-1 b|^2 over the first n rows of the whitened system (A = G^T G and b =
/// G^T w summed over them; sfd_msckf_track_statistic()); false when A is not positive definite or
/// the result is not finite.
bool statistic_of_prefix(const double (*G)[kRows], const double *w, int n, double *gamma) {
    double A[3][3];  // G^T G
    double b[3];     // G^T w
    for (int c = 0; c < 3; ++c) {
        double v = 0.0;
        for (int i = 0; i < n; ++i) v += G[c][i] * w[i];
        b[c] = v;
        for (int d = 0; d <= c; ++d) {
            double x = 0.0;
            for (int i = 0; i < n; ++i) x += G[c][i] * G[d][i];
            A[c][d] = x;
            A[d][c] = x;
        }
    }
    double M[3][3];
    // A is formed from squares: a rank deficiency shows only above rounding (eps ~ 1e-16).
    if (!la::cholesky(A, la::Dim<3>{}, M, 1e-14)) return false;
    double c3[3];
    la::forward_solve(M, la::Dim<3>{}, b, c3);
    double ww = 0.0;
    for (int i = 0; i < n; ++i) ww += w[i] * w[i];
    const double g_stat = ww - (c3[0] * c3[0] + c3[1] * c3[1] + c3[2] * c3[2]);
    if (!std::isfinite(g_stat)) return false;
    *gamma = std::fmax(g_stat, 0.0);  // a perfect fit can round to -eps
    return true;
}

/// The point's columns G (3) and a 2-parameter fault's F over the n whitened rows, fitted
/// together: [G F]^T [G F] = M M^T and c = M^-1 [G F]^T w. |c|^2 is the part of |w|^2 that the
/// point and the fault together explain, its first three entries the point's alone (the Cholesky
/// factor of the Gram matrix nests); the fault's lower-right block of M is the Cholesky factor
/// of F^T P F and its entries of c are that factor's inverse times F^T P w, with P the projection
/// off G (the Schur complement). False when the five columns are not independent above rounding
/// (the fault lies in the point's span: no motion) or a result is not finite.
bool point_and_fault(const double (*G)[kRows], const double (*F)[kRows], const double *w, int n,
                     double M[5][5], double c5[5]) {
    const double *col[5] = {G[0], G[1], G[2], F[0], F[1]};
    double A[5][5];
    double b[5];
    for (int c = 0; c < 5; ++c) {
        double v = 0.0;
        for (int i = 0; i < n; ++i) v += col[c][i] * w[i];
        b[c] = v;
        for (int d = 0; d <= c; ++d) {
            double x = 0.0;
            for (int i = 0; i < n; ++i) x += col[c][i] * col[d][i];
            A[c][d] = x;
            A[d][c] = x;
        }
    }
    if (!la::cholesky(A, la::Dim<5>{}, M, 1e-12)) return false;
    la::forward_solve(M, la::Dim<5>{}, b, c5);
    return std::isfinite(c5[3]) && std::isfinite(c5[4]);
}

/// The ramp's GLR over the n whitened rows: c_3^2 + c_4^2 of point_and_fault() (the part of
/// |w|^2 the ramp explains beyond the point; core/docs/parity_space.md "Ramp").
bool ramp_glr_of(const double (*G)[kRows], const double (*F)[kRows], const double *w, int n,
                 double *glr) {
    double M[5][5];
    double c5[5];
    if (!point_and_fault(G, F, w, n, M, c5)) return false;
    const double g = c5[3] * c5[3] + c5[4] * c5[4];
    if (!std::isfinite(g)) return false;
    *glr = g;
    return true;
}

/// The first n of the reversed rows of a 2-column fault signature `cols` (rows x 2), whitened by
/// the Cholesky factor L of the reversed S: F[c] = L_n^-1 (cols reversed)[0..n)[c], the prefix of
/// the forward substitution (n = rows: all of them; n = the tail: the tail's rows, whose block of
/// L is the tail's own factor).
void whiten_pair(const double (*L)[kRows], const double (*cols)[2], int rows, int n,
                 double F[2][kRows]) {
    for (int c = 0; c < 2; ++c) {
        for (int i = 0; i < n; ++i) F[c][i] = cols[rows - 1 - i][c];
        la::forward_solve(L, n, F[c], F[c]);
    }
}

/// The motion's fit over the n whitened rows (sfd_window_motion_t): with the fault's block
/// B = M[3..4][3..4] of point_and_fault() (lower triangular), info = B B^T and score = B c[3..4].
bool motion_fit_of(const double (*G)[kRows], const double (*F)[kRows], const double *w, int n,
                   sfd_window_motion_t *fit) {
    double M[5][5];
    double c5[5];
    if (!point_and_fault(G, F, w, n, M, c5)) return false;
    fit->info[0] = M[3][3] * M[3][3];
    fit->info[1] = M[3][3] * M[4][3];
    fit->info[2] = M[4][3] * M[4][3] + M[4][4] * M[4][4];
    fit->score[0] = M[3][3] * c5[3];
    fit->score[1] = M[4][3] * c5[3] + M[4][4] * c5[4];
    return all_finite(fit->info, 3) && all_finite(fit->score, 2);
}

}  // namespace
}  // namespace sfd

sfd_status_t sfd::msckf_statistic_tail(const sfd_msckf_track_t &t,
                                       const double (*S)[SFD_MSCKF_TRACK_ROWS], int tail_first,
                                       double gamma[2], int32_t dof[2],
                                       const double (*ramp_cols)[2], double *ramp_glr,
                                       const double (*motion_cols)[2],
                                       sfd_window_motion_t *motion) {
    const int rows = t.rows;
    const int tail = rows - tail_first;
    if (rows < 4 || rows > kRows || tail_first < 0 || (tail_first > 0 && tail < 4)) {
        return SFD_ERR_INVAL;
    }
    // The rows in reverse order (the last first): the Cholesky factor of the reversed S starts
    // with the factor of the tail's block, and forward substitution's first entries depend on
    // the first rows only, so one factor whitens both systems.
    // Sb's lower triangle from S's lower triangle (the only half the callers must fill): entry
    // (i, j), j <= i, of the reversed S is S(rows-1-i, rows-1-j) = S(rows-1-j, rows-1-i).
    double Sb[kRows][kRows];
    for (int i = 0; i < rows; ++i) {
        for (int j = 0; j <= i; ++j) Sb[i][j] = S[rows - 1 - j][rows - 1 - i];
    }
    // S = L L^T; w = L^-1 r; G = L^-1 H_f (column by column).
    double L[kRows][kRows];
    if (!la::cholesky(Sb, rows, L)) return SFD_ERR_NUMERIC;
    double rb[kRows];
    for (int i = 0; i < rows; ++i) rb[i] = t.r[rows - 1 - i];
    double w[kRows];
    la::forward_solve(L, rows, rb, w);
    double G[3][kRows];
    for (int c = 0; c < 3; ++c) {
        for (int i = 0; i < rows; ++i) G[c][i] = t.Hf[rows - 1 - i][c];
        la::forward_solve(L, rows, G[c], G[c]);
    }
    double g_all = 0.0;
    if (!statistic_of_prefix(G, w, rows, &g_all)) return SFD_ERR_NUMERIC;
    double g_tail = 0.0;
    if (tail_first > 0 && !statistic_of_prefix(G, w, tail, &g_tail)) return SFD_ERR_NUMERIC;
    if (ramp_cols != nullptr && ramp_glr != nullptr) {
        // whitened like H_f's columns (rows reversed); rows - 5 >= 1 residual rows remain
        double F[2][kRows];
        whiten_pair(L, ramp_cols, rows, rows, F);
        double g = 0.0;
        *ramp_glr = (rows >= 6 && ramp_glr_of(G, F, w, rows, &g)) ? g : -1.0;
    }
    if (motion_cols != nullptr && motion != nullptr) {
        // the tail's rows are the first `tail` of the reversed system: its whitened columns are
        // the prefix of the forward substitution (as for the tail's statistic)
        double F[2][kRows];
        whiten_pair(L, motion_cols, rows, tail, F);
        sfd_window_motion_t fit{};
        if (tail >= 6 && motion_fit_of(G, F, w, tail, &fit)) {
            fit.ok = 1;
        } else {
            fit = sfd_window_motion_t{};  // ok 0, info and score 0
        }
        *motion = fit;
    }
    gamma[0] = g_tail;
    dof[0] = (tail_first > 0) ? tail - 3 : 0;
    gamma[1] = g_all;
    dof[1] = rows - 3;
    return SFD_OK;
}

extern "C" sfd_status_t sfd_msckf_track_statistic(const sfd_msckf_track_t *t,
                                                  const double (*S)[SFD_MSCKF_TRACK_ROWS],
                                                  double *gamma, int32_t *dof) {
    if (t == nullptr || S == nullptr || gamma == nullptr || dof == nullptr || t->projected != 0 ||
        t->rows < 4 || t->rows > kRows) {
        return SFD_ERR_INVAL;
    }
    double g[2] = {0.0, 0.0};
    int32_t d[2] = {0, 0};
    const sfd_status_t st =
        msckf_statistic_tail(*t, S, 0, g, d, nullptr, nullptr, nullptr, nullptr);
    if (st != SFD_OK) return st;
    *gamma = g[1];
    *dof = d[1];
    return SFD_OK;
}

extern "C" sfd_status_t sfd_msckf_stack_reset(sfd_msckf_stack_t *s, int32_t n) {
    if (s == nullptr || n < 1 || n > kDim) return SFD_ERR_INVAL;
    s->n = n;
    s->folded = 0;
    s->residual_ss = 0.0;
    for (int i = 0; i < kDim; ++i) {
        s->used[i] = 0;
        for (int j = 0; j <= kDim; ++j) s->Tq[i][j] = 0.0;
    }
    return SFD_OK;
}

extern "C" sfd_status_t sfd_msckf_stack_fold(sfd_msckf_stack_t *s, const sfd_msckf_track_t *t) {
    if (s == nullptr || t == nullptr || t->projected != 1 || t->rows < 1 || t->rows > kRows ||
        s->n < 1 || s->n > kDim || t->n != s->n) {
        return SFD_ERR_INVAL;
    }
    const int m = t->rows, n = s->n;
    double L[kRows][kRows];
    if (!la::cholesky(t->R, m, L)) return SFD_ERR_NUMERIC;
    int lo = 0, hi = 0;
    column_span(*t, m, &lo, &hi);
    // Whitened rows W = L^-1 [H_o | r_o] (forward substitution down the rows; the columns
    // outside H_o's span stay zero).
    double W[kRows][kDim + 1];
    for (int i = 0; i < m; ++i) {
        // row i minus the earlier whitened rows, row by row (contiguous; each entry subtracts
        // over k in the same order)
        for (int j = 0; j < n; ++j) W[i][j] = 0.0;
        for (int j = lo; j < hi; ++j) W[i][j] = t->Hx[i][j];
        for (int k = 0; k < i; ++k) {
            const double lik = L[i][k];
            for (int j = lo; j < hi; ++j) W[i][j] -= lik * W[k][j];
        }
        for (int j = lo; j < hi; ++j) W[i][j] /= L[i][i];
        double v = t->r[i];
        for (int k = 0; k < i; ++k) v -= L[i][k] * W[k][n];
        W[i][n] = v / L[i][i];
    }
    for (int i = 0; i < m; ++i) {
        if (!all_finite(W[i], std::size_t(n) + 1)) return SFD_ERR_NUMERIC;
    }
    // Each whitened row w (with its residual w_n) into the normal equations over its span:
    // Y += w w^T (upper triangle), b += w w_n, and the residual's square into residual_ss.
    for (int i = 0; i < m; ++i) {
        const double *v = W[i];
        for (int a = lo; a < hi; ++a) {
            const double va = v[a];  // a local: the row's stores cannot change it
            if (!(std::fabs(va) > 0.0)) continue;
            s->used[a] = 1;
            double *row = s->Tq[a];
            for (int c = a; c < hi; ++c) row[c] += va * v[c];
            row[n] += va * v[n];
        }
        s->residual_ss += v[n] * v[n];
        ++s->folded;
    }
    return SFD_OK;
}

namespace sfd {
namespace {

/// Row i of H_x is zero outside the columns [span[i][0], span[i][1]) (0, 0 for a zero row).
void row_spans(const sfd_msckf_track_t &t, int (*span)[2]) {
    for (int i = 0; i < t.rows; ++i) {
        int a = 0;
        while (a < t.n && !(std::fabs(t.Hx[i][a]) > 0.0)) ++a;
        int b = t.n;
        while (b > a && !(std::fabs(t.Hx[i][b - 1]) > 0.0)) --b;
        span[i][0] = a < b ? a : 0;
        span[i][1] = a < b ? b : 0;
    }
}

/// R is exactly the identity (rows x rows): the track's rows have unit noise.
bool unit_noise(const sfd_msckf_track_t &t) {
    for (int i = 0; i < t.rows; ++i) {
        for (int j = 0; j < t.rows; ++j) {
            const double e = (i == j) ? 1.0 : 0.0;
            if (!(t.R[i][j] >= e && t.R[i][j] <= e)) return false;  // equal in value
        }
    }
    return true;
}

}  // namespace
}  // namespace sfd

bool sfd::msckf_range_basis(const sfd_msckf_track_t &t, double (*Q)[3]) {
    const int rows = t.rows;
    double A[kRows][3] = {};  // H_f, reduced in place to the triangular factor
    double fro = 0.0;
    for (int i = 0; i < rows; ++i) {
        for (int j = 0; j < 3; ++j) {
            A[i][j] = t.Hf[i][j];
            fro += A[i][j] * A[i][j];
        }
    }
    fro = std::sqrt(fro);
    double V[3][kRows] = {};  // the reflectors' vectors v_j (entries j..rows-1) and v_j^T v_j
    double vv[3];
    for (int j = 0; j < 3; ++j) {
        double x2 = 0.0;
        for (int i = j; i < rows; ++i) x2 += A[i][j] * A[i][j];
        const double xn = std::sqrt(x2);
        // |R_jj| = xn: the pivot sfd_msckf_track_project() tests (its Givens rotations and these
        // reflections give the same triangular factor up to signs).
        if (!(xn > 1e-9 * fro)) return false;
        const double alpha = A[j][j] >= 0.0 ? -xn : xn;  // no cancellation in v_j's first entry
        for (int i = j; i < rows; ++i) V[j][i] = A[i][j];
        V[j][j] -= alpha;
        double s = 0.0;
        for (int i = j; i < rows; ++i) s += V[j][i] * V[j][i];
        vv[j] = s;
        for (int c = j + 1; c < 3; ++c) {
            double d = 0.0;
            for (int i = j; i < rows; ++i) d += V[j][i] * A[i][c];
            const double f = 2.0 * d / s;
            for (int i = j; i < rows; ++i) A[i][c] -= f * V[j][i];
        }
        A[j][j] = alpha;
    }
    // Q_1 = H_0 H_1 H_2 applied to the first three columns of the identity.
    for (int i = 0; i < rows; ++i) {
        for (int c = 0; c < 3; ++c) Q[i][c] = (i == c) ? 1.0 : 0.0;
    }
    for (int j = 2; j >= 0; --j) {
        for (int c = 0; c < 3; ++c) {
            double d = 0.0;
            for (int i = j; i < rows; ++i) d += V[j][i] * Q[i][c];
            const double f = 2.0 * d / vv[j];
            for (int i = j; i < rows; ++i) Q[i][c] -= f * V[j][i];
        }
    }
    for (int i = 0; i < rows; ++i) {
        if (!all_finite(Q[i], 3)) return false;
    }
    return true;
}

sfd_status_t sfd::msckf_fold_unit_noise(sfd_msckf_stack_t *s, const sfd_msckf_track_t &t,
                                        const double (*Q)[3]) {
    const int rows = t.rows, n = s->n;
    int span[kRows][2];
    row_spans(t, span);
    int lo = n, hi = 0;
    for (int i = 0; i < rows; ++i) {
        if (span[i][0] < span[i][1]) {
            lo = span[i][0] < lo ? span[i][0] : lo;
            hi = span[i][1] > hi ? span[i][1] : hi;
        }
    }
    if (lo >= hi) lo = hi = 0;
    // Z = Q_1^T H_x over the rows' spans, z = Q_1^T r.
    double Z[3][kDim] = {};
    double z[3] = {0.0, 0.0, 0.0};
    for (int i = 0; i < rows; ++i) {
        for (int c = 0; c < 3; ++c) {
            const double q = Q[i][c];
            for (int j = span[i][0]; j < span[i][1]; ++j) Z[c][j] += q * t.Hx[i][j];
            z[c] += q * t.r[i];
        }
    }
    for (int c = 0; c < 3; ++c) {
        if (!all_finite(Z[c] + lo, std::size_t(hi - lo)) || !std::isfinite(z[c])) {
            return SFD_ERR_NUMERIC;
        }
    }
    // Y += H_x^T H_x (each row over its own span) - Z^T Z; b += H_x^T r - Z^T z.
    double rr = 0.0;
    for (int i = 0; i < rows; ++i) {
        const double *h = t.Hx[i];
        const int b = span[i][1];
        for (int a = span[i][0]; a < b; ++a) {
            const double ha = h[a];
            if (!(std::fabs(ha) > 0.0)) continue;
            s->used[a] = 1;
            double *row = s->Tq[a];
            for (int c = a; c < b; ++c) row[c] += ha * h[c];
            row[n] += ha * t.r[i];
        }
        rr += t.r[i] * t.r[i];
    }
    for (int a = lo; a < hi; ++a) {
        const double z0 = Z[0][a], z1 = Z[1][a], z2 = Z[2][a];
        double *row = s->Tq[a];
        for (int c = a; c < hi; ++c) row[c] -= z0 * Z[0][c] + z1 * Z[1][c] + z2 * Z[2][c];
        row[n] -= z0 * z[0] + z1 * z[1] + z2 * z[2];
    }
    s->residual_ss += std::fmax(rr - (z[0] * z[0] + z[1] * z[1] + z[2] * z[2]), 0.0);
    s->folded += rows - 3;
    return SFD_OK;
}

extern "C" sfd_status_t sfd_msckf_stack_fold_unprojected(sfd_msckf_stack_t *s,
                                                         const sfd_msckf_track_t *t) {
    if (s == nullptr || t == nullptr || t->projected != 0 || t->rows < 4 || t->rows > kRows ||
        s->n < 1 || s->n > kDim || t->n != s->n || !track_finite(*t) || !unit_noise(*t)) {
        return SFD_ERR_INVAL;
    }
    double Q[kRows][3];
    if (!msckf_range_basis(*t, Q)) return SFD_ERR_NUMERIC;
    return msckf_fold_unit_noise(s, *t, Q);
}

extern "C" sfd_status_t sfd_msckf_update(sfd_msckf_stack_t *s, double *P, double *dx,
                                         sfd_msckf_work_t *w) {
    if (s == nullptr || P == nullptr || dx == nullptr || w == nullptr || s->n < 1 || s->n > kDim) {
        return SFD_ERR_INVAL;
    }
    const int n = s->n;
    // The compressed rows, in place: Y = U^T U (Cholesky, row by row over the touched columns;
    // row c of Tq becomes U's row with pivot c) and q = U^-T b (into Tq[c][n]). U's rows with unit
    // noise carry exactly the information of every folded row (the R factor of their QR
    // decomposition, up to signs). A pivot that has lost all but 1e-12 of its column's diagonal
    // is a direction the rows do not observe (the window's gauge, for one): that row is dropped,
    // which the exact factor would have zero.
    int k = 0;
    int piv[kDim] = {};  // the pivot column of each kept row
    for (int c = 0; c < n; ++c) {
        if (s->used[c] == 0) continue;
        double *row = s->Tq[c];
        const double ycc = row[c];
        double d = ycc;
        for (int r = 0; r < k; ++r) d -= s->Tq[piv[r]][c] * s->Tq[piv[r]][c];
        if (!(d > 1e-12 * ycc) || !(ycc > 0.0)) {
            s->used[c] = 0;
            continue;
        }
        const double u = std::sqrt(d);
        for (int j = c + 1; j <= n; ++j) {  // the last column: b, becoming q
            double v = row[j];
            for (int r = 0; r < k; ++r) v -= s->Tq[piv[r]][c] * s->Tq[piv[r]][j];
            row[j] = v / u;
        }
        row[c] = u;
        piv[k++] = c;
    }
    if (k == 0) {
        for (int i = 0; i < n; ++i) dx[i] = 0.0;
        return SFD_OK;
    }
    // B = P T^T (n x k; T's row r is zero left of its pivot); S = T B + I (k x k).
    for (int i = 0; i < n; ++i) {
        for (int r = 0; r < k; ++r) {
            const double *t = s->Tq[piv[r]];
            double v = 0.0;
            for (int l = piv[r]; l < n; ++l) v += P[i * kDim + l] * t[l];
            w->B[i][r] = v;
        }
    }
    // S is formed in the stack's own rows, which T no longer needs once read: row r of S needs
    // T's row piv[r] >= r only, so with the rows taken in order S's row r can replace Tq's row r
    // (every later row r' reads T's row piv[r'] >= r' > r). q, T's last column, is taken first.
    double q[kDim], z[kDim], dxn[kDim];
    for (int r = 0; r < k; ++r) q[r] = s->Tq[piv[r]][n];
    double(*S)[kDim + 1] = s->Tq;
    for (int r = 0; r < k; ++r) {
        const double *t = s->Tq[piv[r]];
        double row[kDim];
        for (int c = 0; c <= r; ++c) {
            double v = 0.0;
            for (int l = piv[r]; l < n; ++l) v += t[l] * w->B[l][c];
            row[c] = v + (r == c ? 1.0 : 0.0);
        }
        for (int c = 0; c <= r; ++c) S[r][c] = row[c];  // the lower triangle: all cholesky reads
    }
    if (!la::cholesky(S, k, S)) return SFD_ERR_NUMERIC;  // S = L L^T, L in place
    // With C = B L^-T (K = C L^-1) and z = L^-1 q: dx = K q = C z and
    // P' = P - K S K^T = P - C C^T. For the optimal gain this equals the Joseph form
    // (I - K T) P (I - K T)^T + K K^T at n^2 k / 2 products instead of about 2.5 n^3 (a fifth of
    // a frame, callgrind). What the Joseph form guards against, a P that loses positive
    // definiteness to rounding, is checked instead: a negative diagonal refuses the update.
    la::forward_solve(S, k, q, z);
    for (int i = 0; i < n; ++i) {
        la::forward_solve(S, k, w->B[i], w->B[i]);  // row i of C, in place
        double v = 0.0;
        for (int r = 0; r < k; ++r) v += w->B[i][r] * z[r];
        dxn[i] = v;
    }
    // P' lower triangle into the stack's rows too (L is no longer needed), so that P changes
    // only once every entry is known to be valid.
    double(*Pn)[kDim + 1] = s->Tq;
    for (int i = 0; i < n; ++i) {
        for (int j = 0; j <= i; ++j) {
            double v = 0.0;
            for (int r = 0; r < k; ++r) v += w->B[i][r] * w->B[j][r];
            Pn[i][j] = P[i * kDim + j] - v;
        }
    }
    for (int i = 0; i < n; ++i) {
        if (!all_finite(Pn[i], std::size_t(i) + 1) || !std::isfinite(dxn[i]) ||
            !(Pn[i][i] >= 0.0)) {
            return SFD_ERR_NUMERIC;
        }
    }
    for (int i = 0; i < n; ++i) {
        dx[i] = dxn[i];
        for (int j = 0; j <= i; ++j) {
            P[i * kDim + j] = Pn[i][j];
            P[j * kDim + i] = Pn[i][j];
        }
    }
    return SFD_OK;
}
