/* SPDX-License-Identifier: MIT */
/**
 * @file sfd_parity.h
 * @brief Stochastic parity-space test for spurious features (Tornqvist, Schon, Gustafsson 2008),
 *        with isolation inside failing groups and fault-signature classification (sfd additions).
 *
 * Two levels:
 * - sfd_parity_test_group(): the test of eqs. (24)-(33) on one group of n features over a window
 *   of L frames, from explicit inputs. Used by the detector, the paper reproduction and tests.
 * - sfd_parity_t: the detector. It keeps the sliding window of tracked features (caller-owned,
 *   fixed size), forms groups, runs the group tests, isolates the spurious features, and writes one
 *   verdict per input feature.
 *
 * Frames and symbols (paper notation): frame 0 is the oldest frame of the window and plays the
 * world frame. R_t = R_C0toCt rotates frame-0 coordinates into camera t (R_0 = I); p_t is camera
 * t's centre in frame 0 (m). y_{i,t} are undistorted normalized coordinates (x/z, y/z) of feature
 * i in frame t; zhat_{i,t} its predicted depth along camera t's optical axis (m).
 *
 * Design note with the derivations and every assumption the paper leaves open:
 * core/docs/parity_space.md.
 */
#ifndef SFD_PARITY_H
#define SFD_PARITY_H

#include <stdint.h>

#include "sfd_camera.h"
#include "sfd_chi2.h"
#include "sfd_config.h"
#include "sfd_params.h"
#include "sfd_status.h"
#include "sfd_window.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Largest residual dimension of one group: n (2L - 2) when the rotations leave the feature depth
 *  unobservable (rank(O_i) = 2); (2L - 3) n otherwise. */
#define SFD_PARITY_MAX_RESIDUAL (SFD_MAX_GROUP * (2 * SFD_MAX_WINDOW - 2))

/* ---------------------------------------------------------------------------------------------
 * Group test
 * ------------------------------------------------------------------------------------------- */

/** One group of n features over L frames: the inputs of eqs. (24)-(33). */
typedef struct {
    int32_t window_frames;     /**< L, 2..SFD_MAX_WINDOW */
    int32_t group_size;        /**< n, 1..SFD_MAX_GROUP */
    int32_t translation_known; /**< 1: p_t given (Section III-A); 0: eliminated (III-B) */
    int32_t
        exact_depth_covariance; /**< 1: depth term of eq. (22) from y_pred; 0: eq. (28) from y */
    double R_C0toCt[SFD_MAX_WINDOW][9];         /**< R_t, row-major; [0] must be identity */
    double p_CtInC0_m[SFD_MAX_WINDOW][3];       /**< p_t (m); used when translation_known */
    double y[SFD_MAX_GROUP][SFD_MAX_WINDOW][2]; /**< measured normalized coordinates */
    double y_pred[SFD_MAX_GROUP][SFD_MAX_WINDOW]
                 [2]; /**< predicted (xhat/zhat, yhat/zhat), eq. (22) */
    double cov_y[SFD_MAX_GROUP][SFD_MAX_WINDOW][3]; /**< sensor noise Cov(e^c) of y: xx, xy, yy */
    double depth_m[SFD_MAX_GROUP][SFD_MAX_WINDOW];  /**< zhat_{i,t} > 0 (m) */
    double depth_var_m2[SFD_MAX_GROUP][SFD_MAX_WINDOW]; /**< P_z = Cov(zhat_{i,t}) >= 0 (m^2) */
} sfd_parity_group_t;

/** Outcome of one group test. All GLR values are chi-square distributed under H0 with the dof
 *  beside them. */
