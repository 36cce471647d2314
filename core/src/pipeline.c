/* SPDX-License-Identifier: MIT */
/* The transport-free pipeline (sfd_pipeline.h): input ordering, the frame slots, and the three
 * judgement stages over the IMU ring, the navigation side (nav.c) and the parity detector. */
#include "sfd/sfd_pipeline.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

#include "bits_equal.h"
#include "track_index.h"

const char *sfd_reject_reason_str(int reason) {
    static const char *const names[SFD_REJECT_NUM_REASONS] = {"decode",
                                                              "count",
                                                              "nonfinite",
                                                              "order",
                                                              "camera_id",
                                                              "depth",
                                                              "no_camera_info",
                                                              "imu_gap",
                                                              "imu_late",
                                                              "imu_overflow",
                                                              "capacity",
                                                              "core",
                                                              "time_jump",
                                                              "restart",
                                                              "feature_nonfinite",
                                                              "feature_duplicate",
                                                              "feature_outside",
                                                              "calib_intrinsics",
                                                              "calib_distortion",
                                                              "calib_extrinsics",
                                                              "frame_gap"};
    if (reason < 0 || reason >= SFD_REJECT_NUM_REASONS) return "unknown";
    return names[reason];
}

void sfd_pipeline_count_reject(sfd_pipeline_t *p, int reason) {
    if (p != NULL && reason >= 0 && reason < SFD_REJECT_NUM_REASONS) p->counters.rejected[reason]++;
}

/* A republished calibration is bit-identical. */
static int same_calibration(const sfd_camera_t *a, const sfd_camera_t *b,
                            const sfd_extrinsics_t *ea, const sfd_extrinsics_t *eb) {
    const double ka[4] = {a->fx_px, a->fy_px, a->cx_px, a->cy_px};
    const double kb[4] = {b->fx_px, b->fy_px, b->cx_px, b->cy_px};
    return a->model == b->model && a->width_px == b->width_px && a->height_px == b->height_px &&
           sfd_bits_equal(ka, kb, 4) && sfd_bits_equal(a->dist, b->dist, 4) &&
           sfd_bits_equal(ea->R_CtoI, eb->R_CtoI, 9) && sfd_bits_equal(ea->p_CinI, eb->p_CinI, 3);
}

void sfd_pipeline_config_default(sfd_pipeline_config_t *cfg) {
    if (cfg == NULL) return;
    memset(cfg, 0, sizeof *cfg);
    sfd_params_default(&cfg->params);
    /* the pipeline runs the window filter: parity takes the translation from it (Section III-A),
     * and with it the alarm hold, paid out of alpha by alarm_hold_alpha_scale (core/docs/
     * parity_space.md "Alarm hold"; docs/evaluation.md: V1_02 semi-real parity F1 0.813 -> 0.864
     * at about the same clean-log false-alarm rate), and the ramp test beside the evidence test
     * (parity_space.md "Ramp"; docs/evaluation.md, 10 seeds: mistracking and moving-object
     * `both` F1 +0.015 and +0.025); a held alarm below 0.4 times the full threshold ends the
     * hold (parity_space.md "Alarm hold"; docs/evaluation.md "Releasing the hold", 10 seeds:
     * `both` F1 +0.002..+0.003 on V1_02 semi-real and the two flights, false alarms 8-13 % fewer);
     * a held track with a fitted motion is tested one-sided along its direction at 0.2
     * (parity_space.md "Directional hold"; docs/evaluation.md "Directional hold", 10 seeds:
     * `both` F1 +0.009 on V1_02 semi-real, +0.008 and +0.010 on mistracking and moving-object,
     * every seed gaining, false alarms 0.52 -> 0.45 % on V1_02 semi-real)
     */
    cfg->params.translation_known = 1;
    cfg->params.alarm_hold_ratio = 0.25;
    cfg->params.alarm_hold_min_statistic = 0.4;
    cfg->params.evidence_ramp_share = 0.6;
    cfg->params.alarm_hold_direction_alpha = 0.2;
    sfd_nav_config_default(&cfg->nav);
    sfd_time_guard_params_default(&cfg->time);
}

