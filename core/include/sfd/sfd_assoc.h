/* SPDX-License-Identifier: MIT */
/**
 * @file sfd_assoc.h
 * @brief Data association inside the EKF (Kilic 2014 Chapter III): one-point RANSAC with epipolar
 *        constraint (OPRF, Section 3.2 and Table 1), the baselines 1-point RANSAC with reprojection
 *        distance (Civera et al. 2010, Table 1), fundamental-matrix RANSAC (Table 2) and no
 *        association. Each run judges every match, updates the filter with the accepted ones and
 *        reports what it did. Bounded: at most max_hypotheses hypotheses per frame.
 *
 * Derivations, the readings chosen where the thesis is ambiguous, and the limitations:
 * core/docs/association.md.
 */
#ifndef SFD_ASSOC_H
#define SFD_ASSOC_H
#include <stdint.h>
#include "sfd_camera.h"
#include "sfd_config.h"
#include "sfd_ekf.h"
#include "sfd_params.h"
#include "sfd_prng.h"
#include "sfd_status.h"
#ifdef __cplusplus
extern "C" {
#endif

/** One correspondence: the previous frame's observation of a track and the current one, the
 *  track's landmark and the pixel noise of both observations through the distortion (zero:
 *  isotropic). The landmark is referred to, not copied (72 B a match on a 64-bit host instead of
 *  152): the caller keeps it in place and unchanged while the match is used (the pipeline's
 *  matches point into its landmark map's entries). A match whose landmark pointers are NULL or
 *  whose values are not finite is judged unusable, as a landmark behind the camera is. */
typedef struct {
    double prev_uv_px[2];          /**< undistorted pixel in the previous frame */
    double uv_px[2];               /**< undistorted pixel in the current frame */
    const double *landmark_W_m;    /**< the track's landmark in the world (3 values, m) */
    const double *landmark_cov_m2; /**< its covariance (9, row-major, symmetric PSD; zeros =
                                        exact) */
    sfd_pixel_noise_t noise;       /**< covariances of both pixels in units of sigma^2, minus I
                                        (sfd_camera_pixel_noise()); all zero = isotropic */
} sfd_match_t;

/** Block width of OPRF's hypothesis scoring (floats scored together); the packed arrays below
 *  are padded to a multiple of it. */
#define SFD_ASSOC_SCORE_BLOCK 8
/** Capacity of the packed scoring arrays: SFD_MAX_FEATURES rounded up to the block width. */
#define SFD_ASSOC_PACKED_CAP                                                    \
    (((SFD_MAX_FEATURES + SFD_ASSOC_SCORE_BLOCK - 1) / SFD_ASSOC_SCORE_BLOCK) * \
     SFD_ASSOC_SCORE_BLOCK)

/** Parameters of the association methods. */
typedef struct {
    int32_t method;          /**< SFD_METHOD_NONE, _OPRF, _RANSAC1 or _RANSACF */
    double false_alarm_rate; /**< alpha of the inlier thresholds (chi-square), in (0, 0.5] */
    double confidence;       /**< p of eq. (27), in (0, 1) */
    int32_t max_hypotheses;  /**< budget per frame, 1..SFD_MAX_HYPOTHESES (both stages together) */
    double min_parallax_px;  /**< OPRF: below this expected parallax the motion is degenerate
                                  for epipolar geometry (px), >= 0 */
    uint64_t seed;           /**< seed of the hypothesis draws */
} sfd_assoc_params_t;

/** OPRF's hypothesis scoring inputs: the valid matches in normalized image coordinates (K^-1 x)
 *  and their pixel-noise excess dC (sfd_pixel_noise_t), single precision, structure of arrays,
 *  padded with NaN to a whole block. */
typedef struct {
    float nx_prev_u[SFD_ASSOC_PACKED_CAP];
    float nx_prev_v[SFD_ASSOC_PACKED_CAP];
    float nx_curr_u[SFD_ASSOC_PACKED_CAP];
    float nx_curr_v[SFD_ASSOC_PACKED_CAP];
    float dc_prev_xx[SFD_ASSOC_PACKED_CAP]; /**< C_prev - I, xx (dimensionless) */
    float dc_prev_xy[SFD_ASSOC_PACKED_CAP];
    float dc_prev_yy[SFD_ASSOC_PACKED_CAP];
    float dc_curr_xx[SFD_ASSOC_PACKED_CAP]; /**< C_curr - I, xx (dimensionless) */
    float dc_curr_xy[SFD_ASSOC_PACKED_CAP];
    float dc_curr_yy[SFD_ASSOC_PACKED_CAP];
    float packed_stat[SFD_ASSOC_PACKED_CAP]; /**< statistic of each packed match (sigma^2 units) */
} sfd_assoc_oprf_work_t;

/** The fundamental-matrix RANSAC's compacted inputs (sfd_ransacf()). */
typedef struct {
    double x_prev[SFD_MAX_FEATURES][2];
    double x_curr[SFD_MAX_FEATURES][2];
    sfd_pixel_noise_t noise[SFD_MAX_FEATURES];
} sfd_assoc_ransacf_work_t;

/** 1-point RANSAC's reprojection covariance per match:
 *  S = sigma^2 C_curr + J_L C_L J_L^T (px^2; xx, xy, yy). */
typedef struct {
    double S_px2[SFD_MAX_FEATURES][3];
} sfd_assoc_ransac1_work_t;

/**
 * The method's work space (the method is fixed at init: one member is ever used), owned by the
 * caller and separate from sfd_assoc_t so that it can share memory with work of other stages
 * (sfd_nav_t overlays it with the window filter's). It carries data from sfd_assoc_select() to
 * sfd_assoc_apply() (RANSAC1's per-match covariances): pass the same work space to both, and
 * touch it in between only through them.
 */
typedef union {
    sfd_assoc_oprf_work_t oprf;
    sfd_assoc_ransacf_work_t ransacf;
    sfd_assoc_ransac1_work_t ransac1;
} sfd_assoc_work_t;

/** Caller-owned association object: parameters, the seeded generator and the per-frame
 *  workspace (no large arrays on the stack). Initialise with sfd_assoc_init(). */
typedef struct {
    sfd_assoc_params_t params;
    sfd_prng_t rng;
    double chi2_1; /**< chi2_{1, 1-alpha}: Sampson threshold in units of sigma^2 */
    double chi2_2; /**< chi2_{2, 1-alpha}: reprojection / transfer threshold in sigma^2 units */
    double chi2_1_trunc_median; /**< median of chi2(1) truncated at chi2_1: its quantile at
                                     (1 - alpha) / 2 (the noise scale's refinement) */
    double sampson_scale; /**< this frame's noise scale of the Sampson distance, from the chosen
                               hypothesis' distances (core/docs/association.md "Noise scale");
                               1 for other scores */
    int32_t valid_idx[SFD_MAX_FEATURES];
    uint8_t valid[SFD_MAX_FEATURES];
    uint8_t cur[SFD_MAX_FEATURES];
    uint8_t best[SFD_MAX_FEATURES];
    uint8_t rescued[SFD_MAX_FEATURES];
    float cur_stat[SFD_MAX_FEATURES];
    float best_stat[SFD_MAX_FEATURES];
    /** private: the caller's work space (sfd_assoc_work_t) during a call of sfd_assoc_select()
     *  or sfd_assoc_apply(); NULL between calls */
    sfd_assoc_work_t *work;
    /* between sfd_assoc_select() and sfd_assoc_apply() */
    int32_t selected;      /**< 1 after select, 0 after apply */
    int32_t n;             /**< matches of the selected frame */
    int32_t score_kind;    /**< distance used by the selection (private) */
    int8_t stage;          /**< SFD_STAGE_* of the method */
    double prev_R_CtoW[9]; /**< previous camera pose of the selected frame */
    double prev_p_CinW_m[3];
    double prior_p_m[3]; /**< the prior select saw (apply checks it is unchanged) */
    double prior_q[4];
    int32_t initialized;
} sfd_assoc_t;

/** What one run decided. Entries follow the input order of the matches. */
typedef struct {
    int32_t n;
    int8_t status[SFD_MAX_FEATURES];   /**< SFD_VERDICT_* (sfd_parity.h) */
    int8_t stage[SFD_MAX_FEATURES];    /**< SFD_STAGE_* of the method that decided */
    float statistic[SFD_MAX_FEATURES]; /**< normalized distance that decided (sigma^2 units) */
    int32_t num_consistent;
    int32_t num_spurious;
    int32_t num_untested;      /**< landmark behind the camera or non-finite input */
    int32_t hypotheses_used;   /**< hypotheses drawn, <= max_hypotheses */
    int32_t budget_exhausted;  /**< 1 when eq. (27) asked for at least the whole budget */
    int32_t degenerate_motion; /**< 1 when OPRF fell back to the rotation-only check */
    int32_t inliers_stage1;    /**< Table 1 inlier set 1 */
    int32_t inliers_stage2;    /**< Table 1 inlier set 2 (rescued from set 1's outliers) */
    int32_t update_status;     /**< sfd_status_t of the EKF update(s) */
    sfd_ekf_update_info_t update;
} sfd_assoc_result_t;

/** @brief Defaults: method OPRF, alpha 0.01, p 0.99, 100 hypotheses, 1 px minimum parallax,
 *         seed 1. @return SFD_OK; SFD_ERR_INVAL for null. */
sfd_status_t sfd_assoc_params_default(sfd_assoc_params_t *params);

/** @brief The association parameters carried by the detector parameters (method, alpha,
 *         confidence, budget, seed); min_parallax_px keeps its default.
 *  @return SFD_OK; SFD_ERR_INVAL for null. */
sfd_status_t sfd_assoc_params_from(const sfd_params_t *p, sfd_assoc_params_t *params);

/** @brief Validates the parameters, seeds the generator, computes the thresholds.
 *  @return SFD_OK; SFD_ERR_INVAL for null or out-of-range values (method PARITY or BOTH
 *          included: those are not association methods); SFD_ERR_CAPACITY for a budget above
 *          SFD_MAX_HYPOTHESES. */
sfd_status_t sfd_assoc_init(sfd_assoc_t *assoc, const sfd_assoc_params_t *params);

/**
 * @brief Association proper, without touching the filter: validates every match at the prior,
 *        then runs the method's selection (OPRF/RANSAC1: Table 1 lines 1-7; RANSACF: Table 2;
 *        NONE: all valid). @p out holds the provisional verdicts (set 1).
 *        Follow with sfd_assoc_apply() on the same matches, the same @p work and the unchanged
 *        filter. The split
 *        lets a caller time association and update separately (SPEC SFD_TIMING stages).
 * @return SFD_OK; SFD_ERR_STATE when @p assoc or @p ekf is not initialized; SFD_ERR_INVAL for
 *         null pointers, n outside [0, SFD_MAX_FEATURES] or a non-finite previous pose.
 */
sfd_status_t sfd_assoc_select(sfd_assoc_t *assoc, sfd_assoc_work_t *work, const sfd_ekf_t *ekf,
                              const sfd_ekf_camera_t *cam, const double prev_R_CtoW[9],
                              const double prev_p_CinW_m[3], const sfd_match_t *matches, int32_t n,
                              sfd_assoc_result_t *out);

/**
 * @brief Completes a selection: OPRF's individual-compatibility gate on set 1 (an sfd addition,
 *        computed from the linearization the update needs anyway), the filter update with set 1
 *        (Table 1 line 8), then for OPRF and
 *        RANSAC1 rescores set 1's outliers under the updated filter (lines 9-12) and updates with
 *        the rescued set 2 (line 13). @p out receives the final verdicts.
 * @return SFD_OK (EKF trouble is reported in out->update_status, verdicts stay valid);
 *         SFD_ERR_STATE without a preceding select, when @p n differs from the selection's, or
 *         when the filter changed since the selection; SFD_ERR_INVAL for null pointers.
 */
sfd_status_t sfd_assoc_apply(sfd_assoc_t *assoc, sfd_assoc_work_t *work, sfd_ekf_t *ekf,
                             const sfd_ekf_camera_t *cam, const sfd_match_t *matches, int32_t n,
                             sfd_assoc_result_t *out);

/**
 * @brief sfd_assoc_select() then sfd_assoc_apply(): judges the matches of one frame and updates
 *        the filter with the accepted ones.
 *
 * @p ekf holds the prior at the current frame (propagated by the IMU); on return it holds the
 * posterior (unless the update failed, see update_status). @p prev_R_CtoW / @p prev_p_CinW_m
 * are the previous frame's camera pose (the filter's posterior there), needed by the epipolar
 * methods. Methods:
 * - OPRF (Table 1 + Section 3.2): hypotheses = one random match -> single-match EKF update of a
 *   scratch pose -> F of the relative pose previous camera / hypothesized camera (eq. (26)) ->
 *   Sampson distance of every match's (previous, current) pixels; eq. (27) adapts the count;
 *   update with set 1; rescore set 1's outliers with the updated pose (set 2); update with set 2.
 * - RANSAC1: the same loop, scored by the reprojection distance of the landmark.
 * - RANSACF: Table 2 on the (previous, current) pixels, then the update with its inliers.
 * - NONE: every valid match is accepted and used.
 * @return SFD_OK (the verdicts are in @p out, also when the EKF update failed: update_status);
 *         SFD_ERR_STATE when @p assoc or @p ekf is not initialized; SFD_ERR_INVAL for null
 *         pointers, n outside [0, SFD_MAX_FEATURES] or a non-finite previous pose.
 */
sfd_status_t sfd_assoc_run(sfd_assoc_t *assoc, sfd_assoc_work_t *work, sfd_ekf_t *ekf,
                           const sfd_ekf_camera_t *cam, const double prev_R_CtoW[9],
                           const double prev_p_CinW_m[3], const sfd_match_t *matches, int32_t n,
                           sfd_assoc_result_t *out);

#ifdef __cplusplus
}
#endif
#endif /* SFD_ASSOC_H */
