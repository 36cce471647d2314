/* SPDX-License-Identifier: MIT */
/* Unit tests of the camera model (core/src/camera_model.cpp, core/docs/camera_model.md).
 *
 * Calibrations used:
 *  - EuRoC MAV dataset, VI-Sensor cam0 (mav0/cam0/sensor.yaml): 752x480, radial-tangential.
 *  - TUM VI dataset, 512x512 cam0 (Kalibr camchain "pinhole-equi-512"): equidistant, about
 *    195 deg field of view, so the image corners see rays beyond 90 deg from the optical axis.
 *  - The EuRoC intrinsics without distortion (pinhole).
 * Reference pixels in camera_opencv_reference_* were computed once with OpenCV 4.6
 * (cv::projectPoints and cv::fisheye::projectPoints, rvec = tvec = 0, skew 0), an implementation
 * independent of this one, and are hardcoded with 17 significant digits. */
#include "sfd_test.h"

#include <string.h>

#include "sfd/sfd_camera.h"

/* ---------------------------------------------------------------------------------------------
 * Fixtures
 * ------------------------------------------------------------------------------------------- */

static const double kEurocDist[4] = {-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05};
static const double kTumviDist[4] = {0.0034823894022493434, 0.0007150348452162257,
                                     -0.0020532361418706202, 0.00020293673591811182};
static const double kZeroDist[4] = {0.0, 0.0, 0.0, 0.0};

static sfd_camera_t euroc_cam0(void) {
    sfd_camera_t cam;
    memset(&cam, 0, sizeof cam);
    assert_status(sfd_camera_init(&cam, SFD_DISTORTION_RADTAN, 752, 480, 458.654, 457.296, 367.215,
                                  248.375, kEurocDist),
                  SFD_OK);
    return cam;
}

static sfd_camera_t tumvi_cam0(void) {
    sfd_camera_t cam;
    memset(&cam, 0, sizeof cam);
    assert_status(
        sfd_camera_init(&cam, SFD_DISTORTION_EQUIDISTANT, 512, 512, 190.97847715128717,
                        190.9733070521226, 254.93170605935475, 256.8974428996504, kTumviDist),
        SFD_OK);
    return cam;
}

static sfd_camera_t euroc_pinhole(void) {
    sfd_camera_t cam;
    memset(&cam, 0, sizeof cam);
    assert_status(sfd_camera_init(&cam, SFD_DISTORTION_PINHOLE, 752, 480, 458.654, 457.296, 367.215,
                                  248.375, kZeroDist),
                  SFD_OK);
    return cam;
}

/* Deterministic xorshift64* (the tests do not depend on the core PRNG module). */
static uint64_t g_rng_state = 0x9E3779B97F4A7C15u;

static double rand_uniform(double lo, double hi) {
    g_rng_state ^= g_rng_state >> 12;
    g_rng_state ^= g_rng_state << 25;
    g_rng_state ^= g_rng_state >> 27;
    const uint64_t bits = (g_rng_state * 0x2545F4914F6CDD1Du) >> 11; /* 53 bits */
    return lo + (hi - lo) * ((double)bits / 9007199254740992.0);
}

/* Sample positions along one image axis of n pixels: every 4 px from the first pixel centre,
 * the last pixel centre n - 1, and the outer image borders -0.5 and n - 0.5. */
enum { kAxisCap = 256 };

static int grid_axis(int n, double out[kAxisCap]) {
    int count = 0;
    out[count++] = -0.5;
    for (int i = 0; i < n - 1 && count < kAxisCap - 2; i += 4) out[count++] = (double)i;
    out[count++] = (double)(n - 1);
    out[count++] = (double)n - 0.5;
    return count;
}

/* Pixel distance between the pixel and distort(undistort(pixel)); asserts both calls succeed. */
static double round_trip_error_px(const sfd_camera_t *cam, double u, double v) {
    const double uv[2] = {u, v};
    double xn[2], uv2[2];
    assert_status(sfd_camera_undistort(cam, uv, xn, NULL), SFD_OK);
    assert_status(sfd_camera_distort(cam, xn, uv2, NULL), SFD_OK);
    return hypot(uv2[0] - u, uv2[1] - v);
}

/* Worst round-trip error over the whole-image grid; every sample must be invertible. */
static double worst_round_trip_px(const sfd_camera_t *cam, int *samples) {
    double us[kAxisCap], vs[kAxisCap];
    const int nu = grid_axis(cam->width_px, us);
    const int nv = grid_axis(cam->height_px, vs);
    double worst = 0.0;
    for (int j = 0; j < nv; ++j) {
        for (int i = 0; i < nu; ++i) {
            const double e = round_trip_error_px(cam, us[i], vs[j]);
            if (e > worst) worst = e;
        }
    }
    *samples = nu * nv;
    return worst;
}

/* Central finite differences of distort with respect to xn (row-major 2x2). */
static void fd_distort(const sfd_camera_t *cam, const double xn[2], double h, double J[4]) {
    for (int c = 0; c < 2; ++c) {
        double xp[2] = {xn[0], xn[1]}, xm[2] = {xn[0], xn[1]};
        double up[2], um[2];
        xp[c] += h;
        xm[c] -= h;
        assert_status(sfd_camera_distort(cam, xp, up, NULL), SFD_OK);
        assert_status(sfd_camera_distort(cam, xm, um, NULL), SFD_OK);
        J[0 * 2 + c] = (up[0] - um[0]) / (2.0 * h);
        J[1 * 2 + c] = (up[1] - um[1]) / (2.0 * h);
    }
}

