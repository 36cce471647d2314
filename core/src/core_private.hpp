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
#include <utility>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/LU>

#include "sfd/sfd_config.h"
#include "sfd/sfd_msckf.h"
#include "sfd/sfd_status.h"
#include "sfd/sfd_window.h"

#pragma GCC poison malloc calloc realloc free aligned_alloc posix_memalign

static_assert(std::numeric_limits<double>::is_iec559, "sfd core assumes IEEE 754 doubles");

namespace sfd {

using Vec2 = Eigen::Matrix<double, 2, 1>;
using Vec3 = Eigen::Matrix<double, 3, 1>;
using Mat2 = Eigen::Matrix<double, 2, 2, Eigen::RowMajor>;
using Mat3 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;
using Quat = Eigen::Quaternion<double>;

/// True when every entry is finite (no NaN, no Inf). Branch-free over the bits (as
/// all_finite_repr below): an exponent field of all ones carries into bit 63 when one unit of the
/// exponent is added to it, no other exponent does. Every entry is read (no early exit), two per
/// step in GCC's generic vectors: for the few to few hundred entries of its calls that costs less
/// than a branch per entry.
inline bool all_finite(const double *v, std::size_t n) {
    typedef std::uint64_t U64x2 __attribute__((vector_size(16)));
    constexpr std::uint64_t kExp = 0x7FF0000000000000ULL;
    constexpr std::uint64_t kUnit = 0x0010000000000000ULL;
    const U64x2 exponent = {kExp, kExp};
    const U64x2 unit = {kUnit, kUnit};
    U64x2 acc2 = {0, 0};
    std::size_t i = 0;
    for (; i + 2 <= n; i += 2) {
        U64x2 x;
        std::memcpy(&x, v + i, sizeof x);
        acc2 |= (x & exponent) + unit;
    }
    std::uint64_t acc = acc2[0] | acc2[1];
    if (i < n) {
        std::uint64_t b = 0;
        std::memcpy(&b, v + i, sizeof b);
        acc |= (b & kExp) + kUnit;
    }
    return (acc >> 63) == 0;
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

// Sorts v[lo..hi] ascending in place by a heap sort (no recursion, O(n log n)).
inline void heap_sort_range(float *v, int lo, int hi) {
    float *w = v + lo;
    const int n = hi - lo + 1;
    for (int start = n / 2 - 1; start >= 0; --start) {
        int root = start;
        for (int guard = 0; guard < 32 && 2 * root + 1 < n; ++guard) {
            int child = 2 * root + 1;
            if (child + 1 < n && w[child] < w[child + 1]) ++child;
            if (!(w[root] < w[child])) break;
            const float t = w[root];
            w[root] = w[child];
            w[child] = t;
            root = child;
        }
    }
    for (int end = n - 1; end > 0; --end) {
        const float t = w[0];
        w[0] = w[end];
        w[end] = t;
        int root = 0;
        for (int guard = 0; guard < 32 && 2 * root + 1 < end; ++guard) {
            int child = 2 * root + 1;
            if (child + 1 < end && w[child] < w[child + 1]) ++child;
            if (!(w[root] < w[child])) break;
            const float x = w[root];
            w[root] = w[child];
            w[child] = x;
            root = child;
        }
    }
}

// Rearranges v[0..n) (1 <= n, 0 <= k < n, no NaN) so that v[k] is its k-th smallest value, with
// v[0..k) <= v[k] <= v(k..n): Hoare partitions around the median of three (no recursion; each
// pass shrinks the range), a heap sort of what is left after 64 passes (O(n log n) at worst,
// O(n) expected). A NaN cannot make it loop or leave the array; v[k] is then some entry.
inline float select_kth(float *v, int n, int k) {
    int lo = 0, hi = n - 1;
    for (int pass = 0; pass < 64 && lo < hi; ++pass) {
        const int mid = lo + (hi - lo) / 2;
        if (v[mid] < v[lo]) std::swap(v[mid], v[lo]);
        if (v[hi] < v[lo]) std::swap(v[hi], v[lo]);
        if (v[hi] < v[mid]) std::swap(v[hi], v[mid]);
        const float pivot = v[mid];
        int i = lo, j = hi;
        while (i <= j) {  // i only rises, j only falls
            while (i < hi && v[i] < pivot) ++i;
            while (j > lo && pivot < v[j]) --j;
            if (i <= j) {
                std::swap(v[i], v[j]);
                ++i;
                --j;
            }
        }
        // v[lo..j] <= pivot <= v[i..hi], and v(j..i) == pivot
        if (k <= j) {
            hi = j;
        } else if (k >= i) {
            lo = i;
        } else {
            return v[k];
        }
    }
    if (lo < hi) heap_sort_range(v, lo, hi);
    return v[k];
}

// Median of v[0..n) (n >= 1, no NaN), reordering v: the middle value, or the mean of the two
// middle values (the larger is selected, the smaller is the largest below it).
inline double median_in_place(float *v, int n) {
    const int k = n / 2;
    const float upper = select_kth(v, n, k);
    if (n % 2 == 1) return static_cast<double>(upper);
    float lower = v[0];
    for (int i = 1; i < k; ++i) lower = (lower < v[i]) ? v[i] : lower;
    return 0.5 * (static_cast<double>(lower) + static_cast<double>(upper));
}

/// sfd_msckf_track_statistic() (eq. (3) without forming N) of the unprojected track, gamma[1] and
/// dof[1], and, when tail_first > 0, of its rows tail_first..t.rows - 1 alone (their blocks of S,
/// H_f and r), gamma[0] and dof[0], from one factorization (msckf_update.cpp). With ramp_cols
/// (rows x 2, the residual's signature of a 2-parameter fault, e.g. a ramp) and ramp_glr both
/// given, *ramp_glr is the GLR of that fault over all rows, chi2(2) when there is none, from the
/// same factorization, or -1 when it is not available (fewer than 6 rows, or the columns in the
/// point's span). SFD_ERR_INVAL for rows outside 4..SFD_MSCKF_TRACK_ROWS or a tail of fewer than
/// 4 rows; SFD_ERR_NUMERIC as sfd_msckf_track_statistic(); nothing written on error. The caller
/// has checked the pointers.
/// With motion_cols (rows x 2: the ramp over the tail's frames, zero elsewhere) and motion both
/// given, *motion is that ramp's fit over the tail's rows (sfd_window_motion_t; ok 0 when the
/// tail has fewer than 6 rows or the ramp lies in the point's span), from the same factorization.
sfd_status_t msckf_statistic_tail(const sfd_msckf_track_t &t,
                                  const double (*S)[SFD_MSCKF_TRACK_ROWS], int tail_first,
                                  double gamma[2], int32_t dof[2], const double (*ramp_cols)[2],
                                  double *ramp_glr, const double (*motion_cols)[2],
                                  sfd_window_motion_t *motion);

/// Q (rows x 3, row stride 3): an orthonormal basis of the range of the track's H_f (Householder
/// reflections), so that N N^T = I - Q Q^T for the null-space basis N of eq. (2). False when H_f
/// has rank below 3 by sfd_msckf_track_project()'s criterion (a triangular pivot below 1e-9 times
/// its Frobenius norm) or Q is not finite. Reads rows and Hf (msckf_update.cpp).
bool msckf_range_basis(const sfd_msckf_track_t &t, double (*Q)[3]);

/// sfd_msckf_stack_fold_unprojected() with Q from msckf_range_basis(); the caller has checked the
/// arguments (unit noise included). SFD_ERR_NUMERIC (stack unchanged) for a non-finite Q^T H_x.
sfd_status_t msckf_fold_unit_noise(sfd_msckf_stack_t *s, const sfd_msckf_track_t &t,
                                   const double (*Q)[3]);

}  // namespace sfd

#endif  // SFD_CORE_PRIVATE_HPP
