/* SPDX-License-Identifier: MIT */
#include "sfd/sfd_nav.h"

#include <math.h>
#include <string.h>

#include "sfd/sfd_chi2.h"
#include "sfd/sfd_reject.h"
#include "float_round.h"
#include "track_index.h"

void sfd_nav_config_default(sfd_nav_config_t *cfg) {
    memset(cfg, 0, sizeof *cfg);
    cfg->enabled = 1;
    sfd_ekf_noise_default(&cfg->noise);
    /* White noise about three times the datasheet-level densities of sfd_ekf_noise_default():
     * a real IMU's errors beyond its white noise and bias walk (vibration, scale factor,
     * misalignment, timing) show as extra white noise to the filter. On the real EuRoC V1_02 IMU
     * the datasheet values left the position NEES at 8 (covariance 2.7 times too small); these
     * bring it to 3.2 and the ATE from 0.034 to 0.026 m, while the simulated flights, whose IMU
     * follows the datasheet values exactly, stay near consistent (NEES 2.0-2.3) at an ATE 0-8 %
     * larger (docs/evaluation.md "IMU noise for a real IMU"). */
    cfg->noise.gyro_noise_rad_s_rthz = 1.0e-3;
    cfg->noise.accel_noise_m_s2_rthz = 1.2e-2;
    for (int k = 0; k < 3; ++k) {
        cfg->p0_diag[SFD_EKF_IDX_P + k] = 1e-6;
        cfg->p0_diag[SFD_EKF_IDX_V + k] = 1e-4;
        cfg->p0_diag[SFD_EKF_IDX_THETA + k] = (k == 2) ? 1e-6 : 1e-4;
        cfg->p0_diag[SFD_EKF_IDX_BG + k] = 1e-4;
        cfg->p0_diag[SFD_EKF_IDX_BA + k] = 1e-2;
    }
    cfg->window_filter = 1;
    cfg->window_size = SFD_MAX_WINDOW;
    cfg->window_depth_priors = 2;
    cfg->window_gate_alpha = 0.01;
    cfg->window_flagged_earlier = 1;
    cfg->first_estimates = 0;
    cfg->observability_constrained = 1;
    cfg->keyframe_parallax_rad = 0.0;
    cfg->init_rest_s = 1.0;
    cfg->gyro_bias_at_rest = 1;
    cfg->landmark_depth_var_m2 = 100.0;
    cfg->landmark_max_age_s = 2.0;
    cfg->landmark_gate_alpha = 0.001;
    cfg->min_parallax_px = 1.0;
    cfg->consider_position = 1;
}

int32_t sfd_nav_assoc_method(int32_t detector_method) {
    switch (detector_method) {
        case SFD_METHOD_OPRF:
        case SFD_METHOD_RANSAC1:
        case SFD_METHOD_RANSACF:
            return detector_method;
        case SFD_METHOD_BOTH:
            return SFD_METHOD_OPRF;
        default:
            return SFD_METHOD_NONE;
    }
}

