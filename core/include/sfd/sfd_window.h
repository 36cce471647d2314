/* SPDX-License-Identifier: MIT */
/**
 * @file sfd_window.h
 * @brief The sliding-window navigation filter (multi-state constraint Kalman filter, Mourikis &
 *        Roumeliotis 2007; core/docs/window_filter.md): the IMU state plus a fixed window of
 *        cloned IMU poses, propagated with every IMU sample, updated from feature tracks whose
 *        residuals are projected onto the left null space of their landmark Jacobian and
 *        chi-square gated (sfd_msckf.h) before they reach the update.
 *
 * Nominal state: position p_IinW (m), velocity v_IinW (m/s), orientation R_ItoW (quaternion w, x,
 * y, z), gyro bias bg (rad/s), accelerometer bias ba (m/s^2); then L clones (p_IinW, R_ItoW), the
 * IMU pose at each of the last L frames (with the keyframe option, at L frames of which the
 * newest keyframe_recent are the last ones), oldest first. World frame: z up, gravity (0, 0, -g).
 *
 * Error state (15 + 6 L, order SFD_WINDOW_IDX_*, clone i at 15 + 6 i: dp, dtheta):
 *   p = p^ + dp, v = v^ + dv, R = Exp(dtheta) R^ (dtheta in the WORLD frame, "global", unlike the
 *   local error of sfd_ekf.h: it makes the unobservable yaw direction the same vector for every
 *   pose, which the consistency treatment relies on), bg = bg^ + dbg, ba = ba^ + dba.
 *
 * Consistency (default): observability-constrained Jacobians (Hesch et al., IEEE T-RO 2014). The
 * Jacobians are evaluated at the current estimate, then the columns acting on the attitude error
 * along gravity (Phi_ptheta, Phi_vtheta and each clone's measurement Jacobian) get the smallest
 * rank-one correction that keeps the four unobservable directions unobservable: global
 * translation (dp = dp_i = I) and yaw about gravity (dp = g x p, dv = g x v, dtheta = g, and
 * dp_i = g x p_i, dtheta_i = g for clone i), at the estimates before each update. Then
 * Phi N_k = N_k+1 and H N = 0, and the filter does not gain false confidence in them. Roll and
 * pitch keep the current-estimate Jacobian. First-estimate Jacobians (Li & Mourikis 2013) are an
 * option (first_estimates = 1): consistent from the default P0, over-confident from ten times it
 * (core/docs/window_filter.md). Residuals, and the perspective derivative d(x/z, y/z)/dp_C, are
 * always evaluated at the current estimate (the point where it was triangulated).
 *
 * Per frame (sfd_window_frame): clone the current IMU pose into the window; add the frame's
 * observations (normalized undistorted coordinates, their 2x2 covariance from the pixel noise
 * through the distortion Jacobian, the wire's depth prior); drop the tracks the caller flags;
 * use every track that ended (not seen in this frame) or that starts in the oldest clone of a
 * full window when that clone leaves: triangulate it over the clones (bounded Gauss-Newton),
 * project, gate with chi2(rows - 3, 1 - alpha), fold the accepted ones; one update; then
 * marginalize the oldest clone when the window is full (with keyframes, a middle clone that
 * moved too little; its observations are deleted unused). A used or gated track's observations are
 * deleted (each observation informs the filter at most once; a gated one never).
 *
 * Capacities: SFD_MAX_WINDOW clones, SFD_WINDOW_MAX_TRACKS tracks of up to SFD_MAX_WINDOW
 * observations. Overflow is counted and the observation ignored, never written past an array.
 * No heap, no global state, no recursion; every loop has a fixed bound. The filter is large
 * (sizeof(sfd_window_t), ~58 KiB at the defaults, plus the caller's sfd_window_scratch_t,
 * ~53 KiB): declare them static or inside a static owner.
 */
