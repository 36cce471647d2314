/* SPDX-License-Identifier: MIT */
/* Deterministic synthetic feed (header-only C, heap-free): a camera flying over ground landmarks,
 * producing sfd_frame_t/sfd_frame_motion_t exactly as a caller would (pixels through a pinhole
 * camera, gyro-exact rotation between frames, translation known or not), with spurious features
 * injected and labelled. World frame: camera 0 looks down (camera z = world z, i.e. depth along
 * +z), landmarks at depth 40 +- 10 m spread over the view. Per frame: rotation N(0, rot_sigma^2)
 * per axis, translation (0.4, 0.2, 0.05) m + N(0, 0.05^2). */
#ifndef SFD_SCENE_SIM_H
#define SFD_SCENE_SIM_H

#include <math.h>
#include <string.h>

#include <sfd/sfd_camera.h>
#include <sfd/sfd_parity.h>
#include <sfd/sfd_prng.h>
#include <sfd/sfd_rotation.h>

#include "sfd_sim_math.h"

enum { SCENE_MAX = SFD_MAX_FEATURES };

typedef struct {
    sfd_camera_t cam;
    sfd_prng_t rng;
    int n;
    double m[SCENE_MAX][3]; /* landmarks in world (m) */
    double R_WtoC[9];       /* current camera orientation */
    double p_CinW[3];       /* current camera centre */
    double sigma_px;
    double rot_sigma;
    int axis_only;
    int64_t utime;
    int frame;
    /* per-landmark fault state */
    double offset_px[SCENE_MAX][2]; /* accumulated mistrack offset (jump) */
    double drift_px[SCENE_MAX][2];  /* per-frame drift (moving object) */
    int respawn;                    /* 1: a landmark leaving the image is replaced (new track id) */
    int generation[SCENE_MAX];      /* respawn count per landmark slot */
} scene_t;

/* Places landmark i at a random pixel of the current view, 30-50 m deep. */
static inline void scene_place(scene_t *s, int i) {
    const double z = 30.0 + 20.0 * sfd_prng_uniform(&s->rng);
    const double u = 60.0 + 632.0 * sfd_prng_uniform(&s->rng);
    const double v = 60.0 + 360.0 * sfd_prng_uniform(&s->rng);
    const double c[3] = {(u - 367.215) / 458.654 * z, (v - 248.375) / 457.296 * z, z};
    /* world = R_WtoC^T c + p */
    for (int r = 0; r < 3; ++r) {
        s->m[i][r] = s->p_CinW[r];
        for (int k = 0; k < 3; ++k) s->m[i][r] += s->R_WtoC[3 * k + r] * c[k];
    }
    s->offset_px[i][0] = s->offset_px[i][1] = 0.0;
}

static inline void scene_init(scene_t *s, uint64_t seed, int n, double sigma_px) {
    memset(s, 0, sizeof *s);
    const double nodist[4] = {0, 0, 0, 0};
    sfd_camera_init(&s->cam, SFD_DISTORTION_PINHOLE, 752, 480, 458.654, 457.296, 367.215, 248.375,
                    nodist);
    sfd_prng_seed(&s->rng, seed);
    s->n = n;
    s->sigma_px = sigma_px;
    s->rot_sigma = 0.01;
    const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    memcpy(s->R_WtoC, I, sizeof I);
    for (int i = 0; i < n; ++i) scene_place(s, i);
    s->utime = 1000000;
}

/* Advances one frame and fills frame + motion. depth priors: true depth (+ N(0, depth_var)). */
static inline void scene_step(scene_t *s, sfd_frame_t *frame, sfd_frame_motion_t *motion,
                              double depth_var) {
    if (s->frame > 0) {
        double phi[3], dR[9], R_new[9];
        for (int k = 0; k < 3; ++k) phi[k] = s->rot_sigma * sfd_prng_gaussian(&s->rng);
        if (s->axis_only) phi[0] = phi[1] = 0.0;
        sfd_so3_exp(phi, dR);
        sfd_sim_mat3_mul(dR, s->R_WtoC, R_new); /* R_WtoCnew = dR R_WtoCold, dR = R_ColdToCnew */
        const double step[3] = {0.4 + 0.05 * sfd_prng_gaussian(&s->rng),
                                0.2 + 0.05 * sfd_prng_gaussian(&s->rng),
                                0.05 + 0.05 * sfd_prng_gaussian(&s->rng)};
        double p_new[3];
        for (int k = 0; k < 3; ++k) p_new[k] = s->p_CinW[k] + step[k];
        /* R_CcurToCprev = R_WtoCold R_WtoCnew^T ; p_CcurInCprev = R_WtoCold (p_new - p_old) */
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) {
                double acc = 0;
                for (int k = 0; k < 3; ++k) acc += s->R_WtoC[3 * r + k] * R_new[3 * c + k];
                motion->R_CcurToCprev[3 * r + c] = acc;
            }
        for (int r = 0; r < 3; ++r) {
            double acc = 0;
            for (int k = 0; k < 3; ++k) acc += s->R_WtoC[3 * r + k] * step[k];
            motion->p_CcurInCprev_m[r] = acc;
        }
        motion->translation_known = 1;
        memcpy(s->R_WtoC, R_new, sizeof R_new);
        memcpy(s->p_CinW, p_new, sizeof p_new);
        s->utime += 50000;
    } else {
        memset(motion, 0, sizeof *motion);
        motion->R_CcurToCprev[0] = motion->R_CcurToCprev[4] = motion->R_CcurToCprev[8] = 1.0;
    }
    int k = 0;
    for (int i = 0; i < s->n; ++i) {
        double c[3];
        for (int r = 0; r < 3; ++r) {
            c[r] = 0;
            for (int j = 0; j < 3; ++j) c[r] += s->R_WtoC[3 * r + j] * (s->m[i][j] - s->p_CinW[j]);
        }
        double uv[2];
        const int ok = sfd_camera_project(&s->cam, c, uv, NULL) == SFD_OK;
        if (s->respawn && (!ok || uv[0] < 0 || uv[0] >= 752 || uv[1] < 0 || uv[1] >= 480)) {
            scene_place(s, i);
            s->generation[i]++;
            for (int r = 0; r < 3; ++r) {
                c[r] = 0;
                for (int j = 0; j < 3; ++j)
                    c[r] += s->R_WtoC[3 * r + j] * (s->m[i][j] - s->p_CinW[j]);
            }
            if (sfd_camera_project(&s->cam, c, uv, NULL) != SFD_OK) continue;
        } else if (!ok) {
            continue;
        }
        s->offset_px[i][0] += s->drift_px[i][0];
        s->offset_px[i][1] += s->drift_px[i][1];
        sfd_feature_t *f = &frame->features[k++];
        f->track_id = 1000 + i + 1000000 * (int64_t)s->generation[i];
        f->u_px = uv[0] + s->offset_px[i][0] + s->sigma_px * sfd_prng_gaussian(&s->rng);
        f->v_px = uv[1] + s->offset_px[i][1] + s->sigma_px * sfd_prng_gaussian(&s->rng);
        f->depth_m = c[2] + (depth_var > 0 ? sqrt(depth_var) * sfd_prng_gaussian(&s->rng) : 0.0);
        f->depth_var_m2 = depth_var;
    }
    frame->num_features = k;
    frame->utime = s->utime;
    s->frame++;
}

#endif /* SFD_SCENE_SIM_H */