sfd_status_t sfd_pipeline_init(sfd_pipeline_t *p, const sfd_pipeline_config_t *cfg) {
    if (p == NULL || cfg == NULL) return SFD_ERR_INVAL;
    const sfd_status_t v = sfd_params_validate(&cfg->params);
    if (v != SFD_OK) return v;
    const int32_t m = cfg->params.method;
    const int needs_filter = m == SFD_METHOD_OPRF || m == SFD_METHOD_RANSAC1 ||
                             m == SFD_METHOD_RANSACF || m == SFD_METHOD_BOTH;
    if (needs_filter && !cfg->nav.enabled) return SFD_ERR_INVAL;
    if (sfd_time_guard_params_validate(&cfg->time) != SFD_OK) return SFD_ERR_INVAL;
    /* method both: parity at share * alpha, then OPRF on its survivors at (1 - share) * alpha */
    p->stage_params = cfg->params;
    sfd_params_t oprf_params = cfg->params;
    if (m == SFD_METHOD_BOTH) {
        p->stage_params.false_alarm_rate *= cfg->params.both_parity_share;
        oprf_params.false_alarm_rate *= 1.0 - cfg->params.both_parity_share;
    }
    if (sfd_nav_init(&p->nav, &cfg->nav, &oprf_params) != SFD_OK) return SFD_ERR_INVAL;
    (void)sfd_time_guard_init(&p->imu_time, &cfg->time); /* validated above */
    (void)sfd_time_guard_init(&p->frame_time, &cfg->time);
    p->cfg = *cfg;
    memset(&p->counters, 0, sizeof p->counters);
    sfd_imu_ring_init(&p->ring);
    p->have_camera = 0;
    p->last_imu_utime = INT64_MIN;
    p->last_frame_utime = INT64_MIN;
    p->prev_frame_utime = 0;
    p->have_prev_frame = 0;
    for (int k = 0; k < SFD_PIPELINE_FRAME_SLOTS; ++k) {
        p->slot_state[k] = SFD_PIPELINE_SLOT_FREE;
        p->slot_reason[k] = SFD_REJECT_NONE;
        p->slot_seq[k] = 0;
        p->slot_restart[k] = 0;
    }
    p->next_seq = 0;
    p->period_count = 0;
    p->period_next = 0;
    p->cur_slot = -1;
    p->stage = 0;
    p->nav_ok = 0;
    p->num_matches = 0;
    p->select_status = SFD_OK;
    p->have_output = 0;
    return SFD_OK;
}

int sfd_pipeline_set_camera(sfd_pipeline_t *p, const sfd_camera_t *cam,
                            const sfd_extrinsics_t *ext) {
    if (p == NULL || cam == NULL || ext == NULL) return SFD_REJECT_CORE;
    if (p->have_camera && same_calibration(cam, &p->camera, ext, &p->ext)) {
        return SFD_REJECT_NONE; /* periodic republication of the same calibration */
    }
    if (sfd_parity_init(&p->parity, &p->stage_params, cam) != SFD_OK) {
        sfd_pipeline_count_reject(p, SFD_REJECT_CORE);
        return SFD_REJECT_CORE;
    }
    p->camera = *cam;
    p->ext = *ext;
    sfd_nav_set_camera(&p->nav, cam, ext);
    p->have_camera = 1;
    p->have_prev_frame = 0; /* a changed calibration restarts the window */
    return SFD_REJECT_NONE;
}

static int waiting_slot(const sfd_pipeline_t *p) {
    for (int k = 0; k < SFD_PIPELINE_FRAME_SLOTS; ++k) {
        if (p->slot_state[k] == SFD_PIPELINE_SLOT_WAITING) return k;
    }
    return -1;
}

static void make_due(sfd_pipeline_t *p, int slot, int reason) {
    p->slot_state[slot] = SFD_PIPELINE_SLOT_DUE;
    p->slot_reason[slot] = reason;
}

/* The verdict of the time policy as a rejection reason (ACCEPT, RESYNC: none). */
static int time_reason(sfd_time_verdict_t v) {
    if (v == SFD_TIME_ORDER) return SFD_REJECT_ORDER;
    if (v == SFD_TIME_JUMP) return SFD_REJECT_TIME_JUMP;
    return SFD_REJECT_NONE;
}

/* A new IMU time base: the old samples are of no use to any frame to come, and the filter's time
 * refers to the old base. A frame waiting for IMU of the old base will not get it. */