typedef struct {
    int32_t per_feature_dim; /**< d = 2L - rank(O_i): residual dimension of one feature */
    int32_t residual_dim;    /**< nu of the group test: n d (known), (n - 1) d (unknown) */
    int32_t rank_O;          /**< rank of the per-feature observability block O_i (3 or 2) */
    double glr;              /**< eq. (13) with the general fault (H^f = I): |rbar|^2 */
    double feature_glr[SFD_MAX_GROUP];  /**< GLR of a general fault on feature j alone */
    int32_t feature_dof[SFD_MAX_GROUP]; /**< its dof (d, or 0 when the group cannot tell) */
    double jump_glr[SFD_MAX_GROUP];     /**< GLR of a jump: fault on feature j's newest y only */
    int32_t jump_dof[SFD_MAX_GROUP];    /**< its dof (<= 2) */
    double drift_glr[SFD_MAX_GROUP];    /**< GLR of a drift: fault growing linearly in t */
    int32_t drift_dof[SFD_MAX_GROUP];   /**< its dof (<= 2) */
    double whitened[SFD_PARITY_MAX_RESIDUAL]; /**< rbar = W^T Z (eq. 10/26/30), residual_dim long */
} sfd_parity_result_t;

/**
 * @brief Runs the parity test of eqs. (24)-(33) on one group.
 *
 * Residual: r = B^T Z with B an orthonormal basis of the orthogonal complement of O (eq. 27) or
 * of Otilde = [O O_2] (eqs. 29-33); whitened rbar = L^{-1} r with L L^T = B^T S B (a Cholesky
 * whitening: it differs from (B^T S B)^{-1/2} by an orthogonal matrix, which leaves every GLR
 * statistic unchanged); glr = |rbar|^2 = eq. (13) with H^f = I.
 *
 * @return SFD_OK (a group whose residual dimension is 0 is OK with glr = 0 and residual_dim = 0:
 *         it cannot be tested); SFD_ERR_INVAL for null, sizes out of range, non-finite values,
 *         depth <= 0, negative variance or R_0 != I; SFD_ERR_NUMERIC when a noise covariance
 *         B^T S B is not positive definite (e.g. zero pixel noise).
 */
sfd_status_t sfd_parity_test_group(const sfd_parity_group_t *group, sfd_parity_result_t *result);

/**
 * @brief Non-centrality lambda of eq. (16) for an additive fault on one measurement: y of feature
 *        @p feature in frame @p frame moves by @p fault (normalized coordinates). The group GLR is
 *        then non-central chi-square with residual_dim dof and this lambda.
 * @return as sfd_parity_test_group(), plus SFD_ERR_INVAL for an index out of range.
 */
sfd_status_t sfd_parity_noncentrality(const sfd_parity_group_t *group, int32_t feature,
                                      int32_t frame, const double fault[2], double *lambda);

/**
 * @brief Orthonormal basis of the orthogonal complement of O (known translation) or Otilde
 *        (unknown) for a whole group, as a dense row-major (2 n L) x dim matrix in @p basis
 *        (capacity @p capacity doubles). Rows are ordered feature-major: row 2(L i + t) + c is
 *        coordinate c of feature i in frame t. For tests and tools; the detector never forms it.
 * @return SFD_OK; SFD_ERR_INVAL; SFD_ERR_CAPACITY when capacity < 2 n L dim.
 */
sfd_status_t sfd_parity_group_basis(const sfd_parity_group_t *group, double *basis,
                                    int32_t capacity, int32_t *dim);

/* ---------------------------------------------------------------------------------------------
 * Detector
 * ------------------------------------------------------------------------------------------- */

/** Per-feature verdict status (numerically identical to the LCM feature_verdict_t constants). */
enum { SFD_VERDICT_UNTESTED = 0, SFD_VERDICT_CONSISTENT = 1, SFD_VERDICT_SPURIOUS = 2 };

/** Stage that decided (numerically identical to the LCM constants). */
enum {
    SFD_STAGE_NONE = 0,
    SFD_STAGE_PARITY = 1,
    SFD_STAGE_OPRF = 2,
    SFD_STAGE_RANSAC_1PT = 3,
    SFD_STAGE_RANSAC_F = 4
};

