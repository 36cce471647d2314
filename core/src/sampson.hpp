// SPDX-License-Identifier: MIT
// The Sampson (first-order geometric) distance of Kilic 2014 eq. (25), x1^T F x2 = 0, in px^2:
// one definition for the fundamental-matrix RANSAC, OPRF and sfd_sampson_sq_px2(), with per-point
// pixel-noise covariances (core/docs/fundamental_matrix.md "Noise through the distortion").
#ifndef SFD_SAMPSON_HPP
#define SFD_SAMPSON_HPP

#include "core_private.hpp"
#include "sfd/sfd_camera.h"

namespace sfd {

/// I + dC (units of sigma^2) positive definite, for a finite dC (pixel_noise_valid() checks that
/// first, so that 1 + dC and the determinant are finite in double).
inline bool noise_excess_pd(const float *dC) {
    const double xx = 1.0 + static_cast<double>(dC[0]);
    const double xy = static_cast<double>(dC[1]);
    const double yy = 1.0 + static_cast<double>(dC[2]);
    return xx > 0.0 && yy > 0.0 && xx * yy - xy * xy > 0.0;
}

/// Both covariances I + dC of a match's pixel noise are usable: the six floats
/// finite, read as three pairs (a float's exponent field of all ones carries into its top bit,
/// bit 31 or 63 of the pair, when one unit of the exponent is added; the low half cannot carry
/// into the high one), then each positive definite.
inline bool pixel_noise_valid(const sfd_pixel_noise_t &n) {
    static_assert(sizeof n == 6 * sizeof(float), "sfd_pixel_noise_t is six floats");
    const unsigned char *bytes = reinterpret_cast<const unsigned char *>(&n);
    std::uint64_t acc = 0;
    for (std::size_t k = 0; k < 3; ++k) {
        std::uint64_t b = 0;
        std::memcpy(&b, bytes + sizeof b * k, sizeof b);
        acc |= (b & 0x7F8000007F800000ULL) + 0x0080000000800000ULL;
    }
    if ((acc & 0x8000000080000000ULL) != 0U) return false;
    return noise_excess_pd(n.prev_dC) && noise_excess_pd(n.curr_dC);
}

/// The quadratic form r^T (I + D)^-1 r of a 2-vector for a symmetric 2x2 D = (d00, d01, d11)
/// (the squared Mahalanobis distance under the covariance I + D, in units of its scale); D = 0
/// gives |r|^2 exactly (the isotropic statistic, bit-for-bit); +infinity when I + D is not
/// positive definite.
inline double quad_inv_excess(double r0, double r1, double d00, double d01, double d11) {
    // D = 0: a = c = det = 1, y = r exactly, and r0 y0 + r1 y1 is |r|^2 in the same order.
    const double a = 1.0 + d00;
    const double c = 1.0 + d11;
    const double det = a * c - d01 * d01;
    if (!(a > 0.0 && det > 0.0)) return std::numeric_limits<double>::infinity();
    // y = (I + D)^-1 r, then r^T (I + D)^-1 r = r^T y
    const double y0 = (c * r0 - d01 * r1) / det;
    const double y1 = (a * r1 - d01 * r0) / det;
    return r0 * y0 + r1 * y1;
}

/// The residual e = x1^T F x2 and its first-order variance in units of sigma^2,
/// den = g1^T C1 g1 + g2^T C2 g2 with g1 = (F x2)_12 = de/dx1, g2 = (F^T x1)_12 = de/dx2 and
/// Ck = I + dCk the covariance of point k in units of sigma^2 (the homogeneous 1 folded in).
/// Var(e) = sigma^2 den assumes independent noise in the two images, linear in the pixels.
/// The isotropic part |g1|^2 + |g2|^2 is summed first and the excess g^T dC g added after, so
/// with dC1 = dC2 = 0 (or null) the result is bit-for-bit the isotropic Sampson denominator.
inline void sampson_terms(const double *F, const double *x1, const double *x2, const float *dc1,
                          const float *dc2, double *e, double *den) {
    const double fx0 = F[0] * x2[0] + F[1] * x2[1] + F[2];
    const double fx1 = F[3] * x2[0] + F[4] * x2[1] + F[5];
    const double fx2 = F[6] * x2[0] + F[7] * x2[1] + F[8];
    const double ft0 = F[0] * x1[0] + F[3] * x1[1] + F[6];
    const double ft1 = F[1] * x1[0] + F[4] * x1[1] + F[7];
    *e = x1[0] * fx0 + x1[1] * fx1 + fx2;
    *den = fx0 * fx0 + fx1 * fx1 + ft0 * ft0 + ft1 * ft1;
    if (dc1 != nullptr && dc2 != nullptr) {
        *den += (dc1[0] * fx0 * fx0 + 2.0 * dc1[1] * fx0 * fx1 + dc1[2] * fx1 * fx1) +
                (dc2[0] * ft0 * ft0 + 2.0 * dc2[1] * ft0 * ft1 + dc2[2] * ft1 * ft1);
    }
}

/// Sampson distance e^2 / den in px^2 (sampson_terms(); @p dc1 / @p dc2 the pixel-noise excess
/// C - I of each point, null for isotropic noise); +infinity when the denominator is not
/// positive or the result is not finite (such a match is never an inlier).
inline double sampson_px2(const double *F, const double *x1, const double *x2,
                          const float *dc1 = nullptr, const float *dc2 = nullptr) {
    double e = 0.0;
    double den = 0.0;
    sampson_terms(F, x1, x2, dc1, dc2, &e, &den);
    if (!(den > 0.0)) return std::numeric_limits<double>::infinity();  // also NaN
    const double d = e * e / den;
    return std::isfinite(d) ? d : std::numeric_limits<double>::infinity();
}

}  // namespace sfd

#endif  // SFD_SAMPSON_HPP