static void restart_imu_side(sfd_pipeline_t *p) {
    sfd_pipeline_count_reject(p, SFD_REJECT_RESTART);
    sfd_imu_ring_init(&p->ring);
    p->nav.ready = 0;
    const int w = waiting_slot(p);
    if (w >= 0) make_due(p, w, SFD_REJECT_IMU_GAP);
}

/* 1 when every axis of the sample is finite and within the physical bounds (sfd_imu.h). */
static int imu_values_plausible(const sfd_imu_sample_t *s) {
    for (int k = 0; k < 3; ++k) {
        if (!(fabs(s->gyro_rad_s[k]) <= SFD_IMU_MAX_GYRO_RAD_S) ||
            !(fabs(s->accel_m_s2[k]) <= SFD_IMU_MAX_ACCEL_M_S2)) {
            return 0; /* NaN fails the comparison too */
        }
    }
    return 1;
}

int sfd_pipeline_push_imu(sfd_pipeline_t *p, const sfd_imu_sample_t *s) {
    if (p == NULL || s == NULL) return SFD_REJECT_DECODE;
    if (!imu_values_plausible(s)) {
        sfd_pipeline_count_reject(p, SFD_REJECT_NONFINITE);
        return SFD_REJECT_NONFINITE;
    }
    const sfd_time_verdict_t v = sfd_time_guard_check(&p->imu_time, s->t_us, &p->frame_time);
    const int tr = time_reason(v);
    if (tr != SFD_REJECT_NONE) {
        sfd_pipeline_count_reject(p, tr);
        return tr;
    }
    if (v == SFD_TIME_RESYNC) restart_imu_side(p);
    p->last_imu_utime = s->t_us;
    const int r = sfd_imu_ring_push(&p->ring, s);
    sfd_pipeline_count_reject(p, r); /* overflow: stored, oldest dropped */
    const int w = waiting_slot(p);
    if (w >= 0 && s->t_us >= p->frames[w].utime) make_due(p, w, SFD_REJECT_NONE);
    return r;
}

/* The frame period: the median of the last in-step intervals (insertion sort of at most
 * SFD_PIPELINE_PERIOD_SAMPLES values). */
static int64_t frame_period(const sfd_pipeline_t *p) {
    int64_t v[SFD_PIPELINE_PERIOD_SAMPLES] = {0};
    const int32_t n = p->period_count;
    for (int32_t i = 0; i < n; ++i) {
        const int64_t x = p->period_us[i];
        int32_t j = i;
        while (j > 0 && v[j - 1] > x) {
            v[j] = v[j - 1];
            --j;
        }
        v[j] = x;
    }
    return v[n / 2];
}

/* An accepted interval dt > 0 (within the time horizon): k periods count k - 1 missing frames
 * once 4 intervals are known; in-step intervals (<= 1.5 periods) feed the period. */
static void count_frame_gap(sfd_pipeline_t *p, int64_t dt_us) {
    int in_step = 1;
    if (p->period_count >= 4) {
        const int64_t period = frame_period(p);
        if (period > 0 && dt_us > period + period / 2) {
            in_step = 0;
            const int64_t missing = (dt_us + period / 2) / period - 1;
            if (missing > 0) p->counters.rejected[SFD_REJECT_FRAME_GAP] += missing;
        }
    }
    if (!in_step) return;
    p->period_us[p->period_next] = dt_us;
    p->period_next = (p->period_next + 1) % SFD_PIPELINE_PERIOD_SAMPLES;
    if (p->period_count < SFD_PIPELINE_PERIOD_SAMPLES) p->period_count++;
}

/* Counts an accepted frame's malformed features (they stay in the frame; the detectors judge
 * them as before): a NaN/Inf pixel, a track id repeated in the frame, a pixel outside the
 * calibrated image. */
