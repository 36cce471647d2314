/* SPDX-License-Identifier: MIT */
#include "sfd_node_core.h"

#include <string.h>

static int64_t now_us(const sfd_node_t *n) {
    return n->clock ? n->clock(n->ctx) : 0;
}

static int32_t clamp_i32(int64_t v) {
    return v > INT32_MAX ? INT32_MAX : (v < 0 ? 0 : (int32_t)v);
}

/* Bitwise equality of doubles (a republished calibration is bit-identical). */
static int same_bits(const double *a, const double *b, int n) {
    for (int i = 0; i < n; ++i) {
        uint64_t x, y;
        memcpy(&x, &a[i], sizeof x);
        memcpy(&y, &b[i], sizeof y);
        if (x != y) return 0;
    }
    return 1;
}

static int same_calibration(const sfd_camera_t *a, const sfd_camera_t *b,
                            const sfd_extrinsics_t *ea, const sfd_extrinsics_t *eb) {
    const double ka[4] = {a->fx_px, a->fy_px, a->cx_px, a->cy_px};
    const double kb[4] = {b->fx_px, b->fy_px, b->cx_px, b->cy_px};
    return a->model == b->model && a->width_px == b->width_px && a->height_px == b->height_px &&
           same_bits(ka, kb, 4) && same_bits(a->dist, b->dist, 4) &&
           same_bits(ea->R_CtoI, eb->R_CtoI, 9) && same_bits(ea->p_CinI, eb->p_CinI, 3);
}

static void count(sfd_node_t *n, int reason) {
    if (reason >= 0 && reason < SFD_REJECT_NUM_REASONS) n->counters.rejected[reason]++;
}

sfd_status_t sfd_node_init(sfd_node_t *node, const sfd_node_config_t *cfg,
                           sfd_node_publish_fn publish, sfd_node_clock_fn clock, void *ctx) {
    if (node == NULL || cfg == NULL || publish == NULL) return SFD_ERR_INVAL;
    const sfd_status_t v = sfd_params_validate(&cfg->params);
    if (v != SFD_OK) return v;
    if (cfg->params.method != SFD_METHOD_NONE && cfg->params.method != SFD_METHOD_PARITY) {
        return SFD_ERR_INVAL;
    }
    memset(&node->counters, 0, sizeof node->counters);
    node->cfg = *cfg;
    node->publish = publish;
    node->clock = clock;
    node->ctx = ctx;
    sfd_imu_ring_init(&node->ring);
    node->camera_id = cfg->camera_id;
    node->have_camera = 0;
    for (int k = 0; k < 3; ++k) node->last_utime[k] = INT64_MIN;
    node->have_prev_frame = 0;
    node->prev_frame_utime = 0;
    node->have_pending = 0;
    node->pending_ingest_us = 0;
    return SFD_OK;
}

static void publish_results(sfd_node_t *n, const sfd_frame_t *frame, int64_t ingest_us,
                            int64_t parity_us, int64_t t_start) {
    sfd_feature_verdict_t *w = &n->wire_verdict;
    const sfd_verdict_t *v = &n->verdict;
    w->utime = frame->utime;
    w->camera_id = n->camera_id;
    w->num_features = frame->num_features;
    for (int i = 0; i < frame->num_features; ++i) {
        w->track_id[i] = v->features[i].track_id;
        w->status[i] = v->features[i].status;
        w->statistic[i] = v->features[i].statistic;
        w->stage[i] = v->features[i].stage;
    }
    /* entries past num_features are padding on the wire: zero them for byte-identical logs */
    const int rest = SFD_FEATURE_VERDICT_T_CAPACITY - frame->num_features;
    memset(&w->track_id[frame->num_features], 0, sizeof(int64_t) * (size_t)rest);
    memset(&w->status[frame->num_features], 0, (size_t)rest);
    memset(&w->statistic[frame->num_features], 0, sizeof(double) * (size_t)rest);
    memset(&w->stage[frame->num_features], 0, (size_t)rest);
    int size = sfd_feature_verdict_t_encode(n->out_buf, 0, SFD_NODE_MAX_MESSAGE, w);
    if (size > 0) n->publish(n->ctx, SFD_NODE_OUT_VERDICT, n->out_buf, size, frame->utime);
    n->counters.frames_processed++;
    if (v->num_consistent + v->num_spurious == 0) n->counters.frames_untested++;
    if (!n->cfg.publish_timing) return;
    sfd_timing_t *t = &n->wire_timing;
    memset(t, 0, sizeof *t);
    t->utime = frame->utime;
    t->features_in = frame->num_features;
    t->ingest_us = clamp_i32(ingest_us);
    t->parity_us = clamp_i32(parity_us);
    t->total_us = clamp_i32(now_us(n) - t_start + ingest_us);
    for (int k = 0; k < SFD_REJECT_NUM_REASONS; ++k) t->rejected[k] = n->counters.rejected[k];
    size = sfd_timing_t_encode(n->out_buf, 0, SFD_NODE_MAX_MESSAGE, t);
    if (size > 0) n->publish(n->ctx, SFD_NODE_OUT_TIMING, n->out_buf, size, frame->utime);
}

