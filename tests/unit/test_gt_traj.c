/* SPDX-License-Identifier: MIT */
/* unit.gt_traj: the semi-real feed's ground-truth helpers (drivers/sim/sfd_gt_traj.h): pose
 * interpolation, camera pose from the IMU pose and T_BS, projection with distortion, room hits.
 * Expected values are computed here by hand (closed forms, an own quaternion-to-matrix and an own
 * radial-tangential formula), not with the functions under test. */
#include "sfd_test.h"

#include "euroc_calib.h"
#include "sfd_gt_traj.h"

/* Hamilton quaternion (w, x, y, z) to rotation matrix, written out (not sfd_quat_to_rotmat). */
static void q_to_R(const double q[4], double R[9]) {
    const double w = q[0], x = q[1], y = q[2], z = q[3];
    const double M[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
                         2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                         2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
    for (int i = 0; i < 9; ++i) R[i] = M[i];
}

/* OpenCV / Kalibr radial-tangential model: pixel of normalized (x, y). */
static void radtan_px(const double k[4], double fx, double fy, double cx, double cy, double x,
                      double y, double uv[2]) {
    const double r2 = x * x + y * y;
    const double radial = 1.0 + k[0] * r2 + k[1] * r2 * r2;
    const double xd = x * radial + 2.0 * k[2] * x * y + k[3] * (r2 + 2.0 * x * x);
    const double yd = y * radial + k[2] * (r2 + 2.0 * y * y) + 2.0 * k[3] * x * y;
    uv[0] = fx * xd + cx;
    uv[1] = fy * yd + cy;
}

static sfd_camera_t euroc_cam(void) {
    sfd_camera_t cam;
    assert_status(sfd_camera_init(&cam, SFD_DISTORTION_RADTAN, 752, 480, kEurocFx, kEurocFy,
                                  kEurocCx, kEurocCy, kEurocRadtan),
                  SFD_OK);
    return cam;
}

/* GIVEN two poses 50 ms apart, the second turned 0.4 rad about z and moved by (1, -2, 0.5) m
 * WHEN interpolated at a quarter of the interval
 * THEN the rotation is 0.1 rad about z (slerp) and the position a quarter of the way (linear). */
static void gt_interpolate_quarter_slerp_and_linear(void **state) {
    (void)state;
    const sfd_gt_pose_t a = {1000000000, {0.0, 0.0, 0.0}, {1.0, 0.0, 0.0, 0.0}};
    const sfd_gt_pose_t b = {1050000000, {1.0, -2.0, 0.5}, {cos(0.2), 0.0, 0.0, sin(0.2)}};
    sfd_gt_pose_t out = {0, {0, 0, 0}, {0, 0, 0, 0}};
    assert_int_equal(sfd_gt_interpolate(&a, &b, 1012500000, &out), 0);
    assert_true(out.t_ns == 1012500000);
    assert_near(out.q_ItoW[0], cos(0.05), 1e-12);
    assert_near(out.q_ItoW[1], 0.0, 1e-12);
    assert_near(out.q_ItoW[2], 0.0, 1e-12);
    assert_near(out.q_ItoW[3], sin(0.05), 1e-12);
    assert_near(out.p_IinW_m[0], 0.25, 1e-12);
    assert_near(out.p_IinW_m[1], -0.5, 1e-12);
    assert_near(out.p_IinW_m[2], 0.125, 1e-12);
}

/* GIVEN the end quaternion given with the opposite sign (the same rotation)
 * WHEN interpolated at the midpoint and at both ends
 * THEN the shortest arc is taken (0.2 rad at the midpoint of a 0.4 rad turn about an oblique
 *      axis; 180 deg halfway from 170 deg to 190 deg), and the ends are reproduced. */
static void gt_interpolate_negated_end_takes_shortest_arc(void **state) {
    (void)state;
    const double n = sqrt(3.0), h = 0.2; /* half angle of the 0.4 rad turn */
    const sfd_gt_pose_t a = {0, {1.0, 2.0, 3.0}, {1.0, 0.0, 0.0, 0.0}};
    const sfd_gt_pose_t b = {
        100, {1.0, 2.0, 3.0}, {-cos(h), -sin(h) / n, -sin(h) / n, -sin(h) / n}};
    sfd_gt_pose_t out = {0, {0, 0, 0}, {0, 0, 0, 0}};
    assert_int_equal(sfd_gt_interpolate(&a, &b, 50, &out), 0);
    assert_near(out.q_ItoW[0], cos(0.1), 1e-12);
    for (int k = 1; k < 4; ++k) assert_near(out.q_ItoW[k], sin(0.1) / n, 1e-12);
    assert_int_equal(sfd_gt_interpolate(&a, &b, 0, &out), 0);
    assert_near(out.q_ItoW[0], 1.0, 1e-12);
    assert_int_equal(sfd_gt_interpolate(&a, &b, 100, &out), 0);
    assert_near(out.q_ItoW[0], cos(h), 1e-12); /* sign fixed to w >= 0 */
    for (int k = 1; k < 4; ++k) assert_near(out.q_ItoW[k], sin(h) / n, 1e-12);
    /* 170 deg to 190 deg (= -170 deg) about z: the short way is through 180 deg, not back
     * through 0 deg */
    const double d85 = 85.0 * M_PI / 180.0, d95 = 95.0 * M_PI / 180.0;
    const sfd_gt_pose_t c = {0, {0, 0, 0}, {cos(d85), 0.0, 0.0, sin(d85)}};
    const sfd_gt_pose_t d = {100, {0, 0, 0}, {cos(d95), 0.0, 0.0, sin(d95)}};
    assert_int_equal(sfd_gt_interpolate(&c, &d, 50, &out), 0);
    assert_near(out.q_ItoW[0], 0.0, 1e-12);
    assert_near(fabs(out.q_ItoW[3]), 1.0, 1e-12);
}

/* GIVEN times outside [t_a, t_b] or an empty interval WHEN interpolated THEN -1. */
static void gt_interpolate_outside_interval_refused(void **state) {
    (void)state;
    const sfd_gt_pose_t a = {10, {0, 0, 0}, {1, 0, 0, 0}};
    const sfd_gt_pose_t b = {20, {0, 0, 0}, {1, 0, 0, 0}};
    sfd_gt_pose_t out = {0, {0, 0, 0}, {0, 0, 0, 0}};
    assert_int_equal(sfd_gt_interpolate(&a, &b, 9, &out), -1);
    assert_int_equal(sfd_gt_interpolate(&a, &b, 21, &out), -1);
    assert_int_equal(sfd_gt_interpolate(&a, &a, 10, &out), -1);
    const sfd_gt_pose_t zero = {20, {0, 0, 0}, {0, 0, 0, 0}};
    assert_int_equal(sfd_gt_interpolate(&a, &zero, 15, &out), -1);
}

/* GIVEN an IMU at (1, 2, 3) m yawed 90 deg (IMU x = world y), a camera looking along IMU x with
 *       its x axis along IMU -y, 0.1 m ahead of the IMU, and EuRoC's intrinsics and distortion
 * WHEN the camera pose is composed and world points projected
 * THEN the optical centre is (1, 2.1, 3), a point 5 m ahead lands on the principal point, and a
 *      point 1 m to the camera's right (world +x) lands at the hand-computed distorted pixel of
 *      normalized (0.2, 0). */
static void gt_camera_pose_and_projection_hand_computed(void **state) {
    (void)state;
    const double T[16] = {0, 0, 1, 0.1, -1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 0, 1};
    sfd_extrinsics_t ext;
    assert_status(sfd_extrinsics_from_matrix(&ext, T), SFD_OK);
    const sfd_gt_pose_t I = {0, {1.0, 2.0, 3.0}, {cos(M_PI / 4), 0.0, 0.0, sin(M_PI / 4)}};
    double R_CtoW[9] = {0}, p_C[3] = {0};
    assert_int_equal(sfd_gt_camera_pose(&I, &ext, R_CtoW, p_C), 0);
    assert_near(p_C[0], 1.0, 1e-12);
    assert_near(p_C[1], 2.1, 1e-12);
    assert_near(p_C[2], 3.0, 1e-12);
    /* camera axes in the world: x = +x, y = -z, z = +y */
    const double expect_R[9] = {1, 0, 0, 0, 0, 1, 0, -1, 0};
    for (int i = 0; i < 9; ++i) assert_near(R_CtoW[i], expect_R[i], 1e-12);
    const sfd_camera_t cam = euroc_cam();
    const double ahead[3] = {1.0, 7.1, 3.0}, right[3] = {2.0, 7.1, 3.0}, behind[3] = {1, -3, 3};
    double uv[2], depth = 0, ref[2];
    assert_int_equal(sfd_gt_project(&cam, R_CtoW, p_C, ahead, uv, &depth), 1);
    assert_near(depth, 5.0, 1e-12);
    assert_near(uv[0], kEurocCx, 1e-9);
    assert_near(uv[1], kEurocCy, 1e-9);
    assert_int_equal(sfd_gt_project(&cam, R_CtoW, p_C, right, uv, &depth), 1);
    radtan_px(kEurocRadtan, kEurocFx, kEurocFy, kEurocCx, kEurocCy, 0.2, 0.0, ref);
    assert_near(uv[0], ref[0], 1e-9);
    assert_near(uv[1], ref[1], 1e-9);
    assert_true(fabs(uv[0] - (kEurocFx * 0.2 + kEurocCx)) > 1.0); /* distortion is applied */
    assert_int_equal(sfd_gt_project(&cam, R_CtoW, p_C, behind, uv, &depth), 0);
    assert_near(depth, -5.1, 1e-12);
}

/* GIVEN EuRoC's cam0 T_BS and V1_02's first ground-truth orientation
 * WHEN a landmark is placed at camera coordinates (0.5, -0.25, 4) m using an independently
 *      composed camera pose (own quaternion formula, R_ItoW R_CtoI, p_I + R_ItoW p_CinI)
 * THEN sfd_gt_camera_pose agrees with that composition and the landmark projects to the
 *      hand-computed radtan pixel of (0.125, -0.0625). */
static void gt_euroc_T_BS_landmark_projects_where_expected(void **state) {
    (void)state;
    sfd_gt_pose_t I = {
        0, {0.515292, 1.996597, 0.971028}, {0.161869, 0.790012, -0.205215, 0.554587}};
    const double n = sqrt(I.q_ItoW[0] * I.q_ItoW[0] + I.q_ItoW[1] * I.q_ItoW[1] +
                          I.q_ItoW[2] * I.q_ItoW[2] + I.q_ItoW[3] * I.q_ItoW[3]);
    for (int k = 0; k < 4; ++k) I.q_ItoW[k] /= n;
    double R_ItoW[9], R_ref[9], p_ref[3];
    q_to_R(I.q_ItoW, R_ItoW);
    for (int r = 0; r < 3; ++r) {
        p_ref[r] = I.p_IinW_m[r];
        for (int c = 0; c < 3; ++c) {
            R_ref[3 * r + c] = 0.0;
            for (int k = 0; k < 3; ++k)
                R_ref[3 * r + c] += R_ItoW[3 * r + k] * kEurocTimuCam[4 * k + c];
            p_ref[r] += R_ItoW[3 * r + c] * kEurocTimuCam[4 * c + 3];
        }
    }
    sfd_extrinsics_t ext;
    assert_status(sfd_extrinsics_from_matrix(&ext, kEurocTimuCam), SFD_OK);
    double R_CtoW[9] = {0}, p_C[3] = {0};
    assert_int_equal(sfd_gt_camera_pose(&I, &ext, R_CtoW, p_C), 0);
    for (int i = 0; i < 9; ++i) assert_near(R_CtoW[i], R_ref[i], 1e-12);
    for (int i = 0; i < 3; ++i) assert_near(p_C[i], p_ref[i], 1e-12);
    const double c[3] = {0.5, -0.25, 4.0};
    double L[3];
    for (int r = 0; r < 3; ++r) {
        L[r] = p_ref[r];
        for (int k = 0; k < 3; ++k) L[r] += R_ref[3 * r + k] * c[k];
    }
    const sfd_camera_t cam = euroc_cam();
    double uv[2], depth = 0, ref[2];
    assert_int_equal(sfd_gt_project(&cam, R_CtoW, p_C, L, uv, &depth), 1);
    assert_near(depth, 4.0, 1e-9);
    radtan_px(kEurocRadtan, kEurocFx, kEurocFy, kEurocCx, kEurocCy, 0.125, -0.0625, ref);
    assert_near(uv[0], ref[0], 1e-7);
    assert_near(uv[1], ref[1], 1e-7);
}

/* GIVEN a 2 x 2 x 2 m room and a point inside WHEN rays are cast THEN they hit the wall, the
 *       floor or the corner they head for; an origin outside (or on a wall) is refused. */
static void gt_room_hit_walls_floor_corner(void **state) {
    (void)state;
    const double lo[3] = {-1, -1, 0}, hi[3] = {1, 1, 2};
    const double o[3] = {0, 0, 1};
    double hit[3] = {0, 0, 0};
    const double dx[3] = {2, 0, 0}, dz[3] = {0, 0, -0.5}, dc[3] = {1, 1, 1};
    assert_int_equal(sfd_gt_room_hit(lo, hi, o, dx, hit), 0);
    assert_near(hit[0], 1.0, 1e-15);
    assert_near(hit[1], 0.0, 1e-15);
    assert_near(hit[2], 1.0, 1e-15);
    assert_int_equal(sfd_gt_room_hit(lo, hi, o, dz, hit), 0);
    assert_near(hit[2], 0.0, 1e-15);
    assert_int_equal(sfd_gt_room_hit(lo, hi, o, dc, hit), 0);
    assert_near(hit[0], 1.0, 1e-15);
    assert_near(hit[1], 1.0, 1e-15);
    assert_near(hit[2], 2.0, 1e-15);
    const double out[3] = {0, 0, 3}, zero[3] = {0, 0, 0};
    assert_int_equal(sfd_gt_room_hit(lo, hi, out, dx, hit), -1);
    assert_int_equal(sfd_gt_room_hit(lo, hi, o, zero, hit), -1);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(gt_interpolate_quarter_slerp_and_linear),
        cmocka_unit_test(gt_interpolate_negated_end_takes_shortest_arc),
        cmocka_unit_test(gt_interpolate_outside_interval_refused),
        cmocka_unit_test(gt_camera_pose_and_projection_hand_computed),
        cmocka_unit_test(gt_euroc_T_BS_landmark_projects_where_expected),
        cmocka_unit_test(gt_room_hit_walls_floor_corner),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