static void check_distort_jacobian(const sfd_camera_t *cam, const double xn[2], double tol) {
    double uv[2], J[4], J_fd[4];
    assert_status(sfd_camera_distort(cam, xn, uv, J), SFD_OK);
    fd_distort(cam, xn, 1e-6, J_fd);
    for (int k = 0; k < 4; ++k) assert_near(J[k], J_fd[k], tol);
}

static void check_project_jacobian(const sfd_camera_t *cam, const double p[3]) {
    double uv[2], J[6];
    assert_status(sfd_camera_project(cam, p, uv, J), SFD_OK);
    const double h = 1e-6; /* m */
    for (int c = 0; c < 3; ++c) {
        double pp[3] = {p[0], p[1], p[2]}, pm[3] = {p[0], p[1], p[2]};
        double up[2], um[2];
        pp[c] += h;
        pm[c] -= h;
        assert_status(sfd_camera_project(cam, pp, up, NULL), SFD_OK);
        assert_status(sfd_camera_project(cam, pm, um, NULL), SFD_OK);
        assert_near(J[0 * 3 + c], (up[0] - um[0]) / (2.0 * h), 1e-5);
        assert_near(J[1 * 3 + c], (up[1] - um[1]) / (2.0 * h), 1e-5);
    }
}

/* J_xn_uv against finite differences of undistort, and against the inverse of J_uv_xn. */
static void check_undistort_jacobian(const sfd_camera_t *cam, const double uv[2]) {
    double xn[2], J[4];
    assert_status(sfd_camera_undistort(cam, uv, xn, J), SFD_OK);
    const double h = 1e-4; /* px */
    for (int c = 0; c < 2; ++c) {
        double up[2] = {uv[0], uv[1]}, um[2] = {uv[0], uv[1]};
        double xp[2], xm[2];
        up[c] += h;
        um[c] -= h;
        assert_status(sfd_camera_undistort(cam, up, xp, NULL), SFD_OK);
        assert_status(sfd_camera_undistort(cam, um, xm, NULL), SFD_OK);
        assert_near(J[0 * 2 + c], (xp[0] - xm[0]) / (2.0 * h), 1e-9);
        assert_near(J[1 * 2 + c], (xp[1] - xm[1]) / (2.0 * h), 1e-9);
    }
    double uv2[2], Jf[4];
    assert_status(sfd_camera_distort(cam, xn, uv2, Jf), SFD_OK);
    /* J_xn_uv * J_uv_xn = I */
    assert_near(J[0] * Jf[0] + J[1] * Jf[2], 1.0, 1e-12);
    assert_near(J[0] * Jf[1] + J[1] * Jf[3], 0.0, 1e-12);
    assert_near(J[2] * Jf[0] + J[3] * Jf[2], 0.0, 1e-12);
    assert_near(J[2] * Jf[1] + J[3] * Jf[3], 1.0, 1e-12);
}

/* theta_d(pi/2) of an equidistant calibration: the distorted radius of a ray at 90 deg. */
static double equidistant_theta_d_at_90deg(const double k[4]) {
    const double th = 1.5707963267948966, t2 = th * th;
    return th * (1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3]))));
}

/* ---------------------------------------------------------------------------------------------
 * Nominal
 * ------------------------------------------------------------------------------------------- */

static void camera_opencv_reference_radtan_matches_below_1e9px(void **state) {
    (void)state;
    SFD_REQ("SFD-CAM-001");
    /* GIVEN the EuRoC cam0 radtan calibration and points projected by cv::projectPoints */
    static const double ref[][5] = {
        /* X, Y, Z (m), u, v (px) */
        {0.0, 0.0, 1.0, 367.21499999999997, 248.375},
        {0.3, -0.2, 1.5, 457.46276228811519, 188.39338974168481},
        {-1.2, -0.7, 1.0, -33.559162070326579, 15.444059434855092},
        {0.9, 0.55, 0.8, 744.48643250658381, 478.39245676611432},
        {-0.05, 0.4, 2.5, 358.1087025431803, 321.01365908789467},
    };
    const sfd_camera_t cam = euroc_cam0();
    for (size_t i = 0; i < sizeof ref / sizeof ref[0]; ++i) {
        /* WHEN sfd projects the same point */
        double uv[2];
        assert_status(sfd_camera_project(&cam, ref[i], uv, NULL), SFD_OK);
        /* THEN the pixels agree with OpenCV to 1e-9 px */
        assert_near(uv[0], ref[i][3], 1e-9);
        assert_near(uv[1], ref[i][4], 1e-9);
    }
}

static void camera_opencv_reference_equidistant_matches_below_1e9px(void **state) {
    (void)state;
    SFD_REQ("SFD-CAM-001");
    SFD_REQ("SFD-CAM-007");
    /* GIVEN the TUM VI cam0 equidistant calibration and points projected by
     * cv::fisheye::projectPoints, including one 76 deg off axis and one 2.2e-6 rad off axis */
    static const double ref[][5] = {
        {0.0, 0.0, 1.0, 254.93170605935475, 256.8974428996504},
        {0.3, -0.2, 1.5, 292.42360858620674, 231.90351785975574},
        {-1.2, -0.7, 1.0, 98.362137327902445, 165.56766698604218},
        {3.0, 2.0, 0.5, 481.72883546642902, 408.09143599199456},
        {-0.05, 0.4, 2.5, 251.14439375437706, 287.19512110965434},
        {1e-6, -2e-6, 1.0, 254.9318970378319, 256.89706095303632},
    };
    const sfd_camera_t cam = tumvi_cam0();
    for (size_t i = 0; i < sizeof ref / sizeof ref[0]; ++i) {
        /* WHEN sfd projects the same point */
        double uv[2];
        assert_status(sfd_camera_project(&cam, ref[i], uv, NULL), SFD_OK);
        /* THEN the pixels agree with OpenCV to 1e-9 px */
        assert_near(uv[0], ref[i][3], 1e-9);
        assert_near(uv[1], ref[i][4], 1e-9);
    }
}

