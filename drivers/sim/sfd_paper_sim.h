/* SPDX-License-Identifier: MIT */
/* Synthetic feed (header-only C, heap-free) for tests and sfd-sim: the paper's simulation scenario
 * (Tornqvist et al. 2008, Section IV) for one group. Frame 0 is the world frame: a downward camera
 * at 58 m, features uniform over 40 x 40 m with depth ~ N(58, 1), normalized-coordinate noise sigma
 * = 0.005. Assumptions the paper leaves open (the same as sfd-sim paper-uav): between frames the
 * camera rotates by a random rotation vector with N(0, 0.02^2) rad per axis and translates by (1,
 * 0.5, 0.1) m + N(0, 0.2^2) m per axis; the fault k(-1, 1)^T is added to one feature's measurement
 * in the newest frame. */
#ifndef SFD_PARITY_SIM_H
#define SFD_PARITY_SIM_H

#include <math.h>
#include <string.h>

#include <sfd/sfd_parity.h>
#include <sfd/sfd_prng.h>
#include <sfd/sfd_rotation.h>

#include "sfd_sim_math.h"

typedef struct {
    double m[SFD_MAX_GROUP][3]; /* landmarks in frame 0 (m) */
    double y_true[SFD_MAX_GROUP][SFD_MAX_WINDOW][2];
    double z_true[SFD_MAX_GROUP][SFD_MAX_WINDOW];
} parity_truth_t;

/* Geometry: rotations, translations and landmarks (no noise). rot_sigma scales the rotation
 * increments; axis_only != 0 makes every rotation about the optical axis (rank drop). */
static inline void sim_geometry(sfd_prng_t *rng, sfd_parity_group_t *g, parity_truth_t *tr, int L,
                                int n, int known, double rot_sigma, int axis_only) {
    memset(g, 0, sizeof *g);
    g->window_frames = L;
    g->group_size = n;
    g->translation_known = known;
    g->exact_depth_covariance = 1;
    double R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    double p[3] = {0, 0, 0};
    for (int t = 0; t < L; ++t) {
        if (t > 0) {
            double phi[3], dR[9];
            for (int k = 0; k < 3; ++k) phi[k] = rot_sigma * sfd_prng_gaussian(rng);
            if (axis_only) phi[0] = phi[1] = 0.0;
            sfd_so3_exp(phi, dR);
            sfd_sim_mat3_mul(dR, R, R); /* R_C0toCt = dR * R_C0toC(t-1) */
            const double v[3] = {1.0, 0.5, 0.1};
            for (int k = 0; k < 3; ++k) p[k] += v[k] + 0.2 * sfd_prng_gaussian(rng);
        }
        memcpy(g->R_C0toCt[t], R, sizeof R);
        memcpy(g->p_CtInC0_m[t], p, sizeof p);
    }
    for (int i = 0; i < n; ++i) {
        tr->m[i][0] = -20.0 + 40.0 * sfd_prng_uniform(rng);
        tr->m[i][1] = -20.0 + 40.0 * sfd_prng_uniform(rng);
        tr->m[i][2] = 58.0 + sfd_prng_gaussian(rng);
        for (int t = 0; t < L; ++t) {
            double c[3];
            for (int r = 0; r < 3; ++r) {
                c[r] = 0;
                for (int k = 0; k < 3; ++k)
                    c[r] += g->R_C0toCt[t][3 * r + k] * (tr->m[i][k] - g->p_CtInC0_m[t][k]);
            }
            tr->z_true[i][t] = c[2];
            tr->y_true[i][t][0] = c[0] / c[2];
            tr->y_true[i][t][1] = c[1] / c[2];
        }
    }
}

/* Measurements: y = y_true + N(0, sigma^2 I) (+ fault on feature 0, newest frame), zhat = z + N(0,
 * depth_var) (kept positive), y_pred = y_true (the exact form of eq. 22). */
static inline void sim_measure(sfd_prng_t *rng, sfd_parity_group_t *g, const parity_truth_t *tr,
                               double sigma, double depth_var, const double fault[2],
                               int fault_feature) {
    const int L = g->window_frames;
    for (int i = 0; i < g->group_size; ++i) {
        for (int t = 0; t < L; ++t) {
            for (int c = 0; c < 2; ++c) {
                g->y[i][t][c] = tr->y_true[i][t][c] + sigma * sfd_prng_gaussian(rng);
                g->y_pred[i][t][c] = tr->y_true[i][t][c];
            }
            if (fault != NULL && i == fault_feature && t == L - 1) {
                g->y[i][t][0] += fault[0];
                g->y[i][t][1] += fault[1];
            }
            g->cov_y[i][t][0] = sigma * sigma;
            g->cov_y[i][t][1] = 0.0;
            g->cov_y[i][t][2] = sigma * sigma;
            double z = tr->z_true[i][t];
            if (depth_var > 0.0) {
                double zh = z;
                for (int tries = 0; tries < 16; ++tries) { /* keep the prior positive */
                    zh = z + sqrt(depth_var) * sfd_prng_gaussian(rng);
                    if (zh > 1.0) break;
                }
                z = zh > 1.0 ? zh : 1.0;
            }
            g->depth_m[i][t] = z;
            g->depth_var_m2[i][t] = depth_var;
        }
    }
}

#endif /* SFD_PARITY_SIM_H */
