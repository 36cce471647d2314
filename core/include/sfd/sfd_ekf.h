/* SPDX-License-Identifier: MIT */
/**
 * @file sfd_ekf.h
 * @brief Fixed-size error-state extended Kalman filter (Kilic 2014 eqs. (14)-(22)) of an IMU
 *        carried by a camera: IMU propagation as the control input, camera updates from matches
 *        between undistorted pixel observations and 3-D landmarks with covariance.
 *
 * Nominal state: position p_IinW (m), velocity v_IinW (m/s), orientation q_ItoW (unit quaternion
 * w, x, y, z; IMU axes in the world), gyro bias bg (rad/s) and accelerometer bias ba (m/s^2).
 * World frame: z up, gravity (0, 0, -gravity_m_s2).
 *
 * Error state (15, order fixed by SFD_EKF_IDX_*): dp, dv, dtheta, dbg, dba, with
 * p = p^ + dp, v = v^ + dv, R_ItoW = R^_ItoW Exp(dtheta) (dtheta in the IMU frame, "local"),
 * bg = bg^ + dbg, ba = ba^ + dba. Covariance P is 15x15 row-major.
 *
 * Landmarks are not filter states (the wire carries no map, SPEC): each observation carries its
 * landmark's covariance, which enters the measurement noise. Observations are assumed mutually
 * independent (independent landmark errors); document any caller that violates it.
 *
 * No heap, no global state; every function is reentrant on distinct filters.
 */
