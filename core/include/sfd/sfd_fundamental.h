/* SPDX-License-Identifier: MIT */
/**
 * @file sfd_fundamental.h
 * @brief Fundamental-matrix RANSAC baseline of Kilic 2014 (Section 3.1.2, Table 2): the normalized
 *        8-point fit, the Sampson distance and the adaptive RANSAC loop around them.
 *
 * Convention (Kilic eq. 25 with p1 = previous frame, p2 = current frame):
 *     x_prev^T F x_curr = 0,   x = (u, v, 1) in undistorted pixel coordinates.
 * For a calibrated camera K whose current-frame coordinates map into the previous camera as
 * X_prev = R X_curr + t, this F is eq. (26): F = K^-T R [R^T t]_x K^-1 (= K^-T [t]_x R K^-1).
 *
 * Pure functions on caller-owned arrays: no heap, no global state, reentrant; the PRNG passed to
 * sfd_ransacf() is the only state it changes. Design note with the choices the thesis leaves open
 * (8-point variant, distance, refit): core/docs/fundamental_matrix.md.
 */
#ifndef SFD_FUNDAMENTAL_H
#define SFD_FUNDAMENTAL_H

#include <stdint.h>

#include "sfd_camera.h"
#include "sfd_config.h"
#include "sfd_prng.h"
#include "sfd_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Matches in one 8-point sample (the minimal linear fit; m of eq. 27). */
#define SFD_FUNDAMENTAL_SAMPLE_SIZE 8

/**
 * @brief Hartley's normalized 8-point algorithm: the F of eq. (25) that best fits the listed
 *        matches in the algebraic least-squares sense, with rank 2 enforced.
 *
 * Each image's points are translated to their centroid and scaled to a mean distance of sqrt(2)
 * (T_prev, T_curr). The null vector of A^T A (rows a = x_prev (x) x_curr of the normalized points)
 * is found by a cyclic Jacobi eigen-decomposition (fixed sweep cap); its smallest singular value is
 * then removed (closest rank-2 matrix in the Frobenius norm), F is denormalized,
 * F = T_prev^T F_n T_curr, and scaled to ||F||_F = 1 with its largest-magnitude entry positive (a
 * canonical sign, so equal inputs give equal matrices). Exactly 8 matches give the exact solution;
 * more give the least-squares one.
 *
 * @param x_prev  Undistorted pixel coordinates (u, v) in the previous frame (px); read only at the
 *                listed indices.
 * @param x_curr  The same matches in the current frame (px).
 * @param idx     Indices of the matches to use, n entries, each in [0, SFD_MAX_FEATURES) (it is
 *                invalid to list an index past the end of x_prev/x_curr). Repeats are allowed
 *                (they add no information and may make the fit degenerate).
 * @param n       Number of listed matches, 8 <= n <= SFD_MAX_FEATURES.
 * @param F       Out: row-major 3x3, ||F||_F = 1, rank 2. Untouched on error.
 * @return SFD_OK; SFD_ERR_INVAL for a null pointer, n or an index out of range, or a non-finite
 *         coordinate; SFD_ERR_NUMERIC for a degenerate configuration (all points of an image
 *         coincide; the two smallest eigenvalues of A^T A are both below 1e-10 times the largest,
 *         i.e. the solution is not unique, as for coplanar points, pure rotation or too few
 *         distinct matches) or when Jacobi did not converge within its sweep cap.
 */
sfd_status_t sfd_fundamental_8point(const double (*x_prev)[2], const double (*x_curr)[2],
                                    const int32_t *idx, int32_t n, double F[9]);

/**
 * @brief Sampson (first-order geometric) error of one match against F, in px^2:
 *        d = (x1^T F x2)^2 / ((F x2)_1^2 + (F x2)_2^2 + (F^T x1)_1^2 + (F^T x1)_2^2),
 *        with x1 = (x_prev, 1), x2 = (x_curr, 1) (eq. 25 normalized by its gradient).
 *
 * d is the squared distance of the 4-vector (x_prev, x_curr) to the variety x1^T F x2 = 0, to first
 * order. With isotropic Gaussian pixel noise of standard deviation sigma in both images, d /
 * sigma^2 is approximately chi-square with 1 dof, so a test at false-alarm rate alpha uses the
 * threshold sigma^2 * chi2_{1, 1-alpha} (sfd_chi2_quantile_upper(alpha, 1, &q)). Independent of the
 * scale of F.
 *
 * @return d >= 0; +infinity when the denominator is 0 or the result is not finite (non-finite
 *         input, null pointer), so such a match is never an inlier. Reentrant.
 */
double sfd_sampson_sq_px2(const double F[9], const double x_prev[2], const double x_curr[2]);