sfd_status_t sfd_nav_init(sfd_nav_t *nav, const sfd_nav_config_t *cfg, const sfd_params_t *params) {
    if (nav == NULL || cfg == NULL || params == NULL) return SFD_ERR_INVAL;
    if (!(cfg->init_rest_s > 0.0 && cfg->init_rest_s < 60.0) ||
        !(cfg->landmark_depth_var_m2 >= 0.0 && isfinite(cfg->landmark_depth_var_m2)) ||
        !(cfg->landmark_max_age_s > 0.0 && isfinite(cfg->landmark_max_age_s)) ||
        !(cfg->landmark_gate_alpha > 0.0 && cfg->landmark_gate_alpha < 1.0)) {
        return SFD_ERR_INVAL;
    }
    for (int i = 0; i < SFD_EKF_DIM; ++i) {
        if (!(cfg->p0_diag[i] >= 0.0 && isfinite(cfg->p0_diag[i]))) return SFD_ERR_INVAL;
    }
    for (int k = 0; k < 3; ++k) {
        if (!isfinite(cfg->init_accel_bias_m_s2[k])) return SFD_ERR_INVAL;
    }
    if ((cfg->window_filter != 0 && cfg->window_filter != 1) ||
        (cfg->first_estimates != 0 && cfg->first_estimates != 1) ||
        (cfg->observability_constrained != 0 && cfg->observability_constrained != 1) ||
        (cfg->window_depth_priors < 0 || cfg->window_depth_priors > 2) ||
        (cfg->window_flagged_earlier != 0 && cfg->window_flagged_earlier != 1) ||
        !(cfg->keyframe_parallax_rad >= 0.0 && isfinite(cfg->keyframe_parallax_rad))) {
        return SFD_ERR_INVAL;
    }
    if (cfg->window_filter) {
        sfd_window_params_t wp;
        sfd_window_params_default(&wp);
        wp.noise = cfg->noise;
        wp.window = cfg->window_size;
        wp.min_observations = wp.window < 3 ? wp.window : 3;
        wp.gate_alpha = cfg->window_gate_alpha;
        wp.first_estimates = cfg->first_estimates;
        wp.observability_constrained = cfg->observability_constrained;
        wp.use_depth_prior = cfg->window_depth_priors;
        wp.flagged_earlier = cfg->window_flagged_earlier;
        /* Keyframes keep the parity test's older window_frames - 1 frames as the newest clones
         * (it tests every frame against them). */
        wp.keyframe_parallax_rad = cfg->keyframe_parallax_rad;
        wp.keyframe_recent = params->window_frames - 1;
        if (sfd_window_init(&nav->win, &wp) != SFD_OK) return SFD_ERR_INVAL;
        sfd_rest_params_t rp;
        sfd_rest_params_default(&rp);
        rp.gravity_m_s2 = cfg->noise.gravity_m_s2;
        if (sfd_rest_init(&nav->work.rest, &rp) != SFD_OK) return SFD_ERR_INVAL;
    }
    nav->win_gated = 0;
    nav->win_used = 0;
    memset(&nav->win_result, 0, sizeof nav->win_result);
    nav->cfg = *cfg;
    nav->params = *params;
    memset(&nav->ekf, 0, sizeof nav->ekf);
    nav->ready = 0;
    nav->starts = 0;
    nav->have_truth0 = 0;
    nav->ekf_utime = 0;
    nav->have_prev = 0;
    nav->prev_n = 0;
    nav->num_matches = 0;
    sfd_assoc_params_t ap;
    sfd_assoc_params_from(params, &ap);
    ap.method = sfd_nav_assoc_method(params->method);
    ap.min_parallax_px = cfg->min_parallax_px;
    sfd_status_t st = sfd_assoc_init(&nav->assoc, &ap);
    if (st != SFD_OK) return st;
    st = sfd_landmark_map_init(&nav->map);
    return st;
}

void sfd_nav_set_camera(sfd_nav_t *nav, const sfd_camera_t *cam, const sfd_extrinsics_t *ext) {
    memset(&nav->ekf_cam, 0, sizeof nav->ekf_cam);
    nav->ekf_cam.fx_px = cam->fx_px;
    nav->ekf_cam.fy_px = cam->fy_px;
    nav->ekf_cam.cx_px = cam->cx_px;
    nav->ekf_cam.cy_px = cam->cy_px;
    nav->ekf_cam.ext = *ext;
    nav->ekf_cam.pixel_sigma_px = nav->params.pixel_sigma_px;
    sfd_landmark_map_init(&nav->map);
    nav->have_prev = 0;
    nav->prev_n = 0;
}

/* Landmarks built from the filter's own poses carry no information on its absolute position:
 * with consider_position the camera updates leave the position uncorrected (Schmidt consider
 * state), so its covariance keeps growing with the velocity error instead of shrinking on
 * re-used information (core/docs/ekf.md, "Consider states"). Called once the filter (re)starts. */
static void started(sfd_nav_t *nav, int64_t utime) {
    nav->ekf_utime = utime;
    nav->ready = 1;
    nav->starts++;
    nav->have_prev = 0; /* no prior pose for the previous frame's matches */
    for (int k = 0; k < 3; ++k) {
        nav->ekf.consider[SFD_EKF_IDX_P + k] = (uint8_t)(nav->cfg.consider_position ? 1 : 0);
    }
}

static int rest_of_span(sfd_nav_t *nav, const sfd_imu_span_t *span, int32_t min_block,
                        sfd_rest_result_t *rr);

/* The window filter starts when the IMU of [t - init_rest_s, t] is at rest by the rest detector
 * (blocks of its default block_samples, as many whole blocks as the samples fill, up to its
 * default window, at least 2; with more samples than that window holds, the default number of
 * longer blocks): gravity's direction and the gyro bias from that window, position 0, yaw 0.
 * Not at rest: no start (not a rejection), the next frame tries again. */