/** Why a feature got its verdict. */
enum {
    SFD_REASON_NONE = 0,        /**< tested in its group, group consistent */
    SFD_REASON_SHORT_TRACK = 1, /**< UNTESTED: tracked for fewer than L frames */
    SFD_REASON_BAD_INPUT = 2, /**< UNTESTED: non-finite pixel, duplicate id, undistortion failed */
    SFD_REASON_NO_GROUP = 3,  /**< UNTESTED: too few testable features for a group or reference */
    SFD_REASON_RANK = 4,      /**< UNTESTED: geometry leaves no residual (nu = 0) */
    SFD_REASON_NUMERIC = 5,   /**< UNTESTED: noise covariance not positive definite */
    SFD_REASON_GROUP_FAILED = 6, /**< SPURIOUS: member of a failing group (paper's discard rule) */
    SFD_REASON_ISOLATED = 7,     /**< decided by isolation inside / re-test outside its group */
    SFD_REASON_INCONCLUSIVE = 8, /**< SPURIOUS: group failed, isolation could not clear it */
    SFD_REASON_FEATURE_TEST = 9, /**< decided by the feature's own test with the translation
                                      and Cov(z) from the window filter (every feature alone) */
    SFD_REASON_EVIDENCE = 10,    /**< SPURIOUS: its window passed, but the test over its
                                      observations since its last alarm at the full threshold
                                      (up to evidence_frames frames) failed: slow drift or a
                                      moving point */
    SFD_REASON_ALARM_HOLD = 11,  /**< SPURIOUS: the track's last alarm_hold_frames
                                      observations were flagged by the window test (evidence
                                      flags, steps above alarm_hold_max_statistic and held
                                      flags below alarm_hold_min_statistic times the full
                                      threshold do not count) and its window test exceeds
                                      alarm_hold_ratio times the threshold but not the threshold
                                      (the statistic is relative to the lowered threshold, as a
                                      held CONSISTENT verdict's is: > 1 still means rejected) */
    SFD_REASON_EVIDENCE_RAMP = 12, /**< SPURIOUS: its window passed, but the ramp test over the
                                        evidence test's frames failed (a constant-rate slide
                                        against the static point; evidence_ramp_share) */
    SFD_REASON_AT_REST = 13        /**< decided by the rest test: the camera did not move
                                        (SFD_MOTION_AT_REST), so the feature must stay where its
                                        earlier observations were (SFD_FLAG_AT_REST) */
};

/** Fault signature of a SPURIOUS feature (needs L >= 3 to tell them apart). */
enum { SFD_FAULT_NONE = 0, SFD_FAULT_JUMP = 1, SFD_FAULT_DRIFT = 2, SFD_FAULT_UNKNOWN = 3 };

/** Per-frame flag bits of sfd_verdict_t.flags. */
#define SFD_FLAG_PARITY_ALARM 0x1u   /**< at least one group failed */
#define SFD_FLAG_RANK_DEFICIENT 0x2u /**< rotations left the depth unobservable (rank(O_i) = 2) */
#define SFD_FLAG_WINDOW_FILLING 0x4u /**< fewer than L frames in the window: nothing tested */
#define SFD_FLAG_BAD_FEATURES 0x8u   /**< some input features were rejected */
#define SFD_FLAG_NO_REFERENCE 0x10u  /**< isolation had no consistent reference features */
#define SFD_FLAG_TRANSLATION_UNKNOWN                                                           \
    0x20u /**< translation_known is configured, but the window filter could not give the       \
               window's poses (not started, a frame it did not clone): the unknown-translation \
               group test of eqs. (29)-(33) judged this frame */
#define SFD_FLAG_AT_REST                                                                      \
    0x40u /**< the frame's motion was SFD_MOTION_AT_REST and its features confirmed it: every \
               feature seen before was tested against its own earlier observations (the rest  \
               test, SFD_REASON_AT_REST; sfd_parity_push_frame_filter) */

/** One feature of an input frame. */
typedef struct {
    int64_t track_id;    /**< stable across frames */
    double u_px, v_px;   /**< raw (distorted) pixel coordinates */
    double depth_m;      /**< depth prior along the optical axis (m); <= 0: unknown, use default */
    double depth_var_m2; /**< variance of that prior (m^2) */
} sfd_feature_t;

/** One camera frame. Large (SFD_MAX_FEATURES entries): declare it static or in caller storage. */
typedef struct {
    int64_t utime;        /**< frame time (us), strictly increasing */
    int32_t num_features; /**< 0..SFD_MAX_FEATURES */
    sfd_feature_t features[SFD_MAX_FEATURES];
} sfd_frame_t;