static void camera_radtan_euroc_whole_image_round_trip_below_1e6px(void **state) {
    (void)state;
    SFD_REQ("SFD-CAM-002");
    /* GIVEN EuRoC cam0 and a 4 px grid over the whole 752x480 image, with the last pixel
     * centres (751, 479) and the outer borders (-0.5, 751.5, 479.5): corners and edges exactly */
    const sfd_camera_t cam = euroc_cam0();
    int samples = 0;
    /* WHEN every sample is undistorted and distorted again */
    const double worst = worst_round_trip_px(&cam, &samples);
    /* THEN every sample is invertible and comes back within 1e-6 px */
    print_message("EuRoC cam0 radtan: worst round trip %.3g px over %d samples\n", worst, samples);
    assert_true(samples > 188 * 120);
    assert_true(worst < 1e-6);
}

static void camera_radtan_euroc_undistort_of_distort_returns_point(void **state) {
    (void)state;
    SFD_REQ("SFD-CAM-002");
    /* GIVEN normalized points over the EuRoC cam0 field of view (beyond the image corners) */
    const sfd_camera_t cam = euroc_cam0();
    for (int i = 0; i < 1000; ++i) {
        const double xn[2] = {rand_uniform(-1.4, 1.4), rand_uniform(-0.9, 0.9)};
        double uv[2], back[2];
        /* WHEN a point is distorted and undistorted */
        assert_status(sfd_camera_distort(&cam, xn, uv, NULL), SFD_OK);
        assert_status(sfd_camera_undistort(&cam, uv, back, NULL), SFD_OK);
        /* THEN the same branch of the model is found: the point itself */
        assert_near(back[0], xn[0], 1e-12);
        assert_near(back[1], xn[1], 1e-12);
    }
}

static void camera_equidistant_tumvi_whole_image_round_trip_below_1e6px(void **state) {
    (void)state;
    SFD_REQ("SFD-CAM-002");
    SFD_REQ("SFD-CAM-006");
    /* GIVEN TUM VI cam0 (195 deg lens) and a 4 px grid over the whole 512x512 image */
    const sfd_camera_t cam = tumvi_cam0();
    const double theta_d_90 = equidistant_theta_d_at_90deg(cam.dist);
    double us[kAxisCap], vs[kAxisCap];
    const int nu = grid_axis(cam.width_px, us);
    const int nv = grid_axis(cam.height_px, vs);
    double worst = 0.0;
    int inside = 0, beyond = 0;
    for (int j = 0; j < nv; ++j) {
        for (int i = 0; i < nu; ++i) {
            const double uv[2] = {us[i], vs[j]};
            const double theta_d =
                hypot((uv[0] - cam.cx_px) / cam.fx_px, (uv[1] - cam.cy_px) / cam.fy_px);
            double xn[2];
            /* WHEN each sample is undistorted */
            const sfd_status_t st = sfd_camera_undistort(&cam, uv, xn, NULL);
            /* THEN rays within 90 deg of the axis come back within 1e-6 px, and rays beyond
             * 90 deg (no normalized coordinates exist) are refused with SFD_ERR_NUMERIC */
            if (theta_d < theta_d_90 - 1e-3) {
                assert_status(st, SFD_OK);
                const double e = round_trip_error_px(&cam, uv[0], uv[1]);
                if (e > worst) worst = e;
                ++inside;
            } else if (theta_d > theta_d_90 + 1e-3) {
                assert_status(st, SFD_ERR_NUMERIC);
                ++beyond;
            }
        }
    }
    print_message(
        "TUM VI cam0 equidistant: worst round trip %.3g px over %d samples "
        "(%d beyond 90 deg refused)\n",
        worst, inside, beyond);
    assert_true(inside > 10000);
    assert_true(beyond > 100);
    assert_true(worst < 1e-6);
}

static void camera_equidistant_near_90deg_round_trip_below_1e6px(void **state) {
    (void)state;
    SFD_REQ("SFD-CAM-002");
    /* GIVEN TUM VI cam0 and pixels on the image diagonal whose rays approach 90 deg */
    const sfd_camera_t cam = tumvi_cam0();
    const double theta_d_90 = equidistant_theta_d_at_90deg(cam.dist);
    static const double fractions[] = {0.5, 0.9, 0.99, 0.999, 0.9999};
    for (size_t i = 0; i < sizeof fractions / sizeof fractions[0]; ++i) {
        const double rd = fractions[i] * theta_d_90 / sqrt(2.0);
        const double uv[2] = {cam.cx_px + cam.fx_px * rd, cam.cy_px - cam.fy_px * rd};
        /* WHEN the pixel is undistorted and distorted again */
        /* THEN it comes back within 1e-6 px */
        assert_true(round_trip_error_px(&cam, uv[0], uv[1]) < 1e-6);
    }
}

