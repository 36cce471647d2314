/* SPDX-License-Identifier: MIT */
/* Synthetic frame pairs for the association methods (header-only C, heap-free): a camera on an
 * IMU (camera looking along IMU x, EuRoC cam0 intrinsics, 752x480) moves between two frames by a
 * chosen baseline and a small rotation; landmarks 4-12 m deep are visible in both; the filter's
 * prior is the truth perturbed by its own covariance; landmark positions carry 2 cm errors with
 * that covariance (exact when the pixel noise is 0); outliers are random (uniform in the image,
 * >= 20 px from the truth) or structured (one consistent 3-15 px shift, like a moving object).
 * Used by unit.association and sfd-bench. */
#ifndef SFD_PAIR_SIM_H
#define SFD_PAIR_SIM_H

#include <math.h>
#include <string.h>

#include <sfd/sfd_assoc.h>
#include <sfd/sfd_prng.h>
#include <sfd/sfd_rotation.h>

enum { SIM_PAIR_MAX = SFD_MAX_FEATURES };

typedef struct {
    sfd_ekf_t ekf; /* prior at the current frame */
    sfd_ekf_camera_t cam;
    double prev_R_CtoW[9], prev_p_C[3];
    double true_R_ItoW[9], true_p_I[3];
    sfd_match_t m[SIM_PAIR_MAX]; /* their landmarks point into landmark_W_m / landmark_cov_m2 */
    double landmark_W_m[SIM_PAIR_MAX][3];
    double landmark_cov_m2[SIM_PAIR_MAX][9];
    uint8_t outlier[SIM_PAIR_MAX];
    int n;
} sim_pair_t;

typedef struct {
    int n;
    double outlier_ratio;
    double sigma_px;        /* pixel noise of the data */
    double translation_m;   /* baseline between the frames */
    int structured;         /* 1: outliers shifted consistently by 3-15 px (moving object) */
    double prior_p_sigma_m; /* prior error of the filter */
    double prior_th_sigma_rad;
} sim_pair_opts_t;

static inline void sim_pair_mat3_mul(const double *A, const double *B, double *C) {
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            C[3 * i + j] = 0.0;
            for (int k = 0; k < 3; ++k) C[3 * i + j] += A[3 * i + k] * B[3 * k + j];
        }
    }
}

/* Pixel of world point L seen by camera (R_CtoW, p_C); returns 0 behind the camera. */
static inline int sim_pair_project_px(const sfd_ekf_camera_t *cam, const double R_CtoW[9],
                                      const double p_C[3], const double L[3], double uv[2]) {
    double c[3];
    for (int r = 0; r < 3; ++r) {
        c[r] = 0.0;
        for (int k = 0; k < 3; ++k) c[r] += R_CtoW[3 * k + r] * (L[k] - p_C[k]);
    }
    if (c[2] < 0.5) return 0;
    uv[0] = cam->fx_px * c[0] / c[2] + cam->cx_px;
    uv[1] = cam->fy_px * c[1] / c[2] + cam->cy_px;
    return uv[0] > 0 && uv[0] < 752 && uv[1] > 0 && uv[1] < 480;
}

/* dst = src with dst's matches referring to dst's own landmarks. */
static inline void sim_pair_copy(sim_pair_t *dst, const sim_pair_t *src) {
    memcpy(dst, src, sizeof *dst);
    for (int i = 0; i < SIM_PAIR_MAX; ++i) {
        if (src->m[i].landmark_W_m == NULL) continue;
        dst->m[i].landmark_W_m = dst->landmark_W_m[i];
        dst->m[i].landmark_cov_m2 = dst->landmark_cov_m2[i];
    }
}

