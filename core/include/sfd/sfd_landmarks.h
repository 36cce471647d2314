/* SPDX-License-Identifier: MIT */
/**
 * @file sfd_landmarks.h
 * @brief Landmark map: a fixed-capacity, caller-owned table of 3-D landmarks (world position and
 *        3x3 covariance) keyed by track id, built by the node itself because the wire carries no
 *        map (SPEC "LCM interface"). A track's landmark is initialized from its first
 *        observation and depth prior (sfd_landmark_init_from_ray) and refined by a gated 3x3 EKF
 *        update with each later observation (sfd_landmark_refine); the EKF and the association
 *        reads it through sfd_landmark_to_obs() (an sfd_ekf_obs_t), the association's matches
 *        (sfd_match_t) refer to the entry in place.
 *
 * Conventions: rotations as in sfd_rotation.h (R_CtoW maps camera coordinates into the world);
 * camera z forward; xn are undistorted normalized coordinates (x/z, y/z) as sfd_camera_undistort
 * returns them; depth is along the optical axis (SPEC FEATURES.depth). A camera pose
 * uncertainty, where given, is the 6x6 covariance of (dp, dtheta) with p_CinW = p^ + dp and
 * R_CtoW = R^_CtoW Exp(dtheta) (dtheta in the camera frame, the EKF's "local" convention).
 *
 * Indices: find/insert return an entry index in [0, SFD_MAX_LANDMARKS). An index stays valid,
 * and keeps naming the same track, until that entry is removed or evicted; entries never move.
 *
 * Memory and time: the map is one fixed-size struct (sizeof printed by proof.state_sizes); no
 * heap; every loop is bounded by SFD_MAX_LANDMARKS. Lookup is open addressing with linear
 * probing in an index of 2 SFD_MAX_LANDMARKS slots (load factor <= 1/2); see each function for
 * its worst case. Not reentrant on one map; distinct maps are independent.
 * Design note: core/docs/landmark_map.md.
 */
#ifndef SFD_LANDMARKS_H
#define SFD_LANDMARKS_H

#include <stdint.h>

#include "sfd_config.h"
#include "sfd_ekf.h"
#include "sfd_rotation.h"
#include "sfd_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Slots of the map's hash index (twice the capacity: load factor <= 1/2). */
#define SFD_LANDMARK_INDEX_SLOTS (2 * SFD_MAX_LANDMARKS)

/** One landmark. Read freely; change only through the functions below. */
typedef struct {
    int64_t track_id;        /**< key: the tracker's track id */
    double p_W_m[3];         /**< position in the world (m) */
    double cov_m2[9];        /**< its covariance (m^2, row-major, symmetric PSD) */
    int64_t last_seen_utime; /**< utime of the last observation fused (us) */
    int32_t observations;    /**< observations fused, the initializing one included */
    int32_t rejections;      /**< observations refused by the refinement gate */
    uint8_t used;            /**< 1 when the entry holds a landmark */
    uint8_t fixed;           /**< 1: a known landmark (sfd_landmark_set): never refined */
    uint32_t frame_stamp;    /**< the map's frame_stamp when its track was last in a frame
                                  (sfd_landmark_keep_in_frame); 0 never */
} sfd_landmark_t;

/** The map. Caller-owned (declare it static: it is ~36 KiB at the default capacity);
 *  initialise with sfd_landmark_map_init(). */
typedef struct {
    sfd_landmark_t entries[SFD_MAX_LANDMARKS];
    int32_t index[SFD_LANDMARK_INDEX_SLOTS]; /**< hash index: entry index, or -1 when empty */
    int32_t free_list[SFD_MAX_LANDMARKS];    /**< stack of unused entry indices */
    int32_t num_free;                        /**< entries on the free stack */
    int32_t count;                           /**< landmarks held */
    uint32_t evictions;                      /**< landmarks dropped to make room (LRU) */
    uint32_t frame_stamp; /**< the current frame's stamp (sfd_landmark_begin_frame), 0 before */
    int32_t initialized;
    /* Private: the last camera pose argument (R_CtoW, p_CinW_m, cov_pose6) that passed
     * validation, bit for bit, with its symmetrized covariance: the landmarks of one frame are
     * initialized and refined from one pose, which is then checked once. */
    int32_t pose_key_state_; /* 0 none, 1 without covariance, 2 with */
    double pose_key_[48];
    double pose_cov_sym_[36];
} sfd_landmark_map_t;

