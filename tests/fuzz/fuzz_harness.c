/* SPDX-License-Identifier: MIT */
#include "fuzz_harness.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

sfd_node_t g_fz_node;

/* A frame the node accepted and still owes a verdict for. At most two are outstanding inside one
 * call (the pending frame judged on arrival of the next, and the next). */
typedef struct {
    int64_t utime;
    int32_t camera_id;
    int32_t num_features;
    int64_t track_id[SFD_FEATURE_FRAME_T_CAPACITY];
} fz_expected_t;

enum { FZ_QUEUE = 4 };

typedef struct {
    fz_expected_t queue[FZ_QUEUE];
    int head, count;
    int64_t verdicts; /* since reset */
    int64_t last_verdict_utime;
    int32_t last_verdict_features;
    int have_verdict;
    int timing_expected; /* a verdict was published, its SFD_TIMING may follow */
    int64_t last_rejected[SFD_TIMING_T_NUM_REASONS];
} fz_checker_t;

static fz_checker_t g_chk;

/* scratch (static: the wire structs are tens of KiB) */
static sfd_feature_frame_t g_ff_check;
static sfd_feature_verdict_t g_fv_check;
static sfd_feature_frame_t g_ff_build;

void fz_fail(const char *file, int line, const char *what) {
    fprintf(stderr, "sfd fuzz invariant violated: %s (%s:%d)\n", what, file, line);
    abort();
}

void fz_default_config(sfd_node_config_t *cfg) {
    sfd_node_config_default(cfg);
}

static void check_verdict(const void *data, int32_t size, int64_t utime) {
    sfd_feature_verdict_t *v = &g_fv_check;
    FZ_CHECK(sfd_feature_verdict_t_decode(data, 0, size, v) == size);
    FZ_CHECK(g_chk.count > 0); /* a verdict for a frame the node accepted */
    const fz_expected_t *e = &g_chk.queue[g_chk.head];
    FZ_CHECK(v->utime == e->utime && utime == e->utime);
    FZ_CHECK(v->camera_id == e->camera_id);
    FZ_CHECK(v->num_features == e->num_features);
    for (int i = 0; i < e->num_features; ++i) {
        FZ_CHECK(v->track_id[i] == e->track_id[i]);
        FZ_CHECK(v->status[i] == SFD_FEATURE_VERDICT_T_UNTESTED ||
                 v->status[i] == SFD_FEATURE_VERDICT_T_CONSISTENT ||
                 v->status[i] == SFD_FEATURE_VERDICT_T_SPURIOUS);
        FZ_CHECK(v->stage[i] >= 0 && v->stage[i] <= SFD_FEATURE_VERDICT_T_RANSAC_F);
        FZ_CHECK(v->status[i] != SFD_FEATURE_VERDICT_T_UNTESTED || v->stage[i] == 0);
        FZ_CHECK(isfinite(v->statistic[i]));
    }
    if (g_chk.have_verdict) FZ_CHECK(v->utime > g_chk.last_verdict_utime);
    g_chk.have_verdict = 1;
    g_chk.last_verdict_utime = v->utime;
    g_chk.last_verdict_features = v->num_features;
    g_chk.timing_expected = 1;
    g_chk.head = (g_chk.head + 1) % FZ_QUEUE;
    g_chk.count--;
    g_chk.verdicts++;
}

