/* SPDX-License-Identifier: MIT */
/* The whole pipeline on a constant scene, core state static (fw_window.h). */
#include "fw_window.h"

#include <math.h>
#include <sfd/sfd.h>
#include <string.h>

/* Camera of the synthetic scene: a 640 x 480 pinhole, f = 400 px. */
#define FW_FX_PX 400.0
#define FW_FY_PX 400.0
#define FW_CX_PX 320.0
#define FW_CY_PX 240.0
#define FW_DEPTH_M 10.0   /* points on the plane z = 10 m in front of the camera */
#define FW_SPACING_M 0.8  /* grid pitch: +-2.8 m, i.e. +-112 px around the principal point */
#define FW_GRID 8         /* FW_GRID x FW_GRID = SFD_FW_FEATURES */
#define FW_FRAME_US 50000 /* 20 Hz camera */
#define FW_IMU_US 5000    /* 200 Hz IMU */
#define FW_GRAVITY_M_S2 9.81
#define FW_REJECTED 100 /* report->status for a refused input: 100 + sfd_reject_reason_t */

/* Everything the core keeps between calls, in one object so that the firmware's budget check
 * (tools/firmware_report.py --state-symbol fw_core_state) can weigh it against SPEC's 256 KiB.
 * The canary build (SFD_FW_CANARY) pads it 1 KiB past that budget, whatever the pipeline's own
 * size: the check must then fail. */
#define FW_STATE_BUDGET_BYTES 262144u
typedef struct {
    sfd_pipeline_t pipe;
#ifdef SFD_FW_CANARY
    uint8_t canary_pad[(sizeof(sfd_pipeline_t) < FW_STATE_BUDGET_BYTES
                            ? FW_STATE_BUDGET_BYTES - sizeof(sfd_pipeline_t)
                            : 0u) +
                       1024u];
#endif
} fw_core_state_t;

/* The caller's input frame: RAM too, but not core state. */
static fw_core_state_t fw_core_state;
static sfd_frame_t fw_frame;

/* Point k of the grid in the camera frame. */
static void fw_point(int32_t k, double p_m[3]) {
    const int32_t row = k / FW_GRID;
    const int32_t col = k % FW_GRID;
    p_m[0] = ((double)col - 0.5 * (FW_GRID - 1)) * FW_SPACING_M;
    p_m[1] = ((double)row - 0.5 * (FW_GRID - 1)) * FW_SPACING_M;
    p_m[2] = FW_DEPTH_M;
}

static void fw_make_frame(int32_t f) {
    fw_frame.utime = (int64_t)f * FW_FRAME_US;
    fw_frame.num_features = SFD_FW_FEATURES;
    for (int32_t k = 0; k < SFD_FW_FEATURES; ++k) {
        double p_m[3];
        fw_point(k, p_m);
        sfd_feature_t *ft = &fw_frame.features[k];
        ft->track_id = k + 1;
        ft->u_px = FW_FX_PX * p_m[0] / p_m[2] + FW_CX_PX; /* pinhole projection */
        ft->v_px = FW_FY_PX * p_m[1] / p_m[2] + FW_CY_PX;
        ft->depth_m = p_m[2];
        ft->depth_var_m2 = 0.01;
    }
}

static int32_t fw_start(void) {
    sfd_pipeline_config_t cfg;
    sfd_pipeline_config_default(&cfg);
    cfg.params.method = SFD_METHOD_BOTH;
    sfd_status_t st = sfd_pipeline_init(&fw_core_state.pipe, &cfg);
    if (st != SFD_OK) return st;
    sfd_camera_t camera;
    static const double no_dist[4] = {0.0, 0.0, 0.0, 0.0};
    st = sfd_camera_init(&camera, SFD_DISTORTION_PINHOLE, 640, 480, FW_FX_PX, FW_FY_PX, FW_CX_PX,
                         FW_CY_PX, no_dist);
    if (st != SFD_OK) return st;
    /* Camera looking along the IMU's x axis (image x along -y, image y along -z), at its origin. */
    sfd_extrinsics_t ext;
    static const double R_CtoI[9] = {0.0, 0.0, 1.0, -1.0, 0.0, 0.0, 0.0, -1.0, 0.0};
    memcpy(ext.R_CtoI, R_CtoI, sizeof R_CtoI);
    memset(ext.p_CinI, 0, sizeof ext.p_CinI);
    const int r = sfd_pipeline_set_camera(&fw_core_state.pipe, &camera, &ext);
    return r == SFD_REJECT_NONE ? SFD_OK : FW_REJECTED + r;
}

int32_t sfd_fw_run_window(sfd_fw_report_t *report) {
    if (report == NULL) return SFD_ERR_INVAL;
    memset(report, 0, sizeof *report);
    int32_t st = fw_start();
    sfd_pipeline_t *p = &fw_core_state.pipe;
    int64_t imu_us = 0;
    for (int32_t f = 1; st == SFD_OK && f <= SFD_FW_FRAMES; ++f) {
        fw_make_frame(f);
        /* At rest and level: the specific force points up (world z), no rotation. */
        while (st == SFD_OK && imu_us < fw_frame.utime) {
            imu_us += FW_IMU_US;
            sfd_imu_sample_t s;
            s.t_us = imu_us;
            s.gyro_rad_s[0] = s.gyro_rad_s[1] = s.gyro_rad_s[2] = 0.0;
            s.accel_m_s2[0] = s.accel_m_s2[1] = 0.0;
            s.accel_m_s2[2] = FW_GRAVITY_M_S2;
            const int r = sfd_pipeline_push_imu(p, &s);
            if (r != SFD_REJECT_NONE) st = FW_REJECTED + r;
        }
        if (st != SFD_OK) break;
        const int r = sfd_pipeline_push_frame(p, &fw_frame);
        if (r != SFD_REJECT_NONE) st = FW_REJECTED + r;
        for (int32_t k = 0; st == SFD_OK && k < SFD_PIPELINE_FRAME_SLOTS; ++k) {
            if (sfd_pipeline_frames_due(p) == 0) break;
            st = sfd_pipeline_judge(p);
            if (st == SFD_OK) report->frames_judged++;
        }
    }
    const sfd_pipeline_output_t *o = sfd_pipeline_output(p);
    if (o != NULL) {
        report->consistent = o->verdict.num_consistent;
        report->spurious = o->verdict.num_spurious;
        report->untested = o->verdict.num_untested;
        report->has_state = o->has_state;
        const double e = sqrt(o->p_IinW_m[0] * o->p_IinW_m[0] + o->p_IinW_m[1] * o->p_IinW_m[1] +
                              o->p_IinW_m[2] * o->p_IinW_m[2]);
        report->position_err_mm = (int32_t)(e * 1000.0 + 0.5);
    }
    report->tracks_used = (int32_t)p->nav.win_used;
    report->status = st;
    return st;
}