/** What one refinement did (PX4 EstimatorAidSource style). */
typedef struct {
    double innovation[2];     /**< nu = z - h(prior), normalized coordinates */
    double innovation_cov[4]; /**< S = H P H^T + R_n at the prior (2x2 row-major) */
    double nis_prior;         /**< nu^T S^-1 nu at the prior (the plain EKF's statistic) */
    double nis;               /**< NIS of the measurement linearized at the refined estimate
                                   (the minimum of the MAP cost), ~ chi2(2) */
    double gate;              /**< chi2_2(1 - alpha) = -2 ln(alpha) */
    uint8_t fused;            /**< 1 when the landmark was updated */
    uint8_t rejected;         /**< 1 when nis and nis_prior exceed gate: landmark unchanged */
} sfd_landmark_update_t;

/**
 * @brief Empties the map.
 * @return SFD_OK; SFD_ERR_INVAL for null.
 */
sfd_status_t sfd_landmark_map_init(sfd_landmark_map_t *map);

/**
 * @brief Entry index of a track's landmark. Average O(1) probes (load factor <= 1/2: about 1.5
 *        for a hit, 2.5 for a miss); worst case count + 1 <= SFD_MAX_LANDMARKS + 1 probes, when
 *        every held id hashes into one cluster.
 * @return the index in [0, SFD_MAX_LANDMARKS); -1 when the track has no landmark, or for a null
 *         or uninitialized map.
 */
int32_t sfd_landmark_find(const sfd_landmark_map_t *map, int64_t track_id);

/**
 * @brief Initializes (or re-initializes, when the track already has one) a track's landmark from
 *        one observation and a depth prior:
 *          p_W = p_CinW + d R r,  r = (xn, yn, 1)  (d along the optical axis),
 *          C = sd2 (R r)(R r)^T + (d^2 + sd2) s^2 R diag(1, 1, 0) R^T
 *              + J_pose C_pose J_pose^T + sd2 (R [r]x) C_theta (R [r]x)^T,
 *        the depth variance along the ray (dp/dd = R r), the bearing noise on the two image axes
 *        (dp/dxn = d R [e1 e2]; d^2 + sd2 = E[d^2], the exact second moment of the product of
 *        independent depth and bearing errors), and the camera pose uncertainty through
 *        J_pose = [ I3 | -d R [r]x ] over (dp, dtheta), plus its depth-rotation product.
 *        PD when sd2 > 0 and s > 0.
 *        When the map is full, the least recently seen landmark is evicted if it was last seen
 *        before @p utime (ties: the lowest index); landmarks seen at @p utime or later are
 *        never evicted. Cost: O(1) average; O(SFD_MAX_LANDMARKS) when it evicts.
 * @param R_CtoW       camera orientation (a rotation within 1e-6).
 * @param p_CinW_m     camera centre in the world (m).
 * @param cov_pose6    nullable: 6x6 row-major covariance of the camera pose (dp m^2, dtheta
 *                     rad^2), symmetric PSD (finite, non-negative diagonal checked); NULL = exact.
 * @param xn           undistorted normalized coordinates of the observation.
 * @param depth_m      prior depth along the optical axis (m), > 0. For an unknown depth (SPEC:
 *                     depth <= 0) pass the configured default with a large variance.
 * @param depth_var_m2 its variance (m^2), >= 0 (0: exact, the covariance is then rank 2).
 * @param sigma_xn     bearing noise per axis in normalized coordinates (pixel sigma / focal
 *                     length), >= 0.
 * @param utime        time of the observation (us): the landmark's last_seen_utime.
 * @param index_out    nullable: the entry index.
 * @return SFD_OK; SFD_ERR_INVAL for null map/R/p/xn, non-finite input, a matrix that is not a
 *         rotation, depth <= 0, a negative variance or sigma, or a bad cov_pose6; SFD_ERR_STATE
 *         for an uninitialized map; SFD_ERR_NUMERIC when the result is not finite; SFD_ERR_CAPACITY
 *         when the map is full and nothing may be evicted. On error the landmarks are unchanged
 * (only the private pose cache may be).
 */
