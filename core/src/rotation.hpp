// SPDX-License-Identifier: MIT
// Internal C++ rotation helpers shared by core modules (conventions: sfd/sfd_rotation.h).
#ifndef SFD_ROTATION_HPP
#define SFD_ROTATION_HPP

#include "core_private.hpp"

namespace sfd {

/// [v]x, the cross-product matrix: skew(a) b = a x b.
Mat3 skew(const Vec3 &v);
/// Rodrigues' formula, exp([phi]x).
Mat3 so3_exp(const Vec3 &phi);
/// Inverse of so3_exp with |phi| <= pi; R must be a rotation.
Vec3 so3_log(const Mat3 &R);
/// exp(phi/2) as a unit quaternion with w >= 0.
Quat quat_from_rotvec(const Vec3 &phi);
/// Rotation vector of a unit quaternion (|phi| <= pi).
Vec3 quat_to_rotvec(const Quat &q);
/// Shepperd's method; returns w >= 0.
Quat rotmat_to_quat(const Mat3 &R);
/// Orthonormal within tol (max abs entry of R R^T - I) and det within tol of +1.
bool is_rotation(const Mat3 &R, double tol);

}  // namespace sfd

#endif  // SFD_ROTATION_HPP
