// SPDX-License-Identifier: MIT
// Camera model: pinhole intrinsics K with radial-tangential or equidistant lens distortion.
// Design note: core/docs/camera_model.md (requirements SFD-CAM-001..007).
//
//   pixel = K d(xn),   K d = (fx d_x + cx, fy d_y + cy),   xn = (x/z, y/z)
//
// d() is one of
//   pinhole      d(xn) = xn
//   radtan       Brown-Conrady with k1 k2 p1 p2, exactly cv::projectPoints with (k1,k2,p1,p2) and
//                Kalibr "radial-tangential" (OpenCV docs, "Camera Calibration and 3D
//                Reconstruction", calib3d module)
//   equidistant  Kannala-Brandt with k1..k4 on the incidence angle theta, exactly
//                cv::fisheye::projectPoints (skew 0) and Kalibr "equidistant" (J. Kannala,
//                S. Brandt, "A Generic Camera Model and Calibration Method for Conventional,
//                Wide-Angle, and Fish-Eye Lenses", IEEE TPAMI 28(8), 2006)
#include "core_private.hpp"

#include "sfd/sfd_camera.h"
#include "small_linalg.hpp"

namespace sfd {
namespace {

/// Depth (m) below which a point counts as on or behind the camera plane (header contract).
constexpr double kMinDepth_m = 1e-9;

/// Largest pixel residual |K d(xn) - uv| (px) that undistortion accepts (header contract).
constexpr double kMaxUndistortResidual_px = 1e-9;

/// Smallest determinant of the (dimensionless) distortion Jacobian dd/dxn that counts as
/// invertible. dd/dxn is the identity at the image centre; a determinant this small means the
/// model folds over (or nearly so) and the pixel has no unique preimage.
constexpr double kMinDistortionDet = 1e-12;

/// Equidistant model: below this normalized radius r the scale theta_d(r)/r and its derivative
/// use their Taylor series (the closed forms are 0/0 at r = 0 and lose digits as r -> 0).
/// The dropped terms are O(r^6) relative in the scale and O(r^4) in g, which multiplies
/// xn xn^T = O(r^2) in the Jacobian: below 1e-24 either way.
constexpr double kEquidistantSeriesRadius = 1e-4;

/// Equidistant undistortion: below this distorted radius theta_d (rad) the ratio
/// tan(theta) / theta_d = 1 + (1/3 - k1) theta_d^2 + O(theta_d^4) is 1 to double precision
/// (the closed form is 0/0 at theta_d = 0).
constexpr double kEquidistantTinyAngle_rad = 1e-8;

constexpr double kHalfPi = 1.57079632679489661923;

/// Distortion d(xn), its Jacobian dd/dxn (dimensionless, row-major), and the radial scale of
/// the model at xn (radtan: 1 + k1 r^2 + k2 r^4; equidistant: theta_d / r; pinhole: 1). A radial
/// scale <= 0 maps xn through the principal point to the opposite side of the image: a folded,
/// non-physical branch of the model.
struct Distorted {
    Vec2 d;
    Mat2 J;
    double radial_scale;
};

/// Checks a calibration (shared by init and every call, since the struct is public and may have
/// been filled by hand): known model, positive size, finite intrinsics with positive focal
/// lengths, finite coefficients, and zero coefficients where the model has none (pinhole), so
/// that a radtan calibration passed with the wrong model tag is rejected rather than ignored.
bool calibration_valid(int model, int width_px, int height_px, double fx_px, double fy_px,
                       double cx_px, double cy_px, const double dist[4]) {
    if (model != SFD_DISTORTION_PINHOLE && model != SFD_DISTORTION_RADTAN &&
        model != SFD_DISTORTION_EQUIDISTANT) {
        return false;
    }
    if (width_px <= 0 || height_px <= 0) return false;
    const double intrinsics[4] = {fx_px, fy_px, cx_px, cy_px};
    if (!all_finite(intrinsics, 4) || !all_finite(dist, 4)) return false;
    if (!(fx_px > 0.0) || !(fy_px > 0.0)) return false;
    if (model == SFD_DISTORTION_PINHOLE) {
        for (int i = 0; i < 4; ++i) {
            if (std::fabs(dist[i]) > 0.0) return false;
        }
    }
    return true;
}

bool camera_valid(const sfd_camera_t *cam) {
    return cam != nullptr &&
           calibration_valid(cam->model, cam->width_px, cam->height_px, cam->fx_px, cam->fy_px,
                             cam->cx_px, cam->cy_px, cam->dist);
}

/// Brown-Conrady radial-tangential distortion (OpenCV calib3d convention):
///   r^2 = x^2 + y^2,  a = 1 + k1 r^2 + k2 r^4
///   d_x = x a + 2 p1 x y + p2 (r^2 + 2 x^2)
///   d_y = y a + p1 (r^2 + 2 y^2) + 2 p2 x y
/// with da/dx = 2 x b, da/dy = 2 y b, b = k1 + 2 k2 r^2.
Distorted distort_radtan(const double k[4], const Vec2 &xn) {
    const double k1 = k[0], k2 = k[1], p1 = k[2], p2 = k[3];
    const double x = xn(0), y = xn(1);
    const double x2 = x * x, y2 = y * y, xy = x * y;
    const double r2 = x2 + y2;
    const double a = 1.0 + r2 * (k1 + k2 * r2);
    const double b = k1 + 2.0 * k2 * r2;
    Distorted out;
    out.d(0) = x * a + 2.0 * p1 * xy + p2 * (r2 + 2.0 * x2);
    out.d(1) = y * a + p1 * (r2 + 2.0 * y2) + 2.0 * p2 * xy;
    out.J(0, 0) = a + 2.0 * x2 * b + 2.0 * p1 * y + 6.0 * p2 * x;
    out.J(0, 1) = 2.0 * xy * b + 2.0 * p1 * x + 2.0 * p2 * y;
    out.J(1, 0) = 2.0 * xy * b + 2.0 * p1 * x + 2.0 * p2 * y;
    out.J(1, 1) = a + 2.0 * y2 * b + 6.0 * p1 * y + 2.0 * p2 * x;
    out.radial_scale = a;
    return out;
}

/// theta_d(theta) = theta (1 + k1 th^2 + k2 th^4 + k3 th^6 + k4 th^8) of Kannala-Brandt.
double equidistant_theta_d(const double k[4], double theta) {
    const double t2 = theta * theta;
    return theta * (1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3]))));
}

