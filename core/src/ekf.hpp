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

/// Per-frame constants of the camera measurement at one filter pose (eqs. (15), (22)), so that
/// each observation costs about 100 multiplications (core/docs/ekf.md).
struct Linearizer {
    double RWI[9];  ///< R_ItoW^T, row-major
    double RIC[9];  ///< R_CtoI^T, row-major
    double pI[3];   ///< p_IinW
    double pCI[3];  ///< p_CinI
    double RWC[9];  ///< R_WtoC = R_CtoI^T R_ItoW^T, row-major
    double pC[3];   ///< p_CinW
    double fx, fy, cx, cy, sigma2;
    Linearizer(const sfd_ekf_t &ekf, const Mat3 &R_ItoW, const sfd_ekf_camera_t &cam);
    /// Landmark in the camera frame; false when not finite or not in front (z <= 1e-6 m).
    bool camera_point(const double L_W[3], double c[3]) const;
    /// Depth (m) of a landmark in the camera frame, the third row of camera_point() alone (the
    /// caller tests it: in front means depth > 1e-6 m and finite).
    double depth_m(const double L_W[3]) const {
        return RWC[6] * (L_W[0] - pC[0]) + RWC[7] * (L_W[1] - pC[1]) + RWC[8] * (L_W[2] - pC[2]);
    }
    /// Full linearization of @p obs; false as camera_point() or when a value is not finite.
    bool linearize(const sfd_ekf_obs_t &obs, Linearized *out) const {
        return linearize(obs.uv_px, obs.landmark_W_m, obs.landmark_cov_m2, out);
    }
    /// The same for an observation given by parts: the undistorted pixel, the landmark (world)
    /// and its covariance (row-major 3x3); false also when a landmark pointer is null.
    bool linearize(const double uv_px[2], const double *L_W, const double *C_L,
                   Linearized *out) const;
};

/// Linearizes @p obs at the filter's prior; false when the landmark is not in front of the
/// camera (depth <= 1e-6 m) or a value is not finite. (One-off; loops use a Linearizer.)
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

/// Information of a set of observations over the pose (eq. (19) regrouped, core/docs/ekf.md):
/// Y = sum H^T R^-1 H, b = sum H^T R^-1 nu, and sum nu^T R^-1 nu for the NIS.
struct PoseInformation {
    Mat6 Y = Mat6::Zero();
    Vec6 b = Vec6::Zero();
    double nu_Rinv_nu = 0.0;
    int32_t used = 0;
    /// Adds one linearized observation; false (nothing added) when its R is not PD.
    bool add(const Linearized &lin);
};

/// The batch update of sfd_ekf_update_camera() from accumulated information: Joseph form, the
/// filter unchanged on numerical trouble (SFD_ERR_NUMERIC, numeric_faults counted). Nothing to do
/// (SFD_OK) when no observation was added. @p nis may be NULL.
sfd_status_t apply_pose_information(sfd_ekf_t *ekf, const PoseInformation &info, double *nis);

/// One observation by its parts: undistorted pixel (2), landmark (3), its covariance (9).
struct ObsParts {
    const double *uv_px;
    const double *landmark_W_m;
    const double *landmark_cov_m2;
};

/// Observations in a plain array.
struct ObsArray {
    const sfd_ekf_obs_t *p;
    ObsParts operator[](int32_t i) const {
        return ObsParts{p[i].uv_px, p[i].landmark_W_m, p[i].landmark_cov_m2};
    }
};

/// The observations of an array of matches (their current pixels and the landmarks they refer
/// to).
struct MatchObs {
    const sfd_match_t *p;
    ObsParts operator[](int32_t i) const {
        return ObsParts{p[i].uv_px, p[i].landmark_W_m, p[i].landmark_cov_m2};
    }
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
