/* SPDX-License-Identifier: MIT */
/**
 * @file fw_window.h
 * @brief The work of the Cortex-M7 firmware example: the whole pipeline (sfd_pipeline_t: IMU
 *        ring, sliding-window filter started at rest, parity and OPRF, method `both`) fed 2.5 s
 *        of a motionless camera over a constant scene, every core object in static storage.
 *
 * Target independent: the firmware image (main_m7.c) calls it once after reset, and the host
 * test example.firmware_window runs the same code and checks the verdicts, since qemu-user
 * cannot run an M-profile image. The image is built against the core at SFD_MAX_FEATURES = 64
 * and SFD_IMU_RING_CAPACITY = 512 (sfd_core_fw); the host test uses the default capacities.
 */
#ifndef SFD_FW_WINDOW_H
#define SFD_FW_WINDOW_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Features of the synthetic scene (an 8 x 8 grid of points 10 m in front of the camera). */
#define SFD_FW_FEATURES 64
/** Frames fed at 20 Hz (the filter starts after 1 s at rest, then runs 1.5 s). */
#define SFD_FW_FRAMES 50

/** What the run decided. */
typedef struct {
    int32_t status;          /**< first failure (sfd_status_t, or an sfd_reject_reason_t + 100
                                  for a refused input), or SFD_OK */
    int32_t frames_judged;   /**< frames with a verdict */
    int32_t consistent;      /**< verdicts of the last frame */
    int32_t spurious;
    int32_t untested;
    int32_t has_state;       /**< 1: the filter runs after the last frame */
    int32_t tracks_used;     /**< tracks the window filter used since its start */
    int32_t position_err_mm; /**< |position| after the last frame (mm; the camera never moves) */
} sfd_fw_report_t;

/**
 * @brief Runs the example once: the pipeline (method both) gets a 200 Hz IMU at rest and
 *        SFD_FW_FRAMES frames of the same SFD_FW_FEATURES points, and judges every frame.
 *        A motionless camera over a constant scene: once tested, every feature should be
 *        CONSISTENT, and the filter should stay where it started.
 * @param report out: the counts above (caller-owned).
 * @return SFD_OK or the first failure (also in report->status). Not reentrant: the core objects
 *         are file-scope statics.
 */
int32_t sfd_fw_run_window(sfd_fw_report_t *report);

#ifdef __cplusplus
}
#endif

#endif /* SFD_FW_WINDOW_H */