static void camera_pinhole_whole_image_round_trip_exact(void **state) {
    (void)state;
    SFD_REQ("SFD-CAM-002");
    /* GIVEN the EuRoC intrinsics without distortion */
    const sfd_camera_t cam = euroc_pinhole();
    int samples = 0;
    /* WHEN the whole-image grid is undistorted and distorted again */
    const double worst = worst_round_trip_px(&cam, &samples);
    /* THEN it comes back to rounding, and xn = ((u - cx) / fx, (v - cy) / fy) */
    assert_true(worst < 1e-12);
    const double uv[2] = {100.0, 400.0};
    double xn[2], J[4];
    assert_status(sfd_camera_undistort(&cam, uv, xn, J), SFD_OK);
    assert_near(xn[0], (100.0 - 367.215) / 458.654, 1e-15);
    assert_near(xn[1], (400.0 - 248.375) / 457.296, 1e-15);
    assert_near(J[0], 1.0 / 458.654, 1e-18);
    assert_near(J[1], 0.0, 0.0);
    assert_near(J[2], 0.0, 0.0);
    assert_near(J[3], 1.0 / 457.296, 1e-18);
}

static void camera_distort_jacobian_matches_central_differences(void **state) {
    (void)state;
    SFD_REQ("SFD-CAM-003");
    /* GIVEN the three models and random normalized points over their fields of view */
    const sfd_camera_t radtan = euroc_cam0();
    const sfd_camera_t equi = tumvi_cam0();
    const sfd_camera_t pinhole = euroc_pinhole();
    for (int i = 0; i < 200; ++i) {
        /* WHEN d(uv)/d(xn) is evaluated analytically and by central differences */
        /* THEN they agree to 1e-5 px per normalized unit (entries are ~200-460) */
        const double xr[2] = {rand_uniform(-1.4, 1.4), rand_uniform(-0.9, 0.9)};
        check_distort_jacobian(&radtan, xr, 1e-5);
        const double xe[2] = {rand_uniform(-4.0, 4.0), rand_uniform(-4.0, 4.0)};
        check_distort_jacobian(&equi, xe, 1e-5);
        check_distort_jacobian(&pinhole, xr, 1e-5);
    }
}

static void camera_project_jacobian_matches_central_differences(void **state) {
    (void)state;
    SFD_REQ("SFD-CAM-003");
    /* GIVEN the three models and random points 0.5 to 20 m in front of the camera */
    const sfd_camera_t cams[3] = {euroc_cam0(), tumvi_cam0(), euroc_pinhole()};
    for (int i = 0; i < 200; ++i) {
        const double z = rand_uniform(0.5, 20.0);
        const double p[3] = {z * rand_uniform(-1.2, 1.2), z * rand_uniform(-0.8, 0.8), z};
        /* WHEN d(uv)/d(p) is evaluated analytically and by central differences */
        /* THEN they agree to 1e-5 px/m */
        for (int c = 0; c < 3; ++c) check_project_jacobian(&cams[c], p);
    }
}

static void camera_undistort_jacobian_is_inverse_of_distort_jacobian(void **state) {
    (void)state;
    SFD_REQ("SFD-CAM-003");
    /* GIVEN the three models and random pixels inside their images (TUM VI: inside the
     * inscribed circle, i.e. rays within 77 deg) */
    const sfd_camera_t radtan = euroc_cam0();
    const sfd_camera_t equi = tumvi_cam0();
    const sfd_camera_t pinhole = euroc_pinhole();
    for (int i = 0; i < 200; ++i) {
        /* WHEN d(xn)/d(uv) is evaluated analytically and by central differences */
        /* THEN they agree to 1e-9 per px, and J_xn_uv J_uv_xn = I to 1e-12 */
        const double uv_r[2] = {rand_uniform(0.0, 751.0), rand_uniform(0.0, 479.0)};
        check_undistort_jacobian(&radtan, uv_r);
        check_undistort_jacobian(&pinhole, uv_r);
        const double ang = rand_uniform(0.0, 6.283185307179586);
        const double rad = rand_uniform(0.0, 250.0);
        const double uv_e[2] = {equi.cx_px + rad * cos(ang), equi.cy_px + rad * sin(ang)};
        check_undistort_jacobian(&equi, uv_e);
    }
}

static void camera_equidistant_near_axis_continuous_and_exact(void **state) {
    (void)state;
    SFD_REQ("SFD-CAM-007");
    /* GIVEN TUM VI cam0 and points on both sides of the 1e-4 normalized radius where the
     * equidistant model switches from its closed form to its Taylor series */
    const sfd_camera_t cam = tumvi_cam0();
    const double c = 0.6, s = 0.8; /* direction (cos, sin) */
    const double below[2] = {c * 1e-4 * (1.0 - 1e-9), s * 1e-4 * (1.0 - 1e-9)};
    const double above[2] = {c * 1e-4 * (1.0 + 1e-9), s * 1e-4 * (1.0 + 1e-9)};
    double ub[2], ua[2], Jb[4], Ja[4];
    /* WHEN both are distorted */
    assert_status(sfd_camera_distort(&cam, below, ub, Jb), SFD_OK);
    assert_status(sfd_camera_distort(&cam, above, ua, Ja), SFD_OK);
    /* THEN pixels and Jacobians join to rounding: a wrong series term would show as ~6e-11 px
     * in the pixel and ~1e-6 in the Jacobian */
    const double step_px = 190.97847715128717 * 1e-4 * 2e-9;
    assert_near(ua[0] - ub[0], c * step_px, 1e-12);
    assert_near(ua[1] - ub[1], s * step_px, 1e-12);
    for (int k = 0; k < 4; ++k) assert_near(Ja[k], Jb[k], 1e-10);
    /* AND at the principal point itself the pixel is (cx, cy), the Jacobian diag(fx, fy), and
     * undistortion returns exactly 0 */
    const double zero[2] = {0.0, 0.0};
    double uv0[2], J0[4], back[2], Jinv[4];
    assert_status(sfd_camera_distort(&cam, zero, uv0, J0), SFD_OK);
    assert_near(uv0[0], cam.cx_px, 0.0);
    assert_near(uv0[1], cam.cy_px, 0.0);
    assert_near(J0[0], cam.fx_px, 0.0);
    assert_near(J0[1], 0.0, 0.0);
    assert_near(J0[2], 0.0, 0.0);
    assert_near(J0[3], cam.fy_px, 0.0);
    const double pp[2] = {cam.cx_px, cam.cy_px};
    assert_status(sfd_camera_undistort(&cam, pp, back, Jinv), SFD_OK);
    assert_near(back[0], 0.0, 0.0);
    assert_near(back[1], 0.0, 0.0);
    /* AND tiny radii (series branch of undistortion too) round-trip */
    static const double radii[] = {1e-12, 1e-9, 3e-8, 1e-6, 5e-5, 2e-4};
    for (size_t i = 0; i < sizeof radii / sizeof radii[0]; ++i) {
        const double xn[2] = {c * radii[i], -s * radii[i]};
        double uv[2], x2[2];
        assert_status(sfd_camera_distort(&cam, xn, uv, NULL), SFD_OK);
        assert_status(sfd_camera_undistort(&cam, uv, x2, NULL), SFD_OK);
        assert_near(x2[0], xn[0], 1e-15);
        assert_near(x2[1], xn[1], 1e-15);
    }
}

