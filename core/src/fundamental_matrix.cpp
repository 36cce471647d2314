// SPDX-License-Identifier: MIT
// Fundamental-matrix RANSAC baseline, Kilic 2014 Section 3.1.2 / Table 2 (sfd/sfd_fundamental.h,
// core/docs/fundamental_matrix.md), and its selection inside the EKF association
// (sfd_assoc.h's SFD_METHOD_RANSACF, core/docs/association.md).
#include "association_internal.hpp"
#include "core_private.hpp"
#include "sampson.hpp"
#include "sfd/sfd_fundamental.h"
#include "sfd/sfd_ransac.h"

namespace sfd {
namespace fmat {
namespace {

constexpr int kSample = SFD_FUNDAMENTAL_SAMPLE_SIZE;

/// Jacobi sweeps before giving up. Cyclic Jacobi converges quadratically once the off-diagonal
/// part is small; the 9x9 matrices of this module need at most 8 sweeps (tests, and 186k random
/// samples; a cap of 6 fails some), so 30 is never reached on data that deserve an answer.
constexpr int kMaxSweeps = 30;

/// Converged when the off-diagonal Frobenius norm is below this times ||A||_F (a few ulps: the
/// eigenvector of an eigenvalue separated by gap from the rest is then accurate to ~kJacobiTol
/// ||A|| / gap, the accuracy the rounding of A itself allows).
constexpr double kJacobiTol = 4.0 * std::numeric_limits<double>::epsilon();

/// Null space of A^T A of dimension > 1: the two smallest eigenvalues of A^T A (squared singular
/// values of A) are both below this times the largest, i.e. sigma_8 / sigma_1 < 1e-5 in the
/// normalized coordinates. Exact degeneracies give 1e-17..1e-16 (rounding). Random minimal samples
/// reach down to ~1e-10 (measured: 186k samples at 1 px noise, 0.006% below 1e-8, none refused);
/// such a near-critical sample's F moves by ~noise / 1e-5 and is worthless anyway.
constexpr double kDegenerateRatio = 1e-10;

/// F_n of rank < 2 (sigma_2 / sigma_1 < 1e-10): no epipolar geometry, refused.
constexpr double kRankOneRatio = 1e-20;

/// Cyclic Jacobi eigen-decomposition of the symmetric N x N matrix A (full storage). On success the
/// diagonal of A holds the eigenvalues and the columns of V the orthonormal eigenvectors. Returns
/// false when the off-diagonal norm did not fall below kJacobiTol ||A||_F in kMaxSweeps sweeps or
/// A is not finite. Rotation formulas as in Rutishauser's (Numerical Recipes jacobi): the
/// rotation angle from t = sgn(theta) / (|theta| + sqrt(theta^2 + 1)), with the update written in
/// tau = s / (1 + c) form for accuracy.
template <std::size_t K>
bool jacobi_eigen(double (&A)[K][K], double (&V)[K][K]) {
    constexpr int N = static_cast<int>(K);
    double norm2 = 0.0;
    for (int r = 0; r < N; ++r) {
        for (int c = 0; c < N; ++c) {
            norm2 += A[r][c] * A[r][c];
            V[r][c] = (r == c) ? 1.0 : 0.0;
        }
    }
    if (!std::isfinite(norm2)) return false;
    const double stop2 = kJacobiTol * kJacobiTol * norm2;
    // Rotations for entries that cannot matter are skipped: when every a_pq^2 <= skip2, the
    // off-diagonal sum is <= stop2 and the next check stops (saves most of the last sweep).
    const double skip2 = stop2 / static_cast<double>(N * (N - 1));
    for (int sweep = 0; sweep <= kMaxSweeps; ++sweep) {
        double off2 = 0.0;
        for (int p = 0; p < N; ++p) {
            for (int q = p + 1; q < N; ++q) off2 += 2.0 * A[p][q] * A[p][q];
        }
        if (off2 <= stop2) return true;  // also the zero matrix
        if (sweep == kMaxSweeps) break;
        for (int p = 0; p < N - 1; ++p) {
            for (int q = p + 1; q < N; ++q) {
                const double apq = A[p][q];
                if (!(apq * apq > skip2)) continue;
                const double theta = (A[q][q] - A[p][p]) / (2.0 * apq);
                // theta^2 would overflow beyond ~1e154; there t = 1 / (2 theta) to full precision.
                double t = (std::fabs(theta) > 1e150)
                               ? 0.5 / std::fabs(theta)
                               : 1.0 / (std::fabs(theta) + std::sqrt(theta * theta + 1.0));
                if (theta < 0.0) t = -t;
                const double c = 1.0 / std::sqrt(t * t + 1.0);
                const double s = t * c;
                const double tau = s / (1.0 + c);
                A[p][p] -= t * apq;
                A[q][q] += t * apq;
                A[p][q] = 0.0;
                A[q][p] = 0.0;
                for (int r = 0; r < N; ++r) {
                    if (r != p && r != q) {
                        const double arp = A[r][p];
                        const double arq = A[r][q];
                        A[r][p] = arp - s * (arq + tau * arp);
                        A[p][r] = A[r][p];
                        A[r][q] = arq + s * (arp - tau * arq);
                        A[q][r] = A[r][q];
                    }
                    const double vrp = V[r][p];
                    const double vrq = V[r][q];
                    V[r][p] = vrp - s * (vrq + tau * vrp);
                    V[r][q] = vrq + s * (vrp - tau * vrq);
                }
            }
        }
    }
    return false;
}

/// Indices of the smallest and second smallest eigenvalue, and the largest value, of diag(A).
template <std::size_t K>
void smallest_two(const double (&A)[K][K], int *i0, int *i1, double *largest) {
    constexpr int N = static_cast<int>(K);
    int a = 0;
    for (int k = 1; k < N; ++k) {
        if (A[k][k] < A[a][a]) a = k;
    }
    int b = (a == 0) ? 1 : 0;
    double mx = A[0][0];
    for (int k = 0; k < N; ++k) {
        if (k != a && A[k][k] < A[b][b]) b = k;
        mx = std::fmax(mx, A[k][k]);
    }
    *i0 = a;
    *i1 = b;
    *largest = mx;
}

/// Hartley's similarity T = [s 0 -s cx; 0 s -s cy; 0 0 1] of one image's listed points: centroid
/// to the origin, mean distance to sqrt(2). False when every point coincides (no scale).
bool hartley_normalization(const double (*x)[2], const int32_t *idx, int32_t n, double *s,
                           double *cx, double *cy) {
    double mx = 0.0;
    double my = 0.0;
    for (int32_t k = 0; k < n; ++k) {
        mx += x[idx[k]][0];
        my += x[idx[k]][1];
    }
    mx /= static_cast<double>(n);
    my /= static_cast<double>(n);
    double mean_dist = 0.0;
    for (int32_t k = 0; k < n; ++k) {
        mean_dist += std::hypot(x[idx[k]][0] - mx, x[idx[k]][1] - my);
    }
    mean_dist /= static_cast<double>(n);
    // Relative test: points spread less than ~1e-12 of their magnitude are one point in doubles.
    const double mag = std::fabs(mx) + std::fabs(my);
    if (!(mean_dist > 1e-12 * mag) || !(mean_dist > 0.0) || !std::isfinite(mean_dist)) {
        return false;
    }
    *s = std::sqrt(2.0) / mean_dist;
    *cx = mx;
    *cy = my;
    return true;
}

/// inlier[i] = (Sampson distance of match i, with its pixel-noise covariances when @p noise is
/// given, <= threshold); returns the count.
int32_t score(const double *F, const double (*x_prev)[2], const double (*x_curr)[2],
              const sfd_pixel_noise_t *noise, int32_t n, double threshold_sq_px2, uint8_t *inlier) {
    int32_t count = 0;
    for (int32_t i = 0; i < n; ++i) {
        const float *dc1 = (noise != nullptr) ? noise[i].prev_dC : nullptr;
        const float *dc2 = (noise != nullptr) ? noise[i].curr_dC : nullptr;
        const bool in = sfd::sampson_px2(F, x_prev[i], x_curr[i], dc1, dc2) <= threshold_sq_px2;
        inlier[i] = in ? 1U : 0U;
        count += in ? 1 : 0;
    }
    return count;
}

}  // namespace
}  // namespace fmat
}  // namespace sfd

