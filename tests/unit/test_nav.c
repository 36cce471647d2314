/* SPDX-License-Identifier: MIT */
/* unit.nav: the pipeline's navigation side (core/include/sfd/sfd_nav.h), its start from TRUTH. */
#include "sfd_test.h"

#include <string.h>

#include <sfd/sfd_nav.h>

static sfd_nav_t g_nav;

/* GIVEN init_from_truth, a configured gyro bias and init_accel_bias_m_s2
 * WHEN two TRUTH poses arrive 50 ms apart
 * THEN the filter starts at the second pose, with the velocity of the difference and exactly the
 *      configured gyro and accelerometer biases. */
static void nav_truth_start_takes_configured_biases(void **state) {
    (void)state;
    sfd_nav_config_t cfg;
    sfd_nav_config_default(&cfg);
    cfg.init_from_truth = 1;
    cfg.init_accel_bias_m_s2[0] = -0.013337;
    cfg.init_accel_bias_m_s2[1] = 0.103464;
    cfg.init_accel_bias_m_s2[2] = 0.093086;
    sfd_params_t params;
    sfd_params_default(&params);
    params.gyro_bias_rad_s[0] = -0.002153;
    params.gyro_bias_rad_s[1] = 0.020744;
    params.gyro_bias_rad_s[2] = 0.075806;
    assert_status(sfd_nav_init(&g_nav, &cfg, &params), SFD_OK);
    const double q[4] = {1, 0, 0, 0}, p0[3] = {1, 2, 3}, p1[3] = {1.05, 2, 3};
    sfd_nav_truth(&g_nav, 1000000, p0, q);
    assert_int_equal(g_nav.ready, 0);
    sfd_nav_truth(&g_nav, 1050000, p1, q);
    assert_int_equal(g_nav.ready, 1);
    assert_near(g_nav.ekf.p_IinW_m[0], 1.05, 1e-15);
    assert_near(g_nav.ekf.v_IinW_m_s[0], 1.0, 1e-12);
    for (int k = 0; k < 3; ++k) {
        assert_near(g_nav.ekf.ba_m_s2[k], cfg.init_accel_bias_m_s2[k], 0.0);
        assert_near(g_nav.ekf.bg_rad_s[k], params.gyro_bias_rad_s[k], 0.0);
    }
}

/* GIVEN a non-finite init_accel_bias_m_s2 WHEN the navigation side is initialized THEN INVAL. */
static void nav_init_nonfinite_accel_bias_refused(void **state) {
    (void)state;
    sfd_nav_config_t cfg;
    sfd_nav_config_default(&cfg);
    for (int k = 0; k < 3; ++k) assert_near(cfg.init_accel_bias_m_s2[k], 0.0, 0.0);
    cfg.init_accel_bias_m_s2[1] = NAN;
    sfd_params_t params;
    sfd_params_default(&params);
    assert_status(sfd_nav_init(&g_nav, &cfg, &params), SFD_ERR_INVAL);
}

/* Starts g_nav from two TRUTH poses 50 ms apart (the origin, then p1_m), with a 640 x 480
 * pinhole camera at the IMU (identity extrinsics) returned in cam. */
static void start_from_truth(const sfd_nav_config_t *cfg, const double p1_m[3], sfd_camera_t *cam) {
    sfd_params_t params;
    sfd_params_default(&params);
    assert_status(sfd_nav_init(&g_nav, cfg, &params), SFD_OK);
    const double dist[5] = {0, 0, 0, 0, 0};
    assert_status(sfd_camera_init(cam, SFD_DISTORTION_PINHOLE, 640, 480, 400, 400, 320, 240, dist),
                  SFD_OK);
    sfd_extrinsics_t ext;
    memset(&ext, 0, sizeof ext);
    ext.R_CtoI[0] = ext.R_CtoI[4] = ext.R_CtoI[8] = 1.0;
    sfd_nav_set_camera(&g_nav, cam, &ext);
    const double q[4] = {1, 0, 0, 0}, p0[3] = {0, 0, 0};
    sfd_nav_truth(&g_nav, 1000000, p0, q);
    sfd_nav_truth(&g_nav, 1050000, p1_m, q);
    assert_int_equal(g_nav.ready, 1);
}

/* GIVEN a started filter and a frame whose track 5 appears twice (a tracker fault) WHEN the
 *      next frame is matched against it
 * THEN each track finds its first occurrence in the previous frame (as a front-to-back search
 *      would), tracks absent from the previous frame get no match, and a previous track lost
 *      among many others is still found (the track index of the previous frame). */
