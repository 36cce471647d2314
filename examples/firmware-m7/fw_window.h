/* SPDX-License-Identifier: MIT */
/**
 * @file fw_window.h
 * @brief The work of the Cortex-M7 firmware example: one parity window and one OPRF frame
 *        through the EKF on a synthetic constant scene, every core object in static storage.
 *
 * Target independent: the firmware image (main_m7.c) calls it once after reset, and the host
 * test example.firmware_window runs the same code and checks the verdicts, since qemu-user
 * cannot run an M-profile image.
 */
#ifndef SFD_FW_WINDOW_H
#define SFD_FW_WINDOW_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Features of the synthetic scene (an 8 x 8 grid of landmarks 10 m in front of the camera). */
#define SFD_FW_FEATURES 64

/** What the run decided (all counts over SFD_FW_FEATURES features). */
typedef struct {
    int32_t status;            /**< first sfd_status_t other than SFD_OK, or SFD_OK */
    int32_t frames_pushed;     /**< parity frames accepted (the window is SFD_MAX_WINDOW) */
    uint32_t parity_flags;     /**< sfd_verdict_t.flags of the last frame */
    int32_t parity_consistent; /**< verdicts of the last frame (window full) */
    int32_t parity_spurious;
    int32_t parity_untested;
    int32_t assoc_consistent; /**< OPRF verdicts of the one association frame */
    int32_t assoc_spurious;
    int32_t assoc_untested;
    int32_t assoc_update_status; /**< sfd_status_t of the EKF update inside the association */
} sfd_fw_report_t;

/**
 * @brief Runs the example once: initialises the parity detector (L = SFD_MAX_WINDOW, known zero
 *        translation), pushes SFD_MAX_WINDOW identical frames with identity motion, then starts
 *        the EKF at rest, propagates one IMU step at rest and runs OPRF on the same features.
 *        A motionless camera over a constant scene: every feature should be CONSISTENT.
 * @param report out: the counts above (caller-owned).
 * @return SFD_OK or the first failing call's status (also in report->status). Not reentrant:
 *         the core objects are file-scope statics.
 */
int32_t sfd_fw_run_window(sfd_fw_report_t *report);

#ifdef __cplusplus
}
#endif

#endif /* SFD_FW_WINDOW_H */