// Normalized 8-point algorithm (Hartley 1997), the model fit of Table 2 step 2 for eq. (25).
extern "C" sfd_status_t sfd_fundamental_8point(const double (*x_prev)[2], const double (*x_curr)[2],
                                               const int32_t *idx, int32_t n, double F[9]) {
    using namespace sfd::fmat;
    if (x_prev == nullptr || x_curr == nullptr || idx == nullptr || F == nullptr) {
        return SFD_ERR_INVAL;
    }
    if (n < kSample || n > SFD_MAX_FEATURES) return SFD_ERR_INVAL;
    for (int32_t k = 0; k < n; ++k) {
        const int32_t i = idx[k];
        if (i < 0 || i >= SFD_MAX_FEATURES) return SFD_ERR_INVAL;
        if (!sfd::all_finite(x_prev[i], 2) || !sfd::all_finite(x_curr[i], 2)) return SFD_ERR_INVAL;
    }
    // Normalization: without it the entries of A span ~1e6 (u^2 vs 1) and the least-squares
    // solution depends on where the image origin is; with it the fit is covariant under
    // similarity transforms of either image (Hartley 1997).
    double s1 = 0.0, c1x = 0.0, c1y = 0.0, s2 = 0.0, c2x = 0.0, c2y = 0.0;
    if (!hartley_normalization(x_prev, idx, n, &s1, &c1x, &c1y) ||
        !hartley_normalization(x_curr, idx, n, &s2, &c2x, &c2y)) {
        return SFD_ERR_NUMERIC;
    }
    // M = A^T A, a = x1n (x) x2n so that a . f = x1n^T F_n x2n with f = F_n row-major.
    double M[9][9] = {};
    for (int32_t k = 0; k < n; ++k) {
        const int32_t i = idx[k];
        const double p[3] = {s1 * (x_prev[i][0] - c1x), s1 * (x_prev[i][1] - c1y), 1.0};
        const double q[3] = {s2 * (x_curr[i][0] - c2x), s2 * (x_curr[i][1] - c2y), 1.0};
        double a[9];
        for (int r = 0; r < 3; ++r) {
            for (int c = 0; c < 3; ++c) a[3 * r + c] = p[r] * q[c];
        }
        for (int r = 0; r < 9; ++r) {
            for (int c = r; c < 9; ++c) M[r][c] += a[r] * a[c];
        }
    }
    for (int r = 0; r < 9; ++r) {
        for (int c = 0; c < r; ++c) M[r][c] = M[c][r];
    }
    double V[9][9];
    if (!jacobi_eigen<9>(M, V)) return SFD_ERR_NUMERIC;
    int i0 = 0, i1 = 0;
    double lmax = 0.0;
    smallest_two<9>(M, &i0, &i1, &lmax);
    // A one-dimensional null space is what makes F unique (up to scale). When the second smallest
    // eigenvalue is ~0 as well, any combination of the two vectors fits: refuse rather than
    // return an arbitrary member of the family.
    if (!(lmax > 0.0) || !(M[i1][i1] > kDegenerateRatio * lmax)) return SFD_ERR_NUMERIC;
    double Fn[3][3];
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) Fn[r][c] = V[3 * r + c][i0];
    }
    // Rank 2 (eq. 25's F is singular): the closest rank-2 matrix in the Frobenius norm drops the
    // smallest singular value, F2 = U diag(s1, s2, 0) V^T = Fn (I - v3 v3^T), with v3 the right
    // singular vector of s3, i.e. the eigenvector of the smallest eigenvalue of Fn^T Fn. U is not
    // needed, so a 3x3 Jacobi on Fn^T Fn is the whole SVD.
    double G[3][3];
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
            G[r][c] = Fn[0][r] * Fn[0][c] + Fn[1][r] * Fn[1][c] + Fn[2][r] * Fn[2][c];
        }
    }
    double W[3][3];
    if (!jacobi_eigen<3>(G, W)) return SFD_ERR_NUMERIC;
    int j0 = 0, j1 = 0;
    double gmax = 0.0;
    smallest_two<3>(G, &j0, &j1, &gmax);
    if (!(gmax > 0.0) || !(G[j1][j1] > kRankOneRatio * gmax)) return SFD_ERR_NUMERIC;
    const double v3[3] = {W[0][j0], W[1][j0], W[2][j0]};
    sfd::Mat3 F2;
    for (int r = 0; r < 3; ++r) {
        const double fv = Fn[r][0] * v3[0] + Fn[r][1] * v3[1] + Fn[r][2] * v3[2];
        for (int c = 0; c < 3; ++c) F2(r, c) = Fn[r][c] - fv * v3[c];
    }
    // Denormalization: x1n^T F2 x2n = x1^T (T1^T F2 T2) x2.
    sfd::Mat3 T1;
    T1 << s1, 0.0, -s1 * c1x, 0.0, s1, -s1 * c1y, 0.0, 0.0, 1.0;
    sfd::Mat3 T2;
    T2 << s2, 0.0, -s2 * c2x, 0.0, s2, -s2 * c2y, 0.0, 0.0, 1.0;
    const sfd::Mat3 Fd = T1.transpose() * F2 * T2;
    const double norm = Fd.norm();
    if (!(norm > 0.0) || !std::isfinite(norm)) return SFD_ERR_NUMERIC;
    // Canonical sign: the largest-magnitude entry (first one on ties) is positive.
    int imax = 0;
    for (int k = 1; k < 9; ++k) {
        if (std::fabs(Fd(k / 3, k % 3)) > std::fabs(Fd(imax / 3, imax % 3))) imax = k;
    }
    const double scale = (Fd(imax / 3, imax % 3) < 0.0) ? -1.0 / norm : 1.0 / norm;
    for (int k = 0; k < 9; ++k) F[k] = Fd(k / 3, k % 3) * scale;
    return SFD_OK;
}