static int start_window_at_rest(sfd_nav_t *nav, const sfd_imu_span_t *span, int64_t t_us) {
    sfd_rest_result_t rr;
    const int r = rest_of_span(nav, span, 0, &rr);
    if (r < 0) return SFD_REJECT_CORE;
    if (r == 0 || !rr.at_rest) return SFD_REJECT_NONE;
    const double *bias =
        nav->cfg.gyro_bias_at_rest ? rr.gyro_mean_rad_s : nav->params.gyro_bias_rad_s;
    if (sfd_window_start_at_rest(&nav->win, t_us, rr.accel_mean_m_s2, bias) != SFD_OK ||
        sfd_window_to_ekf(&nav->win, &nav->ekf) != SFD_OK) {
        return SFD_REJECT_CORE;
    }
    started(nav, t_us);
    return SFD_REJECT_NONE;
}

/* The rest detector over the span's samples (in nav->work.rest): blocks of its default
 * block_samples, as many whole blocks as the samples fill, up to its default window, at least 2;
 * with more samples than that window holds, the default number of longer blocks; with fewer
 * than 2 default blocks and min_block > 0, two blocks of half the samples, each at least
 * min_block (their means scatter more at rest: the test is stricter, not looser). 1 with *rr
 * evaluated (rr->ready set), 0 when the span holds fewer than 2 blocks, -1 when the detector
 * refused its parameters. */
static int rest_of_span(sfd_nav_t *nav, const sfd_imu_span_t *span, int32_t min_block,
                        sfd_rest_result_t *rr) {
    const int32_t n = sfd_imu_span_count(span);
    sfd_rest_params_t rp;
    sfd_rest_params_default(&rp);
    rp.gravity_m_s2 = nav->cfg.noise.gravity_m_s2;
    /* More samples than the default window holds (an IMU faster than 200 Hz): longer blocks, the
     * default number of them, so that the test keeps its degrees of freedom. */
    const int32_t full = rp.block_samples * rp.window_blocks;
    if (n > full) {
        const int32_t bs = n / rp.window_blocks;
        rp.block_samples = bs > 1000 ? 1000 : bs;
    }
    if (min_block > 0 && n < 2 * rp.block_samples && n / 2 >= min_block) rp.block_samples = n / 2;
    int32_t blocks = n / rp.block_samples;
    if (blocks > rp.window_blocks) blocks = rp.window_blocks;
    if (blocks < 2) return 0;
    rp.window_blocks = blocks;
    if (sfd_rest_init(&nav->work.rest, &rp) != SFD_OK) return -1;
    const int32_t first = n - blocks * rp.block_samples;
    for (int32_t i = first; i < n; ++i) {
        const sfd_imu_sample_t s = sfd_imu_span_at(span, i);
        (void)sfd_rest_push(&nav->work.rest, s.t_us, s.gyro_rad_s, s.accel_m_s2);
    }
    return (sfd_rest_evaluate(&nav->work.rest, rr) == SFD_OK && rr->ready) ? 1 : 0;
}

/* The shortest block sfd_nav_imu_at_rest uses right after the IMU starts: 5 samples, 25 ms at
 * 200 Hz, so that the second frame (50 ms in) can already be judged at rest. */
enum { kRestMinBlockSamples = 5 };

int sfd_nav_imu_at_rest(sfd_nav_t *nav, const sfd_imu_ring_t *ring, int64_t since_us,
                        int64_t t_us) {
    if (nav == NULL || ring == NULL || !nav->cfg.enabled || ring->count < 2 || since_us > t_us) {
        return 0;
    }
    const int64_t rest_us = (int64_t)(nav->cfg.init_rest_s * 1e6);
    const int64_t oldest = ring->samples[ring->head].t_us;
    int64_t from = (t_us > INT64_MIN + rest_us) ? t_us - rest_us : INT64_MIN;
    if (from < oldest) from = oldest;
    if (from > since_us) return 0; /* the IMU does not reach back to the previous frame */
    sfd_imu_span_t span;
    if (sfd_imu_ring_span(ring, from, t_us, SFD_IMU_RING_CAPACITY, &span) != SFD_REJECT_NONE) {
        return 0;
    }
    /* the span starts at the last sample at or before `from` (at or before since_us); the whole
     * blocks may leave out fewer than one block of samples at its start */
    sfd_rest_result_t rr;
    return rest_of_span(nav, &span, kRestMinBlockSamples, &rr) == 1 && rr.at_rest;
}