static void nav_build_matches_first_occurrence_of_previous_tracks(void **state) {
    (void)state;
    sfd_nav_config_t cfg;
    sfd_nav_config_default(&cfg);
    cfg.init_from_truth = 1;
    sfd_camera_t cam;
    const double p1[3] = {0.01, 0, 0};
    start_from_truth(&cfg, p1, &cam);

    static sfd_frame_t a, b;
    memset(&a, 0, sizeof a);
    a.utime = 1050000;
    a.num_features = 200;
    for (int i = 0; i < a.num_features; ++i) {
        const int col = i % 20;
        const int row = i / 20;
        a.features[i].track_id = 1000 + i;
        a.features[i].u_px = 20.0 + 30.0 * col;
        a.features[i].v_px = 20.0 + 40.0 * row;
    }
    a.features[3].track_id = 5;
    a.features[150].track_id = 5; /* repeated: the first (index 3) must be the one matched */
    a.features[199].track_id = 9;
    int8_t status[SFD_MAX_FEATURES];
    for (int i = 0; i < a.num_features; ++i) status[i] = SFD_VERDICT_CONSISTENT;
    assert_int_equal(sfd_nav_build(&g_nav, &cam, &a, NULL, NULL), 0); /* no previous frame */
    sfd_nav_finish(&g_nav, &cam, &a, status, NULL);
    assert_int_equal(g_nav.prev_n, 200);

    memset(&b, 0, sizeof b);
    b.utime = 1100000;
    b.num_features = 3;
    b.features[0].track_id = 9;
    b.features[1].track_id = 77; /* new track */
    b.features[2].track_id = 5;
    for (int i = 0; i < b.num_features; ++i) {
        b.features[i].u_px = 300.0 + i;
        b.features[i].v_px = 200.0;
    }
    const int32_t nm = sfd_nav_build(&g_nav, &cam, &b, NULL, NULL);
    assert_int_equal(nm, 2);
    assert_int_equal(g_nav.feature_match[1], -1);
    const sfd_match_t *m9 = &g_nav.work.assoc.matches[g_nav.feature_match[0]];
    const sfd_match_t *m5 = &g_nav.work.assoc.matches[g_nav.feature_match[2]];
    /* xn is kept as float: the undistorted pixel comes back within fx * 6e-8 * |xn| */
    assert_near(m9->prev_uv_px[0], a.features[199].u_px, 1e-4);
    assert_near(m9->prev_uv_px[1], a.features[199].v_px, 1e-4);
    assert_near(m5->prev_uv_px[0], a.features[3].u_px, 1e-4);
    assert_near(m5->prev_uv_px[1], a.features[3].v_px, 1e-4);
}

/* GIVEN the window filter started from TRUTH and 20 static features seen with depth priors from
 *      a hovering camera for three frames
 * WHEN the fourth frame judges tracks 0-5 SPURIOUS and tracks 6-9 SPURIOUS with whole_track set
 * THEN the first six end before the flagged observation (their three earlier observations are
 *      due in that frame: candidates) and the four whole-track flags delete theirs unused; with
 *      whole_track NULL all ten end; with window_flagged_earlier 0 none does. Every flagged
 *      track is gone from the window afterwards (core/docs/window_filter.md "Flagged tracks"). */
static int flagged_run(int flagged_earlier, int pass_whole, sfd_window_result_t *res) {
    sfd_nav_config_t cfg;
    sfd_nav_config_default(&cfg);
    assert_int_equal(cfg.window_filter, 1);
    assert_int_equal(cfg.window_flagged_earlier, 1);
    cfg.init_from_truth = 1;
    cfg.window_flagged_earlier = flagged_earlier;
    sfd_camera_t cam;
    const double hover[3] = {0, 0, 0};
    start_from_truth(&cfg, hover, &cam);
    static sfd_frame_t fr;
    int8_t status[SFD_MAX_FEATURES];
    uint8_t whole[SFD_MAX_FEATURES];
    for (int f = 1; f <= 4; ++f) {
        memset(&fr, 0, sizeof fr);
        fr.utime = 1050000 + 50000 * (int64_t)f;
        fr.num_features = 20;
        for (int i = 0; i < fr.num_features; ++i) {
            fr.features[i].track_id = 500 + i;
            fr.features[i].u_px = 100.0 + 20.0 * i;
            fr.features[i].v_px = 150.0 + 9.0 * i;
            fr.features[i].depth_m = 4.0;
            fr.features[i].depth_var_m2 = 0.01;
            status[i] = (f == 4 && i < 10) ? SFD_VERDICT_SPURIOUS : SFD_VERDICT_CONSISTENT;
            whole[i] = (uint8_t)(f == 4 && i >= 6 && i < 10);
        }
        (void)sfd_nav_build(&g_nav, &cam, &fr, NULL, NULL);
        sfd_nav_finish(&g_nav, &cam, &fr, status, pass_whole ? whole : NULL);
        assert_int_equal(g_nav.ready, 1);
    }
    *res = g_nav.win_result;
    int flagged_left = 0;
    for (int k = 0; k < g_nav.win.num_tracks; ++k) flagged_left += g_nav.win.tracks[k].id < 510;
    return flagged_left;
}