/// d theta_d / d theta = 1 + 3 k1 th^2 + 5 k2 th^4 + 7 k3 th^6 + 9 k4 th^8.
double equidistant_dtheta_d(const double k[4], double theta) {
    const double t2 = theta * theta;
    return 1.0 + t2 * (3.0 * k[0] + t2 * (5.0 * k[1] + t2 * (7.0 * k[2] + t2 * 9.0 * k[3])));
}

/// Kannala-Brandt equidistant distortion (cv::fisheye convention):
///   r = |xn|, theta = atan(r), d = s(r) xn with s(r) = theta_d(theta) / r.
/// Jacobian: dd/dxn = s I + g xn xn^T with g = s'(r) / r and
///   s'(r) = (theta_d'(theta) / (1 + r^2) - s) / r   (d theta / d r = 1 / (1 + r^2)).
/// As r -> 0 (theta = r - r^3/3 + r^5/5 - ...):
///   s = 1 + c1 r^2 + c2 r^4 + O(r^6),  g = 2 c1 + 4 c2 r^2 + O(r^4),
///   c1 = k1 - 1/3,  c2 = 1/5 - k1 + k2.
Distorted distort_equidistant(const double k[4], const Vec2 &xn) {
    const double r = std::hypot(xn(0), xn(1));
    double s = 0.0;
    double g = 0.0;
    if (r < kEquidistantSeriesRadius) {
        const double c1 = k[0] - 1.0 / 3.0;
        const double c2 = 0.2 - k[0] + k[1];
        const double r2 = r * r;
        s = 1.0 + r2 * (c1 + c2 * r2);
        g = 2.0 * c1 + 4.0 * c2 * r2;
    } else {
        const double theta = std::atan(r);
        s = equidistant_theta_d(k, theta) / r;
        const double ds_dr = (equidistant_dtheta_d(k, theta) / (1.0 + r * r) - s) / r;
        g = ds_dr / r;
    }
    Distorted out;
    out.d = s * xn;
    // g * x first, then * y: keeps the product finite for large r, where g ~ -s/r^2.
    out.J(0, 0) = s + (g * xn(0)) * xn(0);
    out.J(0, 1) = (g * xn(0)) * xn(1);
    out.J(1, 0) = out.J(0, 1);
    out.J(1, 1) = s + (g * xn(1)) * xn(1);
    out.radial_scale = s;
    return out;
}

