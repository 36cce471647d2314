// SPDX-License-Identifier: MIT
#include "core_private.hpp"
#include "sfd/sfd_params.h"

extern "C" sfd_status_t sfd_params_default(sfd_params_t *p) {
    if (p == nullptr) return SFD_ERR_INVAL;
    *p = sfd_params_t{};  // all zero: no bias, no flags
    p->method = SFD_METHOD_PARITY;
    p->pixel_sigma_px = 1.0;
    p->false_alarm_rate = 0.01;
    p->window_frames = (SFD_MAX_WINDOW < 3) ? SFD_MAX_WINDOW : 3;
    p->group_size = (SFD_MAX_GROUP < 3) ? SFD_MAX_GROUP : 3;
    p->translation_known = 0;
    p->exact_depth_covariance = 1;
    p->parity_isolation = 1;
    p->default_depth_m = 10.0;
    p->default_depth_var_m2 = 0.0;
    p->max_hypotheses = (SFD_MAX_HYPOTHESES < 100) ? SFD_MAX_HYPOTHESES : 100;
    p->ransac_confidence = 0.99;
    p->max_imu_gap_us = 50000;
    p->seed = 1U;
    p->pixel_noise_adapt = 1;
    p->evidence_frames = SFD_MAX_WINDOW;
    // With the filter's translation, OPRF finds few spurious features that parity has passed
    // (docs/evaluation.md "Method both: the false-alarm split"), so most of alpha goes to parity.
    p->both_parity_share = 0.9;
    p->alarm_hold_ratio = 1.0;
    p->alarm_hold_frames = 1;
    p->alarm_hold_max_statistic = 3.0;
    p->alarm_hold_alpha_scale = 0.3;
    p->evidence_ramp_share = 0.0;
    p->alarm_hold_min_statistic = 0.0;
    p->alarm_hold_direction_alpha = 0.0;
    return SFD_OK;
}

extern "C" sfd_status_t sfd_params_validate(const sfd_params_t *p) {
    if (p == nullptr) return SFD_ERR_INVAL;
    if (p->method < SFD_METHOD_NONE || p->method > SFD_METHOD_BOTH) return SFD_ERR_INVAL;
    if (!(std::isfinite(p->pixel_sigma_px) && p->pixel_sigma_px > 0.0)) return SFD_ERR_INVAL;
    if (!(p->false_alarm_rate > 0.0 && p->false_alarm_rate <= 0.5)) return SFD_ERR_INVAL;
    if (p->window_frames < 2 || p->group_size < 1 || p->max_hypotheses < 1) return SFD_ERR_INVAL;
    if (p->window_frames > SFD_MAX_WINDOW || p->group_size > SFD_MAX_GROUP ||
        p->max_hypotheses > SFD_MAX_HYPOTHESES) {
        return SFD_ERR_CAPACITY;
    }
    if (p->translation_known != 0 && p->translation_known != 1) return SFD_ERR_INVAL;
    if (p->exact_depth_covariance != 0 && p->exact_depth_covariance != 1) return SFD_ERR_INVAL;
    if (p->parity_isolation != 0 && p->parity_isolation != 1) return SFD_ERR_INVAL;
    // the parity detector stores depth priors as float (sfd_parity_obs_t)
    if (!sfd::depth_prior_fits_float(p->default_depth_m, p->default_depth_var_m2)) {
        return SFD_ERR_INVAL;
    }
    if (!(p->ransac_confidence > 0.0 && p->ransac_confidence < 1.0)) return SFD_ERR_INVAL;
    if (!sfd::all_finite(p->gyro_bias_rad_s, 3)) return SFD_ERR_INVAL;
    if (p->max_imu_gap_us <= 0) return SFD_ERR_INVAL;
    if (p->pixel_noise_adapt != 0 && p->pixel_noise_adapt != 1) return SFD_ERR_INVAL;
    if (p->evidence_frames < 0 || p->evidence_frames > SFD_MAX_WINDOW) return SFD_ERR_INVAL;
    if (!(p->both_parity_share > 0.0 && p->both_parity_share < 1.0)) return SFD_ERR_INVAL;
    if (!(p->alarm_hold_ratio > 0.0 && p->alarm_hold_ratio <= 1.0)) return SFD_ERR_INVAL;
    if (p->alarm_hold_frames < 1 || p->alarm_hold_frames > SFD_ALARM_HOLD_MAX_FRAMES)
        return SFD_ERR_INVAL;
    if (!(p->alarm_hold_max_statistic >= 1.0 && p->alarm_hold_max_statistic <= 1e6))
        return SFD_ERR_INVAL;
    if (!(p->alarm_hold_alpha_scale > 0.0 && p->alarm_hold_alpha_scale <= 1.0))
        return SFD_ERR_INVAL;
    if (!(p->evidence_ramp_share >= 0.0 && p->evidence_ramp_share <= 1.0)) return SFD_ERR_INVAL;
    if (!(p->alarm_hold_min_statistic >= 0.0 && p->alarm_hold_min_statistic <= 1.0))
        return SFD_ERR_INVAL;
    if (!(p->alarm_hold_direction_alpha >= 0.0 && p->alarm_hold_direction_alpha < 0.5))
        return SFD_ERR_INVAL;
    return SFD_OK;
}