#ifndef SFD_EKF_H
#define SFD_EKF_H
#include <stdint.h>
#include "sfd_config.h"
#include "sfd_rotation.h"
#include "sfd_status.h"
#ifdef __cplusplus
extern "C" {
#endif

/** Dimension of the error state. */
#define SFD_EKF_DIM 15
/** Offsets of the error-state blocks. */
#define SFD_EKF_IDX_P 0
#define SFD_EKF_IDX_V 3
#define SFD_EKF_IDX_THETA 6
#define SFD_EKF_IDX_BG 9
#define SFD_EKF_IDX_BA 12

/** Continuous-time IMU noise model (densities), the process noise Q of eq. (17). */
typedef struct {
    double gyro_noise_rad_s_rthz;    /**< gyro white noise density (rad/s/sqrt(Hz)), >= 0 */
    double accel_noise_m_s2_rthz;    /**< accelerometer white noise density (m/s^2/sqrt(Hz)) */
    double gyro_bias_rw_rad_s2_rthz; /**< gyro bias random walk (rad/s^2/sqrt(Hz)) */
    double accel_bias_rw_m_s3_rthz;  /**< accelerometer bias random walk (m/s^3/sqrt(Hz)) */
    double gravity_m_s2;             /**< magnitude of gravity (m/s^2), > 0 */
    double max_dt_s;                 /**< largest propagation step accepted (s), > 0 */
} sfd_ekf_noise_t;

/** The filter. Caller-owned; initialise with sfd_ekf_init() or sfd_ekf_init_from_gravity(). */
typedef struct {
    double p_IinW_m[3];
    double v_IinW_m_s[3];
    double q_ItoW[4]; /**< w, x, y, z; w >= 0 is not required */
    double bg_rad_s[3];
    double ba_m_s2[3];
    double P[SFD_EKF_DIM * SFD_EKF_DIM]; /**< error-state covariance, row-major, SPD */
    sfd_ekf_noise_t noise;
    uint32_t numeric_faults;       /**< updates/propagations refused for numerical trouble */
    uint8_t consider[SFD_EKF_DIM]; /**< 1: the camera update does not correct this error state
                                        (Schmidt "consider" state: its gain row is zero, its
                                        covariance stays consistent through the Joseph form).
                                        sfd_ekf_init() clears it. */
    int32_t initialized;
} sfd_ekf_t;

/** Pinhole model of undistorted pixels plus camera-IMU extrinsics, for the camera update. */
typedef struct {
    double fx_px, fy_px, cx_px, cy_px;
    sfd_extrinsics_t ext;  /**< camera pose in the IMU frame */
    double pixel_sigma_px; /**< measurement noise per axis (px), > 0 */
} sfd_ekf_camera_t;

/** One match: an undistorted pixel observation of a landmark with its covariance. */
typedef struct {
    double uv_px[2];           /**< undistorted pixel coordinates in the current frame */
    double landmark_W_m[3];    /**< landmark position in the world */
    double landmark_cov_m2[9]; /**< its covariance (row-major, symmetric PSD; zeros = exact) */
} sfd_ekf_obs_t;

/** What a batch camera update did. */
typedef struct {
    int32_t used;    /**< observations applied */
    int32_t skipped; /**< observations not applied: behind the camera or non-finite */
    double nis;      /**< normalized innovation squared of the applied set (dof = 2 * used) */
} sfd_ekf_update_info_t;

/** @brief Noise defaults: an EuRoC-class MEMS IMU (ADIS16448 data sheet, doubled): gyro 3.4e-4,
 *         accel 4e-3, gyro bias rw 3.9e-5, accel bias rw 6e-3, gravity 9.81, max step 0.1 s.
 *  @return SFD_OK; SFD_ERR_INVAL for null. */
sfd_status_t sfd_ekf_noise_default(sfd_ekf_noise_t *noise);

/**
 * @brief Starts the filter at a given state with a diagonal covariance.
 * @param P0_diag the 15 initial variances (>= 0, finite), in the SFD_EKF_IDX_* order.
 * @return SFD_OK; SFD_ERR_INVAL for null, non-finite input, negative variance, a quaternion not
 *         of unit norm within 1e-6 (it is then renormalized exactly) or bad noise values.
 */
sfd_status_t sfd_ekf_init(sfd_ekf_t *ekf, const sfd_ekf_noise_t *noise, const double p_m[3],
                          const double v_m_s[3], const double q_ItoW[4], const double bg_rad_s[3],
                          const double ba_m_s2[3], const double P0_diag[SFD_EKF_DIM]);

/**
 * @brief Starts the filter at rest (SPEC "LCM interface"): position 0, velocity 0, yaw 0, roll and
 *        pitch from the mean specific force at rest (which points up in the world).
 * @param accel_mean_m_s2 mean accelerometer reading at rest (IMU frame), norm within 30% of g.
 * @param gyro_bias_rad_s initial gyro bias estimate (e.g. the mean gyro at rest).
 * @param P0_diag initial variances as in sfd_ekf_init().
 * @return SFD_OK; SFD_ERR_INVAL for null/non-finite input; SFD_ERR_DOMAIN when the accel norm is
 *         not within 30% of gravity (the vehicle is not at rest).
 */
sfd_status_t sfd_ekf_init_from_gravity(sfd_ekf_t *ekf, const sfd_ekf_noise_t *noise,
                                       const double accel_mean_m_s2[3],
                                       const double gyro_bias_rad_s[3],
                                       const double P0_diag[SFD_EKF_DIM]);

/**
 * @brief Propagation by one IMU interval (eqs. (16)-(18) with the IMU as the control input u_k):
 *        with w = gyro - bg and a = accel - ba held over dt,
 *        R' = R Exp(w dt), v' = v + (R a + g) dt, p' = p + v dt + (R a + g) dt^2 / 2;
 *        P' = F P F^T + Q with F the error-state Jacobian (first order in dt, exact rotation
 *        factor Exp(-w dt)) and Q from the noise densities (white noise integrated over dt,
 *        including the position-velocity correlation of the accelerometer noise).
 * @return SFD_OK; SFD_ERR_STATE when not initialized; SFD_ERR_INVAL for null/non-finite input
 *         or dt outside (0, max_dt_s] (the filter is unchanged); SFD_ERR_NUMERIC when the result
 *         is not finite (the filter is unchanged and numeric_faults counts it).
 */
sfd_status_t sfd_ekf_propagate(sfd_ekf_t *ekf, const double gyro_rad_s[3],
                               const double accel_m_s2[3], double dt_s);

/**
 * @brief Predicted undistorted pixel of an observation's landmark, h(x) of eq. (15), with the
 *        Jacobian of eq. (22) restricted to the pose (the only columns that are non-zero):
 *        H_pose (2x6, row-major) over (dp, dtheta), and the 2x2 noise R = sigma^2 I + J_L C_L J_L^T
 *        (pixel noise plus the landmark covariance C_L seen through the projection).
 * @param H_pose may be NULL; @param R_px2 may be NULL.
 * @return SFD_OK; SFD_ERR_INVAL for null/non-finite input; SFD_ERR_DOMAIN when the landmark is
 *         not in front of the camera (depth <= 1e-6 m).
 */
sfd_status_t sfd_ekf_predict_observation(const sfd_ekf_t *ekf, const sfd_ekf_camera_t *cam,
                                         const sfd_ekf_obs_t *obs, double uv_pred_px[2],
                                         double H_pose[12], double R_px2[4]);

/**
 * @brief Camera update with the observations whose @p use flag is non-zero (all when @p use is
 *        NULL): eqs. (19)-(21) for the stacked measurement, linearized once at the prior
 *        (eq. (22)). Because H is non-zero only in the 6 pose columns and R is block diagonal,
 *        the gain is formed in information form over the pose, K = P_xs (I + Y P_ss)^-1 H^T R^-1
 *        with Y = sum H_i^T R_i^-1 H_i, which is algebraically eq. (19); the covariance uses the
 *        Joseph form (I - K H) P (I - K H)^T + K R K^T, symmetric positive semi-definite by
 *        construction. Observations behind the camera are skipped and counted.
 * @return SFD_OK (also when nothing was applied); SFD_ERR_STATE when not initialized;
 *         SFD_ERR_INVAL for null input or n outside [0, SFD_MAX_FEATURES]; SFD_ERR_NUMERIC when
 *         a factorization fails or the result is not finite (the filter is unchanged and
 *         numeric_faults counts it).
 */
sfd_status_t sfd_ekf_update_camera(sfd_ekf_t *ekf, const sfd_ekf_camera_t *cam,
                                   const sfd_ekf_obs_t *obs, const uint8_t *use, int32_t n,
                                   sfd_ekf_update_info_t *info);

/**
 * @brief Linear measurement update z = H x_err + v, v ~ N(0, R), of m <= 6 rows (eqs. (11)-(13)
 *        with the Joseph covariance form): for position fixes, zero-velocity updates at rest and
 *        tests. @p residual is z minus its prediction; H is m x 15 row-major, R is m x m SPD.
 * @return SFD_OK; SFD_ERR_STATE when not initialized; SFD_ERR_INVAL for null/non-finite input
 *         or m outside [1, 6]; SFD_ERR_NUMERIC when H P H^T + R is not positive definite.
 */
sfd_status_t sfd_ekf_update_linear(sfd_ekf_t *ekf, const double *H, const double *residual,
                                   const double *R, int32_t m);

/**
 * @brief Camera pose in the world from the filter's IMU pose and the extrinsics:
 *        R_CtoW = R_ItoW R_CtoI, p_CinW = p_IinW + R_ItoW p_CinI.
 * @return SFD_OK; SFD_ERR_INVAL for null.
 */
sfd_status_t sfd_ekf_camera_pose(const sfd_ekf_t *ekf, const sfd_extrinsics_t *ext,
                                 double R_CtoW[9], double p_CinW_m[3]);

#ifdef __cplusplus
}
#endif
#endif /* SFD_EKF_H */