static void count_malformed_features(sfd_pipeline_t *p, const sfd_frame_t *frame) {
    const sfd_track_index_t dup =
        sfd_track_index_i16(p->dup_index, SFD_PIPELINE_DUP_SLOTS, &frame->features[0].track_id,
                            sizeof frame->features[0], frame->num_features);
    sfd_track_index_clear(&dup);
    const double w = (double)p->camera.width_px, h = (double)p->camera.height_px;
    for (int32_t i = 0; i < frame->num_features; ++i) {
        const sfd_feature_t *f = &frame->features[i];
        if (!isfinite(f->u_px) || !isfinite(f->v_px)) {
            p->counters.rejected[SFD_REJECT_FEATURE_NONFINITE]++;
        } else if (!(f->u_px >= 0.0 && f->u_px < w && f->v_px >= 0.0 && f->v_px < h)) {
            p->counters.rejected[SFD_REJECT_FEATURE_OUTSIDE]++;
        }
        /* load factor <= 1/2: the table is never full */
        const int32_t first = sfd_track_index_add_first(&dup, f->track_id, i);
        if (first >= 0 && first != i) p->counters.rejected[SFD_REJECT_FEATURE_DUPLICATE]++;
    }
}

static int push_frame(sfd_pipeline_t *p, const sfd_frame_t *frame);

int sfd_pipeline_push_frame(sfd_pipeline_t *p, const sfd_frame_t *frame) {
    if (p == NULL || frame == NULL) return SFD_REJECT_DECODE;
    const int r = push_frame(p, frame);
    if (r != SFD_REJECT_NONE) p->counters.frames_refused++;
    return r;
}

static int push_frame(sfd_pipeline_t *p, const sfd_frame_t *frame) {
    int r = SFD_REJECT_NONE;
    if (!p->have_camera) {
        r = SFD_REJECT_NO_CAMERA_INFO;
    } else if (frame->num_features < 0 || frame->num_features > SFD_MAX_FEATURES) {
        r = SFD_REJECT_CAPACITY;
    }
    if (r != SFD_REJECT_NONE) {
        sfd_pipeline_count_reject(p, r);
        return r;
    }
    int slot = -1;
    for (int k = 0; k < SFD_PIPELINE_FRAME_SLOTS && slot < 0; ++k) {
        if (p->slot_state[k] == SFD_PIPELINE_SLOT_FREE) slot = k;
    }
    const int w = waiting_slot(p);
    if (slot < 0) { /* the caller did not judge due frames; the frame never becomes a reference */
        if (w >= 0) make_due(p, w, SFD_REJECT_IMU_LATE);
        sfd_pipeline_count_reject(p, SFD_REJECT_CAPACITY);
        return SFD_REJECT_CAPACITY;
    }
    const sfd_time_verdict_t v = sfd_time_guard_check(&p->frame_time, frame->utime, &p->imu_time);
    r = time_reason(v);
    if (r != SFD_REJECT_NONE) {
        sfd_pipeline_count_reject(p, r);
        return r;
    }
    /* The waiting frame's IMU never came before this frame: it is judged without motion. */
    if (w >= 0) make_due(p, w, SFD_REJECT_IMU_LATE);
    p->slot_restart[slot] = (v == SFD_TIME_RESYNC);
    if (v == SFD_TIME_RESYNC || p->last_frame_utime == INT64_MIN) {
        p->period_count = 0; /* no interval from another time base */
        p->period_next = 0;
    } else {
        count_frame_gap(p, frame->utime - p->last_frame_utime);
    }
    count_malformed_features(p, frame);
    p->last_frame_utime = frame->utime;
    const size_t used =
        offsetof(sfd_frame_t, features) + (size_t)frame->num_features * sizeof frame->features[0];
    memcpy(&p->frames[slot], frame, used);
    p->slot_seq[slot] = p->next_seq++;
    /* Wait for the IMU (bounded: until the next frame or the end of input) when the frame needs
     * it: for the parity motion from the previous frame, or for the filter. */
    const int needs_imu = p->cfg.params.method != SFD_METHOD_NONE || p->cfg.nav.enabled;
    const int has_interval = p->have_prev_frame || p->cfg.nav.enabled;
    if (needs_imu && has_interval && sfd_imu_ring_newest(&p->ring) < frame->utime) {
        p->slot_state[slot] = SFD_PIPELINE_SLOT_WAITING;
        p->slot_reason[slot] = SFD_REJECT_NONE;
    } else {
        make_due(p, slot, SFD_REJECT_NONE);
    }
    return SFD_REJECT_NONE;
}

void sfd_pipeline_flush(sfd_pipeline_t *p) {
    if (p == NULL) return;
    const int w = waiting_slot(p);
    if (w >= 0) make_due(p, w, SFD_REJECT_IMU_LATE);
}