/* Starts the filter from the IMU of [t - init_rest_s, t] (SPEC: at rest, gravity direction). */
static int start_at_rest(sfd_nav_t *nav, const sfd_imu_ring_t *ring, int64_t t_us) {
    const int64_t rest_us = (int64_t)(nav->cfg.init_rest_s * 1e6);
    sfd_imu_span_t span;
    int r = sfd_imu_ring_span(ring, t_us - rest_us, t_us, SFD_IMU_RING_CAPACITY, &span);
    if (r == SFD_REJECT_IMU_GAP && ring->count == SFD_IMU_RING_CAPACITY) {
        /* The full ring spans less than init_rest_s (an IMU faster than the capacity was sized
         * for): the rest window is what it holds, rather than never starting. */
        r = sfd_imu_ring_span(ring, ring->samples[ring->head].t_us, t_us, SFD_IMU_RING_CAPACITY,
                              &span);
    }
    const int32_t n = (r == SFD_REJECT_NONE) ? sfd_imu_span_count(&span) : 0;
    /* Not yet init_rest_s of IMU before this frame: keep waiting (not a rejection). */
    if (r == SFD_REJECT_IMU_GAP || (r == SFD_REJECT_NONE && n < 2)) return SFD_REJECT_NONE;
    if (r != SFD_REJECT_NONE) return r;
    if (nav->cfg.window_filter) return start_window_at_rest(nav, &span, t_us);
    double f[3] = {0, 0, 0}, w[3] = {0, 0, 0};
    for (int32_t i = 0; i < n; ++i) {
        const sfd_imu_sample_t s = sfd_imu_span_at(&span, i);
        for (int k = 0; k < 3; ++k) {
            f[k] += s.accel_m_s2[k];
            w[k] += s.gyro_rad_s[k];
        }
    }
    for (int k = 0; k < 3; ++k) {
        f[k] /= n;
        w[k] /= n;
    }
    const double *bias = nav->cfg.gyro_bias_at_rest ? w : nav->params.gyro_bias_rad_s;
    if (sfd_ekf_init_from_gravity(&nav->ekf, &nav->cfg.noise, f, bias, nav->cfg.p0_diag) !=
        SFD_OK) {
        return SFD_REJECT_CORE; /* not at rest (or bad values): try again at the next frame */
    }
    started(nav, t_us);
    return SFD_REJECT_NONE;
}

void sfd_nav_truth(sfd_nav_t *nav, int64_t utime, const double p_m[3], const double q_wxyz[4]) {
    if (!nav->cfg.enabled || !nav->cfg.init_from_truth || nav->ready) return;
    if (!nav->have_truth0 || utime <= nav->truth0_utime) {
        nav->have_truth0 = 1;
        nav->truth0_utime = utime;
        memcpy(nav->truth0_p, p_m, sizeof nav->truth0_p);
        return;
    }
    const double dt = (double)(utime - nav->truth0_utime) * 1e-6;
    double v[3];
    for (int k = 0; k < 3; ++k) v[k] = (p_m[k] - nav->truth0_p[k]) / dt;
    double q[4];
    memcpy(q, q_wxyz, sizeof q);
    if (nav->cfg.window_filter) {
        if (sfd_quat_normalize(q) != SFD_OK ||
            sfd_window_start_at(&nav->win, utime, p_m, v, q, nav->params.gyro_bias_rad_s,
                                nav->cfg.init_accel_bias_m_s2) != SFD_OK ||
            sfd_window_to_ekf(&nav->win, &nav->ekf) != SFD_OK) {
            nav->have_truth0 = 0;
            return;
        }
        started(nav, utime);
        return;
    }
    if (sfd_quat_normalize(q) != SFD_OK ||
        sfd_ekf_init(&nav->ekf, &nav->cfg.noise, p_m, v, q, nav->params.gyro_bias_rad_s,
                     nav->cfg.init_accel_bias_m_s2, nav->cfg.p0_diag) != SFD_OK) {
        nav->have_truth0 = 0;
        return;
    }
    started(nav, utime);
}

sfd_status_t sfd_nav_start_at(sfd_nav_t *nav, int64_t utime, const double p_m[3],
                              const double v_m_s[3], const double q_ItoW[4],
                              const double bg_rad_s[3], const double ba_m_s2[3],
                              const double p0_diag[SFD_EKF_DIM]) {
    if (nav == NULL || p_m == NULL || v_m_s == NULL || q_ItoW == NULL || bg_rad_s == NULL ||
        ba_m_s2 == NULL) {
        return SFD_ERR_INVAL;
    }
    if (!nav->cfg.enabled) return SFD_ERR_STATE;
    double q[4];
    memcpy(q, q_ItoW, sizeof q);
    if (sfd_quat_normalize(q) != SFD_OK) return SFD_ERR_INVAL;
    const double *P0 = p0_diag != NULL ? p0_diag : nav->cfg.p0_diag;
    sfd_status_t st;
    if (nav->cfg.window_filter) {
        if (p0_diag != NULL) {
            /* the window filter's P0 is in its parameters; its attitude error is global (the
             * header says what that means for the attitude variances) */
            memcpy(nav->win.prm.p0_diag, p0_diag, sizeof nav->win.prm.p0_diag);
        }
        st = sfd_window_start_at(&nav->win, utime, p_m, v_m_s, q, bg_rad_s, ba_m_s2);
        if (st == SFD_OK) st = sfd_window_to_ekf(&nav->win, &nav->ekf);
    } else {
        st = sfd_ekf_init(&nav->ekf, &nav->cfg.noise, p_m, v_m_s, q, bg_rad_s, ba_m_s2, P0);
    }
    if (st != SFD_OK) return st;
    started(nav, utime);
    return SFD_OK;
}