static void a_spurious_verdict_ends_its_track_unless_it_condemns_the_whole(void **state) {
    (void)state;
    sfd_window_result_t r;
    assert_int_equal(flagged_run(1, 1, &r), 0);
    assert_int_equal(r.dropped, 10);
    assert_int_equal(r.candidates, 6);
    assert_int_equal(r.used + r.gated + r.no_geometry, 6);
    assert_int_equal(flagged_run(1, 0, &r), 0);
    assert_int_equal(r.candidates, 10);
    assert_int_equal(flagged_run(0, 1, &r), 0);
    assert_int_equal(r.dropped, 10);
    assert_int_equal(r.candidates, 0);
}

/* Fills the ring with n samples at 200 Hz from t0: at rest (gravity's reaction, a little noise)
 * or, with accel_step != 0, an accelerometer swinging by accel_step sin(2 pi i / 33) (a vehicle
 * pushed back and forth, 6 Hz, not in step with any block). */
static sfd_imu_ring_t g_ring;
static void fill_ring(int n, int64_t t0_us, double accel_step) {
    sfd_imu_ring_init(&g_ring);
    for (int i = 0; i < n; ++i) {
        sfd_imu_sample_t s;
        s.t_us = t0_us + 5000 * (int64_t)i;
        const double wiggle = 1e-4 * ((i * 7919) % 13 - 6); /* deterministic, zero mean */
        s.gyro_rad_s[0] = 0.002 + wiggle;
        s.gyro_rad_s[1] = -0.001 - wiggle;
        s.gyro_rad_s[2] = 0.0005 + wiggle;
        s.accel_m_s2[0] = 0.1 * wiggle + accel_step * sin(2.0 * M_PI * i / 33.0);
        s.accel_m_s2[1] = -0.1 * wiggle;
        s.accel_m_s2[2] = 9.81 + 0.1 * wiggle;
        assert_int_equal(sfd_imu_ring_push(&g_ring, &s), SFD_REJECT_NONE);
    }
}

/* GIVEN an IMU at rest from t0 WHEN asking sfd_nav_imu_at_rest at the frames 50 ms apart THEN the
 * second frame (11 samples: two blocks of 5) is already judged at rest, and every later one;
 * GIVEN the accelerometer swinging by 1 m/s^2 THEN no frame is at rest;
 * a previous frame before the oldest sample held, a time after t, a disabled filter or a null
 * argument give 0. */
static void imu_at_rest_from_the_second_frame_and_not_when_moving(void **state) {
    (void)state;
    sfd_nav_config_t cfg;
    sfd_nav_config_default(&cfg);
    sfd_params_t params;
    sfd_params_default(&params);
    assert_status(sfd_nav_init(&g_nav, &cfg, &params), SFD_OK);
    const int64_t t0 = 1000000;
    fill_ring(400, t0, 0.0);
    for (int f = 1; f < 40; ++f) {
        const int64_t t = t0 + 50000 * (int64_t)f;
        assert_int_equal(sfd_nav_imu_at_rest(&g_nav, &g_ring, t - 50000, t), 1);
    }
    assert_int_equal(sfd_nav_imu_at_rest(&g_nav, &g_ring, t0 - 1, t0 + 50000), 0);
    assert_int_equal(sfd_nav_imu_at_rest(&g_nav, &g_ring, t0 + 60000, t0 + 50000), 0);
    assert_int_equal(sfd_nav_imu_at_rest(NULL, &g_ring, t0, t0 + 50000), 0);
    assert_int_equal(sfd_nav_imu_at_rest(&g_nav, NULL, t0, t0 + 50000), 0);
    fill_ring(400, t0, 1.0);
    for (int f = 1; f < 40; ++f) {
        const int64_t t = t0 + 50000 * (int64_t)f;
        assert_int_equal(sfd_nav_imu_at_rest(&g_nav, &g_ring, t - 50000, t), 0);
    }
    cfg.enabled = 0;
    assert_status(sfd_nav_init(&g_nav, &cfg, &params), SFD_OK);
    fill_ring(400, t0, 0.0);
    assert_int_equal(sfd_nav_imu_at_rest(&g_nav, &g_ring, t0 + 50000, t0 + 100000), 0);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(nav_truth_start_takes_configured_biases),
        cmocka_unit_test(nav_init_nonfinite_accel_bias_refused),
        cmocka_unit_test(nav_build_matches_first_occurrence_of_previous_tracks),
        cmocka_unit_test(a_spurious_verdict_ends_its_track_unless_it_condemns_the_whole),
        cmocka_unit_test(imu_at_rest_from_the_second_frame_and_not_when_moving),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