sfd_status_t sfd_landmark_init_from_ray(sfd_landmark_map_t *map, int64_t track_id,
                                        const double R_CtoW[9], const double p_CinW_m[3],
                                        const double cov_pose6[36], const double xn[2],
                                        double depth_m, double depth_var_m2, double sigma_xn,
                                        int64_t utime, int32_t *index_out);

/**
 * @brief Sets a track's landmark to a known point (a surveyed map, map-based localization): the
 *        position and covariance as given, marked fixed (the navigation side does not refine it;
 *        sfd_landmark_refine() itself still would). Replaces the track's landmark if it has one;
 *        when the map is full, evicts as sfd_landmark_init_from_ray() does.
 * @param cov_m2 3x3 row-major, symmetric (within rounding) and positive definite.
 * @return SFD_OK; SFD_ERR_INVAL for null, non-finite values or a covariance that is not
 *         symmetric positive definite; SFD_ERR_STATE for an uninitialized map; SFD_ERR_CAPACITY
 *         when the map is full and nothing may be evicted (map unchanged on error).
 */
sfd_status_t sfd_landmark_set(sfd_landmark_map_t *map, int64_t track_id, const double p_W_m[3],
                              const double cov_m2[9], int64_t utime, int32_t *index_out);

/**
 * @brief Refines a landmark with a new observation (EKF update of the 3-D point, pose known):
 *          c = R^T (p - p_C), h = (c_x / c_z, c_y / c_z), H = J_pi R^T (2x3),
 *          R_n = s^2 I + H_pose C_pose H_pose^T, H_pose = J_pi [ -R^T | [c]x ],
 *          S = H P H^T + R_n, K = P H^T S^-1, nu = xn - h,
 *        iterated (iterated EKF: relinearized at the new estimate, at most
 *        SFD_LANDMARK_REFINE_ITERATIONS Gauss-Newton steps, each halved until the point stays in
 *        front of the camera and the MAP cost does not increase) to x*, with the covariance in
 *        Joseph form P+ = (I - K H) P (I - K H)^T + K R_n K^T (symmetric PSD) at x*.
 *        Rejected (landmark unchanged, rejections + 1) when both the prior's NIS nu^T S^-1 nu
 *        and the NIS linearized at x* exceed -2 ln(alpha), the chi2(2) quantile at false-alarm
 *        rate alpha, so a spurious observation does not corrupt its landmark; otherwise
 *        p+ = x*, observations + 1, last_seen_utime = utime. The pose uncertainty, when given,
 *        inflates R_n (first order; treated as independent of the landmark and across frames,
 *        see the design note). O(1) time (bounded iterations).
 * @param index    entry index from sfd_landmark_find / sfd_landmark_init_from_ray.
 * @param cov_pose6 nullable, as in sfd_landmark_init_from_ray.
 * @param sigma_xn bearing noise per axis (normalized coordinates), > 0.
 * @param alpha    gate false-alarm rate, in (0, 1).
 * @param utime    time of the observation (us), >= the landmark's last_seen_utime.
 * @param info     out: what happened (always written on SFD_OK).
 * @return SFD_OK (fused or rejected: see info); SFD_ERR_INVAL for null pointers, an index that
 *         is out of range or not in use, non-finite input, a matrix that is not a rotation,
 *         sigma or alpha out of range, or a bad cov_pose6; SFD_ERR_STATE for an uninitialized
 *         map; SFD_ERR_ORDER when utime is before last_seen_utime; SFD_ERR_DOMAIN when the
 *         landmark is not in front of the camera (depth <= 1e-6 m); SFD_ERR_NUMERIC when S is
 *         not positive definite or the result is not finite. On error the landmarks are unchanged
 * (only the private pose cache may be).
 */