/* 1 when the filter's state and its covariance's diagonal are finite and the variances
 * non-negative (a state that overflowed must not be published nor used). */
static int ekf_state_finite(const sfd_ekf_t *e) {
    for (int k = 0; k < 3; ++k) {
        if (!isfinite(e->p_IinW_m[k]) || !isfinite(e->v_IinW_m_s[k])) return 0;
    }
    for (int k = 0; k < 4; ++k) {
        if (!isfinite(e->q_ItoW[k])) return 0;
    }
    for (int i = 0; i < SFD_EKF_DIM; ++i) {
        if (!(e->P[i * SFD_EKF_DIM + i] >= 0.0) || !isfinite(e->P[i * SFD_EKF_DIM + i])) return 0;
    }
    return 1;
}

int sfd_nav_advance(sfd_nav_t *nav, const sfd_imu_ring_t *ring, int64_t t_us) {
    if (!nav->cfg.enabled) return SFD_REJECT_NONE;
    if (!nav->ready && nav->cfg.init_from_truth) return SFD_REJECT_NONE; /* waits for TRUTH */
    if (!nav->ready) return start_at_rest(nav, ring, t_us);
    if (t_us <= nav->ekf_utime) return SFD_REJECT_NONE;
    sfd_imu_span_t span;
    const int r = sfd_imu_ring_span(ring, nav->ekf_utime, t_us, SFD_IMU_RING_CAPACITY, &span);
    const int32_t n = (r == SFD_REJECT_NONE) ? sfd_imu_span_count(&span) : 0;
    if (r != SFD_REJECT_NONE) {
        if (r == SFD_REJECT_IMU_GAP) nav->ready = 0; /* lost: restart from gravity later */
        return r;
    }
    /* Zero-order hold: sample i holds from its time (or the filter's) to the next sample's
     * (or t_us). The window starts at the last sample at or before ekf_utime. */
    int64_t t = nav->ekf_utime;
    for (int32_t i = 0; i < n && t < t_us; ++i) {
        const sfd_imu_sample_t s = sfd_imu_span_at(&span, i);
        const int64_t t_next = (i + 1 < n) ? sfd_imu_span_at(&span, i + 1).t_us : t_us;
        const int64_t t_end = (t_next < t_us) ? t_next : t_us;
        if (t_end <= t) continue;
        const double dt = (double)(t_end - t) * 1e-6;
        if (dt > nav->cfg.noise.max_dt_s ||
            (nav->cfg.window_filter
                 ? sfd_window_propagate(&nav->win, s.gyro_rad_s, s.accel_m_s2, dt)
                 : sfd_ekf_propagate(&nav->ekf, s.gyro_rad_s, s.accel_m_s2, dt)) != SFD_OK) {
            nav->ready = 0;
            return (dt > nav->cfg.noise.max_dt_s) ? SFD_REJECT_IMU_GAP : SFD_REJECT_CORE;
        }
        t = t_end;
    }
    nav->ekf_utime = t_us;
    if ((nav->cfg.window_filter && sfd_window_to_ekf(&nav->win, &nav->ekf) != SFD_OK) ||
        !ekf_state_finite(&nav->ekf)) {
        nav->ready = 0; /* restart from rest later rather than publish a state that overflowed */
        return SFD_REJECT_CORE;
    }
    return SFD_REJECT_NONE;
}

/* The previous frame's track index (track_index.h) over SFD_NAV_TRACK_SLOTS (more than twice
 * SFD_MAX_FEATURES, so a probe sequence always ends at an empty slot). Holds the first index of
 * each id, as a front-to-back search of prev_track would find it. */
static void prev_index_build(sfd_nav_t *nav) {
    const sfd_track_index_t t =
        sfd_track_index_i16(nav->prev_index, SFD_NAV_TRACK_SLOTS, nav->prev_track,
                            sizeof nav->prev_track[0], nav->prev_n);
    sfd_track_index_clear(&t);
    for (int32_t k = 0; k < nav->prev_n; ++k)
        (void)sfd_track_index_add_first(&t, nav->prev_track[k], k);
}

