/* SPDX-License-Identifier: MIT */
/* One parity window and one OPRF frame on a constant scene, core state static (fw_window.h). */
#include "fw_window.h"

#include <sfd/sfd.h>
#include <string.h>

/* Camera of the synthetic scene: a 640 x 480 pinhole, f = 400 px. */
#define FW_FX_PX 400.0
#define FW_FY_PX 400.0
#define FW_CX_PX 320.0
#define FW_CY_PX 240.0
#define FW_DEPTH_M 10.0   /* landmarks on the plane z = 10 m in front of the camera */
#define FW_SPACING_M 0.8  /* grid pitch: +-2.8 m, i.e. +-112 px around the principal point */
#define FW_GRID 8         /* FW_GRID x FW_GRID = SFD_FW_FEATURES */
#define FW_FRAME_US 50000 /* 20 Hz camera */
#define FW_IMU_DT_S 0.005 /* 200 Hz IMU */
#define FW_GRAVITY_M_S2 9.81

/* Everything the core keeps between calls, in one object so that the firmware's budget check
 * (tools/firmware_report.py --state-symbol fw_core_state) can weigh it against SPEC's 256 KiB.
 * The canary build (SFD_FW_CANARY) pads it past that budget: the check must then fail. */
typedef struct {
    sfd_parity_t parity;
    sfd_ekf_t ekf;
    sfd_assoc_t assoc;
#ifdef SFD_FW_CANARY
    uint8_t canary_pad[160 * 1024];
#endif
} fw_core_state_t;

/* The caller's buffers (input frame, verdicts, matches): RAM too, but not core state. */
static fw_core_state_t fw_core_state;
static sfd_frame_t fw_frame;
static sfd_verdict_t fw_verdict;
static sfd_match_t fw_matches[SFD_FW_FEATURES];
static sfd_assoc_result_t fw_assoc_result;

/* Landmark k of the grid, camera frame = world frame (camera at the origin, identity pose). */
static void fw_landmark(int32_t k, double p_m[3]) {
    const int32_t row = k / FW_GRID;
    const int32_t col = k % FW_GRID;
    p_m[0] = ((double)col - 0.5 * (FW_GRID - 1)) * FW_SPACING_M;
    p_m[1] = ((double)row - 0.5 * (FW_GRID - 1)) * FW_SPACING_M;
    p_m[2] = FW_DEPTH_M;
}

/* Pinhole projection u = fx X / Z + cx, v = fy Y / Z + cy. */
static void fw_project(const double p_m[3], double uv_px[2]) {
    uv_px[0] = FW_FX_PX * p_m[0] / p_m[2] + FW_CX_PX;
    uv_px[1] = FW_FY_PX * p_m[1] / p_m[2] + FW_CY_PX;
}

static int32_t fw_parity_window(sfd_fw_report_t *r) {
    sfd_params_t params;
    sfd_camera_t camera;
    static const double no_dist[4] = {0.0, 0.0, 0.0, 0.0};
    sfd_status_t st = sfd_params_default(&params);
    if (st != SFD_OK) return st;
    params.window_frames = SFD_MAX_WINDOW;
    params.translation_known = 1;
    st = sfd_camera_init(&camera, SFD_DISTORTION_PINHOLE, 640, 480, FW_FX_PX, FW_FY_PX, FW_CX_PX,
                         FW_CY_PX, no_dist);
    if (st != SFD_OK) return st;
    st = sfd_parity_init(&fw_core_state.parity, &params, &camera);
    if (st != SFD_OK) return st;

    /* Identity motion between frames: no rotation, known zero translation. */
    sfd_frame_motion_t motion;
    memset(&motion, 0, sizeof motion);
    motion.R_CcurToCprev[0] = motion.R_CcurToCprev[4] = motion.R_CcurToCprev[8] = 1.0;
    motion.translation_known = 1;

    for (int32_t f = 0; f < SFD_MAX_WINDOW; ++f) {
        fw_frame.utime = 1000000 + (int64_t)f * FW_FRAME_US;
        fw_frame.num_features = SFD_FW_FEATURES;
        for (int32_t k = 0; k < SFD_FW_FEATURES; ++k) {
            double p_m[3];
            double uv_px[2];
            fw_landmark(k, p_m);
            fw_project(p_m, uv_px);
            sfd_feature_t *ft = &fw_frame.features[k];
            ft->track_id = k + 1;
            ft->u_px = uv_px[0];
            ft->v_px = uv_px[1];
            ft->depth_m = p_m[2];
            ft->depth_var_m2 = 1.0;
        }
        st = sfd_parity_push_frame(&fw_core_state.parity, &fw_frame, f == 0 ? NULL : &motion,
                                   &fw_verdict);
        if (st != SFD_OK) return st;
        r->frames_pushed = f + 1;
    }
    r->parity_flags = fw_verdict.flags;
    r->parity_consistent = fw_verdict.num_consistent;
    r->parity_spurious = fw_verdict.num_spurious;
    r->parity_untested = fw_verdict.num_untested;
    return SFD_OK;
}