static inline int sim_pair_make(sim_pair_t *pr, const sim_pair_opts_t *o, uint64_t seed) {
    memset(pr, 0, sizeof *pr);
    sfd_prng_t rng;
    sfd_prng_seed(&rng, seed);
    sfd_ekf_camera_t *cam = &pr->cam;
    /* camera looks along IMU x (camera z = IMU x) */
    const double T[16] = {0, 0, 1, 0.05, -1, 0, 0, 0.0, 0, -1, 0, 0.0, 0, 0, 0, 1};
    sfd_extrinsics_from_matrix(&cam->ext, T);
    cam->fx_px = 458.654;
    cam->fy_px = 457.296;
    cam->cx_px = 367.215;
    cam->cy_px = 248.375;
    cam->pixel_sigma_px = (o->sigma_px > 0.05) ? o->sigma_px : 1.0;

    /* previous IMU pose: identity at origin; current: moved sideways/forward and rotated */
    double R_prev[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, p_prev[3] = {0, 0, 0};
    const double rv[3] = {0.02, -0.03, 0.05};
    double dR[9];
    sfd_so3_exp(rv, dR);
    sim_pair_mat3_mul(R_prev, dR, pr->true_R_ItoW);
    pr->true_p_I[0] = 0.6 * o->translation_m;
    pr->true_p_I[1] = 0.8 * o->translation_m;
    pr->true_p_I[2] = 0.0;

    /* camera poses */
    sfd_ekf_t tmp;
    memset(&tmp, 0, sizeof tmp);
    sfd_rotmat_to_quat(R_prev, tmp.q_ItoW);
    memcpy(tmp.p_IinW_m, p_prev, sizeof p_prev);
    sfd_ekf_camera_pose(&tmp, &cam->ext, pr->prev_R_CtoW, pr->prev_p_C);
    double cur_R_CtoW[9], cur_p_C[3];
    sfd_rotmat_to_quat(pr->true_R_ItoW, tmp.q_ItoW);
    memcpy(tmp.p_IinW_m, pr->true_p_I, sizeof pr->true_p_I);
    sfd_ekf_camera_pose(&tmp, &cam->ext, cur_R_CtoW, cur_p_C);

    /* filter prior: truth perturbed by its own covariance */
    sfd_ekf_noise_t nz;
    sfd_ekf_noise_default(&nz);
    double P0[SFD_EKF_DIM], p_est[3], q_est[4], dth[3], Rn[9];
    for (int k = 0; k < 3; ++k) {
        P0[SFD_EKF_IDX_P + k] = o->prior_p_sigma_m * o->prior_p_sigma_m;
        P0[SFD_EKF_IDX_V + k] = 0.01;
        P0[SFD_EKF_IDX_THETA + k] = o->prior_th_sigma_rad * o->prior_th_sigma_rad;
        P0[SFD_EKF_IDX_BG + k] = 1e-6;
        P0[SFD_EKF_IDX_BA + k] = 1e-4;
        p_est[k] = pr->true_p_I[k] + o->prior_p_sigma_m * sfd_prng_gaussian(&rng);
        dth[k] = o->prior_th_sigma_rad * sfd_prng_gaussian(&rng);
    }
    sfd_so3_exp(dth, dR);
    sim_pair_mat3_mul(pr->true_R_ItoW, dR, Rn);
    sfd_rotmat_to_quat(Rn, q_est);
    const double zero[3] = {0, 0, 0};
    if (sfd_ekf_init(&pr->ekf, &nz, p_est, zero, q_est, zero, zero, P0) != SFD_OK) return -1;

    /* landmarks visible in both frames */
    const double shift_dir = 2.0 * 3.14159265358979 * sfd_prng_uniform(&rng);
    int n = 0;
    for (int tries = 0; n < o->n && tries < 100 * SIM_PAIR_MAX; ++tries) {
        const double depth = 4.0 + 8.0 * sfd_prng_uniform(&rng);
        const double xc = (sfd_prng_uniform(&rng) - 0.5) * 1.4,
                     yc = (sfd_prng_uniform(&rng) - 0.5) * 0.9;
        const double c[3] = {xc * depth, yc * depth, depth};
        double L[3];
        for (int r = 0; r < 3; ++r) {
            L[r] = pr->prev_p_C[r];
            for (int k = 0; k < 3; ++k) L[r] += pr->prev_R_CtoW[3 * r + k] * c[k];
        }
        double uv0[2], uv1[2];
        if (!sim_pair_project_px(cam, pr->prev_R_CtoW, pr->prev_p_C, L, uv0)) continue;
        if (!sim_pair_project_px(cam, cur_R_CtoW, cur_p_C, L, uv1)) continue;
        sfd_match_t *m = &pr->m[n];
        for (int k = 0; k < 2; ++k) {
            m->prev_uv_px[k] = uv0[k] + o->sigma_px * sfd_prng_gaussian(&rng);
            m->uv_px[k] = uv1[k] + o->sigma_px * sfd_prng_gaussian(&rng);
        }
        /* the filter's landmark: truth + N(0, 0.02^2 I) with that covariance */
        for (int k = 0; k < 3; ++k) {
            const double lm_sigma = (o->sigma_px > 0.0) ? 0.02 : 0.0; /* noise-free: exact map */
            pr->landmark_W_m[n][k] = L[k] + lm_sigma * sfd_prng_gaussian(&rng);
            pr->landmark_cov_m2[n][(size_t)4 * (size_t)k] = lm_sigma * lm_sigma;
        }
        m->landmark_W_m = pr->landmark_W_m[n];
        m->landmark_cov_m2 = pr->landmark_cov_m2[n];
        ++n;
    }
    pr->n = n;
    if (n == 0) return -1;
    /* outliers: round(ratio * n) distinct matches drawn at random */
    int n_out = (int)lround(o->outlier_ratio * n);
    if (n_out > n) n_out = n;
    for (int k = 0; k < n_out; ++k) {
        int i = (int)sfd_prng_uniform_index(&rng, (uint32_t)n);
        while (pr->outlier[i]) i = (i + 1) % n;
        pr->outlier[i] = 1;
        sfd_match_t *m = &pr->m[i];
        if (o->structured) {
            const double mag = 3.0 + 12.0 * sfd_prng_uniform(&rng);
            m->uv_px[0] += mag * cos(shift_dir);
            m->uv_px[1] += mag * sin(shift_dir);
        } else {
            double u, v;
            do { /* uniform in the image, at least 20 px from the true position */
                u = 752.0 * sfd_prng_uniform(&rng);
                v = 480.0 * sfd_prng_uniform(&rng);
            } while ((u - m->uv_px[0]) * (u - m->uv_px[0]) + (v - m->uv_px[1]) * (v - m->uv_px[1]) <
                     400.0);
            m->uv_px[0] = u;
            m->uv_px[1] = v;
        }
    }
    return 0;
}

static inline sim_pair_opts_t sim_pair_default_opts(void) {
    sim_pair_opts_t o;
    o.n = 200;
    o.outlier_ratio = 0.3;
    o.sigma_px = 1.0;
    o.translation_m = 0.3;
    o.structured = 0;
    o.prior_p_sigma_m = 0.05;
    o.prior_th_sigma_rad = 0.005;
    return o;
}

#endif /* SFD_PAIR_SIM_H */