static void camera_unproject_ray_reprojects_to_pixel(void **state) {
    (void)state;
    SFD_REQ("SFD-CAM-002");
    /* GIVEN EuRoC cam0 and TUM VI cam0 and random pixels */
    const sfd_camera_t cams[2] = {euroc_cam0(), tumvi_cam0()};
    for (int i = 0; i < 100; ++i) {
        for (int k = 0; k < 2; ++k) {
            const double uv[2] = {rand_uniform(100.0, 400.0), rand_uniform(100.0, 400.0)};
            double ray[3], xn[2], p[3], uv2[2];
            /* WHEN the pixel is unprojected and the ray scaled to a depth of 7 m */
            assert_status(sfd_camera_unproject(&cams[k], uv, ray), SFD_OK);
            assert_status(sfd_camera_undistort(&cams[k], uv, xn, NULL), SFD_OK);
            /* THEN the ray is (xn, yn, 1) and projects back onto the pixel */
            assert_near(ray[0], xn[0], 0.0);
            assert_near(ray[1], xn[1], 0.0);
            assert_near(ray[2], 1.0, 0.0);
            for (int c = 0; c < 3; ++c) p[c] = 7.0 * ray[c];
            assert_status(sfd_camera_project(&cams[k], p, uv2, NULL), SFD_OK);
            assert_near(uv2[0], uv[0], 1e-9);
            assert_near(uv2[1], uv[1], 1e-9);
        }
    }
}

static void camera_undistort_in_place_same_result(void **state) {
    (void)state;
    SFD_REQ("SFD-CAM-002");
    /* GIVEN EuRoC cam0 and a pixel near the corner */
    const sfd_camera_t cam = euroc_cam0();
    const double uv[2] = {3.0, 5.0};
    double xn[2];
    assert_status(sfd_camera_undistort(&cam, uv, xn, NULL), SFD_OK);
    /* WHEN input and output are the same array */
    double buf[2] = {uv[0], uv[1]};
    assert_status(sfd_camera_undistort(&cam, buf, buf, NULL), SFD_OK);
    /* THEN the result is bit-identical to the out-of-place call */
    assert_memory_equal(buf, xn, sizeof xn);
}

/* ---------------------------------------------------------------------------------------------
 * Off-nominal
 * ------------------------------------------------------------------------------------------- */

static void camera_project_point_not_in_front_returns_domain(void **state) {
    (void)state;
    SFD_REQ("SFD-CAM-004");
    /* GIVEN each model and points with z <= 1e-9 m (on or behind the camera plane) */
    const sfd_camera_t cams[3] = {euroc_cam0(), tumvi_cam0(), euroc_pinhole()};
    static const double zs[] = {1e-9, 5e-10, 0.0, -0.0, -1e-9, -1.0, -1e300};
    for (int c = 0; c < 3; ++c) {
        for (size_t i = 0; i < sizeof zs / sizeof zs[0]; ++i) {
            const double p[3] = {0.1, -0.2, zs[i]};
            double uv[2] = {-7.0, -7.0}, J[6] = {-7.0, -7.0, -7.0, -7.0, -7.0, -7.0};
            /* WHEN it is projected */
            /* THEN SFD_ERR_DOMAIN, and nothing is written */
            assert_status(sfd_camera_project(&cams[c], p, uv, J), SFD_ERR_DOMAIN);
            assert_near(uv[0], -7.0, 0.0);
            assert_near(J[5], -7.0, 0.0);
        }
        /* AND just in front of the plane the point is in the domain */
        const double p_ok[3] = {0.0, 0.0, 2e-9};
        double uv[2];
        assert_status(sfd_camera_project(&cams[c], p_ok, uv, NULL), SFD_OK);
    }
}