static int32_t fw_oprf_frame(sfd_fw_report_t *r) {
    sfd_ekf_noise_t noise;
    sfd_status_t st = sfd_ekf_noise_default(&noise);
    if (st != SFD_OK) return st;
    /* At rest and level: the specific force points up (world z), no gyro bias. */
    const double accel_m_s2[3] = {0.0, 0.0, FW_GRAVITY_M_S2};
    const double gyro_rad_s[3] = {0.0, 0.0, 0.0};
    double P0_diag[SFD_EKF_DIM];
    for (int32_t i = 0; i < SFD_EKF_DIM; ++i) P0_diag[i] = 1e-4;
    st = sfd_ekf_init_from_gravity(&fw_core_state.ekf, &noise, accel_m_s2, gyro_rad_s, P0_diag);
    if (st != SFD_OK) return st;
    st = sfd_ekf_propagate(&fw_core_state.ekf, gyro_rad_s, accel_m_s2, FW_IMU_DT_S);
    if (st != SFD_OK) return st;

    sfd_assoc_params_t ap;
    st = sfd_assoc_params_default(&ap); /* OPRF */
    if (st != SFD_OK) return st;
    st = sfd_assoc_init(&fw_core_state.assoc, &ap);
    if (st != SFD_OK) return st;

    /* Camera = IMU (identity extrinsics); the previous camera pose is the start pose. */
    sfd_ekf_camera_t cam;
    memset(&cam, 0, sizeof cam);
    cam.fx_px = FW_FX_PX;
    cam.fy_px = FW_FY_PX;
    cam.cx_px = FW_CX_PX;
    cam.cy_px = FW_CY_PX;
    cam.ext.R_CtoI[0] = cam.ext.R_CtoI[4] = cam.ext.R_CtoI[8] = 1.0;
    cam.pixel_sigma_px = 1.0;
    const double prev_R_CtoW[9] = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
    const double prev_p_CinW_m[3] = {0.0, 0.0, 0.0};
    memset(fw_matches, 0, sizeof fw_matches);
    for (int32_t k = 0; k < SFD_FW_FEATURES; ++k) {
        sfd_match_t *m = &fw_matches[k];
        fw_landmark(k, m->obs.landmark_W_m);
        fw_project(m->obs.landmark_W_m, m->obs.uv_px);
        m->prev_uv_px[0] = m->obs.uv_px[0];
        m->prev_uv_px[1] = m->obs.uv_px[1];
    }
    st = sfd_assoc_run(&fw_core_state.assoc, &fw_core_state.ekf, &cam, prev_R_CtoW, prev_p_CinW_m,
                       fw_matches, SFD_FW_FEATURES, &fw_assoc_result);
    if (st != SFD_OK) return st;
    r->assoc_consistent = fw_assoc_result.num_consistent;
    r->assoc_spurious = fw_assoc_result.num_spurious;
    r->assoc_untested = fw_assoc_result.num_untested;
    r->assoc_update_status = fw_assoc_result.update_status;
    return SFD_OK;
}

int32_t sfd_fw_run_window(sfd_fw_report_t *report) {
    if (report == NULL) return SFD_ERR_INVAL;
    memset(report, 0, sizeof *report);
    int32_t st = fw_parity_window(report);
    if (st == SFD_OK) st = fw_oprf_frame(report);
    report->status = st;
    return st;
}