static void check_timing(const void *data, int32_t size, int64_t utime) {
    sfd_timing_t t;
    FZ_CHECK(sfd_timing_t_decode(data, 0, size, &t) == size);
    FZ_CHECK(t.frame_processed == 0 || t.frame_processed == 1);
    if (t.frame_processed) {
        FZ_CHECK(g_chk.timing_expected); /* follows its frame's verdict */
        g_chk.timing_expected = 0;
        FZ_CHECK(t.utime == g_chk.last_verdict_utime && utime == t.utime);
        FZ_CHECK(t.features_in == g_chk.last_verdict_features);
        FZ_CHECK(t.ingest_us >= 0 && t.parity_us >= 0 && t.total_us >= 0);
    } else {
        /* a status report while no frame is judged: no durations, the newest input time */
        FZ_CHECK(utime == t.utime && t.features_in == 0 && t.total_us == 0);
    }
    /* the frame accounting: every frame received is refused, judged or held (at most 2) */
    const int64_t held = t.frames_in - t.frames_refused - t.frames_processed;
    FZ_CHECK(held >= 0 && held <= SFD_PIPELINE_FRAME_SLOTS);
    FZ_CHECK(t.frames_untested >= 0 && t.frames_untested <= t.frames_processed);
    for (int k = 0; k < SFD_TIMING_T_NUM_REASONS; ++k) {
        FZ_CHECK(t.rejected[k] >= g_chk.last_rejected[k]); /* counters only grow */
        g_chk.last_rejected[k] = t.rejected[k];
    }
}

/* SFD_STATE: after its frame's verdict, decodable, finite, a unit quaternion, variances >= 0. */
static void check_nav_state(const void *data, int32_t size, int64_t utime) {
    sfd_nav_state_t s;
    FZ_CHECK(sfd_nav_state_t_decode(data, 0, size, &s) == size);
    FZ_CHECK(g_chk.have_verdict && s.utime == g_chk.last_verdict_utime && utime == s.utime);
    double qn = 0.0;
    for (int k = 0; k < 3; ++k) {
        FZ_CHECK(isfinite(s.position[k]) && isfinite(s.velocity[k]));
        FZ_CHECK(isfinite(s.position_var[k]) && s.position_var[k] >= 0.0);
    }
    for (int k = 0; k < 4; ++k) {
        FZ_CHECK(isfinite(s.orientation[k]));
        qn += s.orientation[k] * s.orientation[k];
    }
    FZ_CHECK(fabs(qn - 1.0) < 1e-6);
}

static void on_publish(void *ctx, sfd_node_output_t kind, const void *data, int32_t size,
                       int64_t utime) {
    (void)ctx;
    FZ_CHECK(data != NULL && size > 0 && size <= SFD_NODE_MAX_MESSAGE);
    if (kind == SFD_NODE_OUT_VERDICT) {
        check_verdict(data, size, utime);
    } else if (kind == SFD_NODE_OUT_STATE) {
        check_nav_state(data, size, utime);
    } else {
        FZ_CHECK(kind == SFD_NODE_OUT_TIMING);
        check_timing(data, size, utime);
    }
}

void fz_reset(const sfd_node_config_t *cfg) {
    memset(&g_fz_node, 0, sizeof g_fz_node);
    memset(&g_chk, 0, sizeof g_chk);
    FZ_CHECK(sfd_node_init(&g_fz_node, cfg, on_publish, NULL, NULL) == SFD_OK);
}

int64_t fz_verdicts(void) {
    return g_chk.verdicts;
}

/* Frames the node's pipeline holds (waiting for IMU, or due: the node judges those at once). */
static int fz_frames_held(const sfd_node_t *n) {
    int held = 0;
    for (int k = 0; k < SFD_PIPELINE_FRAME_SLOTS; ++k) {
        held += n->pipe.slot_state[k] != SFD_PIPELINE_SLOT_FREE;
    }
    return held;
}

/* Counters as a flat array, for the monotonicity check. */
enum { FZ_NCOUNT = SFD_REJECT_NUM_REASONS + 6 };
static void counters_flat(const sfd_node_counters_t *c, int64_t out[FZ_NCOUNT]) {
    for (int k = 0; k < SFD_REJECT_NUM_REASONS; ++k) out[k] = c->rejected[k];
    out[SFD_REJECT_NUM_REASONS + 0] = c->frames_in;
    out[SFD_REJECT_NUM_REASONS + 1] = c->frames_processed;
    out[SFD_REJECT_NUM_REASONS + 2] = c->frames_untested;
    out[SFD_REJECT_NUM_REASONS + 3] = c->imu_in;
    out[SFD_REJECT_NUM_REASONS + 4] = c->camera_info_in;
    out[SFD_REJECT_NUM_REASONS + 5] = c->frames_refused;
}

