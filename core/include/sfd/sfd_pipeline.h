/* SPDX-License-Identifier: MIT */
/**
 * @file sfd_pipeline.h
 * @brief The whole detection pipeline behind one transport-free handle: the IMU ring and the
 *        frame-motion assembly (sfd_imu_ring.h), the navigation filter (sfd_nav.h: the
 *        sliding-window filter by default), the parity detector (sfd_parity.h), the association
 *        methods (sfd_assoc.h) and the track bookkeeping between them. sfd-node, sfd-replay and
 *        sfd-hil run it through drivers/lcm, which only decodes, validates and publishes.
 *
 * Use:
 *     sfd_pipeline_init(&p, &cfg);
 *     sfd_pipeline_set_camera(&p, &cam, &ext);          once, and on every new calibration
 *     sfd_pipeline_push_imu(&p, &sample);               every IMU sample, in time order
 *     sfd_pipeline_push_frame(&p, &frame);              every feature frame, in time order
 *     while (sfd_pipeline_frames_due(&p) > 0) {         after every push
 *         sfd_pipeline_detect(&p);     filter brought to the frame time, parity verdicts
 *         sfd_pipeline_associate(&p);  matches with the filter's landmarks, hypothesis selection
 *         sfd_pipeline_update(&p);     association verdicts, filter update, track bookkeeping
 *         use sfd_pipeline_output(&p): the frame's verdict and the state after it
 *     }
 * The three stages are separate calls so that a caller can time each (SFD_TIMING's parity_us,
 * association_us, update_us); sfd_pipeline_judge() runs all three. The pipeline itself never
 * reads a clock, so the same inputs give the same outputs bit for bit.
 *
 * A frame is due at once when the IMU already covers its time, else it waits (at most one frame)
 * until an IMU sample reaches its time, the next frame arrives (it is then judged without IMU:
 * UNTESTED, counted as imu_late) or sfd_pipeline_flush() is called. At most two frames are due
 * at a time; a frame that finds both slots taken (a caller that does not judge due frames) is
 * refused with SFD_REJECT_CAPACITY and counted.
 *
 * Heap: none. Every array has a fixed capacity (SFD_MAX_FEATURES, SFD_MAX_WINDOW,
 * SFD_IMU_RING_CAPACITY); the state is caller-owned (declare it static: sizeof(sfd_pipeline_t)).
 * Not reentrant on one object.
 */
#ifndef SFD_PIPELINE_H
#define SFD_PIPELINE_H

#include <stdint.h>

#include "sfd_imu_ring.h"
#include "sfd_nav.h"
#include "sfd_parity.h"
#include "sfd_reject.h"
#include "sfd_status.h"
#include "sfd_time_guard.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Frames the pipeline holds between push_frame and the end of its judgement. */
#define SFD_PIPELINE_FRAME_SLOTS 2

/** Frame intervals whose median is the frame period of the frame_gap counter. */
#define SFD_PIPELINE_PERIOD_SAMPLES 8

/** Slots of the per-frame duplicate-track index (load factor <= 1/2). */
#define SFD_PIPELINE_DUP_SLOTS (2 * SFD_MAX_FEATURES + 1)

typedef struct {
    sfd_params_t params;          /**< detector (method: any sfd_method_t) */
    sfd_nav_config_t nav;         /**< the filter (required by oprf, ransac1, ransacf, both) */
    sfd_time_guard_params_t time; /**< time-glitch policy of both input streams */
} sfd_pipeline_config_t;

/** Counters since init. The transport adds what it saw before the pipeline (messages received,
 *  decode failures through sfd_pipeline_count_reject()), so that one set describes every input. */
typedef struct {
    int64_t rejected[SFD_REJECT_NUM_REASONS]; /**< by sfd_reject_reason_t */
    int64_t frames_in;                        /**< frames received (the transport counts them) */
    int64_t frames_refused;                   /**< of those, refused (any reason, the transport's
                                                   included): frames_in = frames_refused +
                                                   frames judged + frames held */
    int64_t frames_processed;                 /**< frames that produced a verdict */
    int64_t frames_untested; /**< of those, frames with no tested feature (window filling,
                                  IMU missing) */
    int64_t imu_in;          /**< IMU messages received (the transport counts them) */
    int64_t camera_info_in;  /**< calibrations received (the transport counts them) */
} sfd_pipeline_counters_t;

