// SPDX-License-Identifier: MIT
// Private prelude of every core translation unit: the standard and Eigen headers come first,
// then the heap functions are poisoned, so any later use of them in core is a compile error.
// (The symbol check `proof.core_symbols` catches what the preprocessor cannot see, such as
// operator new or a std container instantiated from a header.)
#ifndef SFD_CORE_PRIVATE_HPP
#define SFD_CORE_PRIVATE_HPP

#include "float_round.h"
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <new>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/LU>

#include "sfd/sfd_config.h"
#include "sfd/sfd_msckf.h"
#include "sfd/sfd_status.h"

#pragma GCC poison malloc calloc realloc free aligned_alloc posix_memalign

static_assert(std::numeric_limits<double>::is_iec559, "sfd core assumes IEEE 754 doubles");

namespace sfd {

using Vec2 = Eigen::Matrix<double, 2, 1>;
using Vec3 = Eigen::Matrix<double, 3, 1>;
using Mat2 = Eigen::Matrix<double, 2, 2, Eigen::RowMajor>;
using Mat3 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;
using Quat = Eigen::Quaternion<double>;

/// True when every entry is finite (no NaN, no Inf).
inline bool all_finite(const double *v, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) {
        if (!std::isfinite(v[i])) return false;
    }
    return true;
}

/// True when every entry fits a float's range (|v| <= FLT_MAX; NaN does not): the check before
/// a double is stored as float (a cast of a larger value is undefined behaviour).
inline bool fits_float(const double *v, std::size_t n) {
    return sfd_fits_float(v, static_cast<int>(n)) != 0;
}

/// A double clamped into a float's range, then stored as float (NaN stays NaN).
inline float clamp_to_float(double v) {
    constexpr double kFloatMax = static_cast<double>(std::numeric_limits<float>::max());
    return static_cast<float>(std::fmin(std::fmax(v, -kFloatMax), kFloatMax));
}

/// True when a depth prior (depth_m, depth_var_m2) is one float storage holds: the depth
/// positive and normal in float, the variance finite, non-negative and within float's range.
inline bool depth_prior_fits_float(double depth_m, double depth_var_m2) {
    constexpr double kFloatMax = static_cast<double>(std::numeric_limits<float>::max());
    constexpr double kFloatMin = static_cast<double>(std::numeric_limits<float>::min());
    return depth_m >= kFloatMin && depth_m <= kFloatMax && depth_var_m2 >= 0.0 &&
           depth_var_m2 <= kFloatMax;
}

/// True when each of the @p N doubles stored from @p p on (an object representation, e.g. a
/// struct of doubles; N even) is finite. An exponent field of all ones (Inf, NaN) carries into
/// bit 63 when one unit of the exponent is added to it; no other exponent does. Two doubles per
/// step in GCC's generic vectors (SSE2 / NEON where present, plain integers elsewhere):
/// branch-free, unlike N calls of std::isfinite.
template <std::size_t N>
inline bool all_finite_repr(const void *p) {
    static_assert(N % 2 == 0, "pairs of doubles");
    typedef std::uint64_t U64x2 __attribute__((vector_size(16)));
    const U64x2 exponent = {0x7FF0000000000000ULL, 0x7FF0000000000000ULL};
    const U64x2 unit = {0x0010000000000000ULL, 0x0010000000000000ULL};
    const unsigned char *bytes = static_cast<const unsigned char *>(p);
    U64x2 acc = {0, 0};
#pragma GCC unroll 8
    for (std::size_t i = 0; i < N / 2; ++i) {
        U64x2 v;
        std::memcpy(&v, bytes + i * sizeof v, sizeof v);
        acc |= (v & exponent) + unit;
    }
    return ((acc[0] | acc[1]) >> 63) == 0;
}

// Median of v[0..n) (n >= 1), by a heap sort in place (no recursion, O(n log n)).
inline double median_in_place(float *v, int n) {
    for (int start = n / 2 - 1; start >= 0; --start) {
        int root = start;
        for (int guard = 0; guard < 32 && 2 * root + 1 < n; ++guard) {
            int child = 2 * root + 1;
            if (child + 1 < n && v[child] < v[child + 1]) ++child;
            if (!(v[root] < v[child])) break;
            const float t = v[root];
            v[root] = v[child];
            v[child] = t;
            root = child;
        }
    }
    for (int end = n - 1; end > 0; --end) {
        const float t = v[0];
        v[0] = v[end];
        v[end] = t;
        int root = 0;
        for (int guard = 0; guard < 32 && 2 * root + 1 < end; ++guard) {
            int child = 2 * root + 1;
            if (child + 1 < end && v[child] < v[child + 1]) ++child;
            if (!(v[root] < v[child])) break;
            const float x = v[root];
            v[root] = v[child];
            v[child] = x;
            root = child;
        }
    }
    return (n % 2 == 1) ? static_cast<double>(v[n / 2])
                        : 0.5 * (static_cast<double>(v[n / 2 - 1]) + static_cast<double>(v[n / 2]));
}

/// sfd_msckf_track_statistic() (eq. (3) without forming N) over the rows first..t.rows - 1 of the
/// unprojected track alone: their blocks of S, H_f and r (msckf_update.cpp). At least 4 rows, else
/// SFD_ERR_INVAL; the caller has checked the track and S.
sfd_status_t msckf_statistic_from(const sfd_msckf_track_t &t,
                                  const double (*S)[SFD_MSCKF_TRACK_ROWS], int first, double *gamma,
                                  int32_t *dof);

}  // namespace sfd

#endif  // SFD_CORE_PRIVATE_HPP