static void check_state(const sfd_node_counters_t *before, int64_t verdicts_before) {
    const sfd_node_t *n = &g_fz_node;
    const sfd_node_counters_t *c = &n->pipe.counters;
    int64_t a[FZ_NCOUNT], b[FZ_NCOUNT];
    counters_flat(before, a);
    counters_flat(c, b);
    for (int k = 0; k < FZ_NCOUNT; ++k) FZ_CHECK(b[k] >= a[k]);
    FZ_CHECK(c->frames_processed - before->frames_processed == g_chk.verdicts - verdicts_before);
    FZ_CHECK(c->frames_processed == g_chk.verdicts);
    FZ_CHECK(c->frames_processed <= c->frames_in);
    FZ_CHECK(c->frames_untested <= c->frames_processed);
    FZ_CHECK(n->pipe.ring.count >= 0 && n->pipe.ring.count <= SFD_IMU_RING_CAPACITY);
    FZ_CHECK(n->pipe.ring.head >= 0 && n->pipe.ring.head < SFD_IMU_RING_CAPACITY);
    /* a frame is owed a verdict exactly while it is pending */
    FZ_CHECK(g_chk.count == fz_frames_held(n));
    g_chk.timing_expected = 0; /* SFD_TIMING comes right after its verdict or not at all */
}

/* Independent decode of a FEATURES message: what the node must accept, and the verdict it owes. */
static int expect_features(const void *data, size_t size, fz_expected_t *e) {
    const sfd_node_t *n = &g_fz_node;
    if (size > (size_t)INT32_MAX) return 0;
    if (sfd_feature_frame_t_decode(data, 0, (int)size, &g_ff_check) < 0) return 0;
    const sfd_feature_frame_t *m = &g_ff_check;
    if (m->num_features < 0 || m->num_features > SFD_FEATURE_FRAME_T_CAPACITY ||
        m->num_features > SFD_MAX_FEATURES) {
        return 0;
    }
    if (!n->pipe.have_camera || m->camera_id != n->camera_id) return 0;
    /* the time policy (sfd_time_guard.h), on a copy of the frame stream's guard */
    sfd_time_guard_t guard = n->pipe.frame_time;
    const sfd_time_verdict_t tv = sfd_time_guard_check(&guard, m->utime, &n->pipe.imu_time);
    if (tv == SFD_TIME_ORDER || tv == SFD_TIME_JUMP) return 0;
    e->utime = m->utime;
    e->camera_id = m->camera_id;
    e->num_features = m->num_features;
    memcpy(e->track_id, m->track_id, sizeof(int64_t) * (size_t)m->num_features);
    return 1;
}