/* Index of @p id in the previous frame (its first occurrence), or -1. */
static int32_t prev_index_find(const sfd_nav_t *nav, int64_t id) {
    const sfd_track_index_t t =
        sfd_track_index_view_i16(nav->prev_index, SFD_NAV_TRACK_SLOTS, nav->prev_track,
                                 sizeof nav->prev_track[0], nav->prev_n);
    return sfd_track_index_find(&t, id);
}

/* Feature i's normalized coordinates (stored as float, read as double). */
static void nav_xn(const sfd_nav_t *nav, int32_t i, double xn[2]) {
    xn[0] = (double)nav->xn[i][0];
    xn[1] = (double)nav->xn[i][1];
}

/* Covariance of normalized coordinates xn from isotropic pixel noise sigma through the camera
 * model: J = d(xn)/d(uv) = (d(uv)/d(xn))^-1, Cov = sigma^2 J J^T (xx, xy, yy). 0 when the
 * distortion Jacobian is singular or not finite. */
static int pixel_noise_xn(const sfd_camera_t *cam, double sigma_px, const double xn[2],
                          double cov[3]) {
    double uv[2], F[4];
    if (sfd_camera_distort(cam, xn, uv, F) != SFD_OK) return 0;
    const double det = F[0] * F[3] - F[1] * F[2];
    if (!(fabs(det) > 0.0) || !isfinite(det)) return 0;
    const double J[4] = {F[3] / det, -F[1] / det, -F[2] / det, F[0] / det};
    const double s2 = sigma_px * sigma_px;
    cov[0] = s2 * (J[0] * J[0] + J[1] * J[1]);
    cov[1] = s2 * (J[0] * J[2] + J[1] * J[3]);
    cov[2] = s2 * (J[2] * J[2] + J[3] * J[3]);
    return isfinite(cov[0]) && isfinite(cov[1]) && isfinite(cov[2]) && cov[0] > 0.0 &&
           cov[2] > 0.0 && cov[0] * cov[2] - cov[1] * cov[1] > 0.0;
}

/* The window filter's frame: every feature with a coordinate, flagged when judged SPURIOUS (drop
 * 1: the track ends before it; 2 with whole_track: its observations are deleted); the tracks its
 * gate refuses lose their landmark too, so the association methods do not score against it.
 * Then the IMU state is read back. */
static void window_frame(sfd_nav_t *nav, const sfd_camera_t *cam, const sfd_frame_t *frame,
                         const int8_t *status, const uint8_t *whole_track) {
    int32_t n = 0;
    for (int32_t i = 0; i < frame->num_features && n < SFD_MAX_FEATURES; ++i) {
        if (!nav->ok[i]) continue;
        sfd_window_obs_t *o = &nav->work.window.u.obs[n];
        /* Cov(xn) computed again where read rather than kept per feature (sfd_nav_build checked
         * that it exists; the same computation gives the same bits) */
        nav_xn(nav, i, o->xn);
        if (!pixel_noise_xn(cam, nav->params.pixel_sigma_px, o->xn, o->cov_xn)) continue;
        ++n;
        o->track_id = frame->features[i].track_id;
        o->depth_m = frame->features[i].depth_m;
        o->depth_var_m2 = frame->features[i].depth_var_m2;
        if (!(o->depth_var_m2 >= 0.0) || !isfinite(o->depth_var_m2) || !isfinite(o->depth_m)) {
            o->depth_m = 0.0;
            o->depth_var_m2 = 0.0;
        }
        o->drop = 0;
        if (status[i] == SFD_VERDICT_SPURIOUS) o->drop = (whole_track && whole_track[i]) ? 2 : 1;
    }
    sfd_window_result_t *r = &nav->win_result;
    if (sfd_window_frame(&nav->win, frame->utime, nav->work.window.u.obs, n, &nav->ekf_cam.ext,
                         &nav->work.window, r) != SFD_OK ||
        r->update_status != SFD_OK || sfd_window_to_ekf(&nav->win, &nav->ekf) != SFD_OK) {
        nav->ready = 0; /* restart at rest later */
        return;
    }
    nav->win_gated += r->gated;
    nav->win_used += r->used;
    for (int32_t k = 0; k < r->num_gated_ids; ++k) {
        (void)sfd_landmark_remove(&nav->map, r->gated_ids[k]);
    }
}

