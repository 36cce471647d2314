// SPDX-License-Identifier: MIT
// Internal pieces of the EKF shared with the association methods (OPRF, 1-point RANSAC): the
// per-observation linearization at the prior and the single-match pose update of a hypothesis.
#ifndef SFD_EKF_HPP
#define SFD_EKF_HPP

#include "core_private.hpp"
#include "sfd/sfd_assoc.h"
#include "sfd/sfd_ekf.h"

namespace sfd {

using Mat6 = Eigen::Matrix<double, 6, 6, Eigen::RowMajor>;
using Mat26 = Eigen::Matrix<double, 2, 6, Eigen::RowMajor>;
using Vec6 = Eigen::Matrix<double, 6, 1>;

/// Error-state indices of the pose block (dp, dtheta) in which the camera Jacobian is non-zero.
constexpr int kPoseIdx[6] = {SFD_EKF_IDX_P,     SFD_EKF_IDX_P + 1,     SFD_EKF_IDX_P + 2,
                             SFD_EKF_IDX_THETA, SFD_EKF_IDX_THETA + 1, SFD_EKF_IDX_THETA + 2};

/// One observation linearized at the prior (eqs. (15), (22)): innovation nu = z - h(x^), the pose
/// Jacobian H (2x6 over dp, dtheta) and the noise R = sigma^2 I + J_L C_L J_L^T.
struct Linearized {
    Vec2 nu;
    Mat26 H;
    Mat2 R;
    Vec3 p_LinC;  ///< landmark in the camera frame at the prior (m)
};

/// Camera model of undistorted pixels and the filter pose it is evaluated at.
struct CameraPose {
    Mat3 R_WtoC;  ///< R_CtoW^T
    Vec3 p_CinW;
};

/// R_ItoW of the filter's quaternion.
Mat3 ekf_rotation(const sfd_ekf_t &ekf);

/// Camera pose of a given IMU pose.
CameraPose camera_pose(const Mat3 &R_ItoW, const Vec3 &p_IinW, const sfd_extrinsics_t &ext);

/// Linearizes @p obs at the filter's prior; false when the landmark is not in front of the
/// camera (depth <= 1e-6 m) or a value is not finite.
bool linearize(const sfd_ekf_t &ekf, const Mat3 &R_ItoW, const sfd_ekf_camera_t &cam,
               const sfd_ekf_obs_t &obs, Linearized *out);

/// Projection of a world point by a camera pose into undistorted pixels; false behind the camera.
bool project(const sfd_ekf_camera_t &cam, const CameraPose &pose, const Vec3 &p_W, Vec2 *uv);

/// The pose block P_ss of the filter's covariance (rows/columns kPoseIdx).
Mat6 pose_covariance(const sfd_ekf_t &ekf);

/// Mean of a single-observation EKF update (eqs. (19)-(20) with one match), pose only: the
/// correction dpose = P_ss H^T (H P_ss H^T + R)^-1 nu applied to the prior pose. This is what a
/// one-point hypothesis needs (Kilic 2014 Section 3.2 "EKF Update"); the covariance is not formed.
/// False when H P_ss H^T + R is not positive definite.
bool single_update_pose(const sfd_ekf_t &ekf, const Mat3 &R_ItoW, const Mat6 &P_ss,
                        const Linearized &lin, Mat3 *R_ItoW_out, Vec3 *p_IinW_out);

/// Observations in a plain array.
struct ObsArray {
    const sfd_ekf_obs_t *p;
    const sfd_ekf_obs_t &operator[](int32_t i) const { return p[i]; }
};

/// The observations inside an array of matches (sfd_match_t::obs).
struct MatchObs {
    const sfd_match_t *p;
    const sfd_ekf_obs_t &operator[](int32_t i) const { return p[i].obs; }
};

/// sfd_ekf_update_camera() over a view (static dispatch: the stack proof rejects indirect
/// calls); instantiated in ekf.cpp for ObsArray and MatchObs.
template <typename View>
sfd_status_t update_camera(sfd_ekf_t *ekf, const sfd_ekf_camera_t &cam, const View &obs,
                           const uint8_t *use, int32_t n, sfd_ekf_update_info_t *info);

extern template sfd_status_t update_camera<ObsArray>(sfd_ekf_t *, const sfd_ekf_camera_t &,
                                                     const ObsArray &, const uint8_t *, int32_t,
                                                     sfd_ekf_update_info_t *);
extern template sfd_status_t update_camera<MatchObs>(sfd_ekf_t *, const sfd_ekf_camera_t &,
                                                     const MatchObs &, const uint8_t *, int32_t,
                                                     sfd_ekf_update_info_t *);

}  // namespace sfd

#endif  // SFD_EKF_HPP