/// d(xn) and dd/dxn of the camera's model (camera already validated).
Distorted distort_model(const sfd_camera_t &cam, const Vec2 &xn) {
    if (cam.model == SFD_DISTORTION_RADTAN) return distort_radtan(cam.dist, xn);
    if (cam.model == SFD_DISTORTION_EQUIDISTANT) return distort_equidistant(cam.dist, xn);
    Distorted out;
    out.d = xn;
    out.J = Mat2::Identity();
    out.radial_scale = 1.0;
    return out;
}

/// Pixel of a distorted normalized point: uv = (fx d_x + cx, fy d_y + cy).
Vec2 to_pixel(const sfd_camera_t &cam, const Vec2 &d) {
    return Vec2(cam.fx_px * d(0) + cam.cx_px, cam.fy_px * d(1) + cam.cy_px);
}

/// d(uv)/d(xn) = diag(fx, fy) dd/dxn.
Mat2 pixel_jacobian(const sfd_camera_t &cam, const Mat2 &J_d_xn) {
    Mat2 J;
    J.row(0) = cam.fx_px * J_d_xn.row(0);
    J.row(1) = cam.fy_px * J_d_xn.row(1);
    return J;
}

bool finite2(const Vec2 &v) {
    return std::isfinite(v(0)) && std::isfinite(v(1));
}

bool finite22(const Mat2 &m) {
    return std::isfinite(m(0, 0)) && std::isfinite(m(0, 1)) && std::isfinite(m(1, 0)) &&
           std::isfinite(m(1, 1));
}

/// True when dd/dxn is finite and orientation preserving with det > kMinDistortionDet. A negative
/// determinant means a folded branch of the model (not the physical lens mapping), and a tiny
/// one means no well-defined inverse.
bool invertible(const Mat2 &J) {
    return finite22(J) && J.determinant() > kMinDistortionDet;
}

/// Inverse of a 2x2 matrix whose determinant was checked by invertible().
Mat2 inverse2(const Mat2 &J) {
    const double det = la::det_2x2(J(0, 0), J(0, 1), J(1, 0), J(1, 1));
    return la::inverse_2x2(J(0, 0), J(0, 1), J(1, 0), J(1, 1), det);
}

/// A Newton step at the rounding level of double precision at @p x: |step| <= 4 eps max(1, |x|).
bool converged_step(double step, double x) {
    return std::fabs(step) <=
           4.0 * std::numeric_limits<double>::epsilon() * std::fmax(1.0, std::fabs(x));
}

/// Pinhole / radtan inversion: Newton's method on F(xn) = d(xn) - d_target,
///   xn <- xn - (dd/dxn)^-1 F(xn),
/// from xn = d_target, for at most SFD_UNDISTORT_ITERATIONS steps; it stops once a step is at the
/// rounding level of double precision (converged_step()), where further steps only move xn by
/// rounding. Newton converges quadratically once close (typically 3-5 steps inside the image);
/// the caller verifies the result by its pixel residual.
/// Every iterate must be on the orientation-preserving side of the model (det > 0): an iterate
/// with det <= 0 has crossed a fold, and whatever root Newton finds from there is not the
/// physical one. For barrel distortion (|d| < |xn|) the start d_target lies between the centre
/// and the solution, hence inside the fold-free region; for a pincushion model folding between
/// the solution and the pixel radius the start is already beyond the fold and the call fails
/// (safe refusal, see core/docs/camera_model.md).
bool invert_newton_2d(const sfd_camera_t &cam, const Vec2 &d_target, Vec2 *xn) {
    Vec2 x = d_target;
    for (int it = 0; it < SFD_UNDISTORT_ITERATIONS; ++it) {
        const Distorted f = distort_model(cam, x);
        if (!finite2(f.d) || !invertible(f.J)) return false;
        const Vec2 step = inverse2(f.J) * (f.d - d_target);
        x -= step;
        if (converged_step(step(0), x(0)) && converged_step(step(1), x(1))) break;
    }
    *xn = x;
    return finite2(x);
}