static void camera_init_invalid_arguments_return_inval(void **state) {
    (void)state;
    SFD_REQ("SFD-CAM-005");
    /* GIVEN a valid camera, kept as a copy */
    sfd_camera_t cam = euroc_cam0();
    sfd_camera_t copy;
    memcpy(&copy, &cam, sizeof cam);
    const double nan_v = nan("");
    const double inf_v = HUGE_VAL;
    const double bad_dist_nan[4] = {0.1, nan_v, 0.0, 0.0};
    const double bad_dist_inf[4] = {0.1, 0.0, 0.0, -inf_v};
    const double pinhole_nonzero[4] = {0.0, 0.0, 1e-12, 0.0};
    /* WHEN init is called with each invalid argument */
    /* THEN SFD_ERR_INVAL, and the camera is unchanged */
    assert_status(sfd_camera_init(NULL, 1, 752, 480, 458.0, 457.0, 367.0, 248.0, kEurocDist),
                  SFD_ERR_INVAL);
    assert_status(sfd_camera_init(&cam, 1, 752, 480, 458.0, 457.0, 367.0, 248.0, NULL),
                  SFD_ERR_INVAL);
    assert_status(sfd_camera_init(&cam, -1, 752, 480, 458.0, 457.0, 367.0, 248.0, kZeroDist),
                  SFD_ERR_INVAL);
    assert_status(sfd_camera_init(&cam, 3, 752, 480, 458.0, 457.0, 367.0, 248.0, kZeroDist),
                  SFD_ERR_INVAL);
    assert_status(sfd_camera_init(&cam, 1, 0, 480, 458.0, 457.0, 367.0, 248.0, kEurocDist),
                  SFD_ERR_INVAL);
    assert_status(sfd_camera_init(&cam, 1, 752, -480, 458.0, 457.0, 367.0, 248.0, kEurocDist),
                  SFD_ERR_INVAL);
    assert_status(sfd_camera_init(&cam, 1, 752, 480, 0.0, 457.0, 367.0, 248.0, kEurocDist),
                  SFD_ERR_INVAL);
    assert_status(sfd_camera_init(&cam, 1, 752, 480, 458.0, -457.0, 367.0, 248.0, kEurocDist),
                  SFD_ERR_INVAL);
    assert_status(sfd_camera_init(&cam, 1, 752, 480, nan_v, 457.0, 367.0, 248.0, kEurocDist),
                  SFD_ERR_INVAL);
    assert_status(sfd_camera_init(&cam, 1, 752, 480, inf_v, 457.0, 367.0, 248.0, kEurocDist),
                  SFD_ERR_INVAL);
    assert_status(sfd_camera_init(&cam, 1, 752, 480, 458.0, 457.0, nan_v, 248.0, kEurocDist),
                  SFD_ERR_INVAL);
    assert_status(sfd_camera_init(&cam, 1, 752, 480, 458.0, 457.0, 367.0, -inf_v, kEurocDist),
                  SFD_ERR_INVAL);
    assert_status(sfd_camera_init(&cam, 1, 752, 480, 458.0, 457.0, 367.0, 248.0, bad_dist_nan),
                  SFD_ERR_INVAL);
    assert_status(sfd_camera_init(&cam, 2, 752, 480, 458.0, 457.0, 367.0, 248.0, bad_dist_inf),
                  SFD_ERR_INVAL);
    assert_status(sfd_camera_init(&cam, SFD_DISTORTION_PINHOLE, 752, 480, 458.0, 457.0, 367.0,
                                  248.0, pinhole_nonzero),
                  SFD_ERR_INVAL);
    assert_status(sfd_camera_init(&cam, SFD_DISTORTION_PINHOLE, 752, 480, 458.0, 457.0, 367.0,
                                  248.0, kEurocDist),
                  SFD_ERR_INVAL);
    assert_memory_equal(&cam, &copy, sizeof cam);
    /* AND -0.0 counts as a zero pinhole coefficient */
    const double neg_zero[4] = {-0.0, 0.0, -0.0, 0.0};
    assert_status(sfd_camera_init(&cam, SFD_DISTORTION_PINHOLE, 752, 480, 458.0, 457.0, 367.0,
                                  248.0, neg_zero),
                  SFD_OK);
}

static void camera_calls_invalid_arguments_return_inval(void **state) {
    (void)state;
    SFD_REQ("SFD-CAM-005");
    /* GIVEN a valid camera, cameras corrupted after init, and valid/invalid inputs */
    const sfd_camera_t cam = euroc_cam0();
    sfd_camera_t bad_model = cam, bad_fx = cam, bad_w = cam, bad_k = cam, bad_pin = cam;
    bad_model.model = 7;
    bad_fx.fx_px = -1.0;
    bad_w.width_px = 0;
    bad_k.dist[3] = nan("");
    bad_pin.model = SFD_DISTORTION_PINHOLE; /* radtan coefficients left in */
    const sfd_camera_t *bad_cams[6] = {NULL, &bad_model, &bad_fx, &bad_w, &bad_k, &bad_pin};
    const double xn[2] = {0.1, 0.2}, uv_in[2] = {100.0, 200.0}, p[3] = {0.1, 0.2, 3.0};
    const double xn_nan[2] = {nan(""), 0.2}, uv_inf[2] = {100.0, HUGE_VAL};
    const double p_nan[3] = {0.1, 0.2, nan("")};
    double out[6] = {-7.0, -7.0, -7.0, -7.0, -7.0, -7.0},
           J[6] = {-7.0, -7.0, -7.0, -7.0, -7.0, -7.0};
    /* WHEN any function gets a null/invalid camera, a null pointer or a non-finite input */
    /* THEN SFD_ERR_INVAL, and nothing is written */
    for (int i = 0; i < 6; ++i) {
        assert_status(sfd_camera_distort(bad_cams[i], xn, out, J), SFD_ERR_INVAL);
        assert_status(sfd_camera_undistort(bad_cams[i], uv_in, out, J), SFD_ERR_INVAL);
        assert_status(sfd_camera_project(bad_cams[i], p, out, J), SFD_ERR_INVAL);
        assert_status(sfd_camera_unproject(bad_cams[i], uv_in, out), SFD_ERR_INVAL);
    }
    assert_status(sfd_camera_distort(&cam, NULL, out, J), SFD_ERR_INVAL);
    assert_status(sfd_camera_distort(&cam, xn, NULL, J), SFD_ERR_INVAL);
    assert_status(sfd_camera_distort(&cam, xn_nan, out, J), SFD_ERR_INVAL);
    assert_status(sfd_camera_undistort(&cam, NULL, out, J), SFD_ERR_INVAL);
    assert_status(sfd_camera_undistort(&cam, uv_in, NULL, J), SFD_ERR_INVAL);
    assert_status(sfd_camera_undistort(&cam, uv_inf, out, J), SFD_ERR_INVAL);
    assert_status(sfd_camera_project(&cam, NULL, out, J), SFD_ERR_INVAL);
    assert_status(sfd_camera_project(&cam, p, NULL, J), SFD_ERR_INVAL);
    assert_status(sfd_camera_project(&cam, p_nan, out, J), SFD_ERR_INVAL);
    assert_status(sfd_camera_unproject(&cam, NULL, out), SFD_ERR_INVAL);
    assert_status(sfd_camera_unproject(&cam, uv_in, NULL), SFD_ERR_INVAL);
    assert_status(sfd_camera_unproject(&cam, uv_inf, out), SFD_ERR_INVAL);
    for (int k = 0; k < 6; ++k) {
        assert_near(out[k], -7.0, 0.0);
        assert_near(J[k], -7.0, 0.0);
    }
}

