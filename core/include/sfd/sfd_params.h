/* SPDX-License-Identifier: MIT */
/**
 * @file sfd_params.h
 * @brief The one parameter struct of the detectors, its defaults and its validation.
 *
 * C has no default member initializers: always start from sfd_params_default() and change the
 * fields you need, then let the detector's init call sfd_params_validate().
 */
#ifndef SFD_PARAMS_H
#define SFD_PARAMS_H

#include <stdint.h>

#include "sfd_config.h"
#include "sfd_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Detection methods (SPEC "Commands", sfd-replay --method). */
typedef enum {
    SFD_METHOD_NONE = 0,    /**< accept every feature */
    SFD_METHOD_PARITY = 1,  /**< parity-space test (Tornqvist et al. 2008) */
    SFD_METHOD_OPRF = 2,    /**< one-point RANSAC with epipolar constraint (Kilic 2014) */
    SFD_METHOD_RANSAC1 = 3, /**< 1-point RANSAC, reprojection distance (Civera et al. 2010) */
    SFD_METHOD_RANSACF = 4, /**< fundamental-matrix RANSAC (Kilic 2014, Table 2) */
    SFD_METHOD_BOTH = 5     /**< parity first, then OPRF on the survivors */
} sfd_method_t;

typedef struct {
    int method;                 /**< sfd_method_t */
    double pixel_sigma_px;      /**< std. dev. of a feature's pixel noise per axis (px), > 0 */
    double false_alarm_rate;    /**< design alpha of the chi-square tests, in (0, 0.5] */
    int window_frames;          /**< parity window L (frames), 2..SFD_MAX_WINDOW */
    int group_size;             /**< parity group n (features), 1..SFD_MAX_GROUP */
    int translation_known;      /**< 1: translation from the filter; 0: unknown (eq. 29-33) */
    int exact_depth_covariance; /**< 1: exact noise covariance eq. (22); 0: approximation (28) */
    int parity_isolation;       /**< 1: isolate spurious features inside failing groups (sfd);
                                     0: discard every feature of a failing group (paper) */
    double
        default_depth_m; /**< depth prior when a feature carries none (m), > 0, normal in float */
    double default_depth_var_m2; /**< variance of that prior (m^2), >= 0, within float range */
    int max_hypotheses;          /**< RANSAC hypothesis budget per frame, 1..SFD_MAX_HYPOTHESES */
    double ransac_confidence;  /**< probability p of eq. (27) of drawing one clean sample, (0, 1) */
    double gyro_bias_rad_s[3]; /**< gyro bias subtracted before integration (rad/s) */
    int64_t max_imu_gap_us;    /**< largest IMU sample gap inside a frame interval (us), > 0 */
    uint64_t seed;             /**< PRNG seed of the RANSAC-type methods */
    int pixel_noise_adapt;     /**< 1: the test with the filter's translation scales the pixel
                                    noise variance by an online estimate (the median of each
                                    frame's statistics, core/docs/parity_space.md "Pixel noise
                                    scale"); 0: pixel_sigma_px as given */
    int evidence_frames;       /**< with the filter's translation: a feature whose window passed
                                    is tested again over its observations since its last alarm
                                    at the full threshold, up to this many frames (a
                                    window-limited GLR over the track's life,
                                    core/docs/parity_space.md "Evidence over a track's life");
                                    each test then at alpha / 2. 0 or <= window_frames: off; at
                                    most SFD_MAX_WINDOW */
    double both_parity_share;  /**< method both: the share of false_alarm_rate its parity stage
                                    gets; OPRF, which then judges parity's survivors, gets the
                                    rest, so a clean feature is flagged with probability at most
                                    false_alarm_rate (a weighted Bonferroni split); (0, 1) */
    double alarm_hold_ratio;   /**< with the filter's translation: a track whose last
                                    alarm_hold_frames observations the window test flagged is
                                    tested against this fraction of the window test's threshold (a
                                    two-threshold, hysteresis rule: a moving point stays flagged
                                    through the frames its window alone would pass;
                                    core/docs/parity_space.md "Alarm hold"); 1: off; (0, 1] */
    int alarm_hold_frames;     /**< consecutive flagged observations that start the hold,
                                    1..SFD_ALARM_HOLD_MAX_FRAMES */
    double alarm_hold_max_statistic;   /**< an alarm whose statistic exceeds this many times its
                                            threshold is a step (a jump, a mismatch: the track
                                            then follows another point) and neither starts nor
                                            continues the hold; [1, 1e6] */
    double alarm_hold_alpha_scale;     /**< with the hold on (alarm_hold_ratio < 1): the window test
                                            with the filter's translation runs at this fraction of
                                            its share of false_alarm_rate, so that a clean track's
                                            held repeats of a false alarm stay inside it (measured,
                                            not derived: core/docs/parity_space.md "Alarm hold");
                                            the evidence test (with its ramp test) keeps alpha / 2;
                                            no effect with the hold off; (0, 1] */
    double evidence_ramp_share;        /**< with the evidence test on: the share of its alpha / 2
                                            that the ramp test over the same frames gets (the GLR
                                            of a constant-rate slide, 2 dof;
                                            sfd_window_test_track_evidence(), core/docs/
                                            parity_space.md "Ramp"); the omnibus evidence test keeps
                                            the rest (none at 1); 0: no ramp test; [0, 1] */
    double alarm_hold_min_statistic;   /**< with the hold on: an alarm the hold decided (its
                                            statistic between alarm_hold_ratio and 1 times the
                                            window test's threshold) continues the hold only when
                                            its statistic is at least this many times that
                                            threshold; a weaker one ends the run of alarms, so the
                                            next observation is tested at the full threshold (a
                                            track whose fault has ended, which the lowered
                                            threshold would keep flagging, is released;
                                            core/docs/parity_space.md "Alarm hold"). 0 (or at most
                                            alarm_hold_ratio): every held alarm continues; [0, 1] */
    double alarm_hold_direction_alpha; /**< with the hold on: a held track whose previous
                                            observation's window fitted a motion is tested
                                            one-sided along that motion's direction, at this
                                            false-alarm level, instead of against
                                            alarm_hold_ratio times the threshold (a moving point
                                            or a slide keeps its direction; a track whose fault
                                            has ended does not: core/docs/parity_space.md
                                            "Directional hold"); such an alarm continues the
                                            hold whatever alarm_hold_min_statistic. 0: off;
                                            [0, 0.5) */
} sfd_params_t;

/** Longest run of flagged observations alarm_hold_frames may ask for (the detector counts a
 *  track's consecutive alarms in one byte). */
#define SFD_ALARM_HOLD_MAX_FRAMES 100

/** @brief Fills @p p with the defaults: method PARITY, 1 px, alpha 0.01, L = 3, n = 3, unknown
 *         translation, exact covariance (22), isolation on, depth 10 m with variance 0, 100
 * hypotheses, confidence 0.99, zero gyro bias, 50 ms IMU gap, seed 1, no alarm hold (ratio 1,
 *         after 1 alarm, steps above 3 times the threshold, alpha scale 0.3 when on).
 *  @return SFD_OK; SFD_ERR_INVAL for null. */
sfd_status_t sfd_params_default(sfd_params_t *p);

/** @brief Checks every field against its range and the compile-time capacities.
 *  @return SFD_OK; SFD_ERR_INVAL for null or a value out of range (non-finite included);
 *          SFD_ERR_CAPACITY for window_frames, group_size or max_hypotheses above the
 *          capacity of sfd_config.h. */
sfd_status_t sfd_params_validate(const sfd_params_t *p);

#ifdef __cplusplus
}
#endif

#endif /* SFD_PARAMS_H */
