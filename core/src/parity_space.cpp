// SPDX-License-Identifier: MIT
// Parity-space test on one group (sfd/sfd_parity.h, core/docs/parity_space.md).
#include "parity_space.hpp"

#include <Eigen/Eigenvalues>

#include "rotation.hpp"
#include "small_linalg.hpp"

namespace sfd {
namespace parity {

// O_i = [(I 0) R_0; ...; (I 0) R_{L-1}] (eq. 27, one feature's block). Its rank comes from the
// eigenvalues of the 3x3 Gram matrix O_i^T O_i; the column space U (2L x rank) from the
// eigenvectors, U = O_i V S^{-1}; B is completed from the Householder factorization of U:
// Q = H_0 ... H_{rank-1}, B = Q(:, rank:2L).
bool window_basis(const double (*R_C0toCt)[9], int L, WindowBasis *wb) {
    const int rows = 2 * L;
    double O[kMaxRows][3] = {};
    for (int t = 0; t < L; ++t) {
        if (!all_finite(R_C0toCt[t], 9)) return false;
        for (int c = 0; c < 2; ++c) {
            for (int k = 0; k < 3; ++k) O[2 * t + c][k] = R_C0toCt[t][3 * c + k];
        }
    }
    Eigen::Matrix3d N = Eigen::Matrix3d::Zero();
    for (int r = 0; r < rows; ++r) {
        for (int a = 0; a < 3; ++a) {
            for (int b = 0; b < 3; ++b) N(a, b) += O[r][a] * O[r][b];
        }
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(N);
    if (es.info() != Eigen::Success) return false;
    const Eigen::Vector3d &lambda = es.eigenvalues();  // ascending
    const double s_max = std::sqrt(std::fmax(lambda(2), 0.0));
    int rank = 0;
    double U[kMaxRows][3] = {};
    for (int j = 2; j >= 0; --j) {
        const double s = std::sqrt(std::fmax(lambda(j), 0.0));
        if (!(s > kRankTol * s_max)) break;
        const Eigen::Vector3d v = es.eigenvectors().col(j);
        for (int r = 0; r < rows; ++r) {
            U[r][rank] = (O[r][0] * v(0) + O[r][1] * v(1) + O[r][2] * v(2)) / s;
        }
        ++rank;
    }
    if (rank == 0) return false;
    // Householder vectors of U, v_k stored contiguously in V[k][k..rows). (Stored as the columns
    // of a [kMaxRows][3] array, every loop below strided by 3; GCC 12.2 at -O3 -march=native on
    // an AVX-512 CPU vectorized those loops with an aligned 32-byte load from a local it had
    // placed 16-aligned, and every parity test segfaulted: the host-native preset runs the unit
    // tests built that way. Same arithmetic in the same order, so the same bits.)
    double V[3][kMaxRows] = {};
    for (int k = 0; k < rank; ++k) {
        double norm2 = 0.0;
        for (int r = k; r < rows; ++r) norm2 += U[r][k] * U[r][k];
        const double norm = std::sqrt(norm2);
        const double alpha = (U[k][k] > 0.0) ? -norm : norm;
        double vnorm2 = 0.0;
        for (int r = k; r < rows; ++r) {
            V[k][r] = U[r][k] - ((r == k) ? alpha : 0.0);
            vnorm2 += V[k][r] * V[k][r];
        }
        if (!(vnorm2 > 0.0)) return false;
        const double inv = 1.0 / std::sqrt(vnorm2);
        for (int r = k; r < rows; ++r) V[k][r] *= inv;
        for (int c = k + 1; c < rank; ++c) {  // U <- H_k U
            double dot = 0.0;
            for (int r = k; r < rows; ++r) dot += V[k][r] * U[r][c];
            for (int r = k; r < rows; ++r) U[r][c] -= 2.0 * dot * V[k][r];
        }
    }
    wb->L = L;
    wb->rank = rank;
    wb->d = rows - rank;
    for (int j = rank; j < rows; ++j) {
        double e[kMaxRows] = {};
        e[j] = 1.0;
        for (int k = rank - 1; k >= 0; --k) {  // e <- H_k e, last reflector first
            double dot = 0.0;
            for (int r = k; r < rows; ++r) dot += V[k][r] * e[r];
            for (int r = k; r < rows; ++r) e[r] -= 2.0 * dot * V[k][r];
        }
        for (int r = 0; r < rows; ++r) wb->B[r][j - rank] = e[r];
    }
    return true;
}

namespace {

// reduce_feature for the basis's d given as D (an int, or la::Dim<d> for unrolled loops).
template <typename D>
bool reduce_feature_d(const WindowBasis &wb, const FeatureWindow &fw, const double (*R_C0toCt)[9],
                      const double (*p_CtInC0)[3], bool translation_known, D d,
                      FeatureReduced *out) {
    const int L = wb.L;
    double C[kMaxD][kMaxD];
    for (int k = 0; k < d; ++k) {
        for (int l = 0; l < d; ++l) C[k][l] = 0.0;
    }
    for (int k = 0; k < d; ++k) out->r[k] = 0.0;
    for (int t = 0; t < L; ++t) {
        // Z_t = zhat y_t (+ (I 0) R_t p_t): the depth-scaled measurement of eq. (24) with the
        // known input moved to the left, eq. (25).
        double Z[2] = {fw.depth[t] * fw.y[t][0], fw.depth[t] * fw.y[t][1]};
        if (translation_known) {
            for (int c = 0; c < 2; ++c) {
                for (int k = 0; k < 3; ++k) Z[c] += R_C0toCt[t][3 * c + k] * p_CtInC0[t][k];
            }
        }
        // S_t = Cov(zhat e_t) = zhat^2 Cov(e^c) + P_z y_dir y_dir^T (eq. 22 scaled by Zhat, or 28).
        const double z2 = fw.depth[t] * fw.depth[t];
        const double pz = fw.depth_var[t];
        const double S00 = z2 * fw.cov_y[t][0] + pz * fw.y_dir[t][0] * fw.y_dir[t][0];
        const double S01 = z2 * fw.cov_y[t][1] + pz * fw.y_dir[t][0] * fw.y_dir[t][1];
        const double S11 = z2 * fw.cov_y[t][2] + pz * fw.y_dir[t][1] * fw.y_dir[t][1];
        for (int k = 0; k < d; ++k) {
            const double b0k = wb.B[2 * static_cast<std::ptrdiff_t>(t)][k];
            const double b1k = wb.B[2 * static_cast<std::ptrdiff_t>(t) + 1][k];
            out->r[k] += b0k * Z[0] + b1k * Z[1];
            const double sb0 = S00 * b0k + S01 * b1k;  // (S B_t)(:, k)
            const double sb1 = S01 * b0k + S11 * b1k;
            for (int l = 0; l <= k; ++l) {
                C[k][l] += wb.B[2 * static_cast<std::ptrdiff_t>(t)][l] * sb0 +
                           wb.B[2 * static_cast<std::ptrdiff_t>(t) + 1][l] * sb1;
            }
        }
    }
    for (int k = 0; k < d; ++k) {
        for (int l = 0; l < k; ++l) C[l][k] = C[k][l];
    }
    if (!la::cholesky(C, d, out->Lc)) return false;
    la::chol_inverse(out->Lc, d, out->Cinv);
    double w[kMaxD];
    la::forward_solve(out->Lc, d, out->r, w);
    out->q = 0.0;
    for (int k = 0; k < d; ++k) out->q += w[k] * w[k];
    // Fault signatures in the reduced coordinates: B^T Phi with Phi the fault's image in Z.
    const double den = (L > 1) ? static_cast<double>(L - 1) : 1.0;
    for (int k = 0; k < d; ++k) {
        for (int c = 0; c < 2; ++c) {
            out->phi_jump[k][c] = fw.depth[L - 1] * wb.B[2 * (L - 1) + c][k];
            double acc = 0.0;
            for (int t = 1; t < L; ++t) {
                acc += (static_cast<double>(t) / den) * fw.depth[t] * wb.B[2 * t + c][k];
            }
            out->phi_drift[k][c] = acc;
        }
    }
    return std::isfinite(out->q);
}

// Unknown translation: T = sum q_i - b^T A^{-1} b (computed as a sum of squares) over the features
// listed in idx (GLS form of the projection onto the complement of the common component, see
// parity_space.hpp).
template <typename D>
__attribute__((noinline)) bool schur_statistic(const FeatureReduced *const *f, const int *idx,
                                               int m, D d, double *T, double (*x_out)[kMaxD],
                                               double (*Ainv_out)[kMaxD][kMaxD]) {
    if (m < 1 || m > kMaxN || d < 1 || d > kMaxD) return false;  // sizes are the callers' bounds
    double A[kMaxD][kMaxD];
    double b[kMaxD];
    for (int k = 0; k < d; ++k) {
        b[k] = 0.0;
        for (int l = 0; l < d; ++l) A[k][l] = 0.0;
    }
    for (int a = 0; a < m; ++a) {
        const FeatureReduced &fr = *f[idx[a]];
        for (int k = 0; k < d; ++k) {
            double cr = 0.0;
            for (int l = 0; l < d; ++l) {
                A[k][l] += fr.Cinv[k][l];
                cr += fr.Cinv[k][l] * fr.r[l];
            }
            b[k] += cr;
        }
    }
    double LA[kMaxD][kMaxD];
    if (!la::cholesky(A, d, LA)) return false;
    double x[kMaxD];
    la::chol_solve(LA, d, b, x);
    // T = sum_i (r_i - x)^T C_i^{-1} (r_i - x), equal to sum q_i - b^T x but free of the
    // cancellation between two large numbers when the common component is large.
    double T_sum = 0.0;
    for (int a = 0; a < m; ++a) {
        const FeatureReduced &fr = *f[idx[a]];
        double e[kMaxD];
        for (int k = 0; k < d; ++k) e[k] = fr.r[k] - x[k];
        la::forward_solve(fr.Lc, d, e, e);
        for (int k = 0; k < d; ++k) T_sum += e[k] * e[k];
    }
    *T = T_sum;
    if (x_out != nullptr) {
        for (int k = 0; k < d; ++k) (*x_out)[k] = x[k];
    }
    if (Ainv_out != nullptr) la::chol_inverse(LA, d, *Ainv_out);
    return std::isfinite(*T);
}

// Block j of the projected precision (the residual's information about feature j's reduced
// measurements once the landmarks, and for unknown translation the common component, are
// eliminated): M_jj = C_j^{-1} (known translation, Ainv = nullptr) or
// C_j^{-1} - C_j^{-1} A^{-1} C_j^{-1} with A = sum_i C_i^{-1} (unknown).
template <typename D>
__attribute__((noinline)) void precision_block(const FeatureReduced &fj,
                                               const double (*Ainv)[kMaxD], D d,
                                               double (*M)[kMaxD]) {
    for (int k = 0; k < d; ++k) {
        for (int l = 0; l < d; ++l) M[k][l] = fj.Cinv[k][l];
    }
    if (Ainv == nullptr) return;
    double T1[kMaxD][kMaxD];
    for (int k = 0; k < d; ++k) {
        for (int l = 0; l < d; ++l) {
            double acc = 0.0;
            for (int m = 0; m < d; ++m) acc += Ainv[k][m] * fj.Cinv[m][l];
            T1[k][l] = acc;
        }
    }
    for (int k = 0; k < d; ++k) {
        for (int l = 0; l < d; ++l) {
            double acc = 0.0;
            for (int m = 0; m < d; ++m) acc += fj.Cinv[k][m] * T1[m][l];
            M[k][l] -= acc;
        }
    }
}

// GLR of a fault e_j (x) Phi f: g^T G^+ g with g = Phi^T s_j, G = Phi^T M_jj Phi.
template <typename D>
__attribute__((noinline)) double signature_glr(const double (*phi)[2], const double *s,
                                               const double (*M)[kMaxD], D d, int *dof) {
    double G[2][2] = {};
    double g[2] = {};
    for (int a = 0; a < 2; ++a) {
        for (int k = 0; k < d; ++k) g[a] += phi[k][a] * s[k];
        for (int b = 0; b < 2; ++b) {
            double acc = 0.0;
            for (int k = 0; k < d; ++k) {
                double mk = 0.0;
                for (int l = 0; l < d; ++l) mk += M[k][l] * phi[l][b];
                acc += phi[k][a] * mk;
            }
            G[a][b] = acc;
        }
    }
    return la::pinv_quadratic_2x2(G, g, dof);
}

template <typename D>
bool group_stats_d(const FeatureReduced *const *f, int n, D d, bool translation_known,
                   bool signatures, GroupStats *out) {
    int all[kMaxN] = {};
    for (int i = 0; i < n; ++i) all[i] = i;
    double Ainv[kMaxD][kMaxD] = {};
    if (translation_known) {
        out->nu = n * d;
        out->glr = 0.0;
        for (int i = 0; i < n; ++i) {
            out->glr += f[i]->q;
            out->feature_glr[i] = f[i]->q;
            out->feature_dof[i] = d;
        }
        for (int k = 0; k < d; ++k) out->x[k] = 0.0;
    } else {
        out->nu = (n - 1) * d;
        out->glr = 0.0;
        for (int i = 0; i < n; ++i) {
            out->feature_glr[i] = 0.0;
            out->feature_dof[i] = 0;
        }
        if (n < 2) return true;  // nothing to test: the translation absorbs a lone feature
        if (!schur_statistic(f, all, n, d, &out->glr, &out->x, signatures ? &Ainv : nullptr)) {
            return false;
        }
        for (int j = 0; j < n && signatures; ++j) {
            // General fault on feature j: T - T(without j), chi2(d) under H0.
            int others[kMaxN] = {};
            int m = 0;
            for (int i = 0; i < n; ++i) {
                if (i != j) others[m++] = i;
            }
            double T_rest = 0.0;
            if (m >= 2 && !schur_statistic(f, others, m, d, &T_rest, nullptr, nullptr)) {
                return false;
            }
            out->feature_glr[j] = std::fmax(out->glr - T_rest, 0.0);
            out->feature_dof[j] = d;
        }
    }
    if (!signatures) return true;
    for (int j = 0; j < n; ++j) {
        const FeatureReduced &fr = *f[j];
        double s[kMaxD];
        double M[kMaxD][kMaxD];
        for (int k = 0; k < d; ++k) {
            double acc = 0.0;
            for (int l = 0; l < d; ++l) acc += fr.Cinv[k][l] * (fr.r[l] - out->x[l]);
            s[k] = acc;
        }
        precision_block(fr, translation_known ? nullptr : Ainv, d, M);
        out->jump_glr[j] = signature_glr(fr.phi_jump, s, M, d, &out->jump_dof[j]);
        out->drift_glr[j] = signature_glr(fr.phi_drift, s, M, d, &out->drift_dof[j]);
    }
    return true;
}

template <int D, typename F>
auto call_with_dim(F &f, int d) {
    if constexpr (D <= kMaxD) {
        return f(la::Dim<D>{});
    } else {
        return f(d);  // a case above this build's kMaxD: never taken, d <= kMaxD
    }
}

/// Calls f(la::Dim<d>{}) for 1 <= d <= min(8, kMaxD), f(d) otherwise: a build with
/// SFD_MAX_WINDOW > 5 runs its larger d (up to kMaxD = 2 SFD_MAX_WINDOW - 2) with the run-time
/// size, as fast as before the compile-time sizes. The compile-time size unrolls the d-loops of
/// the kernels above; results are bit-identical to the run-time size (small_linalg.hpp).
template <typename F>
auto with_dim(int d, F &&f) {
    switch (d) {
        case 1:
            return call_with_dim<1>(f, d);
        case 2:
            return call_with_dim<2>(f, d);
        case 3:
            return call_with_dim<3>(f, d);
        case 4:
            return call_with_dim<4>(f, d);
        case 5:
            return call_with_dim<5>(f, d);
        case 6:
            return call_with_dim<6>(f, d);
        case 7:
            return call_with_dim<7>(f, d);
        case 8:
            return call_with_dim<8>(f, d);
        default:
            return f(d);
    }
}

}  // namespace

bool reduce_feature(const WindowBasis &wb, const FeatureWindow &fw, const double (*R_C0toCt)[9],
                    const double (*p_CtInC0)[3], bool translation_known, FeatureReduced *out) {
    if (wb.d < 1 || wb.d > kMaxD || wb.L < 1 || wb.L > kMaxL) return false;  // a corrupted basis
    return with_dim(wb.d, [&](auto d) {
        return reduce_feature_d(wb, fw, R_C0toCt, p_CtInC0, translation_known, d, out);
    });
}

bool group_stats(const FeatureReduced *const *f, int n, int d, bool translation_known,
                 bool signatures, GroupStats *out) {
    if (d < 1 || d > kMaxD || n < 1 || n > kMaxN) return false;  // sizes are the callers' bounds
    return with_dim(
        d, [&](auto dd) { return group_stats_d(f, n, dd, translation_known, signatures, out); });
}

}  // namespace parity
}  // namespace sfd

using namespace sfd;
using namespace sfd::parity;

namespace {

// Helmert basis of the complement of 1_n: column k (k < n - 1) has 1/sqrt((k+1)(k+2)) in rows
// 0..k and -(k+1)/sqrt((k+1)(k+2)) in row k+1.
double helmert(int i, int k) {
    const double den = std::sqrt(static_cast<double>((k + 1) * (k + 2)));
    if (i <= k) return 1.0 / den;
    if (i == k + 1) return -static_cast<double>(k + 1) / den;
    return 0.0;
}

sfd_status_t validate_group(const sfd_parity_group_t *g) {
    if (g == nullptr) return SFD_ERR_INVAL;
    const int L = g->window_frames;
    const int n = g->group_size;
    if (L < 2 || L > SFD_MAX_WINDOW || n < 1 || n > SFD_MAX_GROUP) return SFD_ERR_INVAL;
    if ((g->translation_known != 0 && g->translation_known != 1) ||
        (g->exact_depth_covariance != 0 && g->exact_depth_covariance != 1)) {
        return SFD_ERR_INVAL;
    }
    for (int t = 0; t < L; ++t) {
        if (!is_rotation(Eigen::Map<const Mat3>(g->R_C0toCt[t]), 1e-6)) return SFD_ERR_INVAL;
        if (g->translation_known && !all_finite(g->p_CtInC0_m[t], 3)) return SFD_ERR_INVAL;
    }
    if ((Eigen::Map<const Mat3>(g->R_C0toCt[0]) - Mat3::Identity()).cwiseAbs().maxCoeff() > 1e-9) {
        return SFD_ERR_INVAL;
    }
    for (int i = 0; i < n; ++i) {
        for (int t = 0; t < L; ++t) {
            if (!all_finite(g->y[i][t], 2) || !all_finite(g->cov_y[i][t], 3)) return SFD_ERR_INVAL;
            if (g->exact_depth_covariance && !all_finite(g->y_pred[i][t], 2)) return SFD_ERR_INVAL;
            if (!(std::isfinite(g->depth_m[i][t]) && g->depth_m[i][t] > 0.0)) return SFD_ERR_INVAL;
            if (!(std::isfinite(g->depth_var_m2[i][t]) && g->depth_var_m2[i][t] >= 0.0)) {
                return SFD_ERR_INVAL;
            }
        }
    }
    return SFD_OK;
}

void load_feature(const sfd_parity_group_t *g, int i, FeatureWindow *fw) {
    for (int t = 0; t < g->window_frames; ++t) {
        for (int c = 0; c < 2; ++c) {
            fw->y[t][c] = g->y[i][t][c];
            fw->y_dir[t][c] = g->exact_depth_covariance ? g->y_pred[i][t][c] : g->y[i][t][c];
        }
        for (int c = 0; c < 3; ++c) fw->cov_y[t][c] = g->cov_y[i][t][c];
        fw->depth[t] = g->depth_m[i][t];
        fw->depth_var[t] = g->depth_var_m2[i][t];
    }
}

// Basis + reduced features of a validated group. Returns an sfd status.
// Validated group -> basis and reduced features (the common start of the C entry points).
sfd_status_t prepare(const sfd_parity_group_t *g, WindowBasis *wb, FeatureReduced *fr) {
    const sfd_status_t v = validate_group(g);
    if (v != SFD_OK) return v;
    if (!window_basis(g->R_C0toCt, g->window_frames, wb)) return SFD_ERR_NUMERIC;
    for (int i = 0; i < g->group_size; ++i) {
        FeatureWindow fw{};
        load_feature(g, i, &fw);
        if (!reduce_feature(*wb, fw, g->R_C0toCt, g->p_CtInC0_m, g->translation_known != 0,
                            &fr[i])) {
            return SFD_ERR_NUMERIC;
        }
    }
    return SFD_OK;
}

}  // namespace

extern "C" sfd_status_t sfd_parity_test_group(const sfd_parity_group_t *group,
                                              sfd_parity_result_t *result) {
    if (result == nullptr) return SFD_ERR_INVAL;
    WindowBasis wb;
    FeatureReduced fr[kMaxN];
    const sfd_status_t p = prepare(group, &wb, fr);
    if (p != SFD_OK) return p;
    const int n = group->group_size;
    const int d = wb.d;
    const FeatureReduced *ptr[kMaxN];
    for (int i = 0; i < n; ++i) ptr[i] = &fr[i];
    GroupStats gs;
    if (!group_stats(ptr, n, d, group->translation_known != 0, true, &gs)) return SFD_ERR_NUMERIC;

    // Whitened residual rbar = L^{-1} (basis^T Z) for the basis of sfd_parity_group_basis().
    constexpr int kMaxW = (kMaxN - 1) * kMaxD > 1 ? (kMaxN - 1) * kMaxD : 1;
    for (int k = 0; k < SFD_PARITY_MAX_RESIDUAL; ++k) result->whitened[k] = 0.0;
    if (group->translation_known) {
        for (int i = 0; i < n; ++i) {
            la::forward_solve(fr[i].Lc, d, fr[i].r,
                              result->whitened + static_cast<std::ptrdiff_t>(i) * d);
        }
    } else if (n >= 2) {
        const int m = (n - 1) * d;
        double W[kMaxW][kMaxW];
        double rho[kMaxW];
        for (int k = 0; k < n - 1; ++k) {
            for (int l = 0; l < d; ++l) {
                double acc = 0.0;
                for (int i = 0; i < n; ++i) acc += helmert(i, k) * fr[i].r[l];
                rho[k * d + l] = acc;
            }
        }
        for (int k = 0; k < n - 1; ++k) {
            for (int k2 = 0; k2 < n - 1; ++k2) {
                for (int l = 0; l < d; ++l) {
                    for (int l2 = 0; l2 < d; ++l2) {
                        double acc = 0.0;
                        for (int i = 0; i < n; ++i) {
                            // C_i(l, l2) = (Lc Lc^T)(l, l2)
                            double c = 0.0;
                            for (int s = 0; s < d; ++s) c += fr[i].Lc[l][s] * fr[i].Lc[l2][s];
                            acc += helmert(i, k) * helmert(i, k2) * c;
                        }
                        W[k * d + l][k2 * d + l2] = acc;
                    }
                }
            }
        }
        if (!la::cholesky(W, m, W)) return SFD_ERR_NUMERIC;
        la::forward_solve(W, m, rho, result->whitened);
    }
    result->per_feature_dim = d;
    result->rank_O = wb.rank;
    result->residual_dim = gs.nu;
    result->glr = gs.glr;
    for (int i = 0; i < SFD_MAX_GROUP; ++i) {
        const bool in = i < n;
        result->feature_glr[i] = in ? gs.feature_glr[i] : 0.0;
        result->feature_dof[i] = in ? gs.feature_dof[i] : 0;
        result->jump_glr[i] = in ? gs.jump_glr[i] : 0.0;
        result->jump_dof[i] = in ? gs.jump_dof[i] : 0;
        result->drift_glr[i] = in ? gs.drift_glr[i] : 0.0;
        result->drift_dof[i] = in ? gs.drift_dof[i] : 0;
    }
    return SFD_OK;
}

extern "C" sfd_status_t sfd_parity_noncentrality(const sfd_parity_group_t *group, int32_t feature,
                                                 int32_t frame, const double fault[2],
                                                 double *lambda) {
    if (lambda == nullptr || fault == nullptr || !all_finite(fault, 2) || group == nullptr ||
        feature < 0 || feature >= group->group_size || frame < 0 || frame >= group->window_frames) {
        return SFD_ERR_INVAL;
    }
    WindowBasis wb;
    FeatureReduced fr[kMaxN];
    const sfd_status_t p = prepare(group, &wb, fr);
    if (p != SFD_OK) return p;
    const int n = group->group_size;
    const int d = wb.d;
    // Fault image in the reduced residual of `feature`: B_t^T zhat f (eq. 16's W^T H^f F).
    double dr[kMaxD];
    const double zhat = group->depth_m[feature][frame];
    for (int k = 0; k < d; ++k) {
        const std::ptrdiff_t row = 2 * static_cast<std::ptrdiff_t>(frame);
        dr[k] = zhat * (wb.B[row][k] * fault[0] + wb.B[row + 1][k] * fault[1]);
    }
    // lambda = dr^T M_jj dr (eq. 16 with the projected precision of the faulty feature).
    const bool known = group->translation_known != 0;
    if (!known && n < 2) {
        *lambda = 0.0;  // a lone feature's fault is absorbed by the translation
        return SFD_OK;
    }
    double Ainv[kMaxD][kMaxD] = {};
    if (!known) {
        const FeatureReduced *ptr[kMaxN];
        int all[kMaxN] = {};
        for (int i = 0; i < n; ++i) {
            ptr[i] = &fr[i];
            all[i] = i;
        }
        double T = 0.0;
        if (!schur_statistic(ptr, all, n, d, &T, nullptr, &Ainv)) return SFD_ERR_NUMERIC;
    }
    double M[kMaxD][kMaxD];
    precision_block(fr[feature], known ? nullptr : Ainv, d, M);
    double out = 0.0;
    for (int k = 0; k < d; ++k) {
        for (int l = 0; l < d; ++l) out += dr[k] * M[k][l] * dr[l];
    }
    *lambda = std::fmax(out, 0.0);
    return SFD_OK;
}

extern "C" sfd_status_t sfd_parity_group_basis(const sfd_parity_group_t *group, double *basis,
                                               int32_t capacity, int32_t *dim) {
    if (basis == nullptr || dim == nullptr) return SFD_ERR_INVAL;
    const sfd_status_t v = validate_group(group);
    if (v != SFD_OK) return v;
    WindowBasis wb;
    if (!window_basis(group->R_C0toCt, group->window_frames, &wb)) return SFD_ERR_NUMERIC;
    const int n = group->group_size;
    const int L = group->window_frames;
    const int d = wb.d;
    const int cols = group->translation_known ? n * d : (n - 1) * d;
    const int rows = 2 * n * L;
    if (static_cast<long>(rows) * cols > static_cast<long>(capacity)) return SFD_ERR_CAPACITY;
    for (int i = 0; i < n; ++i) {
        for (int rr = 0; rr < 2 * L; ++rr) {
            const int row = 2 * L * i + rr;
            for (int c = 0; c < cols; ++c) {
                double val;
                if (group->translation_known) {
                    val = (c / d == i) ? wb.B[rr][c % d] : 0.0;
                } else {
                    val = helmert(i, c / d) * wb.B[rr][c % d];
                }
                basis[row * cols + c] = val;
            }
        }
    }
    *dim = cols;
    return SFD_OK;
}