/* Every feature UNTESTED, stage none: the verdict of a frame the detector could not judge. */
static void untested_verdict(sfd_node_t *n, const sfd_frame_t *frame) {
    sfd_verdict_t *v = &n->verdict;
    memset(v, 0, offsetof(sfd_verdict_t, features));
    v->utime = frame->utime;
    v->num_features = frame->num_features;
    v->num_untested = frame->num_features;
    for (int i = 0; i < frame->num_features; ++i) {
        memset(&v->features[i], 0, sizeof v->features[i]);
        v->features[i].track_id = frame->features[i].track_id;
    }
}

/* Judges one frame. imu_reason: SFD_REJECT_NONE when the IMU may cover it, else why it cannot. */
static void process_frame(sfd_node_t *n, const sfd_frame_t *frame, int64_t ingest_us,
                          int imu_reason) {
    const int64_t t0 = now_us(n);
    sfd_frame_motion_t motion;
    const sfd_frame_motion_t *mp = NULL;
    int reason = imu_reason;
    if (n->cfg.params.method == SFD_METHOD_NONE) {
        untested_verdict(n, frame);
        for (int i = 0; i < frame->num_features; ++i) {
            n->verdict.features[i].status = SFD_VERDICT_CONSISTENT; /* accept all */
        }
        n->verdict.num_untested = 0;
        n->verdict.num_consistent = frame->num_features;
        publish_results(n, frame, ingest_us, 0, t0);
        n->prev_frame_utime = frame->utime;
        n->have_prev_frame = 1;
        return;
    }
    if (n->have_prev_frame && reason == SFD_REJECT_NONE) {
        reason = sfd_assemble_motion(&n->ring, &n->ext, n->cfg.params.gyro_bias_rad_s,
                                     n->prev_frame_utime, frame->utime,
                                     n->cfg.params.max_imu_gap_us, n->imu_scratch, &motion);
        if (reason == SFD_REJECT_NONE) mp = &motion;
    }
    if (n->have_prev_frame && mp == NULL) {
        /* No motion for this interval: the window cannot continue. Start a new one here. */
        count(n, reason);
        sfd_parity_reset(&n->parity);
    }
    const sfd_status_t st = sfd_parity_push_frame(&n->parity, frame, mp, &n->verdict);
    if (st != SFD_OK) {
        count(n, SFD_REJECT_CORE);
        sfd_parity_reset(&n->parity);
        untested_verdict(n, frame);
    }
    const int64_t t1 = now_us(n);
    publish_results(n, frame, ingest_us, t1 - t0, t0);
    n->prev_frame_utime = frame->utime;
    n->have_prev_frame = 1;
}

static void handle_imu(sfd_node_t *n, const void *data, int32_t size) {
    sfd_imu_sample_t s;
    n->counters.imu_in++;
    int r = sfd_lcm_decode_imu(data, size, &s);
    if (r == SFD_REJECT_NONE && s.t_us <= n->last_utime[SFD_NODE_IMU]) r = SFD_REJECT_ORDER;
    if (r != SFD_REJECT_NONE) {
        count(n, r);
        return;
    }
    n->last_utime[SFD_NODE_IMU] = s.t_us;
    r = sfd_imu_ring_push(&n->ring, &s);
    if (r != SFD_REJECT_NONE) count(n, r); /* overflow: stored, oldest dropped */
    if (n->have_pending && s.t_us >= n->pending.utime) {
        n->have_pending = 0;
        process_frame(n, &n->pending, n->pending_ingest_us, SFD_REJECT_NONE);
    }
}