/** What one judged frame produced (valid after sfd_pipeline_update() until the next push). */
typedef struct {
    sfd_verdict_t verdict;   /**< per feature, in the frame's order */
    int32_t has_state;       /**< 1: the filter runs and the state below is after this frame */
    double p_IinW_m[3];      /**< IMU position in the world frame (m) */
    double v_IinW_m_s[3];    /**< IMU velocity in the world frame (m/s) */
    double q_ItoW[4];        /**< IMU-to-world rotation, w x y z */
    double p_var_m2[3];      /**< variances of the position (m^2) */
    int32_t hypotheses_used; /**< association hypotheses scored (0 without association) */
    int8_t budget_exhausted; /**< 1: the association stopped at its iteration budget */
} sfd_pipeline_output_t;

typedef enum {
    SFD_PIPELINE_SLOT_FREE = 0,
    SFD_PIPELINE_SLOT_WAITING = 1, /**< waits for IMU up to its time */
    SFD_PIPELINE_SLOT_DUE = 2      /**< to be judged */
} sfd_pipeline_slot_state_t;

typedef struct {
    sfd_pipeline_config_t cfg;
    sfd_params_t stage_params; /**< the parity detector's parameters: cfg.params, with method
                                    both the false-alarm rate times both_parity_share (OPRF, in
                                    nav, gets the rest of it), so that a clean feature is
                                    flagged with probability at most alpha */
    sfd_pipeline_counters_t counters;
    sfd_parity_t parity;
    sfd_nav_t nav;
    sfd_imu_ring_t ring;
    sfd_camera_t camera;
    sfd_extrinsics_t ext;
    int32_t have_camera;
    sfd_time_guard_t imu_time;   /**< time-glitch policy of the IMU stream */
    sfd_time_guard_t frame_time; /**< and of the frames */
    int64_t last_imu_utime;      /**< newest accepted IMU sample (us), INT64_MIN before */
    int64_t last_frame_utime;    /**< newest accepted frame (us), INT64_MIN before */
    /* the frame period for the frame_gap counter: the median of the last in-step intervals */
    int64_t period_us[SFD_PIPELINE_PERIOD_SAMPLES];
    int32_t period_count;
    int32_t period_next;
    int64_t prev_frame_utime; /**< the last judged frame (us) */
    int32_t have_prev_frame;
    /* frames held: waiting for IMU or due, judged oldest first */
    sfd_frame_t frames[SFD_PIPELINE_FRAME_SLOTS];
    int32_t slot_state[SFD_PIPELINE_FRAME_SLOTS];   /**< sfd_pipeline_slot_state_t */
    int32_t slot_reason[SFD_PIPELINE_FRAME_SLOTS];  /**< due: SFD_REJECT_NONE or why no IMU */
    uint32_t slot_seq[SFD_PIPELINE_FRAME_SLOTS];    /**< arrival order */
    int32_t slot_restart[SFD_PIPELINE_FRAME_SLOTS]; /**< 1: the first frame of another time base:
                                                        the frame side restarts before it */
    uint32_t next_seq;
    /* the frame being judged */
    int32_t cur_slot; /**< -1: none */
    int32_t stage;    /**< stages done on it: 0 none, 1 detect, 2 associate */
    int32_t nav_ok;   /**< the filter reached the frame time and runs */
    int32_t num_matches;
    sfd_status_t select_status;
    sfd_pipeline_output_t out;
    int32_t have_output;
    /* scratch */
    int8_t final_status[SFD_MAX_FEATURES];
    /** per feature, one frame: in stage 2 the features sfd_nav_build() skips; in stage 3 the
     *  SPURIOUS verdicts that condemn their whole track (sfd_nav_finish()'s whole_track) */
    uint8_t feature_mark[SFD_MAX_FEATURES];
    int16_t dup_index[SFD_PIPELINE_DUP_SLOTS]; /**< track id -> feature, -1 empty (one frame) */
} sfd_pipeline_t;