void fz_handle(sfd_node_input_t kind, const void *data, size_t size) {
    sfd_node_t *n = &g_fz_node;
    const sfd_node_counters_t before = n->pipe.counters;
    const int64_t verdicts_before = g_chk.verdicts;
    const int had_camera = n->pipe.have_camera;
    const int32_t camera_before = n->camera_id;
    const int64_t last_features_before = n->pipe.last_frame_utime;
    const int32_t size32 = size > (size_t)INT32_MAX ? INT32_MAX : (int32_t)size;

    int accept = 0;
    if (kind == SFD_NODE_FEATURES) {
        FZ_CHECK(g_chk.count < FZ_QUEUE);
        const int tail = (g_chk.head + g_chk.count) % FZ_QUEUE;
        accept = expect_features(data, size, &g_chk.queue[tail]);
        /* Queued before the call: the verdict may be published inside it. A pending frame ahead
         * of it is judged first (the queue is in arrival order). */
        if (accept) g_chk.count++;
    }

    sfd_node_handle(n, kind, data, size32);

    if (kind == SFD_NODE_FEATURES) {
        const int accepted = n->pipe.last_frame_utime != last_features_before;
        FZ_CHECK(accepted == accept);
        if (accepted) FZ_CHECK(n->pipe.last_frame_utime == g_ff_check.utime);
        FZ_CHECK(n->pipe.counters.frames_in == before.frames_in + 1);
    } else {
        FZ_CHECK(n->pipe.counters.frames_in == before.frames_in);
    }
    FZ_CHECK(n->pipe.counters.imu_in == before.imu_in + (kind == SFD_NODE_IMU ? 1 : 0));
    FZ_CHECK(n->pipe.counters.camera_info_in ==
             before.camera_info_in + (kind == SFD_NODE_CAMERA_INFO ? 1 : 0));
    if (had_camera) {
        FZ_CHECK(n->pipe.have_camera);
        FZ_CHECK(n->camera_id == camera_before); /* never switches cameras */
    }
    check_state(&before, verdicts_before);
}

void fz_flush(void) {
    sfd_node_t *n = &g_fz_node;
    const sfd_node_counters_t before = n->pipe.counters;
    const int64_t verdicts_before = g_chk.verdicts;
    sfd_node_flush(n);
    FZ_CHECK(fz_frames_held(n) == 0);
    FZ_CHECK(g_chk.count == 0); /* every accepted frame has had its verdict */
    check_state(&before, verdicts_before);
}

/* --- priming ------------------------------------------------------------------------------ */

int fz_encode_camera_info(uint8_t *buf, int cap, int64_t utime) {
    return fz_encode_camera_info_id(buf, cap, utime, 0);
}

int fz_encode_camera_info_id(uint8_t *buf, int cap, int64_t utime, int32_t camera_id) {
    sfd_camera_info_t ci;
    memset(&ci, 0, sizeof ci);
    ci.utime = utime;
    ci.camera_id = camera_id;
    ci.width = 752;
    ci.height = 480;
    ci.fx = 458.654;
    ci.fy = 457.296;
    ci.cx = 367.215;
    ci.cy = 248.375;
    ci.distortion_model = SFD_CAMERA_INFO_T_RADTAN;
    const double dist[4] = {-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05};
    memcpy(ci.distortion, dist, sizeof dist);
    const double T[16] = {1, 0, 0, 0.05, 0, -1, 0, 0.0, 0, 0, -1, -0.02, 0, 0, 0, 1};
    memcpy(ci.T_imu_cam, T, sizeof T);
    return sfd_camera_info_t_encode(buf, 0, cap, &ci);
}

int fz_encode_imu(uint8_t *buf, int cap, int64_t utime) {
    const sfd_imu_t m = {utime, {0.0, 0.0, 0.0}, {0.0, 0.0, 9.81}};
    return sfd_imu_t_encode(buf, 0, cap, &m);
}

int fz_encode_features(uint8_t *buf, int cap, int64_t utime, int32_t camera_id, int n) {
    sfd_feature_frame_t *f = &g_ff_build;
    memset(f, 0, sizeof *f);
    f->utime = utime;
    f->camera_id = camera_id;
    f->num_features = n;
    for (int i = 0; i < n && i < SFD_FEATURE_FRAME_T_CAPACITY; ++i) {
        f->track_id[i] = i + 1;
        const int col = i % 5, row = i / 5; /* a 5-column grid */
        f->u[i] = 60.0 + 127.0 * col + 3.0 * row;
        f->v[i] = 50.0 + 90.0 * row + 7.0 * col;
        f->depth[i] = 20.0;
        f->depth_var[i] = 0.0;
    }
    return sfd_feature_frame_t_encode(buf, 0, cap, f);
}

static uint8_t g_msg[SFD_NODE_MAX_MESSAGE * 2];

