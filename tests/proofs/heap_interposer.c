/* SPDX-License-Identifier: MIT */
/* proof.heap_interposer: a counting malloc interposer around a long run of core calls.
 *
 * This executable defines malloc, calloc, realloc, free and the aligned allocators itself; glibc
 * resolves every allocation of the process to them (glibc's documented malloc replacement), so
 * the counters see the C heap and C++ operator new/delete (libstdc++ implements them on malloc).
 * The test first proves that the counter works (a positive control through a direct call and
 * through strdup inside libc), then runs every public core function many times and requires
 * zero heap calls. Not built with sanitizers (they own malloc). */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <sfd/sfd.h>

#include "sfd_scene_sim.h"

#include "heap_counter.h"

/* One pass over every public core entry point, with valid and invalid arguments. */
static double exercise_core(sfd_prng_t *rng, sfd_chi2_table_t *table, int iter) {
    double acc = 0.0;
    sfd_params_t p;
    CHECK(sfd_params_default(&p) == SFD_OK);
    CHECK(sfd_params_validate(&p) == SFD_OK);
    p.window_frames = 99;
    CHECK(sfd_params_validate(&p) == SFD_ERR_CAPACITY);
    acc += (double)strlen(sfd_status_str(SFD_ERR_NUMERIC));

    double x = 0, cdf = 0, up = 0;
    const int dof = 1 + iter % SFD_CHI2_MAX_DOF;
    CHECK(sfd_chi2_quantile_upper(0.01, dof, &x) == SFD_OK);
    CHECK(sfd_chi2_cdf(x, dof, &cdf, &up) == SFD_OK);
    CHECK(sfd_ncchi2_cdf(x, dof, 5.0, &cdf) == SFD_OK);
    CHECK(sfd_chi2_quantile_upper(2.0, dof, &x) == SFD_ERR_INVAL);
    if (iter % 50 == 0) CHECK(sfd_chi2_table_init(table, 0.05) == SFD_OK);
    acc += x + cdf + up;

    sfd_camera_t cam;
    const double radtan[4] = {-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05};
    CHECK(sfd_camera_init(&cam, SFD_DISTORTION_RADTAN, 752, 480, 458.654, 457.296, 367.215, 248.375,
                          radtan) == SFD_OK);
    double uv[2] = {752.0 * sfd_prng_uniform(rng), 480.0 * sfd_prng_uniform(rng)}, xn[2], J[6];
    double ray[3], uv2[2];
    CHECK(sfd_camera_undistort(&cam, uv, xn, J) == SFD_OK);
    CHECK(sfd_camera_unproject(&cam, uv, ray) == SFD_OK);
    CHECK(sfd_camera_distort(&cam, xn, uv2, J) == SFD_OK);
    const double pC[3] = {ray[0] * 4.0, ray[1] * 4.0, 4.0};
    CHECK(sfd_camera_project(&cam, pC, uv2, J) == SFD_OK);
    const double behind[3] = {0.0, 0.0, -1.0};
    CHECK(sfd_camera_project(&cam, behind, uv2, NULL) == SFD_ERR_DOMAIN);
    acc += uv2[0];

    double phi[3] = {sfd_prng_gaussian(rng), sfd_prng_gaussian(rng), sfd_prng_gaussian(rng)};
    double R[9], q[4], q2[4], back[3];
    CHECK(sfd_so3_exp(phi, R) == SFD_OK);
    CHECK(sfd_so3_log(R, back) == SFD_OK);
    CHECK(sfd_quat_from_rotvec(phi, q) == SFD_OK);
    CHECK(sfd_quat_to_rotvec(q, back) == SFD_OK);
    CHECK(sfd_quat_multiply(q, q, q2) == SFD_OK);
    CHECK(sfd_quat_normalize(q2) == SFD_OK);
    CHECK(sfd_quat_to_rotmat(q2, R) == SFD_OK);
    CHECK(sfd_rotmat_to_quat(R, q) == SFD_OK);
    const double T[16] = {0, -1, 0, 0.1, 1, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    sfd_extrinsics_t ext;
    double RC[9];
    CHECK(sfd_extrinsics_from_matrix(&ext, T) == SFD_OK);
    CHECK(sfd_extrinsics_camera_rotation(&ext, R, RC) == SFD_OK);
    acc += RC[4];

    sfd_imu_sample_t s[16];
    for (int i = 0; i < 16; ++i) {
        s[i].t_us = (int64_t)5000 * i;
        for (int k = 0; k < 3; ++k) {
            s[i].gyro_rad_s[k] = 0.1 * sfd_prng_gaussian(rng);
            s[i].accel_m_s2[k] = 0.0;
        }
    }
    CHECK(sfd_gyro_integrate(s, 16, 1000, 70000, NULL, 10000, q) == SFD_OK);
    CHECK(sfd_gyro_integrate(s, 16, 1000, 90000, NULL, 10000, q) == SFD_ERR_RANGE);
    acc += q[0] + (double)sfd_prng_uniform_index(rng, 17);
    return acc;
}

/* The parity detector over a simulated flight: every frame a full window test with isolation. */
static sfd_parity_t g_det;
static sfd_frame_t g_frame;
static sfd_verdict_t g_out;
static scene_t g_scene;

static long exercise_parity(int frames) {
    long spurious = 0;
    sfd_params_t p;
    sfd_params_default(&p);
    scene_init(&g_scene, 77, 200, 1.0);
    g_scene.respawn = 1;
    CHECK(sfd_parity_init(&g_det, &p, &g_scene.cam) == SFD_OK);
    for (int f = 0; f < frames; ++f) {
        sfd_frame_motion_t mo;
        if (f % 7 == 3) g_scene.offset_px[f % 200][0] += 10.0; /* a mistrack now and then */
        scene_step(&g_scene, &g_frame, &mo, 0.0);
        mo.translation_known = f % 2;
        CHECK(sfd_parity_push_frame(&g_det, &g_frame, &mo, &g_out) == SFD_OK);
        spurious += g_out.num_spurious;
        if (f == frames / 2) CHECK(sfd_parity_reset(&g_det) == SFD_OK);
    }
    return spurious;
}

int main(void) {
    /* Positive control: the interposer must see a direct call and one made inside libc. */
    unsigned long before = g_heap_calls;
    void *(*volatile do_malloc)(size_t) = malloc;
    void *blk = do_malloc(64);
    free(blk);
    char *dup = strdup("heap");
    free(dup);
    unsigned long control = g_heap_calls - before;
    printf("positive control: %lu heap calls counted (expected 4)\n", control);
    CHECK(control == 4);

    /* stdout's buffer is allocated on first use: flush once before measuring. */
    (void)fflush(stdout);
    sfd_prng_t rng;
    static sfd_chi2_table_t table;
    sfd_prng_seed(&rng, 2026);
    before = g_heap_calls;
    double acc = 0.0;
    enum { ITERATIONS = 20000 };
    for (int i = 0; i < ITERATIONS; ++i) acc += exercise_core(&rng, &table, i);
    unsigned long core_calls = g_heap_calls - before;
    printf("core run: %d iterations of every public entry point, %lu heap calls (checksum %.6g)\n",
           ITERATIONS, core_calls, acc);
    CHECK(core_calls == 0);

    before = g_heap_calls;
    const long spurious = exercise_parity(2000);
    const unsigned long parity_calls = g_heap_calls - before;
    printf("parity detector: 2000 frames of 200 features (%ld judged spurious), %lu heap calls\n",
           spurious, parity_calls);
    CHECK(parity_calls == 0);
    CHECK(spurious > 0);
    CHECK(isfinite(acc));
    printf("%d passed, %d failed\n", g_failures == 0 ? 1 : 0, g_failures == 0 ? 0 : 1);
    return g_failures == 0 ? 0 : 1;
}
