/* SPDX-License-Identifier: MIT */
#include "sfd_node_core.h"

#include <string.h>

static int64_t now_us(const sfd_node_t *n) {
    return n->clock ? n->clock(n->ctx) : 0;
}

static int32_t clamp_i32(int64_t v) {
    return v > INT32_MAX ? INT32_MAX : (v < 0 ? 0 : (int32_t)v);
}

void sfd_node_config_default(sfd_node_config_t *cfg) {
    memset(cfg, 0, sizeof *cfg);
    /* the pipeline's defaults: the window filter, parity with its translation, the alarm hold,
     * the ramp test */
    sfd_pipeline_config_t pc;
    sfd_pipeline_config_default(&pc);
    cfg->params = pc.params;
    cfg->nav = pc.nav;
    cfg->time = pc.time;
    cfg->camera_id = -1;
    cfg->publish_timing = 1;
}

sfd_status_t sfd_node_init(sfd_node_t *node, const sfd_node_config_t *cfg,
                           sfd_node_publish_fn publish, sfd_node_clock_fn clock, void *ctx) {
    if (node == NULL || cfg == NULL || publish == NULL) return SFD_ERR_INVAL;
    sfd_pipeline_config_t pc;
    pc.params = cfg->params;
    pc.nav = cfg->nav;
    pc.time = cfg->time;
    const sfd_status_t s = sfd_pipeline_init(&node->pipe, &pc);
    if (s != SFD_OK) return s;
    node->cfg = *cfg;
    node->publish = publish;
    node->clock = clock;
    node->ctx = ctx;
    node->camera_id = cfg->camera_id;
    for (int k = 0; k < SFD_PIPELINE_FRAME_SLOTS; ++k) {
        node->ingest_utime[k] = INT64_MIN;
        node->ingest_us[k] = 0;
    }
    node->ingest_next = 0;
    node->inputs_since_timing = 0;
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
static int64_t publish_state(sfd_node_t *n, const sfd_pipeline_output_t *o) {
    sfd_nav_state_t *s = &n->wire_state;
    s->utime = o->verdict.utime;
    for (int k = 0; k < 3; ++k) {
        s->position[k] = o->p_IinW_m[k];
        s->velocity[k] = o->v_IinW_m_s[k];
        s->position_var[k] = o->p_var_m2[k];
    }
    for (int k = 0; k < 4; ++k) s->orientation[k] = o->q_ItoW[k];
    const int size = sfd_nav_state_t_encode(n->out_buf, 0, SFD_NODE_MAX_MESSAGE, s);
    return send_out(n, SFD_NODE_OUT_STATE, size, o->verdict.utime);
}

typedef struct {
    int64_t ingest_us, parity_us, association_us, update_us;
} stage_times_t;

/* The counters every SFD_TIMING carries. */
static void fill_counters(const sfd_node_t *n, sfd_timing_t *t) {
    const sfd_pipeline_counters_t *c = &n->pipe.counters;
    t->frames_in = c->frames_in;
    t->frames_refused = c->frames_refused;
    t->frames_processed = c->frames_processed;
    t->frames_untested = c->frames_untested;
    t->imu_in = c->imu_in;
    t->camera_info_in = c->camera_info_in;
    for (int k = 0; k < SFD_REJECT_NUM_REASONS; ++k) t->rejected[k] = c->rejected[k];
}

static void publish_results(sfd_node_t *n, const sfd_pipeline_output_t *o, const stage_times_t *st,
                            int64_t t_start) {
    const sfd_verdict_t *v = &o->verdict;
    sfd_feature_verdict_t *w = &n->wire_verdict;
    w->utime = v->utime;
    w->camera_id = n->camera_id;
    w->num_features = v->num_features;
    for (int i = 0; i < v->num_features; ++i) {
        w->track_id[i] = v->features[i].track_id;
        w->status[i] = v->features[i].status;
        w->statistic[i] = v->features[i].statistic;
        w->stage[i] = v->features[i].stage;
    }
    /* entries past num_features are padding on the wire: zero them for byte-identical logs */
    const int rest = SFD_FEATURE_VERDICT_T_CAPACITY - v->num_features;
    memset(&w->track_id[v->num_features], 0, sizeof(int64_t) * (size_t)rest);
    memset(&w->status[v->num_features], 0, (size_t)rest);
    memset(&w->statistic[v->num_features], 0, sizeof(double) * (size_t)rest);
    memset(&w->stage[v->num_features], 0, (size_t)rest);
    int size = sfd_feature_verdict_t_encode(n->out_buf, 0, SFD_NODE_MAX_MESSAGE, w);
    int64_t publish_us = send_out(n, SFD_NODE_OUT_VERDICT, size, v->utime);
    if (o->has_state) publish_us += publish_state(n, o);
    if (!n->cfg.publish_timing) return;
    sfd_timing_t *t = &n->wire_timing;
    memset(t, 0, sizeof *t);
    t->utime = v->utime;
    t->features_in = v->num_features;
    t->ingest_us = clamp_i32(st->ingest_us);
    t->parity_us = clamp_i32(st->parity_us);
    t->association_us = clamp_i32(st->association_us);
    t->update_us = clamp_i32(st->update_us);
    t->hypotheses_used = o->hypotheses_used;
    t->budget_exhausted = o->budget_exhausted;
    t->total_us = clamp_i32(now_us(n) - t_start + st->ingest_us);
    t->publish_us = clamp_i32(publish_us);
    t->frame_processed = 1;
    fill_counters(n, t);
    size = sfd_timing_t_encode(n->out_buf, 0, SFD_NODE_MAX_MESSAGE, t);
    (void)send_out(n, SFD_NODE_OUT_TIMING, size, v->utime);
    n->inputs_since_timing = 0;
}

/* A status report while no frame is judged (SFD_TIMING with frame_processed 0): the counters,
 * at the newest accepted input time. */
static void publish_status(sfd_node_t *n) {
    sfd_timing_t *t = &n->wire_timing;
    memset(t, 0, sizeof *t);
    const int64_t ti = n->pipe.last_imu_utime, tf = n->pipe.last_frame_utime;
    t->utime = ti > tf ? ti : tf;
    if (t->utime == INT64_MIN) t->utime = 0; /* nothing accepted yet */
    t->frame_processed = 0;
    fill_counters(n, t);
    const int size = sfd_timing_t_encode(n->out_buf, 0, SFD_NODE_MAX_MESSAGE, t);
    (void)send_out(n, SFD_NODE_OUT_TIMING, size, t->utime);
    n->inputs_since_timing = 0;
}

/* Decode time recorded for the frame at utime (0 when not recorded). */
static int64_t take_ingest(sfd_node_t *n, int64_t utime) {
    for (int k = 0; k < SFD_PIPELINE_FRAME_SLOTS; ++k) {
        if (n->ingest_utime[k] == utime) {
            n->ingest_utime[k] = INT64_MIN;
            return n->ingest_us[k];
        }
    }
    return 0;
}

/* Judges every due frame, timing the pipeline's stages, and publishes each one's results. */
static void drain(sfd_node_t *n) {
    for (int guard = 0; guard < SFD_PIPELINE_FRAME_SLOTS && sfd_pipeline_frames_due(&n->pipe) > 0;
         ++guard) {
        stage_times_t times = {0, 0, 0, 0};
        const int64_t t0 = now_us(n);
        sfd_status_t s = sfd_pipeline_detect(&n->pipe);
        const int64_t t1 = now_us(n);
        if (s == SFD_OK) s = sfd_pipeline_associate(&n->pipe);
        const int64_t t2 = now_us(n);
        if (s == SFD_OK) s = sfd_pipeline_update(&n->pipe);
        const int64_t t3 = now_us(n);
        const sfd_pipeline_output_t *o = sfd_pipeline_output(&n->pipe);
        if (s != SFD_OK || o == NULL) { /* cannot happen: a due frame is judged in order */
            sfd_pipeline_count_reject(&n->pipe, SFD_REJECT_CORE);
            return;
        }
        times.parity_us = t1 - t0;
        times.association_us = t2 - t1;
        times.update_us = t3 - t2;
        times.ingest_us = take_ingest(n, o->verdict.utime);
        publish_results(n, o, &times, t0);
    }
}

static void handle_imu(sfd_node_t *n, const void *data, int32_t size) {
    sfd_imu_sample_t s;
    n->pipe.counters.imu_in++;
    const int r = sfd_lcm_decode_imu(data, size, &s);
    if (r != SFD_REJECT_NONE) {
        sfd_pipeline_count_reject(&n->pipe, r);
        return;
    }
    (void)sfd_pipeline_push_imu(&n->pipe, &s); /* rejections are counted by the pipeline */
    drain(n);
}

static void handle_camera_info(sfd_node_t *n, const void *data, int32_t size) {
    sfd_camera_t cam;
    sfd_extrinsics_t ext;
    int32_t id = -1;
    n->pipe.counters.camera_info_in++;
    const int r = sfd_lcm_decode_camera_info(data, size, &n->wire_camera, &cam, &ext, &id);
    if (r != SFD_REJECT_NONE) {
        sfd_pipeline_count_reject(&n->pipe, r);
        return;
    }
    /* The camera is fixed by the config (>= 0) or by the first calibration accepted, whatever
     * its id: a negative id on the wire must not reopen the choice (found by fuzz.camera_info). */
    if ((n->pipe.have_camera || n->camera_id >= 0) && id != n->camera_id) {
        sfd_pipeline_count_reject(&n->pipe, SFD_REJECT_CAMERA_ID);
        return;
    }
    if (sfd_pipeline_set_camera(&n->pipe, &cam, &ext) == SFD_REJECT_NONE) n->camera_id = id;
}

static void handle_features(sfd_node_t *n, const void *data, int32_t size) {
    const int64_t t0 = now_us(n);
    int32_t cam_id = -1;
    int fixed = 0;
    n->pipe.counters.frames_in++;
    int r = sfd_lcm_decode_features(data, size, &n->wire_features, &n->frame, &cam_id, &fixed);
    if (r == SFD_REJECT_NONE && !n->pipe.have_camera) r = SFD_REJECT_NO_CAMERA_INFO;
    if (r == SFD_REJECT_NONE && cam_id != n->camera_id) r = SFD_REJECT_CAMERA_ID;
    if (r != SFD_REJECT_NONE) {
        sfd_pipeline_count_reject(&n->pipe, r);
        n->pipe.counters.frames_refused++;
        return;
    }
    if (sfd_pipeline_push_frame(&n->pipe, &n->frame) != SFD_REJECT_NONE) return; /* counted */
    n->pipe.counters.rejected[SFD_REJECT_DEPTH] += fixed;
    const int k = n->ingest_next;
    n->ingest_next = (k + 1) % SFD_PIPELINE_FRAME_SLOTS;
    n->ingest_utime[k] = n->frame.utime;
    n->ingest_us[k] = now_us(n) - t0;
    drain(n);
}

void sfd_node_handle(sfd_node_t *node, sfd_node_input_t kind, const void *data, int32_t size) {
    node->inputs_since_timing++;
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
                sfd_pipeline_truth(&node->pipe, node->wire_truth.utime, node->wire_truth.position,
                                   node->wire_truth.orientation);
            }
            break;
        default:
            sfd_pipeline_count_reject(&node->pipe, SFD_REJECT_DECODE);
            break;
    }
    /* no frame judged for a while (every input refused, no camera, a time glitch): say so */
    if (node->cfg.publish_timing && node->inputs_since_timing >= SFD_NODE_STATUS_EVERY_INPUTS) {
        publish_status(node);
    }
}

void sfd_node_flush(sfd_node_t *node) {
    sfd_pipeline_flush(&node->pipe);
    drain(node);
}