void fz_imu_until(int64_t until_us, int max_samples) {
    const sfd_node_t *n = &g_fz_node;
    int64_t t = n->pipe.last_imu_utime;
    if (t >= until_us) return;
    const uint64_t gap = (uint64_t)until_us - (uint64_t)t; /* t < until_us: no wrap */
    if (t == INT64_MIN || gap > (uint64_t)max_samples * 5000u) {
        fz_handle(SFD_NODE_IMU, g_msg, (size_t)fz_encode_imu(g_msg, sizeof g_msg, until_us));
        return;
    }
    while (t < until_us) {
        t = (until_us - t > 5000) ? t + 5000 : until_us;
        fz_handle(SFD_NODE_IMU, g_msg, (size_t)fz_encode_imu(g_msg, sizeof g_msg, t));
    }
}

static sfd_node_t g_primed_node[2];
static fz_checker_t g_primed_chk[2];
static int g_primed_ready[2];

void fz_restore_primed(int pending_frame) {
    const int p = pending_frame ? 1 : 0;
    if (!g_primed_ready[p]) {
        sfd_node_config_t cfg;
        fz_default_config(&cfg);
        fz_reset(&cfg);
        fz_handle(SFD_NODE_CAMERA_INFO, g_msg,
                  (size_t)fz_encode_camera_info(g_msg, sizeof g_msg, 800000));
        fz_handle(SFD_NODE_IMU, g_msg, (size_t)fz_encode_imu(g_msg, sizeof g_msg, 800000));
        for (int64_t t = 850000; t <= 950000; t += 50000) {
            fz_imu_until(t, 100);
            fz_handle(SFD_NODE_FEATURES, g_msg,
                      (size_t)fz_encode_features(g_msg, sizeof g_msg, t, 0, 20));
        }
        fz_imu_until(995000, 100);
        if (p) {
            fz_handle(SFD_NODE_FEATURES, g_msg,
                      (size_t)fz_encode_features(g_msg, sizeof g_msg, 1000000, 0, 20));
            FZ_CHECK(fz_frames_held(&g_fz_node) == 1);
        }
        FZ_CHECK(g_chk.verdicts == 3);
        g_primed_node[p] = g_fz_node;
        g_primed_chk[p] = g_chk;
        g_primed_ready[p] = 1;
    }
    g_fz_node = g_primed_node[p];
    g_chk = g_primed_chk[p];
}

/* --- sequence format ---------------------------------------------------------------------- */