/// Equidistant inversion: the model is radially symmetric, so only the radius is unknown.
/// theta_d = |d_target|; solve theta_d(theta) = theta_d by scalar Newton from theta = theta_d
/// for at most SFD_UNDISTORT_ITERATIONS steps, stopping at the rounding level as above
/// (cv::fisheye::undistortPoints has a looser tolerance exit), then
/// xn = (tan(theta) / theta_d) d_target. theta must end in [0, pi/2): a ray at or beyond 90 deg
/// has no normalized coordinates (x/z, y/z).
bool invert_equidistant(const double k[4], const Vec2 &d_target, Vec2 *xn) {
    const double theta_d = std::hypot(d_target(0), d_target(1));
    if (theta_d < kEquidistantTinyAngle_rad) {
        *xn = d_target;
        return true;
    }
    double theta = theta_d;
    for (int it = 0; it < SFD_UNDISTORT_ITERATIONS; ++it) {
        const double slope = equidistant_dtheta_d(k, theta);
        if (!std::isfinite(slope) || !(std::fabs(slope) > kMinDistortionDet)) return false;
        const double step = (equidistant_theta_d(k, theta) - theta_d) / slope;
        theta -= step;
        if (converged_step(step, theta)) break;
    }
    if (!std::isfinite(theta) || !(theta >= 0.0) || !(theta < kHalfPi)) return false;
    *xn = (std::tan(theta) / theta_d) * d_target;
    return finite2(*xn);
}

/// Undistortion shared by undistort() and unproject(): xn and d(xn)/d(uv) on success.
sfd_status_t undistort_impl(const sfd_camera_t *cam, const double uv_px[2], Vec2 *xn,
                            Mat2 *J_xn_uv) {
    if (!camera_valid(cam) || uv_px == nullptr || !all_finite(uv_px, 2)) return SFD_ERR_INVAL;
    const Vec2 uv(uv_px[0], uv_px[1]);
    const Vec2 d_target((uv(0) - cam->cx_px) / cam->fx_px, (uv(1) - cam->cy_px) / cam->fy_px);
    if (cam->model == SFD_DISTORTION_PINHOLE) {  // no distortion: K^{-1} uv, exactly
        if (!finite2(d_target)) return SFD_ERR_NUMERIC;
        *xn = d_target;
        *J_xn_uv << 1.0 / cam->fx_px, 0.0, 0.0, 1.0 / cam->fy_px;
        return SFD_OK;
    }

    Vec2 x = Vec2::Zero();
    const bool solved = (cam->model == SFD_DISTORTION_EQUIDISTANT)
                            ? invert_equidistant(cam->dist, d_target, &x)
                            : invert_newton_2d(*cam, d_target, &x);
    if (!solved) return SFD_ERR_NUMERIC;

    // Verification in the measurement space: the solution must reproduce the pixel, and lie on
    // the physical branch of the model: locally invertible and orientation preserving (else the
    // Jacobian, and the solution, mean nothing) and not mirrored through the principal point
    // (Newton can converge there from pixels beyond the fold of a barrel radtan model, where
    // both eigenvalues of dd/dxn are negative and the determinant is positive again).
    const Distorted f = distort_model(*cam, x);
    if (!finite2(f.d) || !invertible(f.J) || !(f.radial_scale > 0.0)) return SFD_ERR_NUMERIC;
    const Vec2 residual = to_pixel(*cam, f.d) - uv;
    if (!(std::hypot(residual(0), residual(1)) <= kMaxUndistortResidual_px)) {
        return SFD_ERR_NUMERIC;
    }
    // d(xn)/d(uv) = (d(uv)/d(xn))^-1 = (dd/dxn)^-1 diag(1/fx, 1/fy).
    Mat2 J = inverse2(f.J);
    J.col(0) /= cam->fx_px;
    J.col(1) /= cam->fy_px;
    if (!finite22(J)) return SFD_ERR_NUMERIC;
    *xn = x;
    *J_xn_uv = J;
    return SFD_OK;
}