/* The earliest IMU time a frame after the one at t_us can need: the parity motion starts at t_us,
 * a running filter at its own time, a filter waiting to start at rest looks back init_rest_s
 * from the next frame (so at most that far from t_us). Older samples may be overwritten without
 * a loss (sfd_imu_ring_push). */
static int64_t imu_needed_from(const sfd_pipeline_t *p, int64_t t_us) {
    int64_t from = t_us;
    const sfd_nav_t *nav = &p->nav;
    if (p->cfg.nav.enabled && nav->ready && nav->ekf_utime < from) from = nav->ekf_utime;
    if (p->cfg.nav.enabled && !nav->ready && !p->cfg.nav.init_from_truth) {
        const int64_t rest_us = (int64_t)(p->cfg.nav.init_rest_s * 1e6);
        /* The ring's span when full, at the rate seen so far: a ring too short for the rest
         * window makes the start use what it holds (nav.c), so no older sample is needed. */
        const sfd_imu_ring_t *r = &p->ring;
        const double span_full_us =
            r->count >= 2 ? (double)(sfd_imu_ring_newest(r) - r->samples[r->head].t_us) *
                                (double)(SFD_IMU_RING_CAPACITY - 1) / (double)(r->count - 1)
                          : 1e300;
        if (span_full_us >= (double)rest_us) {
            from = (t_us > INT64_MIN + rest_us) ? t_us - rest_us : INT64_MIN;
        }
    }
    return from;
}

void sfd_pipeline_truth(sfd_pipeline_t *p, int64_t utime, const double p_m[3],
                        const double q_wxyz[4]) {
    if (p == NULL || p_m == NULL || q_wxyz == NULL || !p->cfg.nav.init_from_truth) return;
    sfd_nav_truth(&p->nav, utime, p_m, q_wxyz);
    /* the filter may have started from a TRUTH older than the last frame */
    if (p->ring.need_known) { /* a frame was judged, at prev_frame_utime */
        sfd_imu_ring_set_needed(&p->ring, imu_needed_from(p, p->prev_frame_utime));
    }
}

sfd_status_t sfd_pipeline_start_at(sfd_pipeline_t *p, int64_t utime, const double p_m[3],
                                   const double v_m_s[3], const double q_ItoW[4],
                                   const double bg_rad_s[3], const double ba_m_s2[3],
                                   const double p0_diag[SFD_EKF_DIM]) {
    if (p == NULL) return SFD_ERR_INVAL;
    if (p->cur_slot >= 0) return SFD_ERR_STATE;
    const sfd_status_t st =
        sfd_nav_start_at(&p->nav, utime, p_m, v_m_s, q_ItoW, bg_rad_s, ba_m_s2, p0_diag);
    if (st == SFD_OK && p->ring.need_known) {
        sfd_imu_ring_set_needed(&p->ring, imu_needed_from(p, p->prev_frame_utime));
    }
    return st;
}

sfd_status_t sfd_pipeline_known_landmark(sfd_pipeline_t *p, int64_t track_id, const double p_W_m[3],
                                         const double cov_m2[9], int64_t utime) {
    if (p == NULL) return SFD_ERR_INVAL;
    /* not between a frame's stages: its matches refer to the map's entries (sfd_match_t) */
    if (!p->cfg.nav.enabled || p->cur_slot >= 0) return SFD_ERR_STATE;
    return sfd_landmark_set(&p->nav.map, track_id, p_W_m, cov_m2, utime, NULL);
}

int32_t sfd_pipeline_frames_due(const sfd_pipeline_t *p) {
    if (p == NULL) return 0;
    int32_t n = 0;
    for (int k = 0; k < SFD_PIPELINE_FRAME_SLOTS; ++k) {
        if (p->slot_state[k] == SFD_PIPELINE_SLOT_DUE) n++;
    }
    return n;
}