/** Camera motion from the previous frame to this one (unused for the first frame). */
typedef struct {
    double R_CcurToCprev[9];   /**< camera rotation (from the gyro through the extrinsics) */
    int32_t translation_known; /**< 0: unknown; 1: p_CcurInCprev_m is the filter's estimate;
                                    SFD_MOTION_AT_REST (2): the IMU showed the camera at rest
                                    over the interval: the rest test assumes no rotation and no
                                    translation (p is ignored; R is still the gyro's, for the
                                    group test when the features refuse rest) */
    double p_CcurInCprev_m[3]; /**< current camera centre in the previous camera frame (m) */
} sfd_frame_motion_t;

/** sfd_frame_motion_t.translation_known: the camera was at rest between the two frames. */
#define SFD_MOTION_AT_REST 2

/** Verdict on one input feature (the LCM wire type of the same content is sfd_feature_verdict_t,
 *  generated from lcm_types/feature_verdict_t.lcm). */
typedef struct {
    int64_t track_id;
    int8_t status;     /**< SFD_VERDICT_* */
    int8_t stage;      /**< SFD_STAGE_* (PARITY when tested, NONE when not) */
    int8_t reason;     /**< SFD_REASON_* */
    int8_t fault_kind; /**< SFD_FAULT_* (SPURIOUS only) */
    int16_t dof;       /**< dof of the deciding test */
    double statistic;  /**< deciding GLR / its threshold: > 1 rejects; 0 when untested */
} sfd_feature_result_t;

/** Verdict on one frame: every input feature, in input order. */
typedef struct {
    int64_t utime;
    uint32_t flags; /**< SFD_FLAG_* */
    int32_t num_features;
    int32_t num_consistent, num_spurious, num_untested;
    int32_t groups_tested, groups_failed;
    sfd_feature_result_t features[SFD_MAX_FEATURES];
} sfd_verdict_t;

/** Window storage of one observation (plain data; fields are private to the detector; 40 B;
 *  the track id is kept for the newest two frames only, beside their hash tables).
 *  Floats throughout: a relative 6e-8, far below the pixel noise the tests resolve (5e-5 px at
 *  fx = 900 px); values beyond float's range are bad input, never stored clamped. */
typedef struct {
    float xn[2];   /* undistorted normalized coordinates */
    float depth_m; /* depth prior (positive, normal in float) */
    float depth_var_m2;
    float jjt_px2[3];  /* J J^T with J = d xn / d uv (xx, xy, yy): Cov(xn) per px^2 of pixel
                          noise variance, i.e. Cov(xn) = pixel_sigma_px^2 jjt_px2 (stored without
                          the sigma so that float storage cannot underflow at any valid sigma) */
    uint32_t cell_key; /* the spatial grouping's key: Z-order code of the raw pixel's 16-px cell */
    int16_t prev;      /* index of this track in the previous frame, -1 none */
    int8_t run;        /* consecutive frames observed, this one included (saturating at
                          SFD_MAX_WINDOW <= 127) */
    int8_t segment;    /* observations since the track's last alarm at the full threshold (a
                          held one does not count), this one included (saturating at
                          SFD_MAX_WINDOW <= 127; the evidence test's window) */
    int8_t alarm;      /* consecutive observations of the track the window test with the
                          filter's translation flagged (held alarms included) below
                          alarm_hold_max_statistic times the threshold, ending at this one (0:
                          not flagged, flagged by the evidence test, a step's alarm, or a held
                          alarm below alarm_hold_min_statistic times the full threshold that the
                          directional hold did not decide; 1 after an evidence or ramp alarm
                          with the directional hold on and a direction fitted; saturating at
                          SFD_ALARM_HOLD_MAX_FRAMES): the next one's alarm hold */
    int8_t dir;        /* the direction of the motion the window test with the filter's
                          translation fitted beside the point (sfd_window_motion_t), in one byte
                          (parity_space.md "Directional hold"); INT8_MIN: none. The next
                          observation's directional hold tests along it */
    int8_t valid;      /* 1 usable, 0 rejected input */
    int8_t prior; /* 1: depth_m, depth_var_m2 are the wire's prior; 0: the configured default */
} sfd_parity_obs_t;