void store_row_major(const Mat2 &m, double out[4]) {
    out[0] = m(0, 0);
    out[1] = m(0, 1);
    out[2] = m(1, 0);
    out[3] = m(1, 1);
}

}  // namespace
}  // namespace sfd

extern "C" sfd_status_t sfd_camera_init(sfd_camera_t *cam, int model, int width_px, int height_px,
                                        double fx_px, double fy_px, double cx_px, double cy_px,
                                        const double dist[4]) {
    if (cam == nullptr || dist == nullptr) return SFD_ERR_INVAL;
    if (!sfd::calibration_valid(model, width_px, height_px, fx_px, fy_px, cx_px, cy_px, dist)) {
        return SFD_ERR_INVAL;
    }
    cam->model = model;
    cam->width_px = width_px;
    cam->height_px = height_px;
    cam->fx_px = fx_px;
    cam->fy_px = fy_px;
    cam->cx_px = cx_px;
    cam->cy_px = cy_px;
    for (int i = 0; i < 4; ++i) cam->dist[i] = dist[i];
    return SFD_OK;
}

extern "C" sfd_status_t sfd_camera_distort(const sfd_camera_t *cam, const double xn[2],
                                           double uv_px[2], double J_uv_xn[4]) {
    if (!sfd::camera_valid(cam) || xn == nullptr || uv_px == nullptr || !sfd::all_finite(xn, 2)) {
        return SFD_ERR_INVAL;
    }
    const sfd::Distorted f = sfd::distort_model(*cam, sfd::Vec2(xn[0], xn[1]));
    const sfd::Vec2 uv = sfd::to_pixel(*cam, f.d);
    const sfd::Mat2 J = sfd::pixel_jacobian(*cam, f.J);
    if (!sfd::finite2(uv) || (J_uv_xn != nullptr && !sfd::finite22(J))) return SFD_ERR_NUMERIC;
    uv_px[0] = uv(0);
    uv_px[1] = uv(1);
    if (J_uv_xn != nullptr) sfd::store_row_major(J, J_uv_xn);
    return SFD_OK;
}

// Noise of the undistorted pixel from isotropic raw-pixel noise (first order): uv_raw = K d(xn),
// uv = K xn, so A = d(uv_raw)/d(uv) = K_2 D K_2^-1 (K_2 = diag(fx, fy)), and Cov(uv) = sigma^2
// A^-1 A^-T (core/docs/camera_model.md "Noise in undistorted pixels").
extern "C" sfd_status_t sfd_camera_pixel_noise(const sfd_camera_t *cam, const double xn[2],
                                               float dC[3]) {
    if (!sfd::camera_valid(cam) || xn == nullptr || dC == nullptr || !sfd::all_finite(xn, 2)) {
        return SFD_ERR_INVAL;
    }
    if (cam->model == SFD_DISTORTION_PINHOLE) {  // A = I: C = I exactly
        dC[0] = dC[1] = dC[2] = 0.0F;
        return SFD_OK;
    }
    const sfd::Distorted f = sfd::distort_model(*cam, sfd::Vec2(xn[0], xn[1]));
    const double a00 = f.J(0, 0);
    const double a01 = f.J(0, 1) * cam->fx_px / cam->fy_px;
    const double a10 = f.J(1, 0) * cam->fy_px / cam->fx_px;
    const double a11 = f.J(1, 1);
    const double det = a00 * a11 - a01 * a10;
    if (!(std::fabs(det) > 0.0) || !std::isfinite(det)) return SFD_ERR_NUMERIC;
    // A^-1 = [a11 -a01; -a10 a00] / det; C = A^-1 A^-T.
    const double i00 = a11 / det, i01 = -a01 / det, i10 = -a10 / det, i11 = a00 / det;
    const double cxx = i00 * i00 + i01 * i01;
    const double cxy = i00 * i10 + i01 * i11;
    const double cyy = i10 * i10 + i11 * i11;
    if (!std::isfinite(cxx) || !std::isfinite(cxy) || !std::isfinite(cyy)) return SFD_ERR_NUMERIC;
    dC[0] = static_cast<float>(cxx - 1.0);
    dC[1] = static_cast<float>(cxy);
    dC[2] = static_cast<float>(cyy - 1.0);
    return SFD_OK;
}