/**
 * @brief Sampson distance with per-point pixel-noise covariances (px^2 in units of the raw pixel
 *        noise): d = e^2 / (g1^T C1 g1 + g2^T C2 g2), e = x1^T F x2, g1 = (F x2)_12 = de/dx1,
 *        g2 = (F^T x1)_12 = de/dx2, Ck = I + dCk (sfd_pixel_noise_t, units of sigma^2).
 *
 * sigma^2 (g1^T C1 g1 + g2^T C2 g2) is the first-order variance of e when the two pixels carry
 * independent noise sigma^2 C1 and sigma^2 C2 (isotropic raw-pixel noise carried through the
 * distortion Jacobian, sfd_camera_pixel_noise()), so d / sigma^2 is approximately chi-square with
 * 1 dof also at the image edges. dC = 0 gives sfd_sampson_sq_px2() bit-for-bit.
 *
 * @return d >= 0; +infinity as sfd_sampson_sq_px2() (also for a null @p noise). Reentrant.
 */
double sfd_sampson_cov_sq_px2(const double F[9], const double x_prev[2], const double x_curr[2],
                              const sfd_pixel_noise_t *noise);

/** Outcome of one sfd_ransacf() call. */
typedef struct {
    int32_t hypotheses_used;  /**< hypotheses drawn (<= max_hypotheses), degenerate ones included */
    int32_t num_inliers;      /**< number of inlier[i] == 1 */
    int32_t budget_exhausted; /**< 1 when eq. (27) asked for more than the budget */
    double F[9];              /**< row-major, of the final inlier set, ||F||_F = 1 (0 if none) */
} sfd_ransacf_result_t;

/**
 * @brief Fundamental-matrix RANSAC (Kilic 2014 Table 2) over n matches.
 *
 * Each hypothesis draws 8 distinct matches (partial Fisher-Yates with sfd_prng_uniform_index),
 * fits F with sfd_fundamental_8point() (a degenerate sample counts as a used hypothesis and is
 * skipped), and counts the matches whose Sampson distance (sfd_sampson_cov_sq_px2() when @p noise
 * is given) is <= @p threshold_sq_px2. The first
 * hypothesis with the largest count wins; each improvement sets the hypothesis count N by eq. (27)
 * with the inlier ratio best/n and m = 8, never above @p max_hypotheses. sfd addition (not in the
 * thesis): F is refit once by least squares on the winning inlier set and the matches rescored;
 * the refit is kept when it has at least as many inliers. The reported F always classifies
 * exactly the reported inliers.
 *
 * Deterministic: the same inputs and PRNG state give identical outputs and PRNG state.
 * Worst-case time ~ max_hypotheses * (8-point fit + n Sampson distances).
 *
 * @param x_prev           n undistorted pixel coordinates in the previous frame (px).
 * @param x_curr           n undistorted pixel coordinates in the current frame (px).
 * @param noise            n pixel-noise covariances (sfd_pixel_noise_t), or NULL for isotropic
 *                         noise; the Sampson test then uses sfd_sampson_cov_sq_px2().
 * @param n                Number of matches, 0 <= n <= SFD_MAX_FEATURES.
 * @param threshold_sq_px2 Sampson-distance gate (px^2), finite and > 0; see sfd_sampson_sq_px2().
 * @param confidence       p of eq. (27), in (0, 1).
 * @param max_hypotheses   Budget, 1 <= max_hypotheses <= SFD_MAX_HYPOTHESES.
 * @param rng              Seeded generator (caller-owned), advanced by the draws.
 * @param inlier           Out: n flags, 1 = consistent with the final F, 0 = spurious/untested.
 * @param out              Out: counts and the final F.
 * @return SFD_OK; SFD_ERR_INVAL for a null pointer, n < 0, threshold or confidence out of range,
 *         max_hypotheses < 1, a non-finite coordinate, or a noise covariance I + dC that is not
 *         finite and positive definite (nothing written);
 *         SFD_ERR_CAPACITY for n > SFD_MAX_FEATURES or max_hypotheses > SFD_MAX_HYPOTHESES
 *         (nothing written; the same split as sfd_params_validate());
 *         SFD_ERR_RANGE for n < 8: too few matches to fit F, inlier[] all 0 and @p out zeroed
 *         (the caller reports them as untested);
 *         SFD_ERR_NUMERIC when every hypothesis was degenerate: inlier[] all 0, out->F zero,
 *         out->hypotheses_used and out->budget_exhausted set (the matches are untested).
 */
sfd_status_t sfd_ransacf(const double (*x_prev)[2], const double (*x_curr)[2],
                         const sfd_pixel_noise_t *noise, int32_t n, double threshold_sq_px2,
                         double confidence, int32_t max_hypotheses, sfd_prng_t *rng,
                         uint8_t *inlier, sfd_ransacf_result_t *out);

#ifdef __cplusplus
}
#endif

#endif /* SFD_FUNDAMENTAL_H */