// Sampson distance: eq. (25) divided by the norm of its gradient in (u1, v1, u2, v2).
extern "C" double sfd_sampson_sq_px2(const double F[9], const double x_prev[2],
                                     const double x_curr[2]) {
    if (F == nullptr || x_prev == nullptr || x_curr == nullptr) {
        return std::numeric_limits<double>::infinity();
    }
    return sfd::sampson_px2(F, x_prev, x_curr);
}

// The same with per-point noise covariances: e^2 / (g1^T C1 g1 + g2^T C2 g2) (sampson.hpp).
extern "C" double sfd_sampson_cov_sq_px2(const double F[9], const double x_prev[2],
                                         const double x_curr[2], const sfd_pixel_noise_t *noise) {
    if (F == nullptr || x_prev == nullptr || x_curr == nullptr || noise == nullptr) {
        return std::numeric_limits<double>::infinity();
    }
    return sfd::sampson_px2(F, x_prev, x_curr, noise->prev_dC, noise->curr_dC);
}

// Table 2, with the hypothesis count of eq. (27) and a final least-squares refit (sfd addition).
extern "C" sfd_status_t sfd_ransacf(const double (*x_prev)[2], const double (*x_curr)[2],
                                    const sfd_pixel_noise_t *noise, int32_t n,
                                    double threshold_sq_px2, double confidence,
                                    int32_t max_hypotheses, sfd_prng_t *rng, uint8_t *inlier,
                                    sfd_ransacf_result_t *out) {
    using namespace sfd::fmat;
    if (x_prev == nullptr || x_curr == nullptr || rng == nullptr || inlier == nullptr ||
        out == nullptr) {
        return SFD_ERR_INVAL;
    }
    if (n < 0 || max_hypotheses < 1) return SFD_ERR_INVAL;
    if (!(std::isfinite(threshold_sq_px2) && threshold_sq_px2 > 0.0)) return SFD_ERR_INVAL;
    if (!(confidence > 0.0 && confidence < 1.0)) return SFD_ERR_INVAL;
    // Capacities after the plain range checks, as in sfd_params_validate().
    if (n > SFD_MAX_FEATURES || max_hypotheses > SFD_MAX_HYPOTHESES) return SFD_ERR_CAPACITY;
    for (int32_t i = 0; i < n; ++i) {
        if (!sfd::all_finite(x_prev[i], 2) || !sfd::all_finite(x_curr[i], 2)) return SFD_ERR_INVAL;
        if (noise != nullptr && !sfd::pixel_noise_valid(noise[i])) return SFD_ERR_INVAL;
    }
    *out = sfd_ransacf_result_t{};
    for (int32_t i = 0; i < n; ++i) inlier[i] = 0U;
    if (n < kSample) return SFD_ERR_RANGE;  // no F from fewer than 8 matches: all untested

    // perm: the Fisher-Yates pool of the draws; after the loop, the inlier list of the refit.
    int32_t perm[SFD_MAX_FEATURES];
    uint8_t cur[SFD_MAX_FEATURES];
    for (int32_t i = 0; i < n; ++i) perm[i] = i;
    double F[9];
    int32_t best = -1;
    // Table 2 line 1: N starts "big", i.e. at the budget; eq. (27) is evaluated against
    // budget + 1 so that a demand above the budget is visible (budget_exhausted).
    int32_t required = max_hypotheses + 1;
    int32_t needed = max_hypotheses;
    int32_t used = 0;
    for (int32_t h = 0; h < SFD_MAX_HYPOTHESES; ++h) {
        if (h >= needed) break;
        ++used;
        // Partial Fisher-Yates: perm[0..7] becomes a uniform sample of 8 distinct matches. The
        // pool is not reset between hypotheses: any permutation is a valid starting point.
        for (int32_t k = 0; k < kSample; ++k) {
            const int32_t j =
                k + static_cast<int32_t>(sfd_prng_uniform_index(rng, static_cast<uint32_t>(n - k)));
            const int32_t tmp = perm[k];
            perm[k] = perm[j];
            perm[j] = tmp;
        }
        if (sfd_fundamental_8point(x_prev, x_curr, perm, kSample, F) != SFD_OK) continue;
        const int32_t count = score(F, x_prev, x_curr, noise, n, threshold_sq_px2, cur);
        if (count > best) {  // strictly more: the first of equal hypotheses wins
            best = count;
            for (int32_t i = 0; i < n; ++i) inlier[i] = cur[i];
            for (int k = 0; k < 9; ++k) out->F[k] = F[k];
            const double ratio = static_cast<double>(count) / static_cast<double>(n);
            required = sfd_ransac_hypothesis_count(confidence, ratio, kSample, max_hypotheses + 1);
            needed = (required < max_hypotheses) ? required : max_hypotheses;
        }
    }
    out->hypotheses_used = used;
    out->budget_exhausted = (required > max_hypotheses) ? 1 : 0;
    if (best < 0) return SFD_ERR_NUMERIC;  // every sample degenerate: no model, all untested

    // Refit (not in Table 2, which stops at the best hypothesis): the minimal-sample F carries the
    // noise of 8 matches; the least-squares F of all its inliers is far closer to the truth, and
    // one rescoring with it recovers inliers the sample's F cut off near the gate. Kept only when
    // it does not lose inliers, so the refit can never make the result worse by this measure.
    if (best >= kSample) {
        int32_t m = 0;
        for (int32_t i = 0; i < n; ++i) {
            if (inlier[i] != 0U) perm[m++] = i;
        }
        if (sfd_fundamental_8point(x_prev, x_curr, perm, m, F) == SFD_OK) {
            const int32_t count = score(F, x_prev, x_curr, noise, n, threshold_sq_px2, cur);
            if (count >= best) {
                best = count;
                for (int32_t i = 0; i < n; ++i) inlier[i] = cur[i];
                for (int k = 0; k < 9; ++k) out->F[k] = F[k];
            }
        }
    }
    out->num_inliers = best;
    return SFD_OK;
}

