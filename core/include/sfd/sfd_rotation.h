/* SPDX-License-Identifier: MIT */
/**
 * @file sfd_rotation.h
 * @brief Rotations: SO(3) exponential and logarithm, unit quaternions, and the camera-IMU
 *        extrinsics.
 *
 * Conventions (stated once, used everywhere in sfd):
 * - Rotation matrices are row-major double[9]. R_AtoB maps a vector's coordinates in frame A to
 *   frame B: v_B = R_AtoB v_A. Equivalently R_AtoB is the orientation of A expressed in B.
 * - Quaternions are Hamilton, double[4] = (w, x, y, z), active; q and R describe the same
 *   rotation: R(q) v = q (0, v) q*. The functions return quaternions with w >= 0.
 * - Rotation vectors (axis * angle, rad) live in so(3); exp(phi) = I + sin|phi| [u]x +
 *   (1 - cos|phi|) [u]x^2 (Rodrigues).
 */
#ifndef SFD_ROTATION_H
#define SFD_ROTATION_H

#include "sfd_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/** @brief R = exp([phi]x), exact for every angle (Taylor terms below 1e-8 rad).
 *  @return SFD_OK; SFD_ERR_INVAL for null or non-finite input. */
sfd_status_t sfd_so3_exp(const double phi_rad[3], double R[9]);

/** @brief phi = log(R) with |phi| in [0, pi], stable near 0 and near pi. R must be a rotation
 *         (orthonormal within 1e-6, det +1); it is not re-orthonormalized.
 *  @return SFD_OK; SFD_ERR_INVAL for null, non-finite, or a matrix that is not a rotation. */
sfd_status_t sfd_so3_log(const double R[9], double phi_rad[3]);

/** @brief q = exp(phi/2) as a unit quaternion (w >= 0). @return SFD_OK; SFD_ERR_INVAL. */
sfd_status_t sfd_quat_from_rotvec(const double phi_rad[3], double q[4]);

/** @brief Rotation vector of a unit quaternion. @return SFD_OK; SFD_ERR_INVAL for null,
 *         non-finite or a norm off 1 by more than 1e-6. */
sfd_status_t sfd_quat_to_rotvec(const double q[4], double phi_rad[3]);

/** @brief Hamilton product q = a * b (apply b, then a). @return SFD_OK; SFD_ERR_INVAL. */
sfd_status_t sfd_quat_multiply(const double a[4], const double b[4], double q[4]);

/** @brief Normalizes in place, sign fixed to w >= 0. @return SFD_OK; SFD_ERR_INVAL for null,
 *         non-finite or a norm below 1e-12. */
sfd_status_t sfd_quat_normalize(double q[4]);

/** @brief Rotation matrix of a unit quaternion. @return SFD_OK; SFD_ERR_INVAL (norm off 1 by
 *         more than 1e-6). */
sfd_status_t sfd_quat_to_rotmat(const double q[4], double R[9]);

/** @brief Unit quaternion (w >= 0) of a rotation matrix (Shepperd's method).
 *  @return SFD_OK; SFD_ERR_INVAL for a matrix that is not a rotation within 1e-6. */
sfd_status_t sfd_rotmat_to_quat(const double R[9], double q[4]);

/** Rigid camera-IMU extrinsics: the camera pose in the IMU frame. */
typedef struct {
    double R_CtoI[9]; /**< camera axes expressed in the IMU frame (row-major) */
    double p_CinI[3]; /**< camera optical centre in the IMU frame (m) */
} sfd_extrinsics_t;

/**
 * @brief Extrinsics from a row-major 4x4 homogeneous transform T_imu_cam (camera pose in the IMU
 *        frame, p_I = R p_C + t, as CAMERA_INFO and EuRoC's T_BS carry it).
 * @return SFD_OK; SFD_ERR_INVAL for null/non-finite input, a last row other than (0 0 0 1), or a
 *         rotation block that is not orthonormal with det +1 within 1e-6.
 */
sfd_status_t sfd_extrinsics_from_matrix(sfd_extrinsics_t *ext, const double T_imu_cam[16]);

/**
 * @brief Camera motion between two frames from the IMU's: given the IMU orientation change
 *        R_I1toI0 (IMU frame at t1 expressed in the IMU frame at t0, as sfd_gyro_integrate
 *        returns it), the camera's is R_C1toC0 = R_CtoI^T R_I1toI0 R_CtoI.
 * @return SFD_OK; SFD_ERR_INVAL for null input.
 */
sfd_status_t sfd_extrinsics_camera_rotation(const sfd_extrinsics_t *ext, const double R_I1toI0[9],
                                            double R_C1toC0[9]);

#ifdef __cplusplus
}
#endif

#endif /* SFD_ROTATION_H */