int32_t sfd_nav_build(sfd_nav_t *nav, const sfd_camera_t *cam, const sfd_frame_t *frame,
                      const uint8_t *skip, const sfd_parity_t *parity) {
    nav->num_matches = 0;
    for (int32_t i = 0; i < frame->num_features; ++i) {
        nav->feature_match[i] = -1;
        const double uv_raw[2] = {frame->features[i].u_px, frame->features[i].v_px};
        double xn[2], cov_xn[3];
        /* the parity detector's float-rounded coordinates, or the same rounding here */
        nav->ok[i] = (uint8_t)((parity != NULL &&
                                sfd_parity_newest_xn(parity, frame->utime, i, xn) == SFD_OK) ||
                               (sfd_camera_undistort(cam, uv_raw, xn, NULL) == SFD_OK &&
                                sfd_fits_float(xn, 2)));
        if (!nav->ok[i]) continue;
        nav->xn[i][0] = (float)xn[0];
        nav->xn[i][1] = (float)xn[1];
        xn[0] = sfd_float_round_trip(xn[0]); /* as stored (the compiler may not skip it) */
        xn[1] = sfd_float_round_trip(xn[1]);
        nav->ok[i] = (uint8_t)pixel_noise_xn(cam, nav->params.pixel_sigma_px, xn, cov_xn);
    }
    if (!nav->cfg.enabled || !nav->ready || !nav->have_prev) return 0;
    for (int32_t i = 0; i < frame->num_features; ++i) {
        if (!nav->ok[i] || (skip != NULL && skip[i])) continue;
        const int64_t id = frame->features[i].track_id;
        const int32_t p = prev_index_find(nav, id);
        if (p < 0) continue;
        const int32_t li = sfd_landmark_find(&nav->map, id);
        if (li < 0) continue;
        sfd_match_t *m = &nav->work.assoc.matches[nav->num_matches];
        m->prev_uv_px[0] = nav->prev_uv[p][0];
        m->prev_uv_px[1] = nav->prev_uv[p][1];
        double xn[2];
        nav_xn(nav, i, xn);
        const double uv[2] = {cam->fx_px * xn[0] + cam->cx_px,
                              cam->fy_px * xn[1] + cam->cy_px}; /* undistorted pixel */
        /* the match refers to the map's entry: the map is not changed before the association's
         * update (sfd_nav_finish refines, creates and evicts landmarks after it) */
        const sfd_landmark_t *lm = &nav->map.entries[li];
        m->uv_px[0] = uv[0];
        m->uv_px[1] = uv[1];
        m->landmark_W_m = lm->p_W_m;
        m->landmark_cov_m2 = lm->cov_m2;
        /* The pixel noise of both observations through the distortion Jacobian (C = I + dC,
         * sfd_camera_pixel_noise()): the previous one's from its undistorted pixel, recomputed
         * here instead of kept per feature (the camera is the same: a new calibration drops the
         * previous frame). A flagged observation of a known landmark was replaced by where the
         * landmark projects; the noise model there is taken at that pixel. */
        const double xn_prev[2] = {(m->prev_uv_px[0] - cam->cx_px) / cam->fx_px,
                                   (m->prev_uv_px[1] - cam->cy_px) / cam->fy_px};
        if (sfd_camera_pixel_noise(cam, xn_prev, m->noise.prev_dC) != SFD_OK ||
            sfd_camera_pixel_noise(cam, xn, m->noise.curr_dC) != SFD_OK) {
            continue;
        }
        nav->match_feature[nav->num_matches] = (int16_t)i;
        nav->feature_match[i] = (int16_t)nav->num_matches;
        nav->num_matches++;
    }
    return nav->num_matches;
}

/* Undistorted pixel of a world point seen from the camera (R_CtoW, p_C); 0 when it is not in
 * front of the camera. */
static int project_landmark(const sfd_ekf_camera_t *cam, const double R_CtoW[9],
                            const double p_C[3], const double p_W[3], double uv[2]) {
    double pc[3];
    for (int r = 0; r < 3; ++r) {
        pc[r] = 0.0;
        for (int k = 0; k < 3; ++k) pc[r] += R_CtoW[3 * k + r] * (p_W[k] - p_C[k]);
    }
    if (!(pc[2] > 1e-6)) return 0;
    uv[0] = cam->fx_px * pc[0] / pc[2] + cam->cx_px;
    uv[1] = cam->fy_px * pc[1] / pc[2] + cam->cy_px;
    return isfinite(uv[0]) && isfinite(uv[1]);
}

