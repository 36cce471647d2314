// SPDX-License-Identifier: MIT
// The Sampson (first-order geometric) distance of Kilic 2014 eq. (25), x1^T F x2 = 0, in px^2:
// one definition for the fundamental-matrix RANSAC, OPRF and sfd_sampson_sq_px2().
#ifndef SFD_SAMPSON_HPP
#define SFD_SAMPSON_HPP

#include "core_private.hpp"

namespace sfd {

/// The residual e = x1^T F x2 and the Sampson denominator |(F x2)_12|^2 + |(F^T x1)_12|^2
/// (homogeneous 1 folded in); the distance is e^2 / den.
inline void sampson_terms(const double *F, const double *x1, const double *x2, double *e,
                          double *den) {
    const double fx0 = F[0] * x2[0] + F[1] * x2[1] + F[2];
    const double fx1 = F[3] * x2[0] + F[4] * x2[1] + F[5];
    const double fx2 = F[6] * x2[0] + F[7] * x2[1] + F[8];
    const double ft0 = F[0] * x1[0] + F[3] * x1[1] + F[6];
    const double ft1 = F[1] * x1[0] + F[4] * x1[1] + F[7];
    *e = x1[0] * fx0 + x1[1] * fx1 + fx2;
    *den = fx0 * fx0 + fx1 * fx1 + ft0 * ft0 + ft1 * ft1;
}

/// Sampson distance in px^2; +infinity when the denominator is not positive or the result is
/// not finite (such a match is never an inlier).
inline double sampson_px2(const double *F, const double *x1, const double *x2) {
    double e = 0.0;
    double den = 0.0;
    sampson_terms(F, x1, x2, &e, &den);
    if (!(den > 0.0)) return std::numeric_limits<double>::infinity();  // also NaN
    const double d = e * e / den;
    return std::isfinite(d) ? d : std::numeric_limits<double>::infinity();
}

}  // namespace sfd

#endif  // SFD_SAMPSON_HPP
