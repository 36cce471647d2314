/* SPDX-License-Identifier: MIT */
/* proof.heap_interposer_node: the node's per-frame path (drivers/lcm/sfd_node_core: decode,
 * validation, IMU ring, motion assembly, detector, verdict/timing encode) makes no heap call.
 * Messages are encoded beforehand with the generated encoders; the counting interposer (same as
 * proof.heap_interposer) runs around sfd_node_handle only, with a positive control. */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "sfd_node_core.h"
#include "sfd_scene_sim.h"

#include "heap_counter.h"

static long g_published;
static void on_publish(void *ctx, sfd_node_output_t kind, const void *data, int32_t size,
                       int64_t utime) {
    (void)ctx;
    (void)kind;
    (void)data;
    (void)size;
    (void)utime;
    g_published++;
}

static sfd_node_t g_node;
static scene_t g_scene;
static sfd_frame_t g_frame;
static sfd_feature_frame_t g_wire;
static uint8_t g_buf[64 * 1024];

int main(void) {
    unsigned long before = g_heap_calls;
    void *(*volatile do_malloc)(size_t) = malloc;
    free(do_malloc(16));
    CHECK(g_heap_calls - before == 2);
    (void)fflush(stdout);

    sfd_node_config_t cfg;
    sfd_node_config_default(&cfg);
    CHECK(sfd_node_init(&g_node, &cfg, on_publish, NULL, NULL) == SFD_OK);
    scene_init(&g_scene, 5, 200, 1.0);
    g_scene.respawn = 1;
    sfd_camera_info_t ci;
    memset(&ci, 0, sizeof ci);
    ci.width = 752;
    ci.height = 480;
    ci.fx = g_scene.cam.fx_px;
    ci.fy = g_scene.cam.fy_px;
    ci.cx = g_scene.cam.cx_px;
    ci.cy = g_scene.cam.cy_px;
    ci.T_imu_cam[0] = ci.T_imu_cam[5] = ci.T_imu_cam[10] = ci.T_imu_cam[15] = 1.0;
    int n = sfd_camera_info_t_encode(g_buf, 0, (int)sizeof g_buf, &ci);
    before = g_heap_calls;
    sfd_node_handle(&g_node, SFD_NODE_CAMERA_INFO, g_buf, n);
    for (int f = 0; f < 500; ++f) {
        sfd_frame_motion_t mo;
        scene_step(&g_scene, &g_frame, &mo, 0.0);
        /* IMU consistent with the scene's rotation step: constant rate over the 50 ms interval */
        double R[9], phi[3];
        for (int k = 0; k < 9; ++k) R[k] = mo.R_CcurToCprev[k];
        sfd_so3_log(R, phi);
        for (int s = 0; s < 10; ++s) {
            sfd_imu_t imu;
            memset(&imu, 0, sizeof imu);
            imu.utime = g_frame.utime - 50000 + (int64_t)5000 * (s + 1);
            for (int k = 0; k < 3; ++k) imu.gyro[k] = phi[k] / 0.05;
            imu.accel[2] = 9.81;
            n = sfd_imu_t_encode(g_buf, 0, (int)sizeof g_buf, &imu);
            sfd_node_handle(&g_node, SFD_NODE_IMU, g_buf, n);
        }
        memset(&g_wire, 0, sizeof g_wire);
        g_wire.utime = g_frame.utime;
        g_wire.num_features = g_frame.num_features;
        for (int i = 0; i < g_frame.num_features; ++i) {
            g_wire.track_id[i] = g_frame.features[i].track_id;
            g_wire.u[i] = g_frame.features[i].u_px;
            g_wire.v[i] = g_frame.features[i].v_px;
            g_wire.depth[i] = g_frame.features[i].depth_m;
        }
        n = sfd_feature_frame_t_encode(g_buf, 0, (int)sizeof g_buf, &g_wire);
        sfd_node_handle(&g_node, SFD_NODE_FEATURES, g_buf, n);
        if (f == 250) sfd_node_handle(&g_node, SFD_NODE_FEATURES, g_buf, 7); /* corrupt */
    }
    sfd_node_flush(&g_node);
    const unsigned long calls = g_heap_calls - before;
    printf(
        "node: 500 frames, %ld messages published, %lld frames processed, %lld decode "
        "rejections, %lu heap calls\n",
        g_published, (long long)g_node.pipe.counters.frames_processed,
        (long long)g_node.pipe.counters.rejected[SFD_REJECT_DECODE], calls);
    CHECK(calls == 0);
    CHECK(g_node.pipe.counters.frames_processed == 500);
    CHECK(g_node.pipe.counters.frames_untested <= 2);
    printf("%d passed, %d failed\n", g_failures == 0 ? 1 : 0, g_failures == 0 ? 0 : 1);
    return g_failures == 0 ? 0 : 1;
}
