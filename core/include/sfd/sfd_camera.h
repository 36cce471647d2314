/* SPDX-License-Identifier: MIT */
/**
 * @file sfd_camera.h
 * @brief Camera model: pinhole intrinsics with radial-tangential (Brown-Conrady, k1 k2 p1 p2) or
 *        equidistant (Kannala-Brandt, k1..k4) distortion, as in the EuRoC/Kalibr calibration files
 *        and OpenCV (cv::projectPoints / cv::fisheye).
 *
 * Conventions: camera frame z forward, x right, y down. "Normalized" coordinates are the
 * undistorted (x/z, y/z). Pixel coordinates are raw (distorted) image pixels; a pixel's centre has
 * integer coordinates (OpenCV). Jacobians are row-major 2xN arrays.
 *
 * Every call re-validates the camera (the struct is public): a camera that sfd_camera_init() would
 * reject gives SFD_ERR_INVAL. Outputs are written only on SFD_OK, after every input has been read,
 * so an output may alias an input (in-place calls). No state, no heap: reentrant. Run time is
 * bounded by compile-time constants (SFD_UNDISTORT_ITERATIONS).
 * Design note: core/docs/camera_model.md.
 */
#ifndef SFD_CAMERA_H
#define SFD_CAMERA_H

#include "sfd_config.h"
#include "sfd_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Distortion models (numerically identical to the LCM camera_info_t constants). */
typedef enum {
    SFD_DISTORTION_PINHOLE = 0,    /**< no distortion */
    SFD_DISTORTION_RADTAN = 1,     /**< k1, k2 radial; p1, p2 tangential */
    SFD_DISTORTION_EQUIDISTANT = 2 /**< theta_d = th (1 + k1 th^2 + k2 th^4 + k3 th^6 + k4 th^8) */
} sfd_distortion_model_t;

typedef struct {
    int model;           /**< sfd_distortion_model_t */
    int width_px;        /**< image width (px), > 0 */
    int height_px;       /**< image height (px), > 0 */
    double fx_px, fy_px; /**< focal lengths (px) */
    double cx_px, cy_px; /**< principal point (px) */
    double dist[4];      /**< radtan: k1 k2 p1 p2; equidistant: k1 k2 k3 k4; pinhole: all 0 */
} sfd_camera_t;

/**
 * @brief Validates and stores a calibration.
 * @param dist  Four coefficients in the order of sfd_camera_t::dist; never NULL (pass zeros for
 *              the pinhole model).
 * @return SFD_OK; SFD_ERR_INVAL for a null pointer, unknown model, non-finite value, focal
 *         length <= 0, size <= 0, or a non-zero coefficient for the pinhole model (a radtan or
 *         equidistant calibration tagged pinhole by mistake) (the camera is left unchanged).
 */
sfd_status_t sfd_camera_init(sfd_camera_t *cam, int model, int width_px, int height_px,
                             double fx_px, double fy_px, double cx_px, double cy_px,
                             const double dist[4]);

/**
 * @brief Distorts normalized coordinates and applies the intrinsics: pixel = K * d(xn).
 * @param xn      Normalized undistorted coordinates (x/z, y/z).
 * @param uv_px   Out: raw pixel coordinates.
 * @param J_uv_xn Out (nullable): 2x2 row-major Jacobian d(uv)/d(xn).
 * @return SFD_OK; SFD_ERR_INVAL for null/non-finite input; SFD_ERR_NUMERIC when the result
 *         overflows (|xn| absurdly large, e.g. 1e100).
 */
sfd_status_t sfd_camera_distort(const sfd_camera_t *cam, const double xn[2], double uv_px[2],
                                double J_uv_xn[4]);

/**
 * @brief Inverse of sfd_camera_distort: raw pixels to normalized undistorted coordinates by at most
 *        SFD_UNDISTORT_ITERATIONS Newton steps on the distortion model (fewer once converged to
 *        double precision).
 * @param J_xn_uv Out (nullable): 2x2 Jacobian d(xn)/d(uv) at the solution (inverse of the forward
 *        Jacobian), used to carry pixel noise into normalized coordinates.
 * @return SFD_OK; SFD_ERR_INVAL for null/non-finite input; SFD_ERR_NUMERIC when the distortion
 *         model is not invertible there (singular Jacobian) or the residual after the fixed
 *         iterations exceeds 1e-9 px (pixel far outside the calibrated field of view; for the
 *         equidistant model also a pixel whose ray is at or beyond 90 deg from the optical axis).
 */
sfd_status_t sfd_camera_undistort(const sfd_camera_t *cam, const double uv_px[2], double xn[2],
                                  double J_xn_uv[4]);

/** Pixel noise of one match beyond the isotropic model, in undistorted pixels: for the previous
 *  and the current observation, dC = C - I (xx, xy, yy) with C the covariance of the undistorted
 *  pixel in units of sigma^2 (sfd_camera_pixel_noise()). All zero means isotropic noise sigma^2 I
 *  in undistorted pixels: exactly the pinhole camera, and what a zero-initialised match assumes.
 *  Single precision: C only scales a test statistic (relative error ~1e-7). */
typedef struct {
    float prev_dC[3]; /**< previous frame: C - I (xx, xy, yy), dimensionless */
    float curr_dC[3]; /**< current frame: C - I (xx, xy, yy), dimensionless */
} sfd_pixel_noise_t;

/**
 * @brief Covariance, in units of sigma^2, of the undistorted pixel uv = K xn when the raw pixel
 *        carries isotropic noise sigma^2 I, minus the identity (first order):
 *        A = d(uv_raw)/d(uv) = diag(fx, fy) D diag(1/fx, 1/fy) with D = d(distorted xn)/d(xn),
 *        C = A^-1 A^-T, dC = C - I. Output as (xx, xy, yy), single precision; exactly zero for
 *        the pinhole model (A = I).
 * @param xn  Normalized undistorted coordinates (x/z, y/z) of the feature.
 * @param dC  Out: C - I (xx, xy, yy).
 * @return SFD_OK; SFD_ERR_INVAL for null/non-finite input or an invalid camera; SFD_ERR_NUMERIC
 *         when A is singular or C is not finite (dC untouched).
 */
sfd_status_t sfd_camera_pixel_noise(const sfd_camera_t *cam, const double xn[2], float dC[3]);

/**
 * @brief Projects a 3-D point in the camera frame to raw pixels.
 * @param p_FinC  Point (m) in the camera frame.
 * @param J_uv_p  Out (nullable): 2x3 row-major Jacobian d(uv)/d(p_FinC).
 * @return SFD_OK; SFD_ERR_INVAL for null/non-finite input; SFD_ERR_DOMAIN for z <= 1e-9 m
 *         (point behind or on the camera plane); SFD_ERR_NUMERIC when the result overflows.
 */
sfd_status_t sfd_camera_project(const sfd_camera_t *cam, const double p_FinC[3], double uv_px[2],
                                double J_uv_p[6]);

/**
 * @brief Bearing of a pixel: the unit-depth ray (xn, yn, 1) of sfd_camera_undistort().
 * @return As sfd_camera_undistort().
 */
sfd_status_t sfd_camera_unproject(const sfd_camera_t *cam, const double uv_px[2], double ray_C[3]);

#ifdef __cplusplus
}
#endif

#endif /* SFD_CAMERA_H */