/** @brief Defaults: sfd_params_default() with the filter's translation (translation_known 1),
 *         the alarm hold (alarm_hold_ratio 0.25) and its release (alarm_hold_min_statistic
 *         0.4), and the ramp test (evidence_ramp_share 0.6); sfd_nav_config_default(),
 *         sfd_time_guard_params_default(). */
void sfd_pipeline_config_default(sfd_pipeline_config_t *cfg);

/**
 * @brief Initializes the pipeline; the detector starts with the first sfd_pipeline_set_camera().
 * @return SFD_OK; SFD_ERR_INVAL for null arguments, invalid parameters (detector, filter, time
 *         policy), or a method that needs the filter (OPRF, RANSAC1, RANSACF, BOTH) with
 *         cfg->nav.enabled = 0.
 */
sfd_status_t sfd_pipeline_init(sfd_pipeline_t *p, const sfd_pipeline_config_t *cfg);

/**
 * @brief A calibration (validated by the caller: sfd_camera_validate()). The same calibration
 *        bit for bit is a no-op (periodic republication); a new one restarts the detector's
 *        window and the filter's tracks and landmarks.
 * @return SFD_REJECT_NONE; SFD_REJECT_CORE (counted) when the detector refuses the camera.
 */
int sfd_pipeline_set_camera(sfd_pipeline_t *p, const sfd_camera_t *cam,
                            const sfd_extrinsics_t *ext);

/**
 * @brief One IMU sample. A waiting frame whose time it reaches becomes due. Its time is judged by
 *        the time-glitch policy (sfd_time_guard.h, docs/time_glitches.md); the sample that makes
 *        a new time base (a restarted IMU) empties the ring and stops the filter (it restarts
 *        from rest), and a waiting frame becomes due without IMU (imu_gap); counted as restart.
 * @return SFD_REJECT_NONE; SFD_REJECT_NONFINITE (a rate or specific force that is NaN, Inf or
 *         beyond SFD_IMU_MAX_GYRO_RAD_S / SFD_IMU_MAX_ACCEL_M_S2 on an axis: dropped before its
 *         time is looked at); SFD_REJECT_ORDER (not after the previous sample, within the
 *         horizon: dropped); SFD_REJECT_TIME_JUMP (farther than the horizon: dropped, never the
 *         reference); SFD_REJECT_IMU_OVERFLOW (stored, but the ring overwrote a sample a frame
 *         may need). Every reason is counted.
 */
int sfd_pipeline_push_imu(sfd_pipeline_t *p, const sfd_imu_sample_t *sample);

/**
 * @brief One feature frame (copied). A waiting frame becomes due first, without IMU. An
 *        accepted frame's malformed features are counted, per feature (they stay in the frame):
 *        a NaN/Inf pixel (feature_nonfinite), a track id that came earlier in the frame
 *        (feature_duplicate), a pixel outside the calibrated image (feature_outside); frames
 *        missing before it are counted (frame_gap: an interval of k frame periods, the period
 *        being the median of the last SFD_PIPELINE_PERIOD_SAMPLES in-step intervals, counts
 *        k - 1 once 4 intervals are known; an interval over 1.5 periods is a gap). Its time is
 *        judged by the time-glitch policy (sfd_time_guard.h); the frame that makes a new time base
 *        (a restarted camera or publisher) is accepted, and before it is judged the frame side
 *        restarts (parity window, filter, tracks; counted as restart), after the frames of the
 *        old time base.
 * @return SFD_REJECT_NONE (due or waiting); SFD_REJECT_NO_CAMERA_INFO (no calibration yet);
 *         SFD_REJECT_ORDER (not after the previous frame, within the horizon);
 *         SFD_REJECT_TIME_JUMP (farther than the horizon from the streams); SFD_REJECT_CAPACITY
 *         (more than SFD_MAX_FEATURES features, or no free slot: due frames were not judged).
 *         Every reason is counted; a refused frame gets no verdict.
 */
int sfd_pipeline_push_frame(sfd_pipeline_t *p, const sfd_frame_t *frame);

/** @brief End of input: a waiting frame becomes due without IMU (judged UNTESTED, imu_late). */
void sfd_pipeline_flush(sfd_pipeline_t *p);

