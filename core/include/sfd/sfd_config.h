/* SPDX-License-Identifier: MIT */
/**
 * @file sfd_config.h
 * @brief Compile-time capacities of the core. Every limit may be overridden with -D before
 *        this header is included (all translation units of one build must agree).
 *
 * Memory cost at 256 features and L = 5 (x86-64, printed by the `proof.state_sizes` test):
 * sfd_parity_t 61368 B (the sliding window of observations, linear in SFD_MAX_FEATURES *
 * SFD_MAX_WINDOW), sfd_landmark_map_t 36536 B (SFD_MAX_LANDMARKS = 256), sfd_assoc_t 4392 B
 * with its work space sfd_assoc_work_t 14336 B, sfd_ekf_t 2000 B: 120336 B for the detectors
 * with the single-state EKF. The whole pipeline with the sliding-window filter
 * (sfd_pipeline_t) is 261736 B, within SPEC's 256 KiB; that test checks it (also at compile
 * time, so the cross builds prove it; core/docs/pipeline.md "Memory"). Stack per
 * call is bounded separately (`proof.stack_usage`).
 */
#ifndef SFD_CONFIG_H
#define SFD_CONFIG_H

/** Features per frame the core accepts. Cost: linear in state size and per-frame time. */
#ifndef SFD_MAX_FEATURES
#define SFD_MAX_FEATURES 256
#endif

/** Longest sliding window L (frames) of the parity test, 2..127 (a stored observation counts
 *  its track's frames in one byte). Cost: window storage is linear in L; the per-group
 *  matrices grow as (2L)^2. */
#ifndef SFD_MAX_WINDOW
#define SFD_MAX_WINDOW 5
#endif

/** Largest parity-test group n (features tested jointly). Cost: per-group matrices grow as
 *  (2Ln)^2 on the stack, so keep it small. */
#ifndef SFD_MAX_GROUP
#define SFD_MAX_GROUP 4
#endif

/** Hypothesis budget of the RANSAC-type methods per frame. Cost: bounded time only. */
#ifndef SFD_MAX_HYPOTHESES
#define SFD_MAX_HYPOTHESES 256
#endif

/** Largest chi-square degree of freedom with a precomputed threshold. Cost: 8 bytes each. */
#ifndef SFD_CHI2_MAX_DOF
#define SFD_CHI2_MAX_DOF 64
#endif

/** Landmarks the node's map holds (sfd_landmarks.h): one per track of a frame. A match needs
 *  its track in the previous frame and a landmark, and a full map evicts the least recently
 *  seen landmark but never one of the frame being processed (sfd_landmark_keep_in_frame), so
 *  the tracks of one frame (at most SFD_MAX_FEATURES) keep theirs; a track
 *  that drops out and comes back keeps its landmark while the frames leave room (the default
 *  was 2 * SFD_MAX_FEATURES until 2026-11-26: replays of every sfd-sim log scenario are
 *  byte-identical with either). Cost: 128 bytes per landmark plus 12 bytes of index, i.e.
 *  ~35 KiB at the default 256; find/insert/remove are O(1) on average and
 *  O(SFD_MAX_LANDMARKS) in the worst case. */
#ifndef SFD_MAX_LANDMARKS
#define SFD_MAX_LANDMARKS (SFD_MAX_FEATURES)
#endif

/** Most linearizations of one landmark refinement (iterated EKF, sfd_landmark_refine); 1 is the
 *  plain EKF. Cost: bounded time only (a 3x3 update each, ~300 flops). */
#ifndef SFD_LANDMARK_REFINE_ITERATIONS
#define SFD_LANDMARK_REFINE_ITERATIONS 5
#endif

/** Newton iterations at most to invert a lens distortion model (the loop stops earlier once a
 *  step is at the rounding level of double precision). */
#ifndef SFD_UNDISTORT_ITERATIONS
#define SFD_UNDISTORT_ITERATIONS 12
#endif

/** IMU samples a single gyro integration call may walk through (bounds the loop). */
#ifndef SFD_MAX_IMU_SAMPLES
#define SFD_MAX_IMU_SAMPLES 1024
#endif

#if SFD_MAX_FEATURES < 1 || SFD_MAX_WINDOW < 2 || SFD_MAX_WINDOW > 127 || SFD_MAX_GROUP < 1 || \
    SFD_MAX_HYPOTHESES < 1
#error "sfd_config.h: capacities out of range"
#endif
#if SFD_LANDMARK_REFINE_ITERATIONS < 1 || SFD_LANDMARK_REFINE_ITERATIONS > 100
#error "sfd_config.h: SFD_LANDMARK_REFINE_ITERATIONS must be in [1, 100]"
#endif
#if SFD_MAX_LANDMARKS < 1 || SFD_MAX_LANDMARKS > 1048576
#error "sfd_config.h: SFD_MAX_LANDMARKS must be in [1, 2^20]"
#endif
#if SFD_CHI2_MAX_DOF < 1 || SFD_CHI2_MAX_DOF > 512
#error "sfd_config.h: SFD_CHI2_MAX_DOF must be in [1, 512]"
#endif

#endif /* SFD_CONFIG_H */