typedef struct {
    int64_t utime;
    int32_t num;
    int32_t translation_known;
    double R_CtoCprev[9];
    double p_CinCprev_m[3];
    sfd_parity_obs_t obs[SFD_MAX_FEATURES];
} sfd_parity_frame_t;

#define SFD_PARITY_HASH_SLOTS (2 * SFD_MAX_FEATURES + 1)

/** The detector: caller-owned, fixed size (see proof.state_sizes). Not reentrant: one detector
 *  per thread; it is invalid to use one before sfd_parity_init() returned SFD_OK. */
typedef struct {
    uint32_t magic_;
    sfd_params_t params;
    sfd_camera_t camera;
    sfd_chi2_table_t chi2;
    sfd_chi2_table_t chi2_median; /* medians of chi2(k): the pixel noise scale's reference */
    sfd_chi2_table_t chi2_window; /* the window test with the filter's translation: alpha / 2
                                     with the evidence test (alpha without), times
                                     alarm_hold_alpha_scale with the alarm hold on */
    sfd_chi2_table_t chi2_half;   /* the omnibus evidence test: alpha / 2, times
                                     1 - evidence_ramp_share */
    double ramp_threshold;        /* the ramp test's chi2(2) threshold at evidence_ramp_share times
                                     alpha / 2; 0 when it is off */
    double hold_direction_z;      /* the directional hold's one-sided threshold: the standard
                                     normal's upper alarm_hold_direction_alpha quantile (0 when
                                     that is off) */
    double noise_scale;           /* pixel noise variance factor (pixel_noise_adapt), 1 at init */
    float stat_scratch[SFD_MAX_FEATURES]; /* one frame's statistics for the scale (no content
                                             kept between frames) */
    int32_t head;                         /* ring index of the newest frame */
    int32_t count;                        /* frames in the ring, <= L */
    sfd_parity_frame_t frames[SFD_MAX_WINDOW];
    int16_t hash[2][SFD_PARITY_HASH_SLOTS]; /* track id -> index, for the newest two frames */
    int64_t track_id[2][SFD_MAX_FEATURES];  /* their observations' track ids (side hash_cur: the
                                               newest frame) */
    int32_t hash_cur;
} sfd_parity_t;

/**
 * @brief Initializes the detector: validates @p params (window_frames, group_size,
 *        false_alarm_rate, pixel_sigma_px, depth defaults, translation and covariance modes) and
 *        copies them with @p camera; precomputes the chi-square thresholds.
 * @return SFD_OK; SFD_ERR_INVAL / SFD_ERR_CAPACITY from validation (detector left unusable).
 */
sfd_status_t sfd_parity_init(sfd_parity_t *det, const sfd_params_t *params,
                             const sfd_camera_t *camera);

/** @brief Empties the window (after a sensor gap or a reset of the caller's tracker).
 *  @return SFD_OK; SFD_ERR_STATE if not initialized; SFD_ERR_INVAL for null. */
sfd_status_t sfd_parity_reset(sfd_parity_t *det);

/**
 * @brief Undistorted normalized coordinates of feature @p index of the newest frame, as
 *        sfd_parity_push_frame() computed them with sfd_camera_undistort() and the detector's
 *        camera and stored them: rounded to float (bit-identical to rounding the result of
 *        calling it again), so that a caller working on the same frame with the same camera
 *        need not undistort twice.
 * @param utime the frame the caller means: must be the newest frame's time.
 * @return SFD_OK with @p xn filled; SFD_ERR_INVAL for null arguments, an index outside the newest
 *         frame, a different @p utime, an empty window, or a feature the frame rejected at
 *         ingest (not finite, not undistortable, or a repeated track id): @p xn untouched;
 *         SFD_ERR_STATE if not initialized.
 */
sfd_status_t sfd_parity_newest_xn(const sfd_parity_t *det, int64_t utime, int32_t index,
                                  double xn[2]);