static void camera_undistort_beyond_fold_returns_numeric(void **state) {
    (void)state;
    SFD_REQ("SFD-CAM-006");
    /* GIVEN a barrel radtan model d = x (1 - 0.3 r^2): its distorted radius peaks at 0.7027
     * (r = 1.054) and then folds back, so larger distorted radii have no physical preimage.
     * Newton can still converge onto a non-physical root there: at 1.1 onto the mirrored point
     * xn = -2.23 (reached only through iterates with det(dd/dxn) < 0), at 8.6 onto xn = -3.42
     * (radial scale 1 - 0.3 r^2 < 0, det > 0) */
    const double k[4] = {-0.3, 0.0, 0.0, 0.0};
    sfd_camera_t cam;
    assert_status(
        sfd_camera_init(&cam, SFD_DISTORTION_RADTAN, 640, 480, 400.0, 400.0, 320.0, 240.0, k),
        SFD_OK);
    static const double beyond[] = {0.7028, 0.8, 1.1, 2.0, 8.6, 50.0};
    static const double angles[] = {0.0, 0.3, 2.0, 4.0};
    for (size_t i = 0; i < sizeof beyond / sizeof beyond[0]; ++i) {
        for (size_t a = 0; a < sizeof angles / sizeof angles[0]; ++a) {
            const double uv[2] = {320.0 + 400.0 * beyond[i] * cos(angles[a]),
                                  240.0 + 400.0 * beyond[i] * sin(angles[a])};
            double xn[2] = {-7.0, -7.0}, J[4] = {-7.0, -7.0, -7.0, -7.0};
            double ray[3] = {-7.0, -7.0, -7.0};
            /* WHEN a pixel beyond the fold is undistorted or unprojected */
            /* THEN SFD_ERR_NUMERIC, and nothing is written */
            assert_status(sfd_camera_undistort(&cam, uv, xn, J), SFD_ERR_NUMERIC);
            assert_status(sfd_camera_unproject(&cam, uv, ray), SFD_ERR_NUMERIC);
            assert_near(xn[0], -7.0, 0.0);
            assert_near(J[0], -7.0, 0.0);
            assert_near(ray[2], -7.0, 0.0);
        }
    }
    /* AND pixels up to the fold are inverted */
    static const double before[] = {0.3, 0.6, 0.7, 0.7027};
    for (size_t i = 0; i < sizeof before / sizeof before[0]; ++i) {
        assert_true(round_trip_error_px(&cam, 320.0 + 400.0 * before[i], 240.0) < 1e-9);
    }
}

static void camera_undistort_folded_root_returns_numeric(void **state) {
    (void)state;
    SFD_REQ("SFD-CAM-006");
    /* GIVEN a pincushion-then-fold radtan model d = x (1 + r^2 - r^4), folding at r = 0.9157
     * (distorted radius 1.0397), and the pixel at distorted radius 1.0: xn = (1, 0) maps exactly
     * onto it but lies beyond the fold (dd/dx = -1); the physical preimage is xn = (0.82, 0).
     * Newton starts at the distorted point, i.e. on the folded root itself */
    const double k[4] = {1.0, -1.0, 0.0, 0.0};
    sfd_camera_t cam;
    assert_status(
        sfd_camera_init(&cam, SFD_DISTORTION_RADTAN, 640, 480, 400.0, 400.0, 320.0, 240.0, k),
        SFD_OK);
    const double uv[2] = {720.0, 240.0};
    double xn[2] = {-7.0, -7.0};
    /* WHEN it is undistorted */
    /* THEN the folded root is not returned: SFD_ERR_NUMERIC (a safe refusal; see the design note
     * on starting points), and nothing is written */
    assert_status(sfd_camera_undistort(&cam, uv, xn, NULL), SFD_ERR_NUMERIC);
    assert_near(xn[0], -7.0, 0.0);
    /* AND a pixel whose start lies inside the monotone region is inverted */
    assert_true(round_trip_error_px(&cam, 320.0 + 400.0 * 0.9, 240.0) < 1e-9);
}