namespace sfd {
namespace assoc {

sfd_status_t ransacf_select(sfd_assoc_t *a, const SelectInputs &in, sfd_assoc_result_t *out) {
    const sfd_assoc_params_t &prm = a->params;
    const int32_t nv = in.nv;
    a->stage = SFD_STAGE_RANSAC_F;
    sfd_ransacf_result_t rf;
    // cur[] holds the compacted inlier flags of the nv valid matches.
    sfd_assoc_ransacf_work_t &w = a->work->ransacf;
    const sfd_status_t st = sfd_ransacf(w.x_prev, w.x_curr, w.noise, nv, a->chi2_1 * in.sigma2,
                                        prm.confidence, prm.max_hypotheses, &a->rng, a->cur, &rf);
    if (st == SFD_ERR_RANGE || st == SFD_ERR_NUMERIC) {
        // fewer than 8 matches, or every sample degenerate: nothing can be judged
        for (int32_t k = 0; k < nv; ++k) a->valid[a->valid_idx[k]] = 0U;
        return SFD_OK;
    }
    if (st != SFD_OK) return st;
    out->hypotheses_used = rf.hypotheses_used;
    out->budget_exhausted = rf.budget_exhausted;
    out->inliers_stage1 = rf.num_inliers;
    for (int32_t k = 0; k < nv; ++k) {
        const int32_t i = a->valid_idx[k];
        a->best[i] = a->cur[k];
        const double d =
            sampson_px2(rf.F, w.x_prev[k], w.x_curr[k], w.noise[k].prev_dC, w.noise[k].curr_dC);
        a->best_stat[i] = static_cast<float>(std::fmin(d / in.sigma2, 3.0e38));
    }
    return SFD_OK;
}

}  // namespace assoc
}  // namespace sfd