void fz_config_from_byte(uint8_t b, sfd_node_config_t *cfg) {
    fz_default_config(cfg);
    static const int windows[4] = {3, 2, 4, 5};
    static const int groups[4] = {3, 1, 2, 4};
    const int L = windows[b & 3u];
    const int n = groups[(b >> 6) & 3u];
    cfg->params.window_frames = L < SFD_MAX_WINDOW ? L : SFD_MAX_WINDOW;
    cfg->params.group_size = n < SFD_MAX_GROUP ? n : SFD_MAX_GROUP;
    if (b & 4u) { /* bits 4 and 5 then pick the filter methods; 6 and 7 both: the EKF */
        static const int32_t methods[4] = {SFD_METHOD_NONE, SFD_METHOD_OPRF, SFD_METHOD_BOTH,
                                           SFD_METHOD_RANSAC1};
        cfg->params.method = methods[(b >> 4) & 3u];
        if (cfg->params.method == SFD_METHOD_RANSAC1 && (b & 1u)) {
            cfg->params.method = SFD_METHOD_RANSACF;
        }
        /* `both` with a 2-frame parity window: the window filter's keyframe option (a middle
         * clone leaves; keyframe_recent 1) */
        if (cfg->params.method == SFD_METHOD_BOTH && (b & 3u) == 1u &&
            cfg->nav.window_size >= cfg->params.window_frames + 1) {
            cfg->nav.keyframe_parallax_rad = 0.02;
        }
        if ((b & 0xC0u) == 0xC0u) cfg->nav.window_filter = 0; /* the single-state EKF */
    } else if ((b & 0xC0u) == 0xC0u) {
        cfg->params.translation_known = 1; /* parity with the filter's translation */
    }
    if ((b & 0x84u) == 0x80u) { /* parity's alarm hold: off, or after 1 or 2 alarms in a row
                                   at the alpha scale 0.3 or unscaled (the default: 0.25, 0.3) */
        cfg->params.alarm_hold_ratio = (b & 2u) ? 1.0 : 0.5;
        cfg->params.alarm_hold_frames = (b & 8u) ? 2 : 1;
        cfg->params.alarm_hold_alpha_scale = (b & 1u) ? 1.0 : 0.3;
        /* every held alarm continues the hold, or none does (the default: 0.4) */
        cfg->params.alarm_hold_min_statistic = (b & 16u) ? 1.0 : 0.0;
        /* the directional hold off, or at its largest level (the default: 0.2) */
        cfg->params.alarm_hold_direction_alpha = (b & 32u) ? 0.0 : 0.4999;
    }
    if ((b & 0x84u) == 0x84u) { /* the ramp test alone (omnibus evidence test off) or no ramp
                                   test; otherwise the default share, 0.6 */
        cfg->params.evidence_ramp_share = (b & 2u) ? 1.0 : 0.0;
    }
    if (b & 8u) cfg->camera_id = 0;
    if (b & 16u) cfg->params.parity_isolation = 0;
    if (b & 32u) cfg->params.exact_depth_covariance = 0;
}

static void get_bytes(const uint8_t *p, size_t len, size_t off, void *out, size_t n) {
    memset(out, 0, n);
    if (off < len) memcpy(out, p + off, (len - off) < n ? (len - off) : n);
}

int fz_compact_to_wire(const uint8_t *payload, size_t len, uint8_t *buf, int cap) {
    sfd_feature_frame_t *f = &g_ff_build;
    memset(f, 0, sizeof *f);
    get_bytes(payload, len, 0, &f->utime, 8);
    get_bytes(payload, len, 8, &f->camera_id, 4);
    get_bytes(payload, len, 12, &f->num_features, 4);
    for (size_t i = 0; i < SFD_FEATURE_FRAME_T_CAPACITY; ++i) {
        const size_t off = FZ_COMPACT_HEADER + i * FZ_COMPACT_FEATURE;
        if (off >= len) break;
        get_bytes(payload, len, off, &f->track_id[i], 8);
        get_bytes(payload, len, off + 8, &f->u[i], 8);
        get_bytes(payload, len, off + 16, &f->v[i], 8);
        get_bytes(payload, len, off + 24, &f->depth[i], 8);
        get_bytes(payload, len, off + 32, &f->depth_var[i], 8);
    }
    return sfd_feature_frame_t_encode(buf, 0, cap, f);
}

void fz_imu_burst(const uint8_t *payload, size_t len) {
    int64_t t0;
    int32_t step;
    uint16_t count;
    sfd_imu_t m;
    get_bytes(payload, len, 0, &t0, 8);
    get_bytes(payload, len, 8, &step, 4);
    get_bytes(payload, len, 12, &count, 2);
    get_bytes(payload, len, 14, m.gyro, 24);
    get_bytes(payload, len, 38, m.accel, 24);
    const int n = count < FZ_BURST_MAX ? count : FZ_BURST_MAX;
    for (int k = 0; k < n; ++k) {
        const uint64_t t = (uint64_t)t0 + (uint64_t)(int64_t)step * (uint64_t)k; /* wraps */
        memcpy(&m.utime, &t, sizeof t);
        const int size = sfd_imu_t_encode(g_msg, 0, (int)sizeof g_msg, &m);
        FZ_CHECK(size > 0);
        fz_handle(SFD_NODE_IMU, g_msg, (size_t)size);
    }
}