/**
 * @brief Adds a frame to the window and judges every feature of it.
 *
 * Features tracked through all L frames of the window are tested; the others are UNTESTED with
 * a reason. Features with bad values (non-finite, duplicate track id in the frame, a pixel the
 * camera model cannot undistort) are UNTESTED (BAD_INPUT) and do not enter the window.
 *
 * The rest test (core/docs/parity_space.md "At rest"): with translation_known in the parameters
 * and @p motion SFD_MOTION_AT_REST, from the second frame on, every feature seen in the previous
 * frame is tested over its newest m = min(L, run) observations, back to the first frame whose
 * interval was not at rest: their deviation from their weighted mean, chi2(2 (m - 1)) at alpha,
 * SFD_REASON_AT_REST (SFD_REASON_NUMERIC when no statistic could be formed), whatever the window
 * holds (no filter is needed: at rest the motion is known, none). The features must agree: when
 * fewer than 16 are tested or, with the configured pixel noise, the median of their statistics
 * over their chi2 medians exceeds 2, the camera moved after all (a constant velocity or a small
 * constant acceleration, which an IMU's rest detector does not see): the frame is judged as one
 * of unknown translation, as below, with the motion's rotation.
 *
 * @param motion  camera motion since the previous frame (ignored for the first frame after init
 *                or reset; may be NULL then).
 * @param out     verdict, one entry per input feature in input order (caller-owned).
 * @return SFD_OK; SFD_ERR_INVAL for null or a motion that is not a rotation / non-finite / has a
 *         translation_known other than 0, 1 and SFD_MOTION_AT_REST (window unchanged);
 * SFD_ERR_CAPACITY for num_features outside [0, SFD_MAX_FEATURES] (window unchanged); SFD_ERR_ORDER
 * for utime not after the previous frame's (window unchanged); SFD_ERR_STATE if not initialized.
 */
sfd_status_t sfd_parity_push_frame(sfd_parity_t *det, const sfd_frame_t *frame,
                                   const sfd_frame_motion_t *motion, sfd_verdict_t *out);

/**
 * @brief sfd_parity_push_frame() with the translation known from a running window filter
 *        (Section III-A; core/docs/parity_space.md "Known translation from the window filter").
 *
 * When the parameters say translation_known and @p filter holds the window's frames (its newest
 * L - 1 clones are the window's older frames and its current state is at this frame's time),
 * every feature tracked through at least 2 of the L frames is tested alone, over min(its run,
 * L) frames, with sfd_window_test_track(): the
 * filter's poses and their covariance, the newest depth prior as a measurement, the threshold
 * chi2(dof, 1 - alpha) (alpha / 2 with the evidence test, times alarm_hold_alpha_scale with the
 * alarm hold on), or alarm_hold_ratio times it for a track whose last alarm_hold_frames
 * observations this test flagged (SFD_REASON_ALARM_HOLD when that flags it), or, with
 * alarm_hold_direction_alpha > 0 and a direction fitted at the track's previous observation,
 * one-sided along that direction (the directional hold: SFD_REASON_ALARM_HOLD with dof 1;
 * core/docs/parity_space.md "Directional hold"). Reason
 * SFD_REASON_FEATURE_TEST otherwise; a feature that cannot be triangulated is UNTESTED
 * (SFD_REASON_RANK). A feature whose window passed and whose segment is longer than L is tested
 * again over it (evidence_frames): the omnibus evidence test (SFD_REASON_EVIDENCE) at
 * (1 - evidence_ramp_share) alpha / 2 and the ramp test (SFD_REASON_EVIDENCE_RAMP,
 * sfd_window_test_track_evidence()) at evidence_ramp_share alpha / 2. Otherwise (no filter, not
 * started, a frame it did not clone, or translation_known = 0) this is sfd_parity_push_frame(), and
 * with translation_known the verdict carries SFD_FLAG_TRANSLATION_UNKNOWN when the
 * unknown-translation test judged the frame.
 *
 * @param filter may be NULL; @p scratch the filter's work space for the tests and @p ext the
 *        camera's pose in the IMU frame (both required with a filter).
 * @return as sfd_parity_push_frame().
 */
sfd_status_t sfd_parity_push_frame_filter(sfd_parity_t *det, const sfd_frame_t *frame,
                                          const sfd_frame_motion_t *motion, sfd_window_t *filter,
                                          sfd_window_scratch_t *scratch,
                                          const sfd_extrinsics_t *ext, sfd_verdict_t *out);

#ifdef __cplusplus
}
#endif

#endif /* SFD_PARITY_H */
