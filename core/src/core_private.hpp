// SPDX-License-Identifier: MIT
// Private prelude of every core translation unit: the standard and Eigen headers come first,
// then the heap functions are poisoned, so any later use of them in core is a compile error.
// (The symbol check `proof.core_symbols` catches what the preprocessor cannot see, such as
// operator new or a std container instantiated from a header.)
#ifndef SFD_CORE_PRIVATE_HPP
#define SFD_CORE_PRIVATE_HPP

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

}  // namespace sfd

#endif  // SFD_CORE_PRIVATE_HPP