/* Every feature UNTESTED, stage none: the verdict of a frame the detector could not judge. */
static void untested_verdict(sfd_verdict_t *v, const sfd_frame_t *frame) {
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

/* The camera translation between the previous frame and this one from the filter (the previous
 * frame's posterior and this frame's prior), in the previous camera frame (translation_known). */
static void filter_translation(const sfd_nav_t *nav, sfd_frame_motion_t *motion) {
    double R_CtoW[9], p_C[3];
    sfd_ekf_camera_pose(&nav->ekf, &nav->ekf_cam.ext, R_CtoW, p_C);
    const double *Rp = nav->prev_R_CtoW;
    for (int r = 0; r < 3; ++r) {
        motion->p_CcurInCprev_m[r] = 0.0;
        for (int k = 0; k < 3; ++k) {
            motion->p_CcurInCprev_m[r] += Rp[3 * k + r] * (p_C[k] - nav->prev_p_CinW_m[k]);
        }
    }
    motion->translation_known = 1;
}

/* The parity detector on the frame (methods PARITY and BOTH): verdict in p->out.verdict. */
static void run_parity(sfd_pipeline_t *p, const sfd_frame_t *frame, int imu_reason) {
    sfd_frame_motion_t motion;
    const sfd_frame_motion_t *mp = NULL;
    int reason = imu_reason;
    const int filter_runs = p->cfg.nav.enabled && p->nav.ready;
    if (p->have_prev_frame && reason == SFD_REJECT_NONE) {
        /* the filter's gyro bias once it runs (estimated at rest and online), else the config's */
        const double *bias = filter_runs ? p->nav.ekf.bg_rad_s : p->cfg.params.gyro_bias_rad_s;
        reason = sfd_assemble_motion(&p->ring, &p->ext, bias, p->prev_frame_utime, frame->utime,
                                     p->cfg.params.max_imu_gap_us, &motion);
        if (reason == SFD_REJECT_NONE) {
            mp = &motion;
            motion.translation_known = 0;
            /* the single-state EKF: its translation between the two frames, taken as exact; the
             * window filter gives its poses and their covariance to the test instead (below) */
            if (p->cfg.params.translation_known && filter_runs && p->nav.have_prev &&
                !p->cfg.nav.window_filter) {
                filter_translation(&p->nav, &motion);
            }
            /* Until the window filter can test (started, with the window's older frames as
             * clones): the IMU at rest since before the previous frame means no motion at all,
             * the parity detector's rest test (core/docs/parity_space.md "At rest"). */
            const int filter_tests =
                filter_runs && (!p->cfg.nav.window_filter ||
                                p->nav.win.num_clones >= p->cfg.params.window_frames - 1);
            if (p->cfg.params.translation_known && !filter_tests &&
                sfd_nav_imu_at_rest(&p->nav, &p->ring, p->prev_frame_utime, frame->utime)) {
                motion.translation_known = SFD_MOTION_AT_REST;
            }
        }
    }
    if (p->have_prev_frame && mp == NULL) {
        /* No motion for this interval: the window cannot continue. Start a new one here. */
        sfd_pipeline_count_reject(p, reason);
        sfd_parity_reset(&p->parity);
    }
    /* Known translation from the window filter once it runs and was advanced to this frame. */
    sfd_window_t *win = (p->cfg.nav.window_filter && p->nav_ok) ? &p->nav.win : NULL;
    if (sfd_parity_push_frame_filter(&p->parity, frame, mp, win, &p->nav.work.window, &p->ext,
                                     &p->out.verdict) != SFD_OK) {
        sfd_pipeline_count_reject(p, SFD_REJECT_CORE);
        sfd_parity_reset(&p->parity);
        untested_verdict(&p->out.verdict, frame);
    }
}

/* A new frame time base: the parity window, the filter (its clones are at old frame times) and
 * the tracks and landmarks start over; the IMU ring is kept (a restarted publisher's IMU is in
 * the new base already, or restarts on its own). */
static void restart_frame_side(sfd_pipeline_t *p) {
    sfd_pipeline_count_reject(p, SFD_REJECT_RESTART);
    p->have_prev_frame = 0;
    sfd_parity_reset(&p->parity);
    p->nav.ready = 0;
    if (p->have_camera) sfd_nav_set_camera(&p->nav, &p->camera, &p->ext);
}

sfd_status_t sfd_pipeline_detect(sfd_pipeline_t *p) {
    if (p == NULL) return SFD_ERR_INVAL;
    if (p->cur_slot >= 0) return SFD_ERR_STATE;
    int slot = -1;
    for (int k = 0; k < SFD_PIPELINE_FRAME_SLOTS; ++k) {
        if (p->slot_state[k] != SFD_PIPELINE_SLOT_DUE) continue;
        if (slot < 0 || (int32_t)(p->slot_seq[k] - p->slot_seq[slot]) < 0) slot = k;
    }
    if (slot < 0) return SFD_ERR_STATE;
    if (p->slot_restart[slot]) {
        /* The first frame of a new time base, judged after every frame of the old one. */
        p->slot_restart[slot] = 0;
        restart_frame_side(p);
    }
    p->cur_slot = slot;
    p->have_output = 0;
    const sfd_frame_t *frame = &p->frames[slot];
    const int imu_reason = p->slot_reason[slot];
    const int32_t method = p->cfg.params.method;
    /* The filter first: its propagation needs the same IMU as the parity motion. */
    p->nav_ok = 0;
    if (p->cfg.nav.enabled && imu_reason == SFD_REJECT_NONE) {
        const int r = sfd_nav_advance(&p->nav, &p->ring, frame->utime);
        sfd_pipeline_count_reject(p, r);
        p->nav_ok = (r == SFD_REJECT_NONE) && p->nav.ready;
    } else if (p->cfg.nav.enabled && p->nav.ready) {
        p->nav.ready = 0; /* no IMU for this interval: restart from gravity later */
    }
    if (method == SFD_METHOD_PARITY || method == SFD_METHOD_BOTH) {
        run_parity(p, frame, imu_reason);
    } else {
        untested_verdict(&p->out.verdict, frame);
        if (method == SFD_METHOD_NONE) {
            for (int i = 0; i < frame->num_features; ++i) {
                p->out.verdict.features[i].status = SFD_VERDICT_CONSISTENT; /* accept all */
            }
        }
    }
    p->stage = 1;
    return SFD_OK;
}

sfd_status_t sfd_pipeline_associate(sfd_pipeline_t *p) {
    if (p == NULL) return SFD_ERR_INVAL;
    if (p->cur_slot < 0 || p->stage != 1) return SFD_ERR_STATE;
    const sfd_frame_t *frame = &p->frames[p->cur_slot];
    const int32_t method = p->cfg.params.method;
    p->num_matches = 0;
    p->select_status = SFD_OK;
    if (p->nav_ok) {
        /* PARITY: the filter uses what parity accepted; BOTH: OPRF judges parity's survivors */
        for (int i = 0; i < frame->num_features; ++i) {
            const int8_t ps = p->out.verdict.features[i].status;
            p->feature_mark[i] =
                (uint8_t)((method == SFD_METHOD_PARITY && ps != SFD_VERDICT_CONSISTENT) ||
                          (method == SFD_METHOD_BOTH && ps == SFD_VERDICT_SPURIOUS));
        }
        /* parity undistorted this frame's features with the same camera: reuse them */
        const int parity_ran = method == SFD_METHOD_PARITY || method == SFD_METHOD_BOTH;
        sfd_nav_t *nv = &p->nav;
        p->num_matches =
            sfd_nav_build(nv, &p->camera, frame, p->feature_mark, parity_ran ? &p->parity : NULL);
        p->select_status = sfd_assoc_select(&nv->assoc, &nv->work.assoc.scratch, &nv->ekf,
                                            &nv->ekf_cam, nv->prev_R_CtoW, nv->prev_p_CinW_m,
                                            nv->work.assoc.matches, p->num_matches, &nv->result);
    }
    p->stage = 2;
    return SFD_OK;
}

/* The association's update and verdicts (stage 3, when the filter runs). */
static void apply_association(sfd_pipeline_t *p, const sfd_frame_t *frame) {
    const int32_t method = p->cfg.params.method;
    sfd_nav_t *nv = &p->nav;
    /* The window filter makes the update itself (sfd_nav_finish): the association's update then
     * runs on a copy, for its verdicts only. */
    sfd_ekf_t *assoc_ekf = &nv->ekf;
    if (p->cfg.nav.window_filter) {
        nv->work.assoc.ekf = nv->ekf;
        assoc_ekf = &nv->work.assoc.ekf;
    }
    const sfd_status_t s1 = p->select_status;
    const sfd_status_t s2 =
        (s1 == SFD_OK)
            ? sfd_assoc_apply(&nv->assoc, &nv->work.assoc.scratch, assoc_ekf, &nv->ekf_cam,
                              nv->work.assoc.matches, p->num_matches, &nv->result)
            : s1;
    if (s1 != SFD_OK || s2 != SFD_OK || nv->result.update_status != SFD_OK) {
        sfd_pipeline_count_reject(p, SFD_REJECT_CORE);
    }
    if (s1 != SFD_OK || s2 != SFD_OK) return;
    p->out.hypotheses_used = nv->result.hypotheses_used;
    p->out.budget_exhausted = (int8_t)nv->result.budget_exhausted;
    const int assoc_verdicts = method == SFD_METHOD_OPRF || method == SFD_METHOD_RANSAC1 ||
                               method == SFD_METHOD_RANSACF || method == SFD_METHOD_BOTH;
    for (int i = 0; assoc_verdicts && i < frame->num_features; ++i) {
        const int32_t k = nv->feature_match[i];
        sfd_feature_result_t *f = &p->out.verdict.features[i];
        if (k < 0) continue; /* BOTH: parity's verdict stays; others: UNTESTED */
        f->status = nv->result.status[k];
        f->stage = nv->result.stage[k];
        f->statistic = nv->result.statistic[k];
    }
}

static void fill_state(sfd_pipeline_t *p) {
    const sfd_ekf_t *e = &p->nav.ekf;
    sfd_pipeline_output_t *o = &p->out;
    o->has_state = p->cfg.nav.enabled && p->nav.ready;
    for (int k = 0; k < 3; ++k) {
        o->p_IinW_m[k] = e->p_IinW_m[k];
        o->v_IinW_m_s[k] = e->v_IinW_m_s[k];
        o->p_var_m2[k] = e->P[(SFD_EKF_IDX_P + k) * SFD_EKF_DIM + SFD_EKF_IDX_P + k];
    }
    for (int k = 0; k < 4; ++k) o->q_ItoW[k] = e->q_ItoW[k];
}

sfd_status_t sfd_pipeline_update(sfd_pipeline_t *p) {
    if (p == NULL) return SFD_ERR_INVAL;
    if (p->cur_slot < 0 || p->stage != 2) return SFD_ERR_STATE;
    const int slot = p->cur_slot;
    const sfd_frame_t *frame = &p->frames[slot];
    p->out.hypotheses_used = 0;
    p->out.budget_exhausted = 0;
    if (p->nav_ok) apply_association(p, frame);
    recount(&p->out.verdict);
    /* A SPURIOUS verdict of the parity evidence test judges the track's segment as a whole (a
     * moving point, a drift): its earlier observations go too. Any other ends the track before
     * the flagged observation (core/docs/window_filter.md "Flagged tracks"). */
    for (int i = 0; i < frame->num_features; ++i) {
        const sfd_feature_result_t *f = &p->out.verdict.features[i];
        p->final_status[i] = f->status;
        p->feature_mark[i] =
            (uint8_t)(f->status == SFD_VERDICT_SPURIOUS &&
                      (f->reason == SFD_REASON_EVIDENCE || f->reason == SFD_REASON_EVIDENCE_RAMP));
    }
    if (p->cfg.nav.enabled) {
        sfd_nav_finish(&p->nav, &p->camera, frame, p->final_status, p->feature_mark);
    }
    fill_state(p);
    p->counters.frames_processed++;
    if (p->out.verdict.num_consistent + p->out.verdict.num_spurious == 0) {
        p->counters.frames_untested++;
    }
    p->prev_frame_utime = frame->utime;
    p->have_prev_frame = 1;
    sfd_imu_ring_set_needed(&p->ring, imu_needed_from(p, frame->utime));
    p->slot_state[slot] = SFD_PIPELINE_SLOT_FREE;
    p->cur_slot = -1;
    p->stage = 0;
    p->have_output = 1;
    return SFD_OK;
}

sfd_status_t sfd_pipeline_judge(sfd_pipeline_t *p) {
    sfd_status_t s = sfd_pipeline_detect(p);
    if (s == SFD_OK) s = sfd_pipeline_associate(p);
    if (s == SFD_OK) s = sfd_pipeline_update(p);
    return s;
}

const sfd_pipeline_output_t *sfd_pipeline_output(const sfd_pipeline_t *p) {
    return (p != NULL && p->have_output) ? &p->out : NULL;
}