/**
 * @brief A ground-truth pose (evaluation only, SPEC): used when cfg.nav.init_from_truth is set
 *        to start the filter (sfd_nav_truth()), ignored otherwise.
 */
void sfd_pipeline_truth(sfd_pipeline_t *p, int64_t utime, const double p_m[3],
                        const double q_wxyz[4]);

/**
 * @brief Starts the filter at a known state at @p utime instead of at rest (sfd_nav_start_at():
 *        a filter handed over from another source, or evaluation from a known start). IMU from
 *        @p utime on propagates it; frames before it are judged without the filter.
 * @return as sfd_nav_start_at(); SFD_ERR_STATE also while a frame is being judged.
 */
sfd_status_t sfd_pipeline_start_at(sfd_pipeline_t *p, int64_t utime, const double p_m[3],
                                   const double v_m_s[3], const double q_ItoW[4],
                                   const double bg_rad_s[3], const double ba_m_s2[3],
                                   const double p0_diag[SFD_EKF_DIM]);

/**
 * @brief A known landmark of a track (map-based localization: a surveyed map): the association
 *        methods match the track against it and the filter is updated with it; it is never
 *        refined. Call it before the frame that observes the track (again after a frame that
 *        judged the track SPURIOUS, which drops its landmark, or after a new calibration,
 *        which empties the map). The map holds SFD_MAX_LANDMARKS: a known landmark whose track
 *        was in no recent frame is evicted like any other when the map is full, so give a map
 *        larger than that shortly before the frames that see it. Works with the single-state EKF
 * (filter.window_filter = 0); the window filter triangulates its own points and does not read the
 * map.
 * @return as sfd_landmark_set(); SFD_ERR_STATE when the filter is not enabled, or between the
 *         stages of a frame (after sfd_pipeline_detect(), before sfd_pipeline_update() has
 *         finished it: the frame's matches refer to the map's entries).
 */
sfd_status_t sfd_pipeline_known_landmark(sfd_pipeline_t *p, int64_t track_id, const double p_W_m[3],
                                         const double cov_m2[9], int64_t utime);

/** @brief Frames due for judgement (0..SFD_PIPELINE_FRAME_SLOTS). */
int32_t sfd_pipeline_frames_due(const sfd_pipeline_t *p);

/**
 * @brief Stage 1 on the oldest due frame: the filter brought to its time (started at rest or
 *        propagated), the parity detector's verdicts (methods PARITY, BOTH).
 * @return SFD_OK; SFD_ERR_STATE when no frame is due or a judgement is in progress.
 */
sfd_status_t sfd_pipeline_detect(sfd_pipeline_t *p);

/**
 * @brief Stage 2: the frame's matches with the filter's landmarks, the association's hypothesis
 *        selection (OPRF, 1-point RANSAC, F-matrix RANSAC). Nothing when the filter does not run.
 * @return SFD_OK; SFD_ERR_STATE unless stage 1 ran on the frame.
 */
sfd_status_t sfd_pipeline_associate(sfd_pipeline_t *p);

/**
 * @brief Stage 3: the association's verdicts, the filter's update (the window filter's gated
 *        update: a flagged track ends before its flagged observation, or after an evidence or
 *        ramp flag is deleted whole; a gated one is dropped), landmarks and tracks kept for the
 * next frame; the output is complete and the frame's slot freed.
 * @return SFD_OK; SFD_ERR_STATE unless stage 2 ran on the frame.
 */
sfd_status_t sfd_pipeline_update(sfd_pipeline_t *p);

/** @brief Stages 1-3 on the oldest due frame. @return as the stages. */
sfd_status_t sfd_pipeline_judge(sfd_pipeline_t *p);

/** @brief The last judged frame's output, or NULL before the first. */
const sfd_pipeline_output_t *sfd_pipeline_output(const sfd_pipeline_t *p);

/** @brief Counts a rejection the transport made before the pipeline (decode, camera id, ...). */
void sfd_pipeline_count_reject(sfd_pipeline_t *p, int reason);

#ifdef __cplusplus
}
#endif

#endif /* SFD_PIPELINE_H */