extern "C" sfd_status_t sfd_camera_undistort(const sfd_camera_t *cam, const double uv_px[2],
                                             double xn[2], double J_xn_uv[4]) {
    if (xn == nullptr) return SFD_ERR_INVAL;
    sfd::Vec2 x;
    sfd::Mat2 J;
    const sfd_status_t st = sfd::undistort_impl(cam, uv_px, &x, &J);
    if (st != SFD_OK) return st;
    xn[0] = x(0);
    xn[1] = x(1);
    if (J_xn_uv != nullptr) sfd::store_row_major(J, J_xn_uv);
    return SFD_OK;
}

extern "C" sfd_status_t sfd_camera_project(const sfd_camera_t *cam, const double p_FinC[3],
                                           double uv_px[2], double J_uv_p[6]) {
    if (!sfd::camera_valid(cam) || p_FinC == nullptr || uv_px == nullptr ||
        !sfd::all_finite(p_FinC, 3)) {
        return SFD_ERR_INVAL;
    }
    const double X = p_FinC[0], Y = p_FinC[1], Z = p_FinC[2];
    if (!(Z > sfd::kMinDepth_m)) return SFD_ERR_DOMAIN;
    const double inv_z = 1.0 / Z;
    const sfd::Vec2 xn(X * inv_z, Y * inv_z);
    const sfd::Distorted f = sfd::distort_model(*cam, xn);
    const sfd::Vec2 uv = sfd::to_pixel(*cam, f.d);
    if (!sfd::finite2(uv)) return SFD_ERR_NUMERIC;
    // d(xn)/d(p) = [1/z 0 -x/z^2; 0 1/z -y/z^2] = (1/z) [I2 | -xn].
    Eigen::Matrix<double, 2, 3, Eigen::RowMajor> J_xn_p;
    J_xn_p << inv_z, 0.0, -xn(0) * inv_z, 0.0, inv_z, -xn(1) * inv_z;
    const Eigen::Matrix<double, 2, 3, Eigen::RowMajor> J = sfd::pixel_jacobian(*cam, f.J) * J_xn_p;
    if (J_uv_p != nullptr) {
        for (int i = 0; i < 6; ++i) {
            if (!std::isfinite(J(i / 3, i % 3))) return SFD_ERR_NUMERIC;
        }
    }
    uv_px[0] = uv(0);
    uv_px[1] = uv(1);
    if (J_uv_p != nullptr) {
        for (int i = 0; i < 6; ++i) J_uv_p[i] = J(i / 3, i % 3);
    }
    return SFD_OK;
}

extern "C" sfd_status_t sfd_camera_unproject(const sfd_camera_t *cam, const double uv_px[2],
                                             double ray_C[3]) {
    if (ray_C == nullptr) return SFD_ERR_INVAL;
    sfd::Vec2 x;
    sfd::Mat2 J;
    const sfd_status_t st = sfd::undistort_impl(cam, uv_px, &x, &J);
    if (st != SFD_OK) return st;
    ray_C[0] = x(0);
    ray_C[1] = x(1);
    ray_C[2] = 1.0;
    return SFD_OK;
}
