/* SPDX-License-Identifier: MIT */
/* proof.state_sizes: sizeof every caller-owned core state struct, printed and checked against
 * SPEC's memory budget (core state <= 256 KiB for 256 features and L = 5). The same checks are
 * compile-time assertions, so a cross build (Cortex-M7) that cannot run this still proves them.
 * Checked: the whole pipeline (sfd_pipeline_t: IMU ring, window filter, detectors, landmark map,
 * frame slots, output), which is what sfd-node runs, at the shipped capacities (256 features,
 * L = 5, 512 IMU samples, 256 landmarks); and the detectors with the single-state EKF (the set
 * below). */
#include <stdio.h>

#include <sfd/sfd.h>

#ifndef SFD_STATE_BUDGET_BYTES
#define SFD_STATE_BUDGET_BYTES 262144
#endif

/* One detector's worth of state: everything a caller instantiates per camera to run the
 * combined pipeline (parity window, EKF, association object, its work space and result,
 * landmark map). */
#define SFD_STATE_TOTAL                                                     \
    (sizeof(sfd_parity_t) + sizeof(sfd_extrinsics_t) + sizeof(sfd_prng_t) + \
     sizeof(sfd_landmark_map_t) + sizeof(sfd_ekf_t) + sizeof(sfd_assoc_t) + \
     sizeof(sfd_assoc_work_t) + sizeof(sfd_assoc_result_t))

_Static_assert(SFD_MAX_FEATURES != 256 || SFD_MAX_WINDOW != 5 ||
                   SFD_STATE_TOTAL <= SFD_STATE_BUDGET_BYTES,
               "core state exceeds SPEC's 256 KiB budget for 256 features and L = 5");

/* The shipped capacities, where SPEC's budget applies. */
#define SFD_STATE_SHIPPED_CAPACITIES                                                   \
    (SFD_MAX_FEATURES == 256 && SFD_MAX_WINDOW == 5 && SFD_IMU_RING_CAPACITY == 512 && \
     SFD_MAX_LANDMARKS == 256)

_Static_assert(!SFD_STATE_SHIPPED_CAPACITIES || sizeof(sfd_pipeline_t) <= SFD_STATE_BUDGET_BYTES,
               "the pipeline's state exceeds SPEC's 256 KiB budget at the shipped capacities");

#ifndef SFD_STATE_SIZES_NO_MAIN
int main(void) {
    printf(
        "capacities: SFD_MAX_FEATURES=%d SFD_MAX_WINDOW=%d SFD_MAX_GROUP=%d "
        "SFD_MAX_HYPOTHESES=%d SFD_CHI2_MAX_DOF=%d SFD_MAX_LANDMARKS=%d\n",
        SFD_MAX_FEATURES, SFD_MAX_WINDOW, SFD_MAX_GROUP, SFD_MAX_HYPOTHESES, SFD_CHI2_MAX_DOF,
        SFD_MAX_LANDMARKS);
    printf("%-22s %8zu B\n", "sfd_params_t", sizeof(sfd_params_t));
    printf("%-22s %8zu B\n", "sfd_camera_t", sizeof(sfd_camera_t));
    printf("%-22s %8zu B\n", "sfd_extrinsics_t", sizeof(sfd_extrinsics_t));
    printf("%-22s %8zu B\n", "sfd_chi2_table_t", sizeof(sfd_chi2_table_t));
    printf("%-22s %8zu B\n", "sfd_prng_t", sizeof(sfd_prng_t));
    printf("%-22s %8zu B\n", "sfd_imu_sample_t", sizeof(sfd_imu_sample_t));
    printf("%-22s %8zu B (window of %d frames x %d features)\n", "sfd_parity_t",
           sizeof(sfd_parity_t), SFD_MAX_WINDOW, SFD_MAX_FEATURES);
    printf("%-22s %8zu B (%d landmarks)\n", "sfd_landmark_map_t", sizeof(sfd_landmark_map_t),
           SFD_MAX_LANDMARKS);
    printf("%-22s %8zu B (15-state error-state EKF)\n", "sfd_ekf_t", sizeof(sfd_ekf_t));
    printf("%-22s %8zu B (association object)\n", "sfd_assoc_t", sizeof(sfd_assoc_t));
    printf("%-22s %8zu B (association work space, caller-owned)\n", "sfd_assoc_work_t",
           sizeof(sfd_assoc_work_t));
    printf("%-22s %8zu B (association verdicts)\n", "sfd_assoc_result_t",
           sizeof(sfd_assoc_result_t));
    printf("%-22s %8zu B (caller's input frame)\n", "sfd_frame_t", sizeof(sfd_frame_t));
    printf("%-22s %8zu B (caller's output)\n", "sfd_verdict_t", sizeof(sfd_verdict_t));
    printf("%-22s %8zu B (sliding-window filter, %d tracks)\n", "sfd_window_t",
           sizeof(sfd_window_t), SFD_WINDOW_MAX_TRACKS);
    printf("%-22s %8zu B (its work space, caller-owned)\n", "sfd_window_scratch_t",
           sizeof(sfd_window_scratch_t));
    printf("%-22s %8zu B (%d samples)\n", "sfd_imu_ring_t", sizeof(sfd_imu_ring_t),
           SFD_IMU_RING_CAPACITY);
    printf("%-22s %8zu B (filter, landmarks, association, matches)\n", "sfd_nav_t",
           sizeof(sfd_nav_t));
    const size_t pipe = sizeof(sfd_pipeline_t);
    const int shipped = SFD_STATE_SHIPPED_CAPACITIES;
    printf("%-22s %8zu B (whole pipeline) of %d B budget (%s)\n", "sfd_pipeline_t", pipe,
           SFD_STATE_BUDGET_BYTES, shipped ? "checked" : "not checked: other capacities");
    const size_t total = SFD_STATE_TOTAL;
    printf("%-22s %8zu B of %d B budget (checked)\n", "detectors + EKF", total,
           SFD_STATE_BUDGET_BYTES);
    const int passed =
        (total <= (size_t)SFD_STATE_BUDGET_BYTES) + (!shipped || pipe <= SFD_STATE_BUDGET_BYTES);
    printf("%d passed, %d failed\n", passed, 2 - passed);
    return passed == 2 ? 0 : 1;
}
#endif
