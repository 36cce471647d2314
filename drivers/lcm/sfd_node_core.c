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

void sfd_node_config_default(sfd_node_config_t *cfg) {
    memset(cfg, 0, sizeof *cfg);
    sfd_params_default(&cfg->params);
    cfg->camera_id = -1;
    cfg->publish_timing = 1;
    sfd_nav_config_default(&cfg->nav);
}

sfd_status_t sfd_node_init(sfd_node_t *node, const sfd_node_config_t *cfg,
                           sfd_node_publish_fn publish, sfd_node_clock_fn clock, void *ctx) {
    if (node == NULL || cfg == NULL || publish == NULL) return SFD_ERR_INVAL;
    const sfd_status_t v = sfd_params_validate(&cfg->params);
    if (v != SFD_OK) return v;
    const int32_t m = cfg->params.method;
    const int needs_filter = m == SFD_METHOD_OPRF || m == SFD_METHOD_RANSAC1 ||
                             m == SFD_METHOD_RANSACF || m == SFD_METHOD_BOTH;
    if (needs_filter && !cfg->nav.enabled) return SFD_ERR_INVAL;
    if (sfd_nav_init(&node->nav, &cfg->nav, &cfg->params) != SFD_OK) return SFD_ERR_INVAL;
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

/* Hands the first size bytes of out_buf to the publish callback; returns the time it took (the
 * transport's send path, reported as SFD_TIMING.publish_us). */
static int64_t send_out(sfd_node_t *n, sfd_node_output_t kind, int size, int64_t utime) {
    if (size <= 0) return 0;
    const int64_t t0 = now_us(n);
    n->publish(n->ctx, kind, n->out_buf, size, utime);
    return now_us(n) - t0;
}

/* SFD_STATE after the frame; returns the time spent in the publish callback. */
static int64_t publish_state(sfd_node_t *n, int64_t utime) {
    const sfd_ekf_t *e = &n->nav.ekf;
    sfd_nav_state_t *s = &n->wire_state;
    s->utime = utime;
    for (int k = 0; k < 3; ++k) {
        s->position[k] = e->p_IinW_m[k];
        s->velocity[k] = e->v_IinW_m_s[k];
        s->position_var[k] = e->P[(SFD_EKF_IDX_P + k) * SFD_EKF_DIM + SFD_EKF_IDX_P + k];
    }
    for (int k = 0; k < 4; ++k) s->orientation[k] = e->q_ItoW[k];
    const int size = sfd_nav_state_t_encode(n->out_buf, 0, SFD_NODE_MAX_MESSAGE, s);
    return send_out(n, SFD_NODE_OUT_STATE, size, utime);
}

typedef struct {
    int64_t ingest_us, parity_us, association_us, update_us;
    int32_t hypotheses_used;
    int8_t budget_exhausted;
} stage_times_t;

static void publish_results(sfd_node_t *n, const sfd_frame_t *frame, const stage_times_t *st,
                            int64_t t_start) {
    const int64_t ingest_us = st->ingest_us;
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
    int64_t publish_us = send_out(n, SFD_NODE_OUT_VERDICT, size, frame->utime);
    n->counters.frames_processed++;
    if (v->num_consistent + v->num_spurious == 0) n->counters.frames_untested++;
    if (n->cfg.nav.enabled && n->nav.ready) publish_us += publish_state(n, frame->utime);
    if (!n->cfg.publish_timing) return;
    sfd_timing_t *t = &n->wire_timing;
    memset(t, 0, sizeof *t);
    t->utime = frame->utime;
    t->features_in = frame->num_features;
    t->ingest_us = clamp_i32(ingest_us);
    t->parity_us = clamp_i32(st->parity_us);
    t->association_us = clamp_i32(st->association_us);
    t->update_us = clamp_i32(st->update_us);
    t->hypotheses_used = st->hypotheses_used;
    t->budget_exhausted = st->budget_exhausted;
    t->total_us = clamp_i32(now_us(n) - t_start + ingest_us);
    t->publish_us = clamp_i32(publish_us);
    for (int k = 0; k < SFD_REJECT_NUM_REASONS; ++k) t->rejected[k] = n->counters.rejected[k];
    size = sfd_timing_t_encode(n->out_buf, 0, SFD_NODE_MAX_MESSAGE, t);
    (void)send_out(n, SFD_NODE_OUT_TIMING, size, frame->utime);
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

static void recount(sfd_verdict_t *v) {
    v->num_consistent = v->num_spurious = v->num_untested = 0;
    for (int i = 0; i < v->num_features; ++i) {
        if (v->features[i].status == SFD_VERDICT_CONSISTENT)
            v->num_consistent++;
        else if (v->features[i].status == SFD_VERDICT_SPURIOUS)
            v->num_spurious++;
        else
            v->num_untested++;
    }
}

/* The parity detector on this frame (methods PARITY and BOTH): verdict in n->verdict. */
static void run_parity(sfd_node_t *n, const sfd_frame_t *frame, int imu_reason) {
    sfd_frame_motion_t motion;
    const sfd_frame_motion_t *mp = NULL;
    int reason = imu_reason;
    if (n->have_prev_frame && reason == SFD_REJECT_NONE) {
        /* the filter's gyro bias once it runs (estimated at rest and online), else the config's */
        const double *bias = (n->cfg.nav.enabled && n->nav.ready) ? n->nav.ekf.bg_rad_s
                                                                  : n->cfg.params.gyro_bias_rad_s;
        reason = sfd_assemble_motion(&n->ring, &n->ext, bias, n->prev_frame_utime, frame->utime,
                                     n->cfg.params.max_imu_gap_us, n->imu_scratch, &motion);
        if (reason == SFD_REJECT_NONE) {
            mp = &motion;
            motion.translation_known = 0;
            /* translation_known: the camera translation between the frames from the filter (the
             * previous frame's posterior and this frame's prior), in the previous camera frame */
            if (n->cfg.params.translation_known && n->cfg.nav.enabled && n->nav.ready &&
                n->nav.have_prev) {
                double R_CtoW[9], p_C[3];
                sfd_ekf_camera_pose(&n->nav.ekf, &n->nav.ekf_cam.ext, R_CtoW, p_C);
                const double *Rp = n->nav.prev_R_CtoW;
                for (int r = 0; r < 3; ++r) {
                    motion.p_CcurInCprev_m[r] = 0.0;
                    for (int k = 0; k < 3; ++k) {
                        motion.p_CcurInCprev_m[r] +=
                            Rp[3 * k + r] * (p_C[k] - n->nav.prev_p_CinW_m[k]);
                    }
                }
                motion.translation_known = 1;
            }
        }
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
}

/* The earliest IMU time a frame after the one at t_us can need: the parity motion starts at t_us,
 * a running filter at its own time, a filter waiting to start at rest looks back init_rest_s
 * from the next frame (so at most that far from t_us). Older samples may be overwritten without
 * a loss (sfd_imu_ring_push). */
static int64_t imu_needed_from(const sfd_node_t *n, int64_t t_us) {
    int64_t from = t_us;
    const sfd_nav_t *nav = &n->nav;
    if (n->cfg.nav.enabled && nav->ready && nav->ekf_utime < from) from = nav->ekf_utime;
    if (n->cfg.nav.enabled && !nav->ready && !n->cfg.nav.init_from_truth) {
        const int64_t rest_us = (int64_t)(n->cfg.nav.init_rest_s * 1e6);
        from = (t_us > INT64_MIN + rest_us) ? t_us - rest_us : INT64_MIN;
    }
    return from;
}

/* Judges one frame. imu_reason: SFD_REJECT_NONE when the IMU may cover it, else why it cannot. */
static void process_frame(sfd_node_t *n, const sfd_frame_t *frame, int64_t ingest_us,
                          int imu_reason) {
    const int64_t t0 = now_us(n);
    const int32_t method = n->cfg.params.method;
    stage_times_t times = {ingest_us, 0, 0, 0, 0, 0};
    /* The filter first: its propagation needs the same IMU as the parity motion. */
    int nav_ok = 0;
    if (n->cfg.nav.enabled && imu_reason == SFD_REJECT_NONE) {
        const int r =
            sfd_nav_advance(&n->nav, &n->ring, frame->utime, n->imu_scratch, SFD_MAX_IMU_SAMPLES);
        if (r != SFD_REJECT_NONE) count(n, r);
        nav_ok = (r == SFD_REJECT_NONE) && n->nav.ready;
    } else if (n->cfg.nav.enabled && n->nav.ready) {
        n->nav.ready = 0; /* no IMU for this interval: restart from gravity later */
    }
    if (method == SFD_METHOD_PARITY || method == SFD_METHOD_BOTH) {
        run_parity(n, frame, imu_reason);
    } else {
        untested_verdict(n, frame);
        if (method == SFD_METHOD_NONE) {
            for (int i = 0; i < frame->num_features; ++i) {
                n->verdict.features[i].status = SFD_VERDICT_CONSISTENT; /* accept all */
            }
        }
    }
    const int64_t t1 = now_us(n);
    times.parity_us = t1 - t0;
    if (nav_ok) {
        /* PARITY: the filter uses what parity accepted; BOTH: OPRF judges parity's survivors */
        for (int i = 0; i < frame->num_features; ++i) {
            const int8_t ps = n->verdict.features[i].status;
            n->skip[i] = (uint8_t)((method == SFD_METHOD_PARITY && ps != SFD_VERDICT_CONSISTENT) ||
                                   (method == SFD_METHOD_BOTH && ps == SFD_VERDICT_SPURIOUS));
        }
        /* parity undistorted this frame's features with the same camera: reuse them */
        const int parity_ran = method == SFD_METHOD_PARITY || method == SFD_METHOD_BOTH;
        const int32_t nm =
            sfd_nav_build(&n->nav, &n->camera, frame, n->skip, parity_ran ? &n->parity : NULL);
        sfd_nav_t *nv = &n->nav;
        const sfd_status_t s1 =
            sfd_assoc_select(&nv->assoc, &nv->ekf, &nv->ekf_cam, nv->prev_R_CtoW, nv->prev_p_CinW_m,
                             nv->matches, nm, &nv->result);
        const int64_t t2 = now_us(n);
        /* The window filter makes the update itself (sfd_nav_finish): the association's update
         * then runs on a copy, for its verdicts only. */
        sfd_ekf_t *assoc_ekf = &nv->ekf;
        if (n->cfg.nav.window_filter) {
            nv->ekf_scratch = nv->ekf;
            assoc_ekf = &nv->ekf_scratch;
        }
        const sfd_status_t s2 =
            (s1 == SFD_OK)
                ? sfd_assoc_apply(&nv->assoc, assoc_ekf, &nv->ekf_cam, nv->matches, nm, &nv->result)
                : s1;
        const int64_t t3 = now_us(n);
        times.association_us = t2 - t1;
        times.update_us = t3 - t2;
        if (s1 != SFD_OK || s2 != SFD_OK || nv->result.update_status != SFD_OK) {
            count(n, SFD_REJECT_CORE);
        }
        if (s1 == SFD_OK && s2 == SFD_OK) {
            times.hypotheses_used = nv->result.hypotheses_used;
            times.budget_exhausted = (int8_t)nv->result.budget_exhausted;
            const int assoc_verdicts = method == SFD_METHOD_OPRF || method == SFD_METHOD_RANSAC1 ||
                                       method == SFD_METHOD_RANSACF || method == SFD_METHOD_BOTH;
            for (int i = 0; assoc_verdicts && i < frame->num_features; ++i) {
                const int32_t k = nv->feature_match[i];
                sfd_feature_result_t *f = &n->verdict.features[i];
                if (k < 0) continue; /* BOTH: parity's verdict stays; others: UNTESTED */
                f->status = nv->result.status[k];
                f->stage = nv->result.stage[k];
                f->statistic = nv->result.statistic[k];
            }
        }
    }
    recount(&n->verdict);
    for (int i = 0; i < frame->num_features; ++i) {
        n->final_status[i] = n->verdict.features[i].status;
    }
    if (n->cfg.nav.enabled) {
        const int64_t t4 = now_us(n);
        sfd_nav_finish(&n->nav, frame, n->final_status);
        if (n->cfg.nav.window_filter) times.update_us += now_us(n) - t4;
    }
    publish_results(n, frame, &times, t0);
    n->prev_frame_utime = frame->utime;
    n->have_prev_frame = 1;
    sfd_imu_ring_set_needed(&n->ring, imu_needed_from(n, frame->utime));
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
    sfd_nav_set_camera(&n->nav, &cam, &ext);
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
    const int needs_imu = n->cfg.params.method != SFD_METHOD_NONE || n->cfg.nav.enabled;
    if (needs_imu && (n->have_prev_frame || n->cfg.nav.enabled) &&
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
        case SFD_NODE_TRUTH:
            if (node->cfg.nav.init_from_truth && data != NULL && size > 0 &&
                sfd_lcm_decode_truth(data, size, &node->wire_truth, &node->wire_truth_v1) ==
                    SFD_REJECT_NONE) {
                sfd_nav_truth(&node->nav, node->wire_truth.utime, node->wire_truth.position,
                              node->wire_truth.orientation);
                /* the filter may have started from a TRUTH older than the last frame */
                if (node->ring.need_known) { /* a frame was judged, at prev_frame_utime */
                    sfd_imu_ring_set_needed(&node->ring,
                                            imu_needed_from(node, node->prev_frame_utime));
                }
            }
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