void sfd_nav_finish(sfd_nav_t *nav, const sfd_camera_t *cam, const sfd_frame_t *frame,
                    const int8_t *status, const uint8_t *whole_track) {
    if (!nav->cfg.enabled || !nav->ready) {
        nav->have_prev = 0;
        return;
    }
    if (nav->cfg.window_filter) {
        window_frame(nav, cam, frame, status, whole_track);
        if (!nav->ready) {
            nav->have_prev = 0;
            return;
        }
    }
    double R_CtoW[9], p_C[3], cov6[36];
    sfd_ekf_camera_pose(&nav->ekf, &nav->ekf_cam.ext, R_CtoW, p_C);
    const int have_cov = sfd_landmark_camera_pose_cov(&nav->ekf, &nav->ekf_cam.ext, cov6) == SFD_OK;
    const double f = 0.5 * (nav->ekf_cam.fx_px + nav->ekf_cam.fy_px);
    const double sigma_xn = nav->params.pixel_sigma_px / f;
    const int64_t t = frame->utime;
    /* The landmarks of this frame's tracks, whatever their verdict, are not evicted to make room
     * for this frame's new ones: the next frame's matches need them. */
    (void)sfd_landmark_begin_frame(&nav->map);
    for (int32_t i = 0; i < frame->num_features; ++i) {
        const int32_t li =
            nav->ok[i] ? sfd_landmark_find(&nav->map, frame->features[i].track_id) : -1;
        if (li >= 0) (void)sfd_landmark_keep_in_frame(&nav->map, li);
    }
    for (int32_t i = 0; i < frame->num_features; ++i) {
        if (!nav->ok[i]) continue;
        const int64_t id = frame->features[i].track_id;
        int32_t li = sfd_landmark_find(&nav->map, id);
        if (status[i] == SFD_VERDICT_SPURIOUS) {
            if (li >= 0 && nav->map.entries[li].fixed) continue; /* a known landmark stays */
            /* The track no longer fits its landmark (a jump, a mover, a mismatch): the landmark
             * is anchored again at this observation, so the track's next observation is tested
             * against it (not left UNTESTED) and a stale landmark never pulls. */
            (void)sfd_landmark_remove(&nav->map, id);
            li = -1;
        }
        if (li >= 0) {
            if (nav->map.entries[li].fixed) {
                nav->map.entries[li].last_seen_utime = t; /* known: seen, never refined */
                continue;
            }
            if (status[i] != SFD_VERDICT_CONSISTENT) continue;
            sfd_landmark_update_t info;
            double xn[2];
            nav_xn(nav, i, xn);
            (void)sfd_landmark_refine(&nav->map, li, R_CtoW, p_C, have_cov ? cov6 : NULL, xn,
                                      sigma_xn, nav->cfg.landmark_gate_alpha, t, &info);
            continue;
        }
        const double d = frame->features[i].depth_m;
        const int known = d > 0.0;
        double xn[2];
        nav_xn(nav, i, xn);
        (void)sfd_landmark_init_from_ray(
            &nav->map, id, R_CtoW, p_C, have_cov ? cov6 : NULL, xn,
            known ? d : nav->params.default_depth_m,
            known ? frame->features[i].depth_var_m2 + 1e-6 : nav->cfg.landmark_depth_var_m2,
            sigma_xn, t, NULL);
    }
    const int64_t max_age_us = (int64_t)(nav->cfg.landmark_max_age_s * 1e6);
    (void)sfd_landmark_evict_older_than(&nav->map, t - max_age_us);
    /* this frame's observations (a flagged one of a known landmark: where it projects) become
     * the next frame's previous ones */
    nav->prev_n = 0;
    for (int32_t i = 0; i < frame->num_features; ++i) {
        if (!nav->ok[i]) continue;
        const int64_t id = frame->features[i].track_id;
        double uv[2];
        uv[0] = nav->ekf_cam.fx_px * nav->xn[i][0] + nav->ekf_cam.cx_px; /* undistorted */
        uv[1] = nav->ekf_cam.fy_px * nav->xn[i][1] + nav->ekf_cam.cy_px;
        if (status[i] == SFD_VERDICT_SPURIOUS) {
            /* a flagged observation of a known landmark: the next frame's epipolar test starts
             * from where the landmark projects now, not from the flagged pixel */
            const int32_t li = sfd_landmark_find(&nav->map, id);
            if (li >= 0 && nav->map.entries[li].fixed &&
                !project_landmark(&nav->ekf_cam, R_CtoW, p_C, nav->map.entries[li].p_W_m, uv)) {
                continue;
            }
        }
        if (!sfd_fits_float(uv, 2)) continue; /* kept as float */
        nav->prev_uv[nav->prev_n][0] = (float)uv[0];
        nav->prev_uv[nav->prev_n][1] = (float)uv[1];
        nav->prev_track[nav->prev_n] = id;
        nav->prev_n++;
    }
    prev_index_build(nav);
    memcpy(nav->prev_R_CtoW, R_CtoW, sizeof R_CtoW);
    memcpy(nav->prev_p_CinW_m, p_C, sizeof p_C);
    nav->have_prev = 1;
}
