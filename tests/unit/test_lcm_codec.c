/* SPDX-License-Identifier: MIT */
/* unit.lcm_codec: every sfd LCM type round-trips through the generated C code; the driver's
 * decode rejects short, corrupt and out-of-range messages before the core sees them; the node's
 * message handling keeps to the camera it follows. */
#include "sfd_test.h"

#include "euroc_calib.h"

#include <stdlib.h>
#include <string.h>

#include "sfd_camera_info_t.h"
#include "sfd_feature_frame_t.h"
#include "sfd_feature_verdict_t.h"
#include "sfd_imu_t.h"
#include "sfd_lcm_codec.h"
#include "sfd_nav_state_t.h"
#include "sfd_node_core.h"
#include "sfd_timing_t.h"
#include "sfd_truth_t.h"
#include "sfd_truth_v1_t.h"

enum { BUF = 64 * 1024 };
static uint8_t g_buf[BUF];
static sfd_feature_frame_t g_ff, g_ff2;
static sfd_feature_verdict_t g_fv, g_fv2;
static sfd_truth_t g_tr, g_tr2;
static sfd_truth_v1_t g_tr1;
static sfd_frame_t g_frame;

#define ROUND_TRIP(type, a, b)                                           \
    do {                                                                 \
        const int n_ = type##_encoded_size(a);                           \
        assert_true(n_ > 0 && n_ <= BUF);                                \
        assert_int_equal(type##_encode(g_buf, 0, BUF, a), n_);           \
        memset(b, 0x5a, sizeof *(b));                                    \
        assert_int_equal(type##_decode(g_buf, 0, n_, b), n_);            \
        assert_int_equal(type##_encode(g_buf + n_, 0, BUF - n_, b), n_); \
        assert_memory_equal(g_buf, g_buf + n_, (size_t)n_);              \
        for (int cut_ = 0; cut_ < n_; cut_ += (cut_ < 64 ? 1 : 97))      \
            assert_true(type##_decode(g_buf, 0, cut_, b) < 0);           \
        g_buf[0] ^= 0x01; /* fingerprint corrupted */                    \
        assert_true(type##_decode(g_buf, 0, n_, b) < 0);                 \
        g_buf[0] ^= 0x01;                                                \
    } while (0)

/* GIVEN a message of every type filled to capacity WHEN encoded and decoded THEN identical bytes
 * after re-encoding; every truncation and a corrupted fingerprint fail to decode. */
static void lcm_every_type_round_trips_at_max_size(void **state) {
    (void)state;
    SFD_REQ("SFD-LCM-001");
    sfd_imu_t imu = {123, {0.1, -0.2, 0.3}, {0.0, 0.1, 9.81}}, imu2;
    ROUND_TRIP(sfd_imu_t, &imu, &imu2);
    sfd_camera_info_t ci, ci2;
    memset(&ci, 0, sizeof ci);
    ci.utime = 5;
    ci.camera_id = 3;
    ci.width = 752;
    ci.height = 480;
    ci.fx = 458.654;
    ci.distortion_model = SFD_CAMERA_INFO_T_RADTAN;
    ci.T_imu_cam[15] = 1.0;
    ROUND_TRIP(sfd_camera_info_t, &ci, &ci2);
    g_ff.utime = 77;
    g_ff.num_features = SFD_FEATURE_FRAME_T_CAPACITY;
    for (int i = 0; i < 512; ++i) {
        g_ff.track_id[i] = (int64_t)i * 1000003;
        g_ff.u[i] = i * 1.5;
        g_ff.v[i] = -i;
        g_ff.depth[i] = 10 + i;
        g_ff.depth_var[i] = 0.5;
    }
    ROUND_TRIP(sfd_feature_frame_t, &g_ff, &g_ff2);
    assert_int_equal(sfd_feature_frame_t_encoded_size(&g_ff), 8 + 8 + 4 + 4 + 512 * 40);
    g_fv.num_features = 512;
    for (int i = 0; i < 512; ++i) {
        g_fv.track_id[i] = i;
        g_fv.status[i] = (int8_t)(i % 3);
        g_fv.statistic[i] = i * 0.01;
        g_fv.stage[i] = SFD_FEATURE_VERDICT_T_PARITY;
    }
    ROUND_TRIP(sfd_feature_verdict_t, &g_fv, &g_fv2);
    sfd_nav_state_t ns = {9, {1, 2, 3}, {4, 5, 6}, {1, 0, 0, 0}, {0.1, 0.2, 0.3}}, ns2;
    ROUND_TRIP(sfd_nav_state_t, &ns, &ns2);
    sfd_timing_t tm, tm2;
    memset(&tm, 0, sizeof tm);
    tm.utime = 10;
    tm.total_us = 123;
    for (int i = 0; i < SFD_TIMING_T_NUM_REASONS; ++i) tm.rejected[i] = (int64_t)i * 7;
    ROUND_TRIP(sfd_timing_t, &tm, &tm2);
    g_tr.num_features = 512;
    for (int i = 0; i < 512; ++i) {
        g_tr.track_id[i] = i;
        g_tr.spurious[i] = (int8_t)(i % 2);
        g_tr.kind[i] = (int8_t)(i % 2 ? 1 + (i / 2) % 5 : 0);
    }
    ROUND_TRIP(sfd_truth_t, &g_tr, &g_tr2);
    /* the driver's reason numbers are the wire's */
    assert_int_equal(SFD_REJECT_NUM_REASONS, SFD_TIMING_T_NUM_REASONS);
    assert_int_equal(SFD_REJECT_CORE, SFD_TIMING_T_REJECT_CORE);
    assert_int_equal(SFD_REJECT_IMU_GAP, SFD_TIMING_T_REJECT_IMU_GAP);
    assert_string_equal(sfd_reject_reason_str(SFD_REJECT_COUNT), "count");
    assert_string_equal(sfd_reject_reason_str(99), "unknown");
}

/* GIVEN TRUTH in the current layout (kind[]) and in the layout of logs written before it
 * (truth_v1_t) WHEN the driver decodes them THEN both give the same poses, ids and labels, the v1
 * one with kind UNSPECIFIED exactly where spurious; a kind out of range, a kind disagreeing with
 * spurious, a bad count, a non-finite pose and a truncation are rejected. */
static void lcm_truth_decodes_current_and_legacy_layouts(void **state) {
    (void)state;
    SFD_REQ("SFD-LCM-006");
    memset(&g_tr, 0, sizeof g_tr);
    g_tr.utime = 42;
    g_tr.position[0] = 1.5;
    g_tr.orientation[0] = 1.0;
    g_tr.num_features = 4;
    const int8_t sp[4] = {0, 1, 1, 0},
                 kind[4] = {0, SFD_TRUTH_T_KIND_DRIFT, SFD_TRUTH_T_KIND_MOVING, 0};
    for (int i = 0; i < 4; ++i) {
        g_tr.track_id[i] = 10 + i;
        g_tr.spurious[i] = sp[i];
        g_tr.kind[i] = kind[i];
    }
    int n = sfd_truth_t_encode(g_buf, 0, BUF, &g_tr);
    assert_true(n > 0);
    assert_int_equal(sfd_lcm_decode_truth(g_buf, n, &g_tr2, &g_tr1), SFD_REJECT_NONE);
    assert_int_equal(g_tr2.utime, 42);
    assert_int_equal(g_tr2.num_features, 4);
    for (int i = 0; i < 4; ++i) {
        assert_int_equal(g_tr2.track_id[i], 10 + i);
        assert_int_equal(g_tr2.kind[i], kind[i]);
    }
    assert_int_equal(sfd_lcm_decode_truth(g_buf, n - 1, &g_tr2, &g_tr1), SFD_REJECT_DECODE);

    /* the same frame as a log before kind[] wrote it */
    memset(&g_tr1, 0, sizeof g_tr1);
    g_tr1.utime = 42;
    g_tr1.position[0] = 1.5;
    g_tr1.orientation[0] = 1.0;
    g_tr1.num_features = 4;
    for (int i = 0; i < 4; ++i) {
        g_tr1.track_id[i] = 10 + i;
        g_tr1.spurious[i] = sp[i];
    }
    n = sfd_truth_v1_t_encode(g_buf, 0, BUF, &g_tr1);
    assert_true(n > 0);
    memset(&g_tr2, 0x5a, sizeof g_tr2);
    assert_int_equal(sfd_lcm_decode_truth(g_buf, n, &g_tr2, &g_tr1), SFD_REJECT_NONE);
    assert_int_equal(g_tr2.utime, 42);
    assert_true(g_tr2.position[0] == 1.5);
    for (int i = 0; i < 4; ++i) {
        assert_int_equal(g_tr2.track_id[i], 10 + i);
        assert_int_equal(g_tr2.spurious[i], sp[i]);
        assert_int_equal(g_tr2.kind[i],
                         sp[i] ? SFD_TRUTH_T_KIND_UNSPECIFIED : SFD_TRUTH_T_KIND_CLEAN);
    }

    /* invalid content */
    g_tr.kind[1] = 6; /* out of range */
    n = sfd_truth_t_encode(g_buf, 0, BUF, &g_tr);
    assert_int_equal(sfd_lcm_decode_truth(g_buf, n, &g_tr2, &g_tr1), SFD_REJECT_DECODE);
    g_tr.kind[1] = 0; /* clean kind on a spurious feature */
    n = sfd_truth_t_encode(g_buf, 0, BUF, &g_tr);
    assert_int_equal(sfd_lcm_decode_truth(g_buf, n, &g_tr2, &g_tr1), SFD_REJECT_DECODE);
    g_tr.kind[1] = SFD_TRUTH_T_KIND_DRIFT;
    g_tr.kind[0] = SFD_TRUTH_T_KIND_JUMP; /* a kind on a clean feature */
    n = sfd_truth_t_encode(g_buf, 0, BUF, &g_tr);
    assert_int_equal(sfd_lcm_decode_truth(g_buf, n, &g_tr2, &g_tr1), SFD_REJECT_DECODE);
    g_tr.kind[0] = 0;
    g_tr.num_features = 513;
    n = sfd_truth_t_encode(g_buf, 0, BUF, &g_tr);
    assert_true(n > 0); /* fixed-size arrays: the count is just a field on the wire */
    assert_int_equal(sfd_lcm_decode_truth(g_buf, n, &g_tr2, &g_tr1), SFD_REJECT_COUNT);
    g_tr.num_features = 4;
    g_tr.position[2] = NAN;
    n = sfd_truth_t_encode(g_buf, 0, BUF, &g_tr);
    assert_int_equal(sfd_lcm_decode_truth(g_buf, n, &g_tr2, &g_tr1), SFD_REJECT_NONFINITE);
    g_tr.position[2] = 0.0;
    g_tr1.num_features = -1;
    n = sfd_truth_v1_t_encode(g_buf, 0, BUF, &g_tr1);
    assert_true(n > 0);
    assert_int_equal(sfd_lcm_decode_truth(g_buf, n, &g_tr2, &g_tr1), SFD_REJECT_COUNT);
    assert_int_equal(sfd_lcm_decode_truth(NULL, 0, &g_tr2, &g_tr1), SFD_REJECT_DECODE);
}

static int encode_ff(void) {
    const int n = sfd_feature_frame_t_encode(g_buf, 0, BUF, &g_ff);
    assert_true(n > 0);
    return n;
}

/* GIVEN FEATURES messages WHEN the driver decodes them THEN valid ones fill the core frame;
 * counts < 0 or > 512 are COUNT, > SFD_MAX_FEATURES CAPACITY, truncations DECODE; unusable depth
 * priors become "unknown" and are counted; non-finite pixels pass to the core (which marks the
 * feature UNTESTED, so the verdict still lists it). */
static void lcm_features_decode_validates_before_core(void **state) {
    (void)state;
    SFD_REQ("SFD-LCM-002");
    int32_t cam = -1;
    int fixed = -1;
    g_ff.utime = 1000;
    g_ff.camera_id = 2;
    g_ff.num_features = 3;
    for (int i = 0; i < 3; ++i) {
        g_ff.track_id[i] = 10 + i;
        g_ff.u[i] = 100 + i;
        g_ff.v[i] = 200 + i;
        g_ff.depth[i] = 5.0;
        g_ff.depth_var[i] = 1.0;
    }
    g_ff.depth[1] = NAN;
    g_ff.depth_var[2] = -1.0;
    g_ff.u[0] = INFINITY;
    int n = encode_ff();
    assert_int_equal(sfd_lcm_decode_features(g_buf, n, &g_ff2, &g_frame, &cam, &fixed),
                     SFD_REJECT_NONE);
    assert_int_equal(cam, 2);
    assert_int_equal(fixed, 2);
    assert_int_equal(g_frame.num_features, 3);
    assert_true(g_frame.utime == 1000);
    assert_true(g_frame.features[2].track_id == 12);
    assert_near(g_frame.features[1].depth_m, 0.0, 0.0);
    assert_near(g_frame.features[0].depth_m, 5.0, 0.0);
    assert_true(isinf(g_frame.features[0].u_px));
    for (int cut = 0; cut < n; cut += 61)
        assert_int_equal(sfd_lcm_decode_features(g_buf, cut, &g_ff2, &g_frame, &cam, &fixed),
                         SFD_REJECT_DECODE);
    g_ff.num_features = -1;
    n = encode_ff();
    assert_int_equal(sfd_lcm_decode_features(g_buf, n, &g_ff2, &g_frame, &cam, &fixed),
                     SFD_REJECT_COUNT);
    g_ff.num_features = 513;
    n = encode_ff();
    assert_int_equal(sfd_lcm_decode_features(g_buf, n, &g_ff2, &g_frame, &cam, &fixed),
                     SFD_REJECT_COUNT);
    g_ff.num_features = SFD_MAX_FEATURES + 1;
    n = encode_ff();
    assert_int_equal(sfd_lcm_decode_features(g_buf, n, &g_ff2, &g_frame, &cam, &fixed),
                     SFD_MAX_FEATURES + 1 <= 512 ? SFD_REJECT_CAPACITY : SFD_REJECT_COUNT);
    assert_int_equal(sfd_lcm_decode_features(NULL, n, &g_ff2, &g_frame, &cam, &fixed),
                     SFD_REJECT_DECODE);
    /* another type's bytes on the FEATURES channel */
    sfd_imu_t imu = {1, {0, 0, 0}, {0, 0, 0}};
    n = sfd_imu_t_encode(g_buf, 0, BUF, &imu);
    assert_int_equal(sfd_lcm_decode_features(g_buf, n, &g_ff2, &g_frame, &cam, &fixed),
                     SFD_REJECT_DECODE);
}

/* GIVEN IMU and CAMERA_INFO messages WHEN decoded THEN valid ones fill core structs; non-finite
 * IMU values are rejected as nonfinite, invalid calibrations by cause (focal length 0, height 0,
 * NaN principal point: intrinsics; unknown model, Inf coefficient: distortion; non-rigid T:
 * extrinsics), and the outputs are left untouched. */
static void lcm_imu_and_camera_info_validated(void **state) {
    (void)state;
    SFD_REQ("SFD-LCM-003");
    sfd_imu_t imu = {42, {0.1, 0.2, 0.3}, {0, 0, 9.8}};
    int n = sfd_imu_t_encode(g_buf, 0, BUF, &imu);
    sfd_imu_sample_t s;
    memset(&s, 0, sizeof s);
    assert_int_equal(sfd_lcm_decode_imu(g_buf, n, &s), SFD_REJECT_NONE);
    assert_true(s.t_us == 42);
    assert_near(s.gyro_rad_s[2], 0.3, 0.0);
    imu.accel[1] = NAN;
    n = sfd_imu_t_encode(g_buf, 0, BUF, &imu);
    s.t_us = -5;
    assert_int_equal(sfd_lcm_decode_imu(g_buf, n, &s), SFD_REJECT_NONFINITE);
    assert_true(s.t_us == -5);
    assert_int_equal(sfd_lcm_decode_imu(g_buf, 3, &s), SFD_REJECT_DECODE);

    sfd_camera_info_t ci, scratch;
    memset(&ci, 0, sizeof ci);
    ci.camera_id = 0;
    ci.width = 752;
    ci.height = 480;
    ci.fx = 458.654;
    ci.fy = 457.296;
    ci.cx = 367.215;
    ci.cy = 248.375;
    ci.distortion_model = SFD_CAMERA_INFO_T_RADTAN;
    const double d[4] = {-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05};
    memcpy(ci.distortion, d, sizeof d);
    const double *T = kEurocTimuCam;
    memcpy(ci.T_imu_cam, T, sizeof ci.T_imu_cam);
    n = sfd_camera_info_t_encode(g_buf, 0, BUF, &ci);
    sfd_camera_t cam;
    sfd_extrinsics_t ext;
    int32_t id = -1;
    assert_int_equal(sfd_lcm_decode_camera_info(g_buf, n, &scratch, &cam, &ext, &id),
                     SFD_REJECT_NONE);
    assert_int_equal(id, 0);
    assert_int_equal(cam.model, SFD_DISTORTION_RADTAN);
    assert_near(ext.p_CinI[0], -0.0216401454975, 0.0);
    sfd_camera_info_t bad = ci;
    bad.fx = 0.0;
    n = sfd_camera_info_t_encode(g_buf, 0, BUF, &bad);
    id = 99;
    assert_int_equal(sfd_lcm_decode_camera_info(g_buf, n, &scratch, &cam, &ext, &id),
                     SFD_REJECT_CALIB_INTRINSICS);
    assert_int_equal(id, 99);
    bad = ci;
    bad.height = 0;
    n = sfd_camera_info_t_encode(g_buf, 0, BUF, &bad);
    assert_int_equal(sfd_lcm_decode_camera_info(g_buf, n, &scratch, &cam, &ext, &id),
                     SFD_REJECT_CALIB_INTRINSICS);
    bad = ci;
    bad.cy = NAN;
    n = sfd_camera_info_t_encode(g_buf, 0, BUF, &bad);
    assert_int_equal(sfd_lcm_decode_camera_info(g_buf, n, &scratch, &cam, &ext, &id),
                     SFD_REJECT_CALIB_INTRINSICS);
    bad = ci;
    bad.distortion_model = 7;
    n = sfd_camera_info_t_encode(g_buf, 0, BUF, &bad);
    assert_int_equal(sfd_lcm_decode_camera_info(g_buf, n, &scratch, &cam, &ext, &id),
                     SFD_REJECT_CALIB_DISTORTION);
    bad = ci;
    bad.distortion[2] = INFINITY;
    n = sfd_camera_info_t_encode(g_buf, 0, BUF, &bad);
    assert_int_equal(sfd_lcm_decode_camera_info(g_buf, n, &scratch, &cam, &ext, &id),
                     SFD_REJECT_CALIB_DISTORTION);
    bad = ci;
    bad.T_imu_cam[0] = 2.0;
    n = sfd_camera_info_t_encode(g_buf, 0, BUF, &bad);
    assert_int_equal(sfd_lcm_decode_camera_info(g_buf, n, &scratch, &cam, &ext, &id),
                     SFD_REJECT_CALIB_EXTRINSICS);
    assert_int_equal(id, 99);
}

static sfd_node_t g_node;
static sfd_feature_verdict_t g_last_verdict;
static int g_verdicts;

static void keep_verdict(void *ctx, sfd_node_output_t kind, const void *data, int32_t size,
                         int64_t utime) {
    (void)ctx;
    (void)utime;
    if (kind != SFD_NODE_OUT_VERDICT) return;
    assert_int_equal(sfd_feature_verdict_t_decode(data, 0, size, &g_last_verdict), size);
    g_verdicts++;
}

static void handle_camera_info(int32_t camera_id) {
    sfd_camera_info_t ci;
    memset(&ci, 0, sizeof ci);
    ci.camera_id = camera_id;
    ci.width = 752;
    ci.height = 480;
    ci.fx = ci.fy = 450.0;
    ci.cx = 376.0;
    ci.cy = 240.0;
    ci.distortion_model = SFD_CAMERA_INFO_T_PINHOLE;
    memcpy(ci.T_imu_cam, kEurocTimuCam, sizeof ci.T_imu_cam);
    ci.fx += camera_id; /* a calibration of its own per camera */
    const int n = sfd_camera_info_t_encode(g_buf, 0, BUF, &ci);
    sfd_node_handle(&g_node, SFD_NODE_CAMERA_INFO, g_buf, n);
}

static void handle_frame(int64_t utime, int32_t camera_id) {
    memset(&g_ff, 0, sizeof g_ff);
    g_ff.utime = utime;
    g_ff.camera_id = camera_id;
    g_ff.num_features = 2;
    g_ff.track_id[0] = 1;
    g_ff.track_id[1] = 2;
    g_ff.u[0] = g_ff.v[0] = 100.0;
    g_ff.u[1] = g_ff.v[1] = 200.0;
    sfd_node_handle(&g_node, SFD_NODE_FEATURES, g_buf, encode_ff());
}

static void handle_imu_at(int64_t utime, double accel_z_m_s2) {
    sfd_imu_t imu;
    memset(&imu, 0, sizeof imu);
    imu.utime = utime;
    imu.accel[2] = accel_z_m_s2;
    const int n = sfd_imu_t_encode(g_buf, 0, BUF, &imu);
    sfd_node_handle(&g_node, SFD_NODE_IMU, g_buf, n);
}

/* Frames take their IMU index (a sample every 5 ms) in this file's IMU-ring tests. */
typedef struct {
    int samples;           /* 200 Hz samples handled, numbered 1.. (t = 5000 i us) */
    int frames;            /* 20 Hz frames handled, at samples 5, 15, 25, ... */
    int last_frame_sample; /* the sample of the last frame */
} imu_feed_t;

/* A fresh node (method PARITY, the filter on, start at rest) fed three ring spans of 200 Hz IMU
 * whose accelerometer reads accel_z_m_s2, with a frame every 10 samples. */
static imu_feed_t feed_node_imu_and_frames(double accel_z_m_s2) {
    sfd_node_config_t cfg;
    sfd_node_config_default(&cfg);
    cfg.params.method = SFD_METHOD_PARITY;
    assert_status(sfd_node_init(&g_node, &cfg, keep_verdict, NULL, NULL), SFD_OK);
    g_verdicts = 0;
    handle_camera_info(0);
    imu_feed_t f = {3 * SFD_IMU_RING_CAPACITY, 0, 0};
    for (int i = 1; i <= f.samples; ++i) {
        const int64_t t = 5000 * (int64_t)i;
        handle_imu_at(t, accel_z_m_s2);
        if (i % 10 == 5) {
            handle_frame(t, 0);
            f.frames++;
            f.last_frame_sample = i;
        }
    }
    assert_true(g_node.pipe.ring.overwritten == f.samples - SFD_IMU_RING_CAPACITY);
    return f;
}

/* Then IMU alone for more than the ring's span; returns the index of the newest sample dropped. */
static int feed_imu_past_the_ring(const imu_feed_t *f, double accel_z_m_s2) {
    const int extra = SFD_IMU_RING_CAPACITY + 5;
    for (int i = f->samples + 1; i <= f->samples + extra; ++i) {
        handle_imu_at(5000 * (int64_t)i, accel_z_m_s2);
    }
    return f->samples + extra - SFD_IMU_RING_CAPACITY;
}

/* GIVEN a node fed 200 Hz IMU and 20 Hz frames for longer than its IMU ring holds (the filter
 * running, started at rest) WHEN the ring wraps over samples the frames have consumed THEN no
 * imu_overflow is reported and every frame is judged; WHEN IMU keeps arriving with no frame to
 * consume it THEN exactly the drops of samples the next frame would need are reported: the next
 * frame's interval starts at the last frame's sample. */
static void lcm_node_reports_imu_overflow_only_for_needed_samples(void **state) {
    (void)state;
    SFD_REQ("SFD-LCM-004");
    const imu_feed_t f = feed_node_imu_and_frames(9.81);
    assert_true(g_node.pipe.ring.lost == 0);
    assert_true(g_node.pipe.counters.rejected[SFD_REJECT_IMU_OVERFLOW] == 0);
    assert_true(g_node.pipe.nav.ready == 1);
    assert_int_equal(g_verdicts, f.frames);
    const int newest_dropped = feed_imu_past_the_ring(&f, 9.81);
    assert_true(g_node.pipe.ring.lost == newest_dropped - f.last_frame_sample + 1);
    assert_true(g_node.pipe.counters.rejected[SFD_REJECT_IMU_OVERFLOW] == g_node.pipe.ring.lost);
}

/* GIVEN a filter that cannot start at rest (the accelerometer reads no gravity) and keeps
 * looking back init_rest_s of IMU from every frame WHEN the ring wraps while frames come THEN
 * nothing is reported; WHEN frames stop for longer than the ring holds THEN exactly the samples
 * from the last one at or before (last frame - init_rest_s) on are reported lost. */
static void lcm_node_waiting_filter_keeps_its_rest_window(void **state) {
    (void)state;
    SFD_REQ("SFD-LCM-004");
    const imu_feed_t f = feed_node_imu_and_frames(0.0);
    assert_int_equal(g_node.pipe.nav.ready, 0);
    assert_true(g_node.pipe.ring.lost == 0);
    assert_true(g_node.pipe.counters.rejected[SFD_REJECT_IMU_OVERFLOW] == 0);
    const int newest_dropped = feed_imu_past_the_ring(&f, 0.0);
    const int rest_samples = (int)(g_node.cfg.nav.init_rest_s * 1e6) / 5000; /* 200 at 1 s */
    const int first_needed = f.last_frame_sample - rest_samples;
    assert_true(g_node.pipe.ring.lost == newest_dropped - first_needed + 1);
    assert_true(g_node.pipe.counters.rejected[SFD_REJECT_IMU_OVERFLOW] == g_node.pipe.ring.lost);
}

static int64_t g_fake_now_us;
static sfd_timing_t g_last_timing;
static int g_timings;

static int64_t fake_clock(void *ctx) {
    (void)ctx;
    return g_fake_now_us;
}

/* A transport whose sends take time: 100 us per verdict, 10 per state, 1000 per timing message;
 * nothing else moves the clock. */
static void slow_publish(void *ctx, sfd_node_output_t kind, const void *data, int32_t size,
                         int64_t utime) {
    (void)ctx;
    (void)utime;
    if (kind == SFD_NODE_OUT_VERDICT) g_fake_now_us += 100;
    if (kind == SFD_NODE_OUT_STATE) g_fake_now_us += 10;
    if (kind == SFD_NODE_OUT_TIMING) {
        g_fake_now_us += 1000;
        assert_int_equal(sfd_timing_t_decode(data, 0, size, &g_last_timing), size);
        g_timings++;
    }
}

/* GIVEN a transport whose sends take time and a node that spends none of its own WHEN frames are
 * judged THEN SFD_TIMING's publish_us is the time inside the sends of the verdict (and, once the
 * filter runs, the state), total_us includes it, and the timing message's own send is in
 * neither. */
static void lcm_node_reports_its_send_time_as_publish_us(void **state) {
    (void)state;
    SFD_REQ("SFD-LCM-004");
    sfd_node_config_t cfg;
    sfd_node_config_default(&cfg);
    cfg.params.method = SFD_METHOD_PARITY;
    g_fake_now_us = 0;
    g_timings = 0;
    assert_status(sfd_node_init(&g_node, &cfg, slow_publish, fake_clock, NULL), SFD_OK);
    handle_camera_info(0);
    handle_imu_at(5000, 9.81);
    handle_imu_at(10000, 9.81);
    handle_frame(10000, 0); /* the filter waits for 1 s of rest: a verdict, no state */
    assert_int_equal(g_timings, 1);
    assert_int_equal(g_last_timing.publish_us, 100);
    assert_int_equal(g_last_timing.total_us, 100);
    for (int i = 3; i <= 400; ++i) {
        handle_imu_at(5000 * (int64_t)i, 9.81);
        if (i % 10 == 0) handle_frame(5000 * (int64_t)i, 0);
    }
    assert_int_equal(g_node.pipe.nav.ready, 1); /* the filter runs: verdict and state each frame */
    assert_int_equal(g_last_timing.publish_us, 110);
    assert_int_equal(g_last_timing.total_us, 110);
}

/* GIVEN a node configured to follow the first camera WHEN the first calibration carries a
 * negative camera_id THEN the node follows that camera and no other: a later CAMERA_INFO and
 * FEATURES of another camera are rejected (CAMERA_ID) and verdicts name the followed camera.
 * (Regression: a negative id used to read as "none chosen yet", so the next camera's calibration
 * replaced it and a frame waiting for IMU was judged and labelled with the new camera; found by
 * fuzz.camera_info.) */
static void lcm_node_follows_first_camera_even_with_negative_id(void **state) {
    (void)state;
    SFD_REQ("SFD-LCM-004");
    sfd_node_config_t cfg;
    sfd_node_config_default(&cfg);
    cfg.params.method = SFD_METHOD_NONE;
    cfg.nav.enabled = 0; /* no IMU in this test: no filter, so frames need no IMU */
    assert_status(sfd_node_init(&g_node, &cfg, keep_verdict, NULL, NULL), SFD_OK);
    g_verdicts = 0;
    handle_camera_info(-7);
    assert_int_equal(g_node.pipe.have_camera, 1);
    assert_int_equal(g_node.camera_id, -7);
    handle_camera_info(3);
    assert_int_equal(g_node.camera_id, -7);
    assert_true(g_node.pipe.counters.rejected[SFD_REJECT_CAMERA_ID] == 1);
    handle_frame(1000, 3);
    assert_true(g_node.pipe.counters.rejected[SFD_REJECT_CAMERA_ID] == 2);
    assert_int_equal(g_verdicts, 0);
    handle_frame(2000, -7);
    assert_int_equal(g_verdicts, 1);
    assert_int_equal(g_last_verdict.camera_id, -7);
    assert_int_equal(g_last_verdict.num_features, 2);
    /* a configured camera is kept the same way */
    cfg.camera_id = 5;
    assert_status(sfd_node_init(&g_node, &cfg, keep_verdict, NULL, NULL), SFD_OK);
    handle_camera_info(-1);
    assert_int_equal(g_node.pipe.have_camera, 0);
    handle_camera_info(5);
    assert_int_equal(g_node.camera_id, 5);
}

static int g_status_reports, g_frame_timings;

static void keep_timing(void *ctx, sfd_node_output_t kind, const void *data, int32_t size,
                        int64_t utime) {
    (void)ctx;
    (void)utime;
    if (kind != SFD_NODE_OUT_TIMING) return;
    assert_int_equal(sfd_timing_t_decode(data, 0, size, &g_last_timing), size);
    if (g_last_timing.frame_processed) {
        g_frame_timings++;
    } else {
        g_status_reports++;
    }
}

/* GIVEN a node with no calibration, fed 200 Hz IMU and 20 Hz frames WHEN every frame is refused
 * THEN SFD_TIMING still comes, as a status report (frame_processed 0) after every
 * SFD_NODE_STATUS_EVERY_INPUTS inputs, with the counters (frames in, no_camera_info); WHEN the
 * calibration comes and frames are judged THEN each judged frame publishes its SFD_TIMING
 * (frame_processed 1) and no status report is added. */
static void lcm_node_reports_status_while_no_frame_is_judged(void **state) {
    (void)state;
    sfd_node_config_t cfg;
    sfd_node_config_default(&cfg);
    cfg.params.method = SFD_METHOD_PARITY;
    assert_status(sfd_node_init(&g_node, &cfg, keep_timing, NULL, NULL), SFD_OK);
    g_status_reports = g_frame_timings = 0;
    int inputs = 0;
    for (int i = 1; i <= 400; ++i) {
        handle_imu_at(5000 * (int64_t)i, 9.81);
        ++inputs;
        if (i % 10 == 5) {
            handle_frame(5000 * (int64_t)i, 0);
            ++inputs;
        }
    }
    assert_int_equal(g_frame_timings, 0);
    assert_int_equal(g_status_reports, inputs / SFD_NODE_STATUS_EVERY_INPUTS);
    assert_int_equal(g_last_timing.frame_processed, 0);
    assert_true(g_last_timing.frames_in >= 30); /* the frames before the 400th input */
    assert_true(g_last_timing.rejected[SFD_TIMING_T_REJECT_NO_CAMERA_INFO] ==
                g_last_timing.frames_in);
    assert_true(g_last_timing.frames_refused == g_last_timing.frames_in);
    assert_true(g_last_timing.imu_in + g_last_timing.frames_in ==
                2 * (int64_t)SFD_NODE_STATUS_EVERY_INPUTS);
    assert_true(g_last_timing.utime > 0);
    handle_camera_info(0);
    const int status_before = g_status_reports;
    for (int i = 401; i <= 1200; ++i) {
        handle_imu_at(5000 * (int64_t)i, 9.81);
        if (i % 10 == 5) handle_frame(5000 * (int64_t)i, 0);
    }
    assert_int_equal(g_status_reports, status_before);
    assert_int_equal(g_frame_timings, 80);
    assert_int_equal(g_last_timing.frame_processed, 1);
    assert_true(g_last_timing.frames_processed == 80);
    assert_true(g_last_timing.frames_in == g_last_timing.frames_refused + 80);
    assert_true(g_last_timing.camera_info_in == 1);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(lcm_every_type_round_trips_at_max_size),
        cmocka_unit_test(lcm_features_decode_validates_before_core),
        cmocka_unit_test(lcm_imu_and_camera_info_validated),
        cmocka_unit_test(lcm_truth_decodes_current_and_legacy_layouts),
        cmocka_unit_test(lcm_node_follows_first_camera_even_with_negative_id),
        cmocka_unit_test(lcm_node_reports_imu_overflow_only_for_needed_samples),
        cmocka_unit_test(lcm_node_waiting_filter_keeps_its_rest_window),
        cmocka_unit_test(lcm_node_reports_its_send_time_as_publish_us),
        cmocka_unit_test(lcm_node_reports_status_while_no_frame_is_judged),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
