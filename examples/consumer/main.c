/* SPDX-License-Identifier: MIT */
/* Smallest use of the installed core from C: the library's version against the headers', then
 * the parity-space detector on a scene it builds itself. A pinhole camera moves sideways past
 * 20 static points 8-12 m away (no rotation, known translation, exact depth priors, no pixel
 * noise); in the last frame the tracker jumps on one feature (14 px). The detector must call
 * that feature SPURIOUS and every other one CONSISTENT, in every frame it tests. Prints the
 * verdicts and exits 0 when they are right, 1 otherwise. */
#include <stdio.h>

#include <sfd/sfd.h>

#define NUM_POINTS 20
#define JUMP_FEATURE 7

/* Caller-owned detector state and frames (large: static, never on the stack). */
static sfd_parity_t g_det;
static sfd_frame_t g_frame;
static sfd_verdict_t g_verdict;

int main(void) {
    if (sfd_version() != SFD_VERSION) { /* a library that is not the headers' */
        fprintf(stderr, "sfd: library %u.%u, headers %d.%d\n", (unsigned)(sfd_version() >> 16),
                (unsigned)(sfd_version() & 0xFFFFu), SFD_VERSION_MAJOR, SFD_VERSION_MINOR);
        return 1;
    }
    sfd_params_t p;
    if (sfd_params_default(&p) != SFD_OK) return 1;
    p.translation_known = 1; /* the motion below gives the translation */
    if (sfd_params_validate(&p) != SFD_OK) return 1;
    const double no_dist[4] = {0.0, 0.0, 0.0, 0.0};
    sfd_camera_t cam;
    if (sfd_camera_init(&cam, SFD_DISTORTION_PINHOLE, 640, 480, 400.0, 400.0, 320.0, 240.0,
                        no_dist) != SFD_OK) {
        return 1;
    }
    sfd_status_t st = sfd_parity_init(&g_det, &p, &cam);
    if (st != SFD_OK) {
        fprintf(stderr, "sfd_parity_init: %s\n", sfd_status_str(st));
        return 1;
    }

    /* World frame = camera 0. Points on a 5 x 4 grid, depths 8..12 m. */
    double p_FinW_m[NUM_POINTS][3];
    for (int i = 0; i < NUM_POINTS; ++i) {
        p_FinW_m[i][0] = -4.0 + 2.0 * (i % 5);
        p_FinW_m[i][1] = -3.0 + 2.0 * (double)(i / 5);
        p_FinW_m[i][2] = 8.0 + (double)((i * 7) % 5);
    }
    /* Camera k: centre (0.2 k, 0.05 k, 0) m, axes of camera 0. */
    const double step_m[3] = {0.2, 0.05, 0.0};
    sfd_frame_motion_t motion = {{1, 0, 0, 0, 1, 0, 0, 0, 1}, 1, {step_m[0], step_m[1], step_m[2]}};
    const int frames = p.window_frames + 1; /* fill the window, then test twice */
    int errors = 0, tested_frames = 0;
    for (int k = 0; k < frames; ++k) {
        g_frame.utime = 1000000 + 50000 * (int64_t)k; /* 20 Hz */
        g_frame.num_features = NUM_POINTS;
        for (int i = 0; i < NUM_POINTS; ++i) {
            const double p_FinC_m[3] = {p_FinW_m[i][0] - step_m[0] * k,
                                        p_FinW_m[i][1] - step_m[1] * k, p_FinW_m[i][2]};
            double uv[2];
            if (sfd_camera_project(&cam, p_FinC_m, uv, NULL) != SFD_OK) return 1;
            if (k == frames - 1 && i == JUMP_FEATURE) { /* the tracker jumps */
                uv[0] += 12.0;
                uv[1] -= 7.0;
            }
            sfd_feature_t *f = &g_frame.features[i];
            f->track_id = 100 + i;
            f->u_px = uv[0];
            f->v_px = uv[1];
            f->depth_m = p_FinC_m[2];
            f->depth_var_m2 = 0.01;
        }
        st = sfd_parity_push_frame(&g_det, &g_frame, k == 0 ? NULL : &motion, &g_verdict);
        if (st != SFD_OK) {
            fprintf(stderr, "sfd_parity_push_frame: %s\n", sfd_status_str(st));
            return 1;
        }
        if (g_verdict.flags & SFD_FLAG_WINDOW_FILLING) continue;
        ++tested_frames;
        for (int i = 0; i < g_verdict.num_features; ++i) {
            const sfd_feature_result_t *v = &g_verdict.features[i];
            const int want = (k == frames - 1 && i == JUMP_FEATURE) ? SFD_VERDICT_SPURIOUS
                                                                    : SFD_VERDICT_CONSISTENT;
            if (v->status != want) {
                fprintf(stderr, "frame %d: track %lld is %d (statistic %.3f), expected %d\n", k,
                        (long long)v->track_id, v->status, v->statistic, want);
                ++errors;
            }
        }
        printf("frame %d: %d consistent, %d spurious, %d untested\n", k, g_verdict.num_consistent,
               g_verdict.num_spurious, g_verdict.num_untested);
    }
    static const char *const status_name[] = {"UNTESTED", "CONSISTENT", "SPURIOUS"};
    const sfd_feature_result_t *jumped = &g_verdict.features[JUMP_FEATURE];
    printf(
        "sfd %d.%d: parity test, L = %d, alpha = %g, %d tested frames: jumped track %lld %s "
        "(statistic %.1f), %d wrong verdicts: %s\n",
        SFD_VERSION_MAJOR, SFD_VERSION_MINOR, p.window_frames, p.false_alarm_rate, tested_frames,
        (long long)jumped->track_id,
        status_name[jumped->status >= 0 && jumped->status <= 2 ? jumped->status : 0],
        jumped->statistic, errors, errors == 0 && tested_frames == 2 ? "ok" : "WRONG");
    return (errors == 0 && tested_frames == 2) ? 0 : 1;
}