static void handle_camera_info(sfd_node_t *n, const void *data, int32_t size) {
    sfd_camera_t cam;
    sfd_extrinsics_t ext;
    int32_t id = -1;
    n->counters.camera_info_in++;
    const int r = sfd_lcm_decode_camera_info(data, size, &n->wire_camera, &cam, &ext, &id);
    if (r != SFD_REJECT_NONE) {
        count(n, r);
        return;
    }
    /* The camera is fixed by the config (>= 0) or by the first calibration accepted, whatever
     * its id: a negative id on the wire must not reopen the choice (found by fuzz.camera_info). */
    if ((n->have_camera || n->camera_id >= 0) && id != n->camera_id) {
        count(n, SFD_REJECT_CAMERA_ID);
        return;
    }
    if (n->have_camera && same_calibration(&cam, &n->camera, &ext, &n->ext)) {
        return; /* periodic republication of the same calibration */
    }
    if (sfd_parity_init(&n->parity, &n->cfg.params, &cam) != SFD_OK) {
        count(n, SFD_REJECT_CORE);
        return;
    }
    n->camera = cam;
    n->ext = ext;
    n->camera_id = id;
    n->have_camera = 1;
    n->have_prev_frame = 0; /* a new calibration starts a new window */
}

static void handle_features(sfd_node_t *n, const void *data, int32_t size) {
    const int64_t t0 = now_us(n);
    int32_t cam_id = -1;
    int fixed = 0;
    n->counters.frames_in++;
    int r = sfd_lcm_decode_features(data, size, &n->wire_features, &n->frame, &cam_id, &fixed);
    if (r == SFD_REJECT_NONE && !n->have_camera) r = SFD_REJECT_NO_CAMERA_INFO;
    if (r == SFD_REJECT_NONE && cam_id != n->camera_id) r = SFD_REJECT_CAMERA_ID;
    if (r == SFD_REJECT_NONE && n->frame.utime <= n->last_utime[SFD_NODE_FEATURES]) {
        r = SFD_REJECT_ORDER;
    }
    if (r != SFD_REJECT_NONE) {
        count(n, r);
        return;
    }
    n->counters.rejected[SFD_REJECT_DEPTH] += fixed;
    n->last_utime[SFD_NODE_FEATURES] = n->frame.utime;
    if (n->have_pending) {
        /* The previous frame's IMU never came before this frame: judge it without motion. */
        n->have_pending = 0;
        process_frame(n, &n->pending, n->pending_ingest_us, SFD_REJECT_IMU_LATE);
    }
    const int64_t ingest = now_us(n) - t0;
    if (n->cfg.params.method != SFD_METHOD_NONE && n->have_prev_frame &&
        sfd_imu_ring_newest(&n->ring) < n->frame.utime) {
        n->pending = n->frame; /* wait (bounded: until the next frame or the end of input) */
        n->pending_ingest_us = ingest;
        n->have_pending = 1;
        return;
    }
    process_frame(n, &n->frame, ingest, SFD_REJECT_NONE);
}

void sfd_node_handle(sfd_node_t *node, sfd_node_input_t kind, const void *data, int32_t size) {
    switch (kind) {
        case SFD_NODE_IMU:
            handle_imu(node, data, size);
            break;
        case SFD_NODE_CAMERA_INFO:
            handle_camera_info(node, data, size);
            break;
        case SFD_NODE_FEATURES:
            handle_features(node, data, size);
            break;
        default:
            count(node, SFD_REJECT_DECODE);
            break;
    }
}

void sfd_node_flush(sfd_node_t *node) {
    if (node->have_pending) {
        node->have_pending = 0;
        process_frame(node, &node->pending, node->pending_ingest_us, SFD_REJECT_IMU_LATE);
    }
}