sfd_status_t sfd_landmark_refine(sfd_landmark_map_t *map, int32_t index, const double R_CtoW[9],
                                 const double p_CinW_m[3], const double cov_pose6[36],
                                 const double xn[2], double sigma_xn, double alpha, int64_t utime,
                                 sfd_landmark_update_t *info);

/**
 * @brief Removes a track's landmark (its index becomes free). Cost: a find plus the index
 *        repair, O(1) average, O(SFD_MAX_LANDMARKS) worst case.
 * @return 1 when removed, 0 when the track had none; SFD_ERR_INVAL for null; SFD_ERR_STATE for
 *         an uninitialized map.
 */
int32_t sfd_landmark_remove(sfd_landmark_map_t *map, int64_t track_id);

/**
 * @brief Starts a frame for the eviction rule: a full map that must make room evicts the least
 *        recently seen landmark, but never one marked with sfd_landmark_keep_in_frame() since
 *        this call (the landmarks of the tracks of the frame being processed, whatever their
 *        verdict; the next frame's matches need them). Call it once per frame, then mark.
 * @return SFD_OK; SFD_ERR_INVAL for null; SFD_ERR_STATE for an uninitialized map.
 */
sfd_status_t sfd_landmark_begin_frame(sfd_landmark_map_t *map);

/**
 * @brief Marks landmark @p index as one of the current frame's (see sfd_landmark_begin_frame):
 *        a full map does not evict it until the next frame begins. Its last_seen_utime and its
 *        age are unchanged.
 * @return SFD_OK; SFD_ERR_INVAL for null or an index out of range or not in use; SFD_ERR_STATE
 *         for an uninitialized map.
 */
sfd_status_t sfd_landmark_keep_in_frame(sfd_landmark_map_t *map, int32_t index);

/**
 * @brief Removes every landmark last seen before @p utime (e.g. tracks lost for longer than a
 *        timeout), in index order. Cost: one pass over SFD_MAX_LANDMARKS entries plus one
 *        removal per landmark dropped.
 * @return the number removed (>= 0); SFD_ERR_INVAL for null; SFD_ERR_STATE for an
 *         uninitialized map.
 */
int32_t sfd_landmark_evict_older_than(sfd_landmark_map_t *map, int64_t utime);

/**
 * @brief Fills an EKF observation (sfd_ekf.h) with a landmark and the current undistorted pixel.
 * @return SFD_OK; SFD_ERR_INVAL for null pointers or an index out of range or not in use.
 */
sfd_status_t sfd_landmark_to_obs(const sfd_landmark_map_t *map, int32_t index,
                                 const double uv_px[2], sfd_ekf_obs_t *obs);

/**
 * @brief The camera pose covariance (the cov_pose6 above) of the filter's camera:
 *        C = T P_pose T^T with P_pose the filter's (dp, dtheta) block and
 *        T = [ I3  -R_ItoW [p_CinI]x ; 0  R_CtoI^T ], from p_CinW = p_IinW + R_ItoW p_CinI and
 *        R_CtoW = R_ItoW Exp(dtheta_I) R_CtoI = R^_CtoW Exp(R_CtoI^T dtheta_I).
 * @return SFD_OK; SFD_ERR_INVAL for null pointers; SFD_ERR_STATE for an uninitialized filter.
 */
sfd_status_t sfd_landmark_camera_pose_cov(const sfd_ekf_t *ekf, const sfd_extrinsics_t *ext,
                                          double cov_pose6[36]);

#ifdef __cplusplus
}
#endif

#endif /* SFD_LANDMARKS_H */