#ifndef SFD_WINDOW_H
#define SFD_WINDOW_H
#include <stdint.h>
#include "sfd_config.h"
#include "sfd_ekf.h"
#include "sfd_msckf.h"
#include "sfd_rotation.h"
#include "sfd_status.h"
#ifdef __cplusplus
extern "C" {
#endif

/** Tracks the filter holds at once (one per feature of a frame). */
#define SFD_WINDOW_MAX_TRACKS SFD_MAX_FEATURES
/** Slots of the track-id index (load factor <= 1/2). */
#define SFD_WINDOW_INDEX_SLOTS (2 * SFD_WINDOW_MAX_TRACKS + 1)
/** Offsets of the IMU error-state blocks. */
#define SFD_WINDOW_IDX_P 0
#define SFD_WINDOW_IDX_V 3
#define SFD_WINDOW_IDX_THETA 6
#define SFD_WINDOW_IDX_BG 9
#define SFD_WINDOW_IDX_BA 12
/** Error-state dimension of the IMU part; clone i starts at SFD_WINDOW_IMU_DIM + 6 i. */
#define SFD_WINDOW_IMU_DIM 15

typedef struct {
    sfd_ekf_noise_t noise;              /**< IMU noise densities, gravity and largest step */
    double p0_diag[SFD_WINDOW_IMU_DIM]; /**< initial variances, SFD_WINDOW_IDX_* order (dtheta
                                             global: yaw is theta z) */
    int32_t window;                     /**< L: clones held, 2..SFD_MAX_WINDOW (5) */
    int32_t min_observations; /**< a track is used with at least this many clones, 2..L (3) */
    double gate_alpha;        /**< false-alarm rate of a consistent track's gate, (0, 0.5] (0.01) */
    double min_depth_m;       /**< a triangulated point closer to any clone is refused (0.1) */
    double max_depth_m;       /**< or farther (1e4) */
    int32_t use_depth_prior;  /**< depth priors of a track that are measurements: 0 none; 1 the
                                   first observation's; 2 the first and the newest observation's
                                   (2, the default; the wire's depth noise taken as independent
                                   between frames, core/docs/window_filter.md "Depth priors") */
    double depth_var_floor_m2;       /**< added to the wire's depth variance (1e-4) */
    int32_t gauss_newton_iterations; /**< triangulation steps, 1..20 (5) */
    int32_t first_estimates;         /**< 1: first-estimate Jacobians (an option: over-confident in
                                          unit.window_start_nees, from ten times the default P0,
                                          core/docs/window_filter.md); it overrides
                                          observability_constrained. 0: current estimates (0) */
    int32_t observability_constrained; /**< with first_estimates 0: 1 the current-estimate
                                            Jacobians corrected along gravity so the unobservable
                                            directions stay unobservable (1, the default); 0 no
                                            consistency treatment */
    double keyframe_parallax_rad;      /**< 0: the oldest clone leaves a full window (0, the
                                            default). > 0: keyframes: the clone just older than the
                                            newest keyframe_recent leaves instead when its mean
                                            rotation-compensated parallax from the clone before it is
                                            below this (normalized image units, about radians), so the
                                            older clones span more motion (core/docs/window_filter.md
                                            "Keyframes") */
    int32_t keyframe_recent; /**< with keyframes: the newest clones always kept consecutive, 1..L-2
                                  (the parity test's window_frames - 1) */
    int32_t flagged_earlier; /**< 1: an observation flagged with drop 1 ends its track: the
                                  observations before it are used as an ended track (through the
                                  gate), then the track is deleted (1, the default); 0: every
                                  flag deletes the track's earlier observations unused, as drop
                                  2 does (core/docs/window_filter.md "Flagged tracks") */
} sfd_window_params_t;

/** One observation handed to sfd_window_frame(). */
typedef struct {
    int64_t track_id;
    double xn[2];        /**< normalized undistorted coordinates (x/z, y/z) */
    double cov_xn[3];    /**< their covariance: xx, xy, yy (from the pixel noise through the
                              distortion Jacobian), positive definite */
    double depth_m;      /**< depth prior along the optical axis (m); <= 0: none */
    double depth_var_m2; /**< its variance (m^2), >= 0 */
    int32_t drop;        /**< 0: use it. 1: the caller judged this observation spurious: it is
                              not added, and the track ends before it (flagged_earlier 1: its
                              earlier observations are due now; 0: deleted). 2 (or any other
                              nonzero value): the whole track is judged spurious: every
                              observation of it is deleted unused */
} sfd_window_obs_t;

/** What one frame did (sfd_window_frame). */
typedef struct {
    int32_t added;       /**< observations added to tracks */
    int32_t dropped;     /**< tracks the caller flagged (drop 1 with flagged_earlier 1: ended,
                              and also counted among the candidates below; otherwise deleted
                              unused) */
    int32_t overflow;    /**< observations ignored: track table full, duplicate id, bad values */
    int32_t candidates;  /**< tracks that ended or reached the oldest clone */
    int32_t too_short;   /**< of those, fewer than min_observations: deleted unused */
    int32_t no_geometry; /**< not triangulable (no parallax, behind a camera): deleted unused */
    int32_t gated;       /**< failed the chi-square gate: deleted, never used */
    int32_t used;        /**< passed and folded into the update */
    int32_t rows;        /**< projected rows folded */
    double nis;          /**< sum of the used tracks' gate statistics (chi2(rows)) */
    sfd_status_t update_status; /**< of the Kalman update (SFD_OK when nothing to update) */
    int32_t num_gated_ids;      /**< entries of gated_ids */
    int64_t gated_ids[SFD_WINDOW_MAX_TRACKS]; /**< the tracks the gate refused in this frame */
} sfd_window_result_t;

typedef struct {
    int32_t used;         /**< observations held (consecutive clones from first_clone) */
    uint32_t first_clone; /**< sequence number of the clone of observation 0 */
    int32_t seen;         /**< 1: observed in the newest frame; 2: flagged in it (drop 1, its
                               earlier observations due now) */
    float depth_last_m;   /**< depth prior of the newest observation, <= 0: none (with
                               depth_last_var_m2 at the end: both in what was padding when L
                               is odd and int64_t is 8-byte aligned, as on the hosts and
                               Cortex-M7; 8 B more per track otherwise) */
    int64_t id;
    float depth_m; /**< depth prior of observation 0, <= 0: none (float: one beyond float's
                        range, or with a variance beyond it, is none) */
    float depth_var_m2;
    /** the observations, stored as float (a relative 6e-8, far below the pixel noise; an
     *  observation outside float's range or whose covariance is not positive definite in float
     *  is refused) and used in double */
    float xn[SFD_MAX_WINDOW][2];
    float cov_xn[SFD_MAX_WINDOW][3];
    float depth_last_var_m2; /**< its variance (m^2) */
} sfd_window_track_t;

typedef struct {
    double p_IinW_m[3];
    double q_ItoW[4];
    double fe_p_IinW_m[3]; /**< first estimate: the pose at cloning (the IMU's first estimate of
                                the position; first-estimate Jacobians, and the point of the
                                clone's yaw direction for the observability constraint) */
    double fe_R_ItoW[9];
    int64_t utime;
    uint32_t seq; /**< sequence number (consecutive over the window) */
} sfd_window_clone_t;

/** The filter (caller-owned). */
typedef struct {
    sfd_window_params_t prm;
    int32_t started;
    int64_t utime; /**< time the IMU state refers to (us) */
    double p_IinW_m[3];
    double v_IinW_m_s[3];
    double q_ItoW[4];
    double bg_rad_s[3];
    double ba_m_s2[3];
    /* first estimates of the IMU state for the next transition (before the last update): the
     * point of the unobservable directions (both treatments) */
    double fe_p_IinW_m[3];
    double fe_v_IinW_m_s[3];
    /* transition and noise accumulated since the covariance was last brought up to date */
    int32_t pending;
    double Phi[SFD_WINDOW_IMU_DIM][SFD_WINDOW_IMU_DIM];
    double Qd[SFD_WINDOW_IMU_DIM][SFD_WINDOW_IMU_DIM];
    int32_t num_clones;
    uint32_t next_seq;
    sfd_window_clone_t clones[SFD_MAX_WINDOW];
    double P[SFD_MSCKF_DIM][SFD_MSCKF_DIM]; /**< covariance of the error state, SPD */
    double gate[SFD_MSCKF_TRACK_ROWS];      /**< chi2(k, 1 - alpha) for k rows */
    int32_t num_tracks;
    sfd_window_track_t tracks[SFD_WINDOW_MAX_TRACKS];
    int16_t index[SFD_WINDOW_INDEX_SLOTS]; /**< track id -> tracks[] entry, -1 empty */
    uint32_t numeric_faults;               /**< updates or propagations refused */
} sfd_window_t;

/**
 * Work space of one call of sfd_window_frame() or sfd_window_test_track(), owned by the caller
 * and separate from sfd_window_t so that a caller can overlay it with other per-frame work
 * (sfd_nav_t shares it with the association's matches, which are dead by then). No content is
 * kept between calls: any scratch of the right type will do, but one scratch must not serve two
 * calls at once. After sfd_window_frame, track holds the last track of that frame whose rows
 * were complete when its rows is nonzero: unprojected, whitened (R = I), with the clone columns
 * of before the frame's marginalization (unit.window projects and reads it).
 */
typedef struct {
    sfd_msckf_track_t track; /**< one track's rows (both calls) */
    sfd_msckf_stack_t stack; /**< the frame's folded tracks (sfd_window_frame) */
    union {
        sfd_msckf_work_t work; /**< the update's matrices (sfd_window_frame) */
        /** where a caller may build the frame's observations for sfd_window_frame(), which
         *  reads every one of them before it writes work */
        sfd_window_obs_t obs[SFD_WINDOW_MAX_TRACKS];
    } u;
    double dx[SFD_MSCKF_DIM];
} sfd_window_scratch_t;

/** @brief The defaults in parentheses above; noise sfd_ekf_noise_default(); P0 position 1e-6 m^2,
 *         velocity 1e-4 m^2/s^2, roll and pitch 1e-4 rad^2, yaw 1e-6 rad^2, gyro bias 1e-6
 *         (rad/s)^2 (estimated at rest), accelerometer bias 4e-3 (m/s^2)^2 (a prior). */
sfd_status_t sfd_window_params_default(sfd_window_params_t *params);

/** @brief Validates the parameters and empties the filter (not started).
 *  @return SFD_OK; SFD_ERR_INVAL for null or a value out of range (filter unchanged). */
sfd_status_t sfd_window_init(sfd_window_t *w, const sfd_window_params_t *params);

/**
 * @brief Starts at rest (WINDOW_FILTER.md "Consistency and start"): position 0, velocity 0,
 *        yaw 0, roll and pitch from the mean specific force (which points up at rest), gyro bias
 *        the mean gyro at rest, accelerometer bias 0 with its prior variance; no clone.
 * @return SFD_OK; SFD_ERR_INVAL for null or non-finite input; SFD_ERR_DOMAIN when |accel| is
 *         not within 30 % of gravity.
 */
sfd_status_t sfd_window_start_at_rest(sfd_window_t *w, int64_t utime, const double accel_m_s2[3],
                                      const double gyro_bias_rad_s[3]);

/** @brief Starts at a given state (evaluation: from TRUTH), with the P0 of the parameters.
 *  @return SFD_OK; SFD_ERR_INVAL for null, non-finite input or a quaternion not of unit norm
 *          within 1e-6. */
sfd_status_t sfd_window_start_at(sfd_window_t *w, int64_t utime, const double p_m[3],
                                 const double v_m_s[3], const double q_ItoW[4],
                                 const double bg_rad_s[3], const double ba_m_s2[3]);

/**
 * @brief Propagates the IMU state by one interval dt with gyro and accel held (zero-order hold):
 *        R' = R Exp(w dt), v' = v + (R a + g) dt, p' = p + v dt + (R a + g) dt^2 / 2 with
 *        w = gyro - bg, a = accel - ba. The transition Phi (eq. (5) of
 *        core/docs/window_filter.md, with the consistency treatment of the parameters) and the
 *        discrete noise accumulate; the covariance is brought
 *        up to date when the next frame or a reader needs it.
 * @return SFD_OK; SFD_ERR_STATE when not started; SFD_ERR_INVAL for null, non-finite values or
 *         dt outside (0, max_dt_s] (nothing changed); SFD_ERR_NUMERIC when the result is not
 *         finite (nothing changed; counted).
 */
sfd_status_t sfd_window_propagate(sfd_window_t *w, const double gyro_rad_s[3],
                                  const double accel_m_s2[3], double dt_s);

/**
 * @brief One frame at the filter's current time (propagate to the frame's time first): clone,
 *        observations, the updates of the tracks that are due, marginalization (file comment).
 * @param obs n observations (n <= SFD_WINDOW_MAX_TRACKS; bad ones counted in overflow); they
 *        may be in scratch->u.obs (read before the update uses that memory).
 * @param ext the camera's pose in the IMU frame.
 * @param scratch the call's work space (required; sfd_window_scratch_t).
 * @param result required.
 * @return SFD_OK (also when nothing was updated; see result->update_status); SFD_ERR_STATE when
 *         not started; SFD_ERR_INVAL for null or n out of range (nothing changed).
 */
sfd_status_t sfd_window_frame(sfd_window_t *w, int64_t utime, const sfd_window_obs_t *obs,
                              int32_t n, const sfd_extrinsics_t *ext, sfd_window_scratch_t *scratch,
                              sfd_window_result_t *result);

/** @brief The IMU state's orientation error covariance in the LOCAL convention of sfd_ekf.h and
 *         the whole IMU state as an sfd_ekf_t (for the association methods' hypotheses, which
 *         work on it): dtheta_local = R^T dtheta_global, other blocks as they are.
 *  @return SFD_OK; SFD_ERR_STATE when not started; SFD_ERR_INVAL for null. */
sfd_status_t sfd_window_to_ekf(sfd_window_t *w, sfd_ekf_t *ekf);

/** One feature over the newest m frames, for sfd_window_test_track(). */
typedef struct {
    int32_t frames;                   /**< m, 2..SFD_MAX_WINDOW */
    int64_t utime[SFD_MAX_WINDOW];    /**< frame times, oldest first (must match the filter's) */
    double xn[SFD_MAX_WINDOW][2];     /**< normalized undistorted coordinates, oldest first */
    double cov_xn[SFD_MAX_WINDOW][3]; /**< their covariance (xx, xy, yy), positive definite */
    double depth_m;                   /**< depth prior of the NEWEST observation; <= 0: none */
    double depth_var_m2;              /**< its variance (m^2), >= 0 */
} sfd_window_test_obs_t;

/**
 * @brief The parity test of one feature with the translation known from the filter and Cov(z)
 *        from its covariance (Tornqvist et al. 2008, Section III-A; core/docs/parity_space.md
 *        "Known translation from the window filter"): the feature's point is triangulated over
 *        the m frames (the newest m - 1 clones and the current, propagated IMU state, which is
 *        the frame being judged), its stacked residual (2 rows per frame, plus the newest depth
 *        prior when the parameters use depth priors) is projected onto the left null space of
 *        the point's Jacobian, and gamma = r_o^T (H_o P H_o^T + R_o)^-1 r_o with the filter's
 *        covariance P of the m poses is chi2(dof) for a static, correctly tracked feature. The
 *        Jacobians are at the current estimates. Nothing of the filter changes (the pending
 *        covariance propagation is applied, which is invisible; scratch->track is overwritten).
 * @return SFD_OK with gamma, dof; SFD_ERR_INVAL for null (scratch included), m out of range,
 * non-finite or not positive definite input; SFD_ERR_STATE when not started, fewer than m - 1
 * clones, or a frame time that is not the filter's; SFD_ERR_NUMERIC when the point cannot be
 *         triangulated (no parallax without a depth prior, behind a camera, out of
 *         [min_depth_m, max_depth_m]) or the test's covariance is not positive definite.
 */
sfd_status_t sfd_window_test_track(sfd_window_t *w, const sfd_extrinsics_t *ext,
                                   const sfd_window_test_obs_t *obs, sfd_window_scratch_t *scratch,
                                   double *gamma, int32_t *dof);

/**
 * @brief sfd_window_test_track() over obs's m frames and, in the same linearization, over the
 *        newest @p inner of them (parity_space.md "The evidence test"): the point is triangulated
 *        once, over the m frames; the inner test is the statistic of the newest inner frames'
 *        rows (and of the depth prior, the newest frame's), with their blocks of S, H_f and r (a
 *        block of a covariance is the covariance of its rows). The projection onto H_f's left
 *        null space removes the point's error to first order, so the inner statistic differs from
 *        sfd_window_test_track() over those frames alone (whose point is triangulated from them)
 *        at second order in the difference of the two points: chi2 with the same dof for a
 *        static, correctly tracked feature. It costs one statistic instead of a second
 *        linearization.
 * @param inner 2 <= inner < m.
 * @param gamma gamma[0] of the inner test, gamma[1] of the m-frame test; dof likewise.
 * @return as sfd_window_test_track(); SFD_ERR_INVAL also for inner out of range. On any error
 *         nothing is written to gamma and dof.
 */
sfd_status_t sfd_window_test_track_nested(sfd_window_t *w, const sfd_extrinsics_t *ext,
                                          const sfd_window_test_obs_t *obs, int32_t inner,
                                          sfd_window_scratch_t *scratch, double gamma[2],
                                          int32_t dof[2]);

/**
 * @brief sfd_window_test_track_nested() and, from the same factorization, the ramp test over
 *        obs's m frames (parity_space.md "Ramp"): the GLR of a fault that shifts frame k's
 *        observation (k = 0 the oldest) by k v in normalized image coordinates, v unknown (a
 *        track sliding off its point at a constant rate since the window's first frame, or a
 *        point moving across the image), against the static point. With the point's three
 *        parameters and v's two fitted, the GLR is chi2(2) for a static, correctly tracked
 *        feature, whatever m: a directed test that needs less evidence than the m-frame
 *        omnibus test (dof 2 m + d - 3) when the fault is a ramp.
 * @param gamma gamma[0], gamma[1] as sfd_window_test_track_nested(); gamma[2] the ramp's GLR.
 * @param dof dof[0], dof[1] likewise; dof[2] = 2, or 0 (gamma[2] = 0) when the ramp cannot be
 *        told from the point (fewer than 6 rows, or no motion that separates them).
 * @return as sfd_window_test_track_nested().
 */
sfd_status_t sfd_window_test_track_evidence(sfd_window_t *w, const sfd_extrinsics_t *ext,
                                            const sfd_window_test_obs_t *obs, int32_t inner,
                                            sfd_window_scratch_t *scratch, double gamma[3],
                                            int32_t dof[3]);

/** The motion of one track over the frames of a test, fitted beside its point
 *  (sfd_window_test_track_motion(); core/docs/parity_space.md "Directional hold"). The motion is
 *  a ramp: frame j of the T frames (j = 0 the oldest) shifted by j v in normalized image
 *  coordinates, v = (v_x, v_y) per frame. With the whitened residual w and the ramp's whitened
 *  columns F, both projected off the point's columns (P), info = F^T P F and score = F^T P w:
 *  the motion's estimate is v = info^-1 score, and along a direction d given in advance the
 *  one-sided statistic z = d^T score / sqrt(d^T info d) is N(0, 1) for a static, correctly
 *  tracked feature, N(d^T info v / sqrt(d^T info d), 1) for one moving by v per frame. */
typedef struct {
    int32_t ok;      /**< 1: fitted; 0: the ramp cannot be told from the point over these frames
                          (fewer than 6 rows, i.e. fewer than 3 frames, or no motion separates
                          them; info and score are then 0) */
    double info[3];  /**< F^T P F: xx, xy, yy (per (normalized unit per frame)^2) */
    double score[2]; /**< F^T P w: x, y */
} sfd_window_motion_t;

/**
 * @brief sfd_window_test_track() (@p inner 0) or sfd_window_test_track_nested() (2 <= @p inner <
 *        m), with the ramp test over the m frames when @p ramp is 1
 *        (sfd_window_test_track_evidence(); only with a nested test), and, from the same
 *        factorization, the ramp's fit over the decisive test's frames: the newest @p inner
 *        frames, or all m with @p inner 0 (sfd_window_motion_t; parity_space.md "Directional
 *        hold"). The parity detector's one call per feature.
 * @param gamma gamma[0] the decisive test's statistic (the m-frame test with inner 0, the inner
 *        test otherwise); gamma[1] the m-frame test's with a nested test (else 0); gamma[2] the
 *        ramp's GLR (0 when not computed). dof likewise (dof[2] = 2, or 0 as for
 *        sfd_window_test_track_evidence()).
 * @param motion the fit; NULL: no fit (the tests alone, at their cost).
 * @return as sfd_window_test_track_nested() (SFD_ERR_INVAL also for inner not 0 nor in
 *         2..m - 1, ramp not 0 or 1, or ramp 1 without a nested test). On any error nothing is
 *         written to gamma, dof and motion.
 */
sfd_status_t sfd_window_test_track_motion(sfd_window_t *w, const sfd_extrinsics_t *ext,
                                          const sfd_window_test_obs_t *obs, int32_t inner,
                                          int32_t ramp, sfd_window_scratch_t *scratch,
                                          double gamma[3], int32_t dof[3],
                                          sfd_window_motion_t *motion);

/** @brief Position variance (m^2, x y z) of the IMU state. SFD_ERR_STATE when not started. */
sfd_status_t sfd_window_position_var(sfd_window_t *w, double var_m2[3]);

#ifdef __cplusplus
}
#endif
#endif /* SFD_WINDOW_H */