static void camera_equidistant_beyond_fold_returns_numeric(void **state) {
    (void)state;
    SFD_REQ("SFD-CAM-006");
    /* GIVEN an equidistant model theta_d = theta (1 - 0.2 theta^2): theta_d peaks at 0.8607 rad
     * (theta = 1.291 rad) and folds back; between theta_d(pi/2) = 0.796 and the peak a second,
     * folded root exists below pi/2 */
    const double k[4] = {-0.2, 0.0, 0.0, 0.0};
    sfd_camera_t cam;
    assert_status(
        sfd_camera_init(&cam, SFD_DISTORTION_EQUIDISTANT, 640, 480, 400.0, 400.0, 320.0, 240.0, k),
        SFD_OK);
    static const double beyond[] = {0.8607, 0.9, 1.5, 3.0, 20.0};
    for (size_t i = 0; i < sizeof beyond / sizeof beyond[0]; ++i) {
        const double uv[2] = {320.0 + 400.0 * beyond[i] * 0.6, 240.0 - 400.0 * beyond[i] * 0.8};
        double xn[2];
        /* WHEN a pixel beyond the peak is undistorted */
        /* THEN SFD_ERR_NUMERIC */
        assert_status(sfd_camera_undistort(&cam, uv, xn, NULL), SFD_ERR_NUMERIC);
    }
    /* AND pixels before the peak are inverted, including those with a folded second root */
    static const double before[] = {0.5, 0.79, 0.80, 0.85, 0.86};
    for (size_t i = 0; i < sizeof before / sizeof before[0]; ++i) {
        const double u = 320.0 + 400.0 * before[i] * 0.6, v = 240.0 - 400.0 * before[i] * 0.8;
        assert_true(round_trip_error_px(&cam, u, v) < 1e-9);
    }
}

static void camera_undistort_far_outside_image_returns_numeric(void **state) {
    (void)state;
    SFD_REQ("SFD-CAM-006");
    /* GIVEN EuRoC cam0 and TUM VI cam0, and a pixel a million pixels away from the image
     * (equidistant: its ray would be far beyond 90 deg) */
    const sfd_camera_t cams[2] = {euroc_cam0(), tumvi_cam0()};
    const double uv[2] = {1e6, -1e6};
    for (int c = 0; c < 2; ++c) {
        double xn[2];
        /* WHEN undistorted */
        /* THEN SFD_ERR_NUMERIC */
        assert_status(sfd_camera_undistort(&cams[c], uv, xn, NULL), SFD_ERR_NUMERIC);
    }
#if SFD_UNDISTORT_ITERATIONS <= 12
    /* AND EuRoC pixels 18 and 30 times as far from the principal point as the image corner,
     * where the model is still invertible but 12 Newton steps leave residuals of ~2e-8 px and
     * ~13 px, are refused by the 1e-9 px residual check (fewer steps leave more) */
    static const double scales[] = {18.0, 30.0};
    for (size_t i = 0; i < 2; ++i) {
        const double far_uv[2] = {367.215 + scales[i] * (-0.5 - 367.215),
                                  248.375 + scales[i] * (-0.5 - 248.375)};
        double xn[2];
        assert_status(sfd_camera_undistort(&cams[0], far_uv, xn, NULL), SFD_ERR_NUMERIC);
    }
#endif
}

static void camera_distort_overflow_returns_numeric(void **state) {
    (void)state;
    SFD_REQ("SFD-CAM-006");
    /* GIVEN EuRoC cam0 and an absurd normalized point whose r^4 overflows */
    const sfd_camera_t cam = euroc_cam0();
    const double xn[2] = {1e100, 1e100};
    double uv[2] = {-7.0, -7.0};
    /* WHEN distorted */
    /* THEN SFD_ERR_NUMERIC, nothing written */
    assert_status(sfd_camera_distort(&cam, xn, uv, NULL), SFD_ERR_NUMERIC);
    assert_near(uv[0], -7.0, 0.0);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        /* Nominal */
        cmocka_unit_test(camera_opencv_reference_radtan_matches_below_1e9px),
        cmocka_unit_test(camera_opencv_reference_equidistant_matches_below_1e9px),
        cmocka_unit_test(camera_radtan_euroc_whole_image_round_trip_below_1e6px),
        cmocka_unit_test(camera_radtan_euroc_undistort_of_distort_returns_point),
        cmocka_unit_test(camera_equidistant_tumvi_whole_image_round_trip_below_1e6px),
        cmocka_unit_test(camera_equidistant_near_90deg_round_trip_below_1e6px),
        cmocka_unit_test(camera_pinhole_whole_image_round_trip_exact),
        cmocka_unit_test(camera_distort_jacobian_matches_central_differences),
        cmocka_unit_test(camera_project_jacobian_matches_central_differences),
        cmocka_unit_test(camera_undistort_jacobian_is_inverse_of_distort_jacobian),
        cmocka_unit_test(camera_equidistant_near_axis_continuous_and_exact),
        cmocka_unit_test(camera_unproject_ray_reprojects_to_pixel),
        cmocka_unit_test(camera_undistort_in_place_same_result),
        /* Off-nominal */
        cmocka_unit_test(camera_project_point_not_in_front_returns_domain),
        cmocka_unit_test(camera_init_invalid_arguments_return_inval),
        cmocka_unit_test(camera_calls_invalid_arguments_return_inval),
        cmocka_unit_test(camera_undistort_beyond_fold_returns_numeric),
        cmocka_unit_test(camera_undistort_folded_root_returns_numeric),
        cmocka_unit_test(camera_equidistant_beyond_fold_returns_numeric),
        cmocka_unit_test(camera_undistort_far_outside_image_returns_numeric),
        cmocka_unit_test(camera_distort_overflow_returns_numeric),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
