/* SPDX-License-Identifier: MIT */
/* unit.window: the sliding-window filter (sfd_window.h) on a simulated flight in a static scene
 * (a 2 m circle with roll, pitch and height oscillations, a camera looking outwards at points on a
 * 6 m cylinder, 20 Hz frames, a 200 Hz IMU with the modelled white noise and bias random walks,
 * 1 px of pixel noise at f = 400 px):
 * - the estimate stays within 2 % of the distance flown, and the position and attitude NEES over
 *   20 Monte Carlo runs of 30 s are inside their 95 % chi-square bands (under way, from rest,
 *   and from rest with ten times the initial uncertainty);
 * - the four unobservable directions (translation, yaw about gravity) stay in the null space of
 *   the linearized system: Phi N_k = N_k+1 over each frame interval and H N = 0 for the tracks,
 *   with the observability constraint and with first estimates, not with current estimates;
 * - the gate refuses a track that jumps to another point (and lists it), the estimate is not
 *   pulled, and the jumped observations never reach the update; a flagged track ends (its earlier
 * observations through the gate) or is deleted whole;
 * - capacities (tracks, window) and bad input are status codes or counters, never writes past an
 *   array. */
#include "sfd_test.h"

#include <stdlib.h>
#include <string.h>

#include <sfd/sfd_chi2.h>
#include <sfd/sfd_prng.h>
#include <sfd/sfd_rotation.h>
#include <sfd/sfd_window.h>

static sfd_window_t g_w;
static sfd_window_scratch_t g_ws; /* the filter's work space for every call */
/* run_flight_from: build each frame's observations in g_ws.u.obs (as sfd_nav_t does) */
static int g_obs_in_scratch = 0;

enum { NPTS = 400, IMU_PER_FRAME = 10 };
static const double kDt = 0.005;       /* IMU period (s) */
static const double kSigmaXn = 0.0025; /* 1 px at f = 400 px */

typedef struct {
    double p[3], v[3], R[9];
} pose_t;

static double g_pts[NPTS][3];

/* The Jacobians a run uses (sfd_window_params_t: first_estimates, observability_constrained). */
enum { JAC_CURRENT = 0, JAC_FIRST_ESTIMATES = 1, JAC_OBSERVABILITY = 2 };
static const char *const kJacName[3] = {"current-estimate", "first-estimate",
                                        "observability-constrained"};

/* The initial uncertainty of a run: P0 (the filter's, and the spread the initial errors and
 * biases are drawn from) is the default's times this. */
static double g_p0_scale = 1.0;

/* Keyframes of a run (sfd_window_params_t.keyframe_parallax_rad, 0: off; keyframe_recent 2) and
 * what the window held: the longest span of its clones in frames, and whether its newest two
 * clones were consecutive frames after every frame. */
static double g_keyframe_rad = 0.0;
static int g_span_max_frames = 0;
static int g_recent_consecutive = 1;
/* frames after which no track had its first observation in the oldest clone */
static int g_oldest_unobserved = 0;
/* Depth priors of a run: sfd_window_params_t.use_depth_prior (0: none, the other tests) and the
 * standard deviation of the depths given with every observation (true camera z + noise). */
static int g_depth_priors = 0;
/* 1: pixel noise correlated (0.9) and anisotropic (deviations 1 : 2), as at an image edge */
static int g_aniso = 0;
static double g_depth_sd_m = 0.0;
/* The filter's first clone sequence number in a run (sfd_window_t.next_seq after the start). */
static uint32_t g_seq_start = 0;

/* Null-space check of a run (g_null_check = 1): the largest relative violations seen. */
static int g_null_check = 0;
static double g_phi_violation = 0.0, g_h_violation = 0.0;
static int g_h_checked = 0;

static void mat_mul(const double A[9], const double B[9], double C[9]) {
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
            C[3 * r + c] = 0.0;
            for (int k = 0; k < 3; ++k) C[3 * r + c] += A[3 * r + k] * B[3 * k + c];
        }
    }
}

static void mat_tmul(const double A[9], const double B[9], double C[9]) { /* A^T B */
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
            C[3 * r + c] = 0.0;
            for (int k = 0; k < 3; ++k) C[3 * r + c] += A[3 * k + r] * B[3 * k + c];
        }
    }
}

/* Seconds at rest before the flight starts (0: the flight is under way at t = 0). With a rest,
 * the flight's own time is tau(t) = 0 until g_rest_s, then s - T (1 - exp(-s / T)) with
 * s = t - g_rest_s, T = 1 s: it starts from rest and reaches full speed in a few seconds. */
static double g_rest_s = 0.0;

/* The true trajectory: position, velocity (analytic) and R_ItoW at t. */
static void truth(double t_in, pose_t *x) {
    double t = t_in, rate = 1.0; /* tau and d tau / dt */
    if (g_rest_s > 0.0) {
        const double s = t_in - g_rest_s;
        t = s > 0.0 ? s - (1.0 - exp(-s)) : 0.0;
        rate = s > 0.0 ? 1.0 - exp(-s) : 0.0;
    }
    const double w = 2.0 * M_PI / 10.0, r = 2.0;
    x->p[0] = r * cos(w * t);
    x->p[1] = r * sin(w * t);
    x->p[2] = 1.0 + 0.3 * sin(0.5 * t);
    x->v[0] = -r * w * sin(w * t);
    x->v[1] = r * w * cos(w * t);
    x->v[2] = 0.15 * cos(0.5 * t);
    for (int k = 0; k < 3; ++k) x->v[k] *= rate;
    const double yaw = w * t + 0.2 * sin(0.9 * t);
    const double rz[3] = {0, 0, yaw}, ry[3] = {0, 0.1 * sin(0.7 * t), 0},
                 rx[3] = {0.1 * sin(1.3 * t), 0, 0};
    double Rz[9], Ry[9], Rx[9], T[9];
    sfd_so3_exp(rz, Rz);
    sfd_so3_exp(ry, Ry);
    sfd_so3_exp(rx, Rx);
    mat_mul(Rz, Ry, T);
    mat_mul(T, Rx, x->R);
}

/* Camera: optical axis along IMU x, image x along IMU -y, image y along IMU -z. */
static void extrinsics(sfd_extrinsics_t *ext) {
    const double R[9] = {0, 0, 1, -1, 0, 0, 0, -1, 0}; /* columns: camera axes in the IMU frame */
    memcpy(ext->R_CtoI, R, sizeof R);
    ext->p_CinI[0] = 0.05;
    ext->p_CinI[1] = 0.0;
    ext->p_CinI[2] = 0.02;
}

/* Point k in the camera of pose x: normalized coordinates; 0 when not visible. */
static double g_last_depth_m = 0.0; /* camera z of the point observe() last projected */
static int observe(const pose_t *x, const sfd_extrinsics_t *ext, const double pw[3], double xn[2]) {
    double R_CtoW[9];
    mat_mul(x->R, ext->R_CtoI, R_CtoW);
    double pc_w[3];
    for (int k = 0; k < 3; ++k) {
        pc_w[k] = x->p[k];
        for (int j = 0; j < 3; ++j) pc_w[k] += x->R[3 * k + j] * ext->p_CinI[j];
    }
    double c[3];
    for (int k = 0; k < 3; ++k) {
        c[k] = 0.0;
        for (int j = 0; j < 3; ++j) c[k] += R_CtoW[3 * j + k] * (pw[j] - pc_w[j]);
    }
    if (!(c[2] > 0.5)) return 0;
    g_last_depth_m = c[2];
    xn[0] = c[0] / c[2];
    xn[1] = c[1] / c[2];
    return fabs(xn[0]) < 0.6 && fabs(xn[1]) < 0.45;
}

static void scene(sfd_prng_t *rng) {
    for (int i = 0; i < NPTS; ++i) {
        const double a = 2.0 * M_PI * sfd_prng_uniform(rng);
        g_pts[i][0] = 6.0 * cos(a);
        g_pts[i][1] = 6.0 * sin(a);
        g_pts[i][2] = -2.0 + 6.0 * sfd_prng_uniform(rng);
    }
}

typedef struct {
    double nees_pose; /* 6-dof (position, global attitude) NEES at the end */
    double nees_pos;
    double pos_err_m;
    double att_err_rad;
    int gated, used, frames;
} run_result_t;

/* A jump: from frame jump_frame on, track jump_track is 20 px off its point (locked onto another
 * image point). */
static void run_flight_from(uint64_t seed, double seconds, int jac, int jump_track, int jump_frame,
                            int at_rest, run_result_t *out);

/* A flight under way at t = 0, the filter started at the truth with errors drawn from P0. */
static void run_flight(uint64_t seed, double seconds, int jac, int jump_track, int jump_frame,
                       run_result_t *out) {
    run_flight_from(seed, seconds, jac, jump_track, jump_frame, 0, out);
}

/* g x a */
static void gcross(double g, const double a[3], double out[3]) { /* (0, 0, -g) x a */
    out[0] = g * a[1];
    out[1] = -g * a[0];
    out[2] = 0.0;
}

/* The unobservable directions of the IMU block at the filter's first estimates (fe_p, fe_v):
 * N[i][c], rows 0..14, columns: translation x, y, z and yaw about gravity (dp = g x p,
 * dv = g x v, dtheta = g). */
static void imu_null(const sfd_window_t *w, const double fe_p[3], const double fe_v[3],
                     double N[SFD_WINDOW_IMU_DIM][4]) {
    const double g = w->prm.noise.gravity_m_s2;
    memset(N, 0, sizeof(double) * SFD_WINDOW_IMU_DIM * 4);
    double gp[3], gv[3];
    gcross(g, fe_p, gp);
    gcross(g, fe_v, gv);
    for (int k = 0; k < 3; ++k) {
        N[SFD_WINDOW_IDX_P + k][k] = 1.0;
        N[SFD_WINDOW_IDX_P + k][3] = gp[k];
        N[SFD_WINDOW_IDX_V + k][3] = gv[k];
    }
    N[SFD_WINDOW_IDX_THETA + 2][3] = -g;
}

/* Phi N_k against N_k+1 over one frame interval (Phi: the transition accumulated since the last
 * frame; N_k at the first estimates before it, N_k+1 at those after it), relative to |N|. */
static double phi_null_violation(const sfd_window_t *w, const double fe_p0[3],
                                 const double fe_v0[3]) {
    double N0[SFD_WINDOW_IMU_DIM][4], N1[SFD_WINDOW_IMU_DIM][4];
    imu_null(w, fe_p0, fe_v0, N0);
    imu_null(w, w->fe_p_IinW_m, w->fe_v_IinW_m_s, N1);
    double worst = 0.0;
    for (int c = 0; c < 4; ++c) {
        double num = 0.0, den = 0.0;
        for (int i = 0; i < SFD_WINDOW_IMU_DIM; ++i) {
            double s = 0.0;
            for (int k = 0; k < SFD_WINDOW_IMU_DIM; ++k) s += w->Phi[i][k] * N0[k][c];
            num += (s - N1[i][c]) * (s - N1[i][c]);
            den += N1[i][c] * N1[i][c];
        }
        if (sqrt(num / den) > worst) worst = sqrt(num / den);
    }
    return worst;
}

/* H N for the last track of a frame projected (g_projected: g_ws.track, whitened and
 * unprojected, projected by sfd_msckf_track_project; its rows are N_f^T H_x, the point projected
 * out), with N at the clones' first-estimate positions: clones[] as they were before the
 * frame's marginalization. Relative to |H row| |N column|. */
static sfd_msckf_track_t g_projected;
static double h_null_violation(const sfd_window_t *w, const sfd_window_clone_t *clones,
                               int num_clones) {
    const sfd_msckf_track_t *tr = &g_projected;
    const double g = w->prm.noise.gravity_m_s2;
    double worst = 0.0;
    for (int c = 0; c < 4; ++c) {
        double Ncol[SFD_MSCKF_DIM] = {0};
        for (int i = 0; i < num_clones; ++i) {
            const int col = SFD_WINDOW_IMU_DIM + 6 * i;
            if (c < 3) {
                Ncol[col + c] = 1.0;
            } else {
                double gp[3];
                gcross(g, clones[i].fe_p_IinW_m, gp);
                for (int k = 0; k < 3; ++k) Ncol[col + k] = gp[k];
                Ncol[col + 5] = -g;
            }
        }
        double nn = 0.0;
        for (int j = 0; j < tr->n; ++j) nn += Ncol[j] * Ncol[j];
        for (int r = 0; r < tr->rows; ++r) {
            double s = 0.0, hh = 0.0;
            for (int j = 0; j < tr->n; ++j) {
                s += tr->Hx[r][j] * Ncol[j];
                hh += tr->Hx[r][j] * tr->Hx[r][j];
            }
            if (hh > 0.0 && fabs(s) / sqrt(hh * nn) > worst) worst = fabs(s) / sqrt(hh * nn);
        }
    }
    return worst;
}

/* at_rest = 1: 1 s at rest first; the filter starts at rest as the product does
 * (sfd_window_start_at_rest from the mean IMU sample of that second), then the flight ramps up.
 * The errors are then those of the estimated start, in the frame the start defines (origin at
 * the start, yaw 0: the truth's own at tau = 0). */
/* sfd_window_test_track over the last 3 frames, before each frame's update, of every point seen
 * in all three (g_track_test = 1): the counts of its statistic. */
static int g_track_test = 0;
typedef struct {
    long tests, alarms; /* clean tracks: tests and statistics above chi2(dof, 0.99) */
    double sum_ratio;   /* sum of gamma / dof over them */
    int jump_alarm[4];  /* the jumped track at jump_frame + 0..3: 1 flagged */
    /* sfd_window_test_track_nested over the last 5 frames, inner 3, of clean tracks seen in all
     * five: tests, inner alarms, alarms that differ from the 3-frame test's, the largest
     * |gamma_inner - gamma_3| / (1 + gamma_3), and m-frame statistics not bit-equal to
     * sfd_window_test_track's over the 5 frames */
    long nested, nested_alarms, nested_disagree, nested_outer_differ;
    double nested_worst;
    /* sfd_window_test_track_evidence over the same 5 frames: results that differ from the
     * nested test's in gamma[0..1] or dof[0..1], ramp tests (dof[2] = 2) and their statistics
     * above chi2(2, 0.99), and the sum of the ramp statistics */
    long ev_differ, ramp_tests, ramp_alarms;
    double ramp_sum;
    double ramp_worst; /* largest |GLR - dense reference| / (1 + GLR) */
    /* sfd_window_test_track_motion: results that differ from sfd_window_test_track's (3 frames)
     * and sfd_window_test_track_evidence's (5 frames, inner 3), fits (ok 1), the largest
     * relative difference of a fit from its dense reference, and the one-sided statistics along
     * x and y (z, two per fit): their number, those above N(0, 1)'s upper 10 % point, their sum */
    long motion_differ, motion_fits, motion_z_tests, motion_z_alarms;
    double motion_worst, motion_z_sum;
} track_test_t;
static track_test_t g_tt;
#define HIST 5
static double g_hist_xn[NPTS][HIST][2]; /* the last HIST observations fed to the filter */
static int g_hist_frame[NPTS][HIST];

static void test_obs(int i, int frames, int64_t t0_us, int f, sfd_window_test_obs_t *o) {
    memset(o, 0, sizeof *o);
    o->frames = frames;
    for (int k = 0; k < frames; ++k) {
        const int h = HIST - frames + k;
        o->utime[k] = t0_us + (int64_t)(f - frames + 1 + k) * 50000;
        o->xn[k][0] = g_hist_xn[i][h][0];
        o->xn[k][1] = g_hist_xn[i][h][1];
        o->cov_xn[k][0] = o->cov_xn[k][2] = kSigmaXn * kSigmaXn;
    }
}

static int seen_since(int i, int f, int frames) {
    for (int k = 0; k < frames; ++k) {
        if (g_hist_frame[i][HIST - 1 - k] != f - k) return 0;
    }
    return 1;
}

/* x = A^-1 B (n x nc) by Gaussian elimination with partial pivoting; A, B overwritten. */
static void dense_solve(int n, double A[12][12], int nc, double B[12][6]) {
    for (int c = 0; c < n; ++c) {
        int piv = c;
        for (int i = c + 1; i < n; ++i)
            if (fabs(A[i][c]) > fabs(A[piv][c])) piv = i;
        for (int j = 0; j < n; ++j) {
            const double t = A[c][j];
            A[c][j] = A[piv][j];
            A[piv][j] = t;
        }
        for (int j = 0; j < nc; ++j) {
            const double t = B[c][j];
            B[c][j] = B[piv][j];
            B[piv][j] = t;
        }
        for (int i = c + 1; i < n; ++i) {
            const double m = A[i][c] / A[c][c];
            for (int j = c; j < n; ++j) A[i][j] -= m * A[c][j];
            for (int j = 0; j < nc; ++j) B[i][j] -= m * B[c][j];
        }
    }
    for (int c = n - 1; c >= 0; --c) {
        for (int j = 0; j < nc; ++j) {
            double s = B[c][j];
            for (int k = c + 1; k < n; ++k) s -= A[c][k] * B[k][j];
            B[c][j] = s / A[c][c];
        }
    }
}

/* b^T (X^T S^-1 X)^-1 b with b = X^T S^-1 r over the first p columns of X (the part of
 * r^T S^-1 r they explain), from S^-1 [X r] (rows x 6, column 5 = S^-1 r). */
static double explained(int rows, const double X[12][5], const double SiXr[12][6], int p) {
    double A[12][12], b[12][6];
    memset(A, 0, sizeof A);
    memset(b, 0, sizeof b);
    for (int i = 0; i < p; ++i) {
        for (int j = 0; j < p; ++j) {
            for (int k = 0; k < rows; ++k) A[i][j] += X[k][i] * SiXr[k][j];
        }
        for (int k = 0; k < rows; ++k) b[i][0] += X[k][i] * SiXr[k][5];
    }
    double c[12][6];
    memcpy(c, b, sizeof c);
    dense_solve(p, A, 1, c);
    double e = 0.0;
    for (int i = 0; i < p; ++i) e += b[i][0] * c[i][0];
    return e;
}

/* The ramp's GLR by dense generalized least squares on the track sfd_window_test_track_evidence
 * left in the scratch (rows, H_f, r, S in R): with X = [H_f F], F's rows 2k, 2k + 1 = (k, 0),
 * (0, k) for frame k of m (oldest 0) and 0 on depth rows, GLR = (part of r^T S^-1 r that X
 * explains) - (part H_f alone explains). */
static double dense_ramp_glr(const sfd_msckf_track_t *t, int m) {
    const int rows = t->rows;
    double X[12][5], S[12][12], SiXr[12][6];
    memset(X, 0, sizeof X);
    for (int i = 0; i < rows; ++i) {
        for (int c = 0; c < 3; ++c) X[i][c] = t->Hf[i][c];
        if (i < 2 * m) X[i][3 + (i & 1)] = (double)(i >> 1); /* frame k of rows 2k, 2k + 1 */
        for (int j = 0; j < rows; ++j) S[i][j] = t->R[i][j];
        for (int c = 0; c < 5; ++c) SiXr[i][c] = X[i][c];
        SiXr[i][5] = t->r[i];
    }
    dense_solve(rows, S, 6, SiXr);
    return explained(rows, X, SiXr, 5) - explained(rows, X, SiXr, 3);
}

/* The motion's fit (sfd_window_motion_t) by dense generalized least squares on the rows
 * 2 k0 .. 2 m - 1 of the track in the scratch (frames k0..m-1; no depth row): with H = H_f and F's
 * rows 2k, 2k + 1 = (k - k0, 0), (0, k - k0), G = [H F]^T S^-1 [H F] and g = [H F]^T S^-1 r over
 * those rows, info = G_FF - G_FH G_HH^-1 G_HF and score = g_F - G_FH G_HH^-1 g_H. */
static void dense_motion(const sfd_msckf_track_t *t, int k0, int m, double info[3],
                         double score[2]) {
    const int r0 = 2 * k0, n = 2 * (m - k0);
    double X[12][5], S[12][12], SiXr[12][6];
    memset(X, 0, sizeof X);
    memset(S, 0, sizeof S);
    for (int i = 0; i < n; ++i) {
        for (int c = 0; c < 3; ++c) X[i][c] = t->Hf[r0 + i][c];
        X[i][3 + (i & 1)] = (double)(i >> 1);
        for (int j = 0; j < n; ++j) S[i][j] = t->R[r0 + i][r0 + j];
        for (int c = 0; c < 5; ++c) SiXr[i][c] = X[i][c];
        SiXr[i][5] = t->r[r0 + i];
    }
    dense_solve(n, S, 6, SiXr);
    double G[5][5], g[5];
    for (int a = 0; a < 5; ++a) {
        g[a] = 0.0;
        for (int i = 0; i < n; ++i) g[a] += X[i][a] * SiXr[i][5];
        for (int b = 0; b < 5; ++b) {
            G[a][b] = 0.0;
            for (int i = 0; i < n; ++i) G[a][b] += X[i][a] * SiXr[i][b];
        }
    }
    double A[12][12], Y[12][6];
    memset(A, 0, sizeof A);
    memset(Y, 0, sizeof Y);
    for (int a = 0; a < 3; ++a) {
        for (int b = 0; b < 3; ++b) A[a][b] = G[a][b];
        Y[a][0] = G[a][3];
        Y[a][1] = G[a][4];
        Y[a][2] = g[a];
    }
    dense_solve(3, A, 3, Y);
    double I[2][2], sc[2];
    for (int a = 0; a < 2; ++a) {
        sc[a] = g[3 + a];
        for (int c = 0; c < 3; ++c) sc[a] -= G[3 + a][c] * Y[c][2];
        for (int b = 0; b < 2; ++b) {
            I[a][b] = G[3 + a][3 + b];
            for (int c = 0; c < 3; ++c) I[a][b] -= G[3 + a][c] * Y[c][b];
        }
    }
    info[0] = I[0][0];
    info[1] = 0.5 * (I[0][1] + I[1][0]);
    info[2] = I[1][1];
    score[0] = sc[0];
    score[1] = sc[1];
}

/* The largest relative difference of a motion fit from its dense reference (over info's and
 * score's scales), and the one-sided statistics along x and along y into the counts. */
static double motion_check(const sfd_window_motion_t *mo, int k0, int m) {
    double info[3], score[2];
    dense_motion(&g_ws.track, k0, m, info, score);
    const double si = sqrt(fabs(info[0] * info[2])) + 1e-300;
    double worst = 0.0;
    for (int c = 0; c < 3; ++c) {
        const double e = fabs(mo->info[c] - info[c]) / si;
        if (e > worst) worst = e;
    }
    const double score_scale[2] = {sqrt(fabs(info[0])), sqrt(fabs(info[2]))};
    for (int c = 0; c < 2; ++c) {
        const double e = fabs(mo->score[c] - score[c]) / score_scale[c];
        if (e > worst) worst = e;
    }
    /* z along (1, 0) and (0, 1): N(0, 1) on a clean track */
    const double zx = mo->score[0] / sqrt(mo->info[0]), zy = mo->score[1] / sqrt(mo->info[2]);
    g_tt.motion_z_alarms += (zx > 1.2815515655446004) + (zy > 1.2815515655446004);
    g_tt.motion_z_sum += zx + zy;
    g_tt.motion_z_tests += 2;
    return worst;
}

static void track_tests(const sfd_extrinsics_t *ext, int f, int64_t t0_us, int jump_track,
                        int jump_frame) {
    sfd_chi2_table_t chi2;
    assert_status(sfd_chi2_table_init(&chi2, 0.01), SFD_OK);
    for (int i = 0; i < NPTS; ++i) {
        if (!seen_since(i, f, 3)) continue;
        sfd_window_test_obs_t o;
        test_obs(i, 3, t0_us, f, &o);
        double gamma = 0.0;
        int32_t dof = 0;
        const sfd_status_t st = sfd_window_test_track(&g_w, ext, &o, &g_ws, &gamma, &dof);
        if (st == SFD_ERR_STATE || st == SFD_ERR_NUMERIC) continue; /* too few clones; geometry */
        assert_status(st, SFD_OK);
        assert_int_equal(dof, 3); /* 2 L - 3, no depth prior */
        if (i == jump_track) {
            if (f >= jump_frame && f < jump_frame + 4)
                g_tt.jump_alarm[f - jump_frame] = gamma > chi2.threshold[dof];
            continue;
        }
        {
            /* the same test with the motion's fit over its 3 frames */
            double gm[3] = {-1, -1, -1};
            int32_t dm[3] = {-1, -1, -1};
            sfd_window_motion_t mo;
            assert_status(sfd_window_test_track_motion(&g_w, ext, &o, 0, 0, &g_ws, gm, dm, &mo),
                          SFD_OK);
            g_tt.motion_differ += !(gm[0] == gamma && dm[0] == dof && gm[1] == 0.0 && dm[1] == 0 &&
                                    gm[2] == 0.0 && dm[2] == 0);
            /* without a fit (motion NULL): the same test */
            double gn[3] = {-1, -1, -1};
            int32_t dn[3] = {-1, -1, -1};
            assert_status(sfd_window_test_track_motion(&g_w, ext, &o, 0, 0, &g_ws, gn, dn, NULL),
                          SFD_OK);
            g_tt.motion_differ += !(gn[0] == gamma && dn[0] == dof);
            if (mo.ok) {
                g_tt.motion_fits++;
                const double e = motion_check(&mo, 0, 3);
                if (e > g_tt.motion_worst) g_tt.motion_worst = e;
            }
        }
        if (seen_since(i, f, 5)) {
            sfd_window_test_obs_t o5;
            test_obs(i, 5, t0_us, f, &o5);
            double g2[2] = {0, 0}, g5 = 0.0;
            int32_t d2[2] = {0, 0}, d5 = 0;
            const sfd_status_t sn = sfd_window_test_track_nested(&g_w, ext, &o5, 3, &g_ws, g2, d2);
            const sfd_status_t s5 = sfd_window_test_track(&g_w, ext, &o5, &g_ws, &g5, &d5);
            assert_status(sn, s5); /* one linearization: the same outcome */
            double g3[3] = {0, 0, 0};
            int32_t d3[3] = {0, 0, 0};
            const sfd_status_t se =
                sfd_window_test_track_evidence(&g_w, ext, &o5, 3, &g_ws, g3, d3);
            assert_status(se, sn);
            {
                /* the same tests with the motion's fit over the inner 3 frames */
                double gm[3] = {-1, -1, -1};
                int32_t dm[3] = {-1, -1, -1};
                sfd_window_motion_t mo;
                const sfd_status_t sm =
                    sfd_window_test_track_motion(&g_w, ext, &o5, 3, 1, &g_ws, gm, dm, &mo);
                assert_status(sm, se);
                if (sm == SFD_OK) {
                    g_tt.motion_differ += !(gm[0] == g3[0] && gm[1] == g3[1] && gm[2] == g3[2] &&
                                            dm[0] == d3[0] && dm[1] == d3[1] && dm[2] == d3[2]);
                    if (mo.ok) {
                        g_tt.motion_fits++;
                        const double e = motion_check(&mo, 2, 5);
                        if (e > g_tt.motion_worst) g_tt.motion_worst = e;
                    }
                }
            }
            if (se == SFD_OK) {
                g_tt.ev_differ +=
                    !(g3[0] == g2[0] && g3[1] == g2[1] && d3[0] == d2[0] && d3[1] == d2[1]);
                if (d3[2] == 2) {
                    assert_int_equal(g_ws.track.rows, 10); /* 5 frames, no depth prior */
                    const double ref = dense_ramp_glr(&g_ws.track, 5);
                    const double rel = fabs(g3[2] - ref) / (1.0 + g3[2]);
                    if (rel > g_tt.ramp_worst) g_tt.ramp_worst = rel;
                    g_tt.ramp_tests++;
                    g_tt.ramp_alarms += g3[2] > -2.0 * log(0.01); /* chi2(2) upper 1 % */
                    g_tt.ramp_sum += g3[2];
                } else {
                    assert_int_equal(d3[2], 0);
                    assert_true(g3[2] == 0.0);
                }
            }
            if (sn == SFD_OK) {
                assert_int_equal(d2[0], 3);
                assert_int_equal(d2[1], 7);
                g_tt.nested++;
                g_tt.nested_alarms += g2[0] > chi2.threshold[3];
                g_tt.nested_disagree += (g2[0] > chi2.threshold[3]) != (gamma > chi2.threshold[3]);
                g_tt.nested_outer_differ += !(g2[1] == g5 && d2[1] == d5);
                const double rel = fabs(g2[0] - gamma) / (1.0 + gamma);
                if (rel > g_tt.nested_worst) g_tt.nested_worst = rel;
            }
        }
        g_tt.tests++;
        g_tt.alarms += gamma > chi2.threshold[dof];
        g_tt.sum_ratio += gamma / dof;
    }
}

static void run_flight_from(uint64_t seed, double seconds, int jac, int jump_track, int jump_frame,
                            int at_rest, run_result_t *out) {
    g_rest_s = at_rest ? 1.0 : 0.0;
    const int rest_samples = at_rest ? 200 : 0;
    sfd_prng_t rng;
    sfd_prng_seed(&rng, seed);
    scene(&rng);
    sfd_extrinsics_t ext;
    extrinsics(&ext);
    sfd_window_params_t prm;
    assert_status(sfd_window_params_default(&prm), SFD_OK);
    prm.first_estimates = jac == JAC_FIRST_ESTIMATES;
    prm.observability_constrained = jac == JAC_OBSERVABILITY;
    for (int i = 0; i < SFD_WINDOW_IMU_DIM; ++i) prm.p0_diag[i] *= g_p0_scale;
    prm.use_depth_prior = g_depth_priors;
    prm.keyframe_parallax_rad = g_keyframe_rad;
    prm.keyframe_recent = 2;
    assert_status(sfd_window_init(&g_w, &prm), SFD_OK);
    /* Initial state drawn from P0 around the truth; true biases drawn from P0 too. */
    pose_t x0;
    truth(0.0, &x0);
    double p[3], v[3], q[4], bg[3] = {0, 0, 0}, ba[3] = {0, 0, 0}, bg_true[3], ba_true[3];
    double dth[3], dR[9], R0[9];
    for (int k = 0; k < 3; ++k) {
        p[k] = x0.p[k] + sqrt(prm.p0_diag[SFD_WINDOW_IDX_P + k]) * sfd_prng_gaussian(&rng);
        v[k] = x0.v[k] + sqrt(prm.p0_diag[SFD_WINDOW_IDX_V + k]) * sfd_prng_gaussian(&rng);
        dth[k] = sqrt(prm.p0_diag[SFD_WINDOW_IDX_THETA + k]) * sfd_prng_gaussian(&rng);
        bg_true[k] = 0.01 + sqrt(prm.p0_diag[SFD_WINDOW_IDX_BG + k]) * sfd_prng_gaussian(&rng);
        bg[k] = 0.01;
        ba_true[k] = sqrt(prm.p0_diag[SFD_WINDOW_IDX_BA + k]) * sfd_prng_gaussian(&rng);
    }
    sfd_so3_exp(dth, dR);
    mat_mul(dR, x0.R, R0); /* global error: R^ = Exp(-dtheta) R, drawn symmetric */
    sfd_rotmat_to_quat(R0, q);
    const sfd_ekf_noise_t *nz = &prm.noise;
    if (!at_rest) {
        assert_status(sfd_window_start_at(&g_w, 0, p, v, q, bg, ba), SFD_OK);
    } else { /* the rest second: white noise and biases on gravity, then the start */
        double mg[3] = {0, 0, 0}, ma[3] = {0, 0, 0};
        for (int i = 0; i < rest_samples; ++i) {
            for (int k = 0; k < 3; ++k) {
                mg[k] +=
                    bg_true[k] + nz->gyro_noise_rad_s_rthz / sqrt(kDt) * sfd_prng_gaussian(&rng);
                ma[k] += (k == 2 ? nz->gravity_m_s2 : 0.0) + ba_true[k] +
                         nz->accel_noise_m_s2_rthz / sqrt(kDt) * sfd_prng_gaussian(&rng);
            }
        }
        for (int k = 0; k < 3; ++k) {
            mg[k] /= rest_samples;
            ma[k] /= rest_samples;
        }
        assert_status(sfd_window_start_at_rest(&g_w, 1000000, ma, mg), SFD_OK);
    }
    g_w.next_seq = g_seq_start;
    const int frames = (int)(seconds * 20.0 + 0.5);
    sfd_window_obs_t obs[SFD_WINDOW_MAX_TRACKS];
    sfd_window_result_t res;
    memset(out, 0, sizeof *out);
    g_phi_violation = 0.0;
    g_h_violation = 0.0;
    g_h_checked = 0;
    for (int f = 1; f <= frames; ++f) {
        double fe_p0[3], fe_v0[3];
        memcpy(fe_p0, g_w.fe_p_IinW_m, sizeof fe_p0);
        memcpy(fe_v0, g_w.fe_v_IinW_m_s, sizeof fe_v0);
        for (int s = 0; s < IMU_PER_FRAME; ++s) {
            const int i = rest_samples + (f - 1) * IMU_PER_FRAME + s;
            pose_t a, b;
            truth(i * kDt, &a);
            truth((i + 1) * kDt, &b);
            /* gyro: R_b = R_a Exp(w dt) exactly; accel: v_b = v_a + (R_a f + g) dt exactly */
            double Rab[9], w[3], acc[3], dv[3];
            mat_tmul(a.R, b.R, Rab);
            sfd_so3_log(Rab, w);
            for (int k = 0; k < 3; ++k) {
                w[k] /= kDt;
                dv[k] = (b.v[k] - a.v[k]) / kDt + (k == 2 ? nz->gravity_m_s2 : 0.0);
            }
            for (int k = 0; k < 3; ++k) {
                acc[k] = 0.0;
                for (int j = 0; j < 3; ++j) acc[k] += a.R[3 * j + k] * dv[j];
            }
            double gm[3], am[3];
            for (int k = 0; k < 3; ++k) {
                gm[k] = w[k] + bg_true[k] +
                        nz->gyro_noise_rad_s_rthz / sqrt(kDt) * sfd_prng_gaussian(&rng);
                am[k] = acc[k] + ba_true[k] +
                        nz->accel_noise_m_s2_rthz / sqrt(kDt) * sfd_prng_gaussian(&rng);
                bg_true[k] += nz->gyro_bias_rw_rad_s2_rthz * sqrt(kDt) * sfd_prng_gaussian(&rng);
                ba_true[k] += nz->accel_bias_rw_m_s3_rthz * sqrt(kDt) * sfd_prng_gaussian(&rng);
            }
            assert_status(sfd_window_propagate(&g_w, gm, am, kDt), SFD_OK);
        }
        pose_t x;
        truth((rest_samples + f * IMU_PER_FRAME) * kDt, &x);
        int n = 0;
        for (int i = 0; i < NPTS && n < SFD_WINDOW_MAX_TRACKS; ++i) {
            double xn[2];
            if (!observe(&x, &ext, g_pts[i], xn)) continue;
            if (i == jump_track && f >= jump_frame) xn[0] += 0.05; /* 20 px: another point */
            memset(&obs[n], 0, sizeof obs[n]);
            obs[n].track_id = 1000 + i;
            const double g1 = sfd_prng_gaussian(&rng);
            const double g2 = sfd_prng_gaussian(&rng);
            if (g_aniso) { /* cov = s^2 [1 1.8; 1.8 4] = L L^T, L = s [1 0; 1.8 sqrt(0.76)] */
                obs[n].xn[0] = xn[0] + kSigmaXn * g1;
                obs[n].xn[1] = xn[1] + kSigmaXn * (1.8 * g1 + sqrt(0.76) * g2);
                obs[n].cov_xn[0] = kSigmaXn * kSigmaXn;
                obs[n].cov_xn[1] = 1.8 * kSigmaXn * kSigmaXn;
                obs[n].cov_xn[2] = 4.0 * kSigmaXn * kSigmaXn;
            } else {
                obs[n].xn[0] = xn[0] + kSigmaXn * g1;
                obs[n].xn[1] = xn[1] + kSigmaXn * g2;
                obs[n].cov_xn[0] = obs[n].cov_xn[2] = kSigmaXn * kSigmaXn;
            }
            if (g_depth_priors > 0) {
                obs[n].depth_m = g_last_depth_m + g_depth_sd_m * sfd_prng_gaussian(&rng);
                obs[n].depth_var_m2 = g_depth_sd_m * g_depth_sd_m;
            }
            if (g_track_test) { /* history of what the filter was given */
                for (int k = 0; k + 1 < HIST; ++k) {
                    g_hist_frame[i][k] = g_hist_frame[i][k + 1];
                    memcpy(g_hist_xn[i][k], g_hist_xn[i][k + 1], sizeof g_hist_xn[i][k]);
                }
                g_hist_frame[i][HIST - 1] = f;
                memcpy(g_hist_xn[i][HIST - 1], obs[n].xn, sizeof obs[n].xn);
            }
            ++n;
        }
        if (g_track_test) {
            track_tests(&ext, f, (int64_t)rest_samples * 5000, jump_track, jump_frame);
        }
        sfd_window_clone_t clones[SFD_MAX_WINDOW];
        int num_clones = 0;
        if (g_null_check) {
            const double vp = phi_null_violation(&g_w, fe_p0, fe_v0);
            if (vp > g_phi_violation) g_phi_violation = vp;
            /* the clones of the frame's update: those held now and the one it adds */
            num_clones = g_w.num_clones;
            memcpy(clones, g_w.clones, sizeof(sfd_window_clone_t) * (size_t)num_clones);
            memcpy(clones[num_clones].fe_p_IinW_m, g_w.fe_p_IinW_m, sizeof g_w.fe_p_IinW_m);
            ++num_clones;
        }
        const sfd_window_obs_t *given = obs;
        if (g_obs_in_scratch) {
            memcpy(g_ws.u.obs, obs, sizeof obs[0] * (size_t)n);
            given = g_ws.u.obs;
        }
        assert_status(sfd_window_frame(&g_w, (int64_t)rest_samples * 5000 + (int64_t)f * 50000,
                                       given, n, &ext, &g_ws, &res),
                      SFD_OK);
        if (g_null_check && g_ws.track.rows >= 4) {
            g_projected = g_ws.track;
            if (sfd_msckf_track_project(&g_projected) == SFD_OK) {
                const double vh = h_null_violation(&g_w, clones, num_clones);
                if (vh > g_h_violation) g_h_violation = vh;
                ++g_h_checked;
            }
        }
        assert_status(res.update_status, SFD_OK);
        if (g_w.num_clones >= 2) {
            const int64_t span = g_w.clones[g_w.num_clones - 1].utime - g_w.clones[0].utime;
            if (span / 50000 > g_span_max_frames) g_span_max_frames = (int)(span / 50000);
            if (g_w.clones[g_w.num_clones - 1].utime - g_w.clones[g_w.num_clones - 2].utime !=
                50000) {
                g_recent_consecutive = 0;
            }
            int observed = 0;
            for (int32_t k = 0; k < g_w.num_tracks; ++k) {
                if (g_w.tracks[k].used > 0 && g_w.tracks[k].first_clone == g_w.clones[0].seq) {
                    observed = 1;
                }
            }
            if (!observed) ++g_oldest_unobserved;
        }
        out->gated += res.gated;
        out->used += res.used;
        for (int k = 0; k < res.num_gated_ids; ++k) {
            if (res.gated_ids[k] == 1000 + jump_track) out->frames = f; /* when it was refused */
        }
    }
    /* errors at the end: dp, dtheta (global: R = Exp(dtheta) R^) */
    pose_t x;
    truth((rest_samples + frames * IMU_PER_FRAME) * kDt, &x);
    if (at_rest) { /* the start defines the origin: the truth's position at tau = 0 */
        for (int k = 0; k < 3; ++k) x.p[k] -= x0.p[k];
    }
    double Rh[9], E[9], e[6];
    sfd_quat_to_rotmat(g_w.q_ItoW, Rh);
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
            E[3 * r + c] = 0.0;
            for (int k = 0; k < 3; ++k) E[3 * r + c] += x.R[3 * r + k] * Rh[3 * c + k];
        }
    }
    sfd_so3_log(E, e + 3);
    for (int k = 0; k < 3; ++k) e[k] = x.p[k] - g_w.p_IinW_m[k];
    out->pos_err_m = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
    out->att_err_rad = sqrt(e[3] * e[3] + e[4] * e[4] + e[5] * e[5]);
    /* NEES = e^T P^-1 e over (p, theta): Cholesky of the 6x6 block */
    double S[6][6];
    const int idx[6] = {0, 1, 2, 6, 7, 8};
    double pv[3];
    sfd_window_position_var(&g_w, pv); /* brings P up to date */
    for (int r = 0; r < 6; ++r) {
        for (int c = 0; c < 6; ++c) S[r][c] = g_w.P[idx[r]][idx[c]];
    }
    double L[6][6] = {{0}};
    for (int j = 0; j < 6; ++j) {
        double d = S[j][j];
        for (int k = 0; k < j; ++k) d -= L[j][k] * L[j][k];
        assert_true(d > 0.0);
        L[j][j] = sqrt(d);
        for (int i = j + 1; i < 6; ++i) {
            double s = S[i][j];
            for (int k = 0; k < j; ++k) s -= L[i][k] * L[j][k];
            L[i][j] = s / L[j][j];
        }
    }
    double y[6] = {0}, nees = 0.0, nees3 = 0.0;
    for (int i = 0; i < 6; ++i) {
        double s = e[i];
        for (int k = 0; k < i; ++k) s -= L[i][k] * y[k];
        y[i] = s / L[i][i];
        nees += y[i] * y[i];
        if (i == 2) nees3 = nees;
    }
    out->nees_pose = nees;
    out->nees_pos = nees3;
    g_rest_s = 0.0;
}

static void flight_stays_close_to_the_truth(void **state) {
    (void)state;
    run_result_t r;
    run_flight(1, 20.0, JAC_OBSERVABILITY, -1, 0, &r);
    printf("  20 s, 25 m: position error %.3f m, tracks used %d, gated %d\n", r.pos_err_m, r.used,
           r.gated);
    assert_true(r.pos_err_m < 0.5); /* 2 % of the 25 m flown (measured 0.31 m) */
    assert_true(r.used > 1000);
    /* consistent tracks gated at about alpha = 1 % */
    assert_true(r.gated < 0.04 * (r.used + r.gated));
}

typedef struct {
    double nees_pos, nees_att; /* means over the runs */
    double pos_err_m, att_err_rad;
    long gated, used; /* tracks over the runs */
} monte_carlo_t;

/* RUNS runs of 30 s (seeds seed0 + k), under way or from a start at rest, with Jacobians jac. */
enum { RUNS = 20 };
static void monte_carlo(uint64_t seed0, int at_rest, int jac, monte_carlo_t *mc) {
    memset(mc, 0, sizeof *mc);
    for (int k = 0; k < RUNS; ++k) {
        run_result_t r;
        run_flight_from(seed0 + (uint64_t)k, 30.0, jac, -1, 0, at_rest, &r);
        mc->nees_pos += r.nees_pos / RUNS;
        mc->nees_att += (r.nees_pose - r.nees_pos) / RUNS;
        mc->pos_err_m += r.pos_err_m / RUNS;
        mc->att_err_rad += r.att_err_rad / RUNS;
        mc->gated += r.gated;
        mc->used += r.used;
    }
}

/* The 95 % band of the mean NEES of a 3-dof block over RUNS runs: chi2(3 RUNS) / RUNS. */
static void nees_band(double *lo, double *hi) {
    assert_status(sfd_chi2_quantile_upper(0.975, 3 * RUNS, lo), SFD_OK);
    assert_status(sfd_chi2_quantile_upper(0.025, 3 * RUNS, hi), SFD_OK);
    *lo /= RUNS;
    *hi /= RUNS;
}

/* The sum over RUNS runs of the position NEES at the end is chi2(3 RUNS) for a consistent
 * filter, the attitude's too. Every Jacobian choice is printed; the default (observability
 * constraint) must be inside the 95 % band for both, and its mean errors no worse than the
 * current-estimate Jacobians': position within 5 %, attitude within 10 % (its error is mostly yaw,
 * a random walk: on these seeds +5 % under way and +3 % from rest, but over 60 other seeds
 * -0.4 % +- 1.1 % under way and +0.8 % +- 2.2 % from rest, paired; core/docs/window_filter.md). */
static void nees_check(uint64_t seed0, int at_rest) {
    double lo = 0.0, hi = 0.0;
    nees_band(&lo, &hi);
    monte_carlo_t mc[3];
    for (int jac = 0; jac < 3; ++jac) {
        monte_carlo(seed0, at_rest, jac, &mc[jac]);
        printf(
            "  %s%s, %s Jacobians: NEES position %.2f, attitude %.2f (band %.2f..%.2f); mean "
            "errors %.3f m, %.2f mrad\n",
            at_rest ? "from rest" : "under way", g_p0_scale > 1.0 ? " (P0 x 10)" : "",
            kJacName[jac], mc[jac].nees_pos, mc[jac].nees_att, lo, hi, mc[jac].pos_err_m,
            1e3 * mc[jac].att_err_rad);
    }
    const monte_carlo_t *oc = &mc[JAC_OBSERVABILITY];
    assert_true(oc->nees_pos >= lo && oc->nees_pos <= hi);
    assert_true(oc->nees_att >= lo && oc->nees_att <= hi);
    assert_true(oc->pos_err_m < 0.6); /* 2 % of the ~28 m flown */
    assert_true(oc->pos_err_m <= 1.05 * mc[JAC_CURRENT].pos_err_m);
    assert_true(oc->att_err_rad <= 1.10 * mc[JAC_CURRENT].att_err_rad);
}

/* A flight under way, the filter started at the truth with errors drawn from P0. */
static void pose_nees_is_inside_its_chi_square_band(void **state) {
    (void)state;
    SFD_REQ("issue16.nees_band");
    nees_check(100, 0);
}

/* Larger start-up errors (P0 times 10: roll and pitch 32 mrad, velocity 3 cm/s, accelerometer
 * bias 0.2 m/s^2), from rest: the first corrections are then large, and first-estimate Jacobians
 * keep linearizing at the estimates from before them (the weakness FEJ2 addresses: Chen, Geneva,
 * Huang, ICRA 2022). The default must stay in its band. (Measured: first estimates 186.9 / 99.7,
 * 2.8 m; core/docs/window_filter.md.) */
static void pose_nees_with_ten_times_the_initial_uncertainty(void **state) {
    (void)state;
    SFD_REQ("issue16.nees_band");
    g_p0_scale = 10.0;
    nees_check(200, 1);
    g_p0_scale = 1.0;
}

/* The product's start: 1 s at rest, sfd_window_start_at_rest, then the flight. */
static void pose_nees_from_a_start_at_rest(void **state) {
    (void)state;
    SFD_REQ("issue16.nees_band");
    nees_check(200, 1);
}

/* Keyframes (core/docs/window_filter.md "Keyframes"): with keyframe_parallax_rad = 0.02 (8 px
 * here; the flight moves about 0.013 per frame at these depths) the clone before the newest two
 * leaves while it moved less than that from the one before it, so the 4 clones held after a frame
 * span more than 3 frame intervals while the newest two stay consecutive (the parity test's
 * frames).
 * Deleting a middle clone is an exact marginalization and its observations are dropped unused,
 * so the filter must stay consistent: the 20-run NEES inside its 95 % band, and the flight
 * within 2 % of the distance. Without keyframes the 4 clones span exactly 3 intervals. The oldest
 * clone keeps its tracks while it stays (they are used when it leaves, not when the window
 * fills: otherwise it would sit in the window with no observation), so after every frame some
 * track starts in it, with keyframes and without. */
static void keyframes_span_more_motion_and_stay_consistent(void **state) {
    (void)state;
    SFD_REQ("issue16.nees_band");
    run_result_t r;
    g_span_max_frames = 0;
    g_recent_consecutive = 1;
    g_oldest_unobserved = 0;
    run_flight(1, 20.0, JAC_OBSERVABILITY, -1, 0, &r);
    assert_int_equal(g_span_max_frames, 3);
    assert_int_equal(g_recent_consecutive, 1);
    printf("  without keyframes: frames with an unobserved oldest clone %d of 400\n",
           g_oldest_unobserved);
    g_keyframe_rad = 0.02;
    g_span_max_frames = 0;
    g_oldest_unobserved = 0;
    double lo = 0.0, hi = 0.0;
    nees_band(&lo, &hi);
    monte_carlo_t mc;
    monte_carlo(100, 0, JAC_OBSERVABILITY, &mc);
    g_keyframe_rad = 0.0;
    const double gated = (double)mc.gated / (double)(mc.gated + mc.used);
    printf(
        "  keyframes at 0.02: window span up to %d frames; NEES position %.2f, attitude %.2f "
        "(band %.2f..%.2f); mean errors %.3f m, %.2f mrad; gated %.4f of %ld tracks; frames "
        "with an unobserved oldest clone %d\n",
        g_span_max_frames, mc.nees_pos, mc.nees_att, lo, hi, mc.pos_err_m, 1e3 * mc.att_err_rad,
        gated, mc.gated + mc.used, g_oldest_unobserved);
    assert_true(g_span_max_frames > 3);
    assert_int_equal(g_recent_consecutive, 1);
    /* 38 of the 12 000 frames (1 of 400 without keyframes); with the oldest clone's tracks
     * used when the window fills although it stays, 5 968 */
    assert_true(g_oldest_unobserved < 120);
    assert_true(mc.nees_pos >= lo && mc.nees_pos <= hi);
    assert_true(mc.nees_att >= lo && mc.nees_att <= hi);
    /* Measured 0.236 m (0.273 m without keyframes, same seeds); observations left one clone
     * off after a middle clone leaves gave 0.853 m (90 % gated), the wrong rows of P deleted
     * NEES 6.1 / 15.4; the gate's rate must stay near its alpha = 1 %. */
    assert_true(mc.pos_err_m < 0.35);
    assert_true(gated < 0.02);
}

/* Depth priors (core/docs/window_filter.md "Depth priors"): every observation carries its depth
 * (true camera z + N(0, 0.02^2) m, independent between frames, at 1-12 m). With 1 the track's
 * first depth is a measurement, with 2 its newest too (a row at the newest clone). Both must stay
 * consistent over 20 runs (NEES inside the 95 % band, the gate near its 1 %), and 2, which adds
 * independent information, must leave a smaller mean position error than 1 (measured 0.1201 m
 * against 0.1218 m: in this scene the error at the end is mostly the unobservable drift, which no
 * depth removes; the flights of docs/evaluation.md show the gain). The newest depth's row put at
 * the first clone instead gave a mean error of 41 m with 62 % of the tracks gated. */
static void the_newest_depth_prior_is_a_second_measurement(void **state) {
    (void)state;
    SFD_REQ("issue16.nees_band");
    double lo = 0.0, hi = 0.0;
    nees_band(&lo, &hi);
    monte_carlo_t mc[2];
    g_depth_sd_m = 0.02;
    for (int k = 0; k < 2; ++k) {
        g_depth_priors = 1 + k;
        monte_carlo(300, 0, JAC_OBSERVABILITY, &mc[k]);
        printf(
            "  depth priors %d: NEES position %.2f, attitude %.2f (band %.2f..%.2f); mean "
            "errors %.4f m, %.2f mrad; gated %.4f\n",
            1 + k, mc[k].nees_pos, mc[k].nees_att, lo, hi, mc[k].pos_err_m, 1e3 * mc[k].att_err_rad,
            (double)mc[k].gated / (double)(mc[k].gated + mc[k].used));
    }
    g_depth_priors = 0;
    g_depth_sd_m = 0.0;
    for (int k = 0; k < 2; ++k) {
        assert_true(mc[k].nees_pos >= lo && mc[k].nees_pos <= hi);
        assert_true(mc[k].nees_att >= lo && mc[k].nees_att <= hi);
        assert_true((double)mc[k].gated / (double)(mc[k].gated + mc[k].used) < 0.02);
    }
    assert_true(mc[1].pos_err_m < mc[0].pos_err_m);
}

/* Pixel noise correlated and anisotropic (covariance s^2 [1 1.8; 1.8 4], as the distortion
 * Jacobian gives at an image edge; noise drawn from it), with both depth rows: the filter whitens
 * each observation's rows by its covariance's Cholesky factor and each depth row by its deviation
 * before gating and folding (core/docs/msckf.md "Fold without projecting"). It must stay
 * consistent over 20 runs (NEES inside the 95 % band) with the gate near its 1 % (measured
 * 0.0085 of 64 454 tracks). A whitening that dropped the correlation (l10 = 0) gated 0.0301. */
static void correlated_anisotropic_pixel_noise_is_whitened(void **state) {
    (void)state;
    SFD_REQ("issue16.nees_band");
    double lo = 0.0, hi = 0.0;
    nees_band(&lo, &hi);
    monte_carlo_t mc;
    g_aniso = 1;
    g_depth_priors = 2;
    g_depth_sd_m = 0.02;
    monte_carlo(500, 0, JAC_OBSERVABILITY, &mc);
    g_aniso = 0;
    g_depth_priors = 0;
    g_depth_sd_m = 0.0;
    const double gated = (double)mc.gated / (double)(mc.gated + mc.used);
    printf(
        "  correlated anisotropic pixel noise: NEES position %.2f, attitude %.2f (band "
        "%.2f..%.2f); mean errors %.4f m, %.2f mrad; gated %.4f of %ld tracks\n",
        mc.nees_pos, mc.nees_att, lo, hi, mc.pos_err_m, 1e3 * mc.att_err_rad, gated,
        mc.gated + mc.used);
    assert_true(mc.nees_pos >= lo && mc.nees_pos <= hi);
    assert_true(mc.nees_att >= lo && mc.nees_att <= hi);
    assert_true(gated < 0.015);
}

/* A track whose first observation carries no depth prior (the wire gave none, or with keyframes
 * the observation left with its clone) starts its triangulation from its newest observation's
 * prior (core/src/window_filter.cpp triangulate): with a hovering camera the rays are parallel,
 * and a track that started from them would be refused for lack of geometry although the newest
 * prior places its point. Without any prior the same tracks are refused. */
static void a_track_without_its_first_prior_starts_from_its_newest(void **state) {
    (void)state;
    enum { kTracks = 20, kFrames = 4 };
    sfd_extrinsics_t ext;
    extrinsics(&ext);
    for (int with_prior = 0; with_prior < 2; ++with_prior) {
        sfd_window_params_t prm;
        assert_status(sfd_window_params_default(&prm), SFD_OK);
        assert_int_equal(prm.use_depth_prior, 2);
        assert_status(sfd_window_init(&g_w, &prm), SFD_OK);
        const double z[3] = {0, 0, 0}, q[4] = {1, 0, 0, 0};
        assert_status(sfd_window_start_at(&g_w, 0, z, z, q, z, z), SFD_OK);
        sfd_window_obs_t obs[kTracks];
        sfd_window_result_t res;
        for (int f = 1; f <= kFrames + 1; ++f) {
            memset(obs, 0, sizeof obs);
            for (int i = 0; i < kTracks; ++i) {
                obs[i].track_id = 100 + i;
                obs[i].xn[0] = 0.01 * (double)(i - 10); /* -0.1 .. 0.09 */
                obs[i].xn[1] = -0.005 * i;
                obs[i].cov_xn[0] = obs[i].cov_xn[2] = kSigmaXn * kSigmaXn;
                /* the point at 4 m depth, a prior from the second observation on */
                obs[i].depth_m = (with_prior && f > 1) ? 4.0 : 0.0;
                obs[i].depth_var_m2 = (with_prior && f > 1) ? 0.01 : 0.0;
            }
            /* the last frame sees none: every track ends with kFrames observations */
            const int n = f <= kFrames ? kTracks : 0;
            assert_status(sfd_window_frame(&g_w, (int64_t)50000 * f, obs, n, &ext, &g_ws, &res),
                          SFD_OK);
        }
        assert_int_equal(res.candidates, kTracks);
        assert_int_equal(res.update_status, SFD_OK);
        if (with_prior) {
            assert_int_equal(res.used, kTracks);
            assert_int_equal(res.no_geometry, 0);
        } else {
            assert_int_equal(res.used, 0);
            assert_int_equal(res.no_geometry, kTracks);
        }
        for (int k = 0; k < 3; ++k) assert_true(isfinite(g_w.p_IinW_m[k]));
    }
}

/* A flagged observation (drop 1) ends its track: the observations before it are due in that
 * frame and pass through the gate like any ended track's, then the track is deleted; drop 2
 * deletes them unused; with flagged_earlier 0 drop 1 does too (core/docs/window_filter.md
 * "Flagged tracks"). A hovering camera with depth priors: every clean track is usable. Tracks
 * 0-4 are flagged with drop 1, 5-9 with drop 2, 10-14 seen again, 15 jumped 20 px in its third
 * frame and flagged with drop 1 in its fourth (its earlier observations disagree: gated), and a
 * duplicate of track 0 after its flag is refused. */
static void a_flagged_observation_ends_its_track(void **state) {
    (void)state;
    enum { kTracks = 16 };
    sfd_extrinsics_t ext;
    extrinsics(&ext);
    for (int earlier = 1; earlier >= 0; --earlier) {
        sfd_window_params_t prm;
        assert_status(sfd_window_params_default(&prm), SFD_OK);
        assert_int_equal(prm.flagged_earlier, 1);
        prm.flagged_earlier = earlier;
        assert_status(sfd_window_init(&g_w, &prm), SFD_OK);
        const double z[3] = {0, 0, 0}, q[4] = {1, 0, 0, 0};
        assert_status(sfd_window_start_at(&g_w, 0, z, z, q, z, z), SFD_OK);
        sfd_window_obs_t obs[kTracks + 1];
        sfd_window_result_t res;
        for (int f = 1; f <= 4; ++f) {
            memset(obs, 0, sizeof obs);
            for (int i = 0; i < kTracks; ++i) {
                obs[i].track_id = 100 + i;
                obs[i].xn[0] = 0.01 * (double)(i - 8);
                obs[i].xn[1] = 0.004 * (double)i;
                if (i == 15 && f >= 3) obs[i].xn[0] += 0.05; /* 20 px: another point */
                obs[i].cov_xn[0] = obs[i].cov_xn[2] = kSigmaXn * kSigmaXn;
                obs[i].depth_m = 4.0;
                obs[i].depth_var_m2 = 0.01;
                if (f == 4 && (i < 5 || i == 15)) obs[i].drop = 1;
                if (f == 4 && i >= 5 && i < 10) obs[i].drop = 2;
            }
            int n = kTracks;
            if (f == 4) { /* track 0 again, unflagged */
                obs[n] = obs[0];
                obs[n].drop = 0;
                ++n;
            }
            assert_status(sfd_window_frame(&g_w, (int64_t)50000 * f, obs, n, &ext, &g_ws, &res),
                          SFD_OK);
            if (f < 4) assert_int_equal(res.candidates, 0);
        }
        assert_int_equal(res.dropped, 11);
        assert_int_equal(res.overflow, 1); /* the duplicate of flagged track 0 */
        assert_int_equal(res.update_status, SFD_OK);
        if (earlier) {
            assert_int_equal(res.candidates, 6); /* tracks 0-4 and 15, 3 observations each */
            assert_int_equal(res.used, 5);
            assert_int_equal(res.gated, 1);
            assert_int_equal(res.num_gated_ids, 1);
            assert_int_equal(res.gated_ids[0], 115);
        } else {
            assert_int_equal(res.candidates, 0);
            assert_int_equal(res.used, 0);
        }
        /* every flagged track is gone; 10-14 go on */
        assert_int_equal(g_w.num_tracks, 5);
        for (int k = 0; k < g_w.num_tracks; ++k) {
            assert_true(g_w.tracks[k].id >= 110 && g_w.tracks[k].id <= 114);
            assert_int_equal(g_w.tracks[k].used, 4);
        }
    }
}

/* Clone sequence numbers are compared modulo 2^32 (core/src/window_filter.cpp seq_offset): a
 * flight whose numbers wrap past UINT32_MAX, with keyframes deleting middle clones (which
 * renumbers the later clones and tracks), must give a bit-identical filter to the same flight
 * numbered from 0. Compared as plain integers, a track whose first clone is numbered just below
 * the wrap would be read as starting after every later clone. */
static void sequence_numbers_wrap_without_changing_the_filter(void **state) {
    (void)state;
    static double P0[SFD_MSCKF_DIM][SFD_MSCKF_DIM];
    double p0[3], q0[4];
    run_result_t r;
    g_keyframe_rad = 0.02;
    g_span_max_frames = 0;
    g_seq_start = 0;
    run_flight(3, 5.0, JAC_OBSERVABILITY, -1, 0, &r);
    assert_true(g_span_max_frames > 3); /* middle clones left */
    const uint32_t clones_made = g_w.next_seq;
    memcpy(P0, g_w.P, sizeof P0);
    memcpy(p0, g_w.p_IinW_m, sizeof p0);
    memcpy(q0, g_w.q_ItoW, sizeof q0);
    g_seq_start = UINT32_MAX - 40u;
    run_flight(3, 5.0, JAC_OBSERVABILITY, -1, 0, &r);
    g_seq_start = 0;
    g_keyframe_rad = 0.0;
    printf("  %lu clone numbers from 0 and from UINT32_MAX - 40 (now %lu)\n",
           (unsigned long)clones_made, (unsigned long)g_w.next_seq);
    assert_true(g_w.next_seq == clones_made - 41u); /* wrapped */
    assert_memory_equal(p0, g_w.p_IinW_m, sizeof p0);
    assert_memory_equal(q0, g_w.q_ItoW, sizeof q0);
    assert_memory_equal(P0, g_w.P, sizeof P0);
}

/* The unobservable directions at the first estimates (translation; yaw about gravity) against
 * the linearized system of a 10 s flight from rest: the accumulated transition of every frame
 * interval must map them onto themselves (Phi N_k = N_k+1) and every projected track's Jacobian
 * must annihilate them (H N = 0), to rounding, with the observability constraint and with first
 * estimates. The current-estimate Jacobians must violate it (the check can fail). */
static void unobservable_directions_stay_unobservable(void **state) {
    (void)state;
    SFD_REQ("issue16.consistency");
    double phi[3], h[3];
    for (int jac = 0; jac < 3; ++jac) {
        run_result_t r;
        g_null_check = 1;
        run_flight_from(300, 10.0, jac, -1, 0, 1, &r);
        g_null_check = 0;
        phi[jac] = g_phi_violation;
        h[jac] = g_h_violation;
        printf(
            "  %s Jacobians: |Phi N_k - N_k+1| / |N| <= %.2e, |H N| / (|H| |N|) <= %.2e "
            "(%d tracks)\n",
            kJacName[jac], phi[jac], h[jac], g_h_checked);
        assert_true(g_h_checked > 100);
    }
    assert_true(phi[JAC_OBSERVABILITY] < 1e-9 && h[JAC_OBSERVABILITY] < 1e-9);
    assert_true(phi[JAC_FIRST_ESTIMATES] < 1e-9 && h[JAC_FIRST_ESTIMATES] < 1e-9);
    assert_true(phi[JAC_CURRENT] > 1e-6 && h[JAC_CURRENT] > 1e-6);
}

static void a_jumped_track_is_gated_and_does_not_pull(void **state) {
    (void)state;
    SFD_REQ("issue16.stale_landmark");
    run_result_t clean, jumped;
    /* the first visible point at frame 40 jumps then; find one that is visible */
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 7);
    scene(&rng);
    sfd_extrinsics_t ext;
    extrinsics(&ext);
    pose_t x;
    truth(40 * IMU_PER_FRAME * kDt, &x);
    int track = -1;
    for (int i = 0; i < NPTS && track < 0; ++i) {
        double xn[2];
        pose_t xp;
        truth(38 * IMU_PER_FRAME * kDt, &xp);
        if (observe(&x, &ext, g_pts[i], xn) && observe(&xp, &ext, g_pts[i], xn)) track = i;
    }
    assert_true(track >= 0);
    run_flight(7, 4.0, JAC_OBSERVABILITY, -1, 0, &clean);
    run_flight(7, 4.0, JAC_OBSERVABILITY, track, 40, &jumped);
    printf("  jump at frame 40 gated at frame %d; error %.3f m (clean %.3f m)\n", jumped.frames,
           jumped.pos_err_m, clean.pos_err_m);
    assert_true(jumped.frames >= 40 && jumped.frames <= 40 + SFD_MAX_WINDOW);
    assert_true(jumped.pos_err_m < clean.pos_err_m + 0.02);
}

/* GIVEN the filter under way WHEN each point seen in the last three frames is tested with
 * sfd_window_test_track (the parity test with the filter's translation and covariance) THEN its
 * statistic is chi2(3): the alarm rate at alpha = 0.01 is inside the 99 % binomial interval
 * (counted with a third of the tests as independent, since consecutive windows share two of
 * their three frames), the mean of gamma / dof is 1 within 5 %; and a track that jumps by 20 px
 * is flagged in the two windows that straddle the jump, not in the one after. AND the nested test
 * over five frames (sfd_window_test_track_nested, inner 3): its 5-frame statistic is
 * sfd_window_test_track's bit for bit, its inner statistic within 5 % of the 3-frame test's (one
 * linearization at the 5-frame point instead of the 3-frame one: a second-order difference), its
 * alarms the same in at least 99 % of the tests and its alarm rate inside the same interval. */
static void the_track_test_with_the_filters_covariance_is_calibrated(void **state) {
    (void)state;
    memset(&g_tt, 0, sizeof g_tt);
    for (int i = 0; i < NPTS; ++i) {
        for (int k = 0; k < HIST; ++k) g_hist_frame[i][k] = -10;
    }
    /* a point seen at frames 118..121 jumps at 120 */
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 11);
    scene(&rng);
    sfd_extrinsics_t ext;
    extrinsics(&ext);
    int track = -1;
    for (int i = 0; i < NPTS && track < 0; ++i) {
        int seen = 1;
        for (int f = 117; f <= 123; ++f) {
            pose_t x;
            double xn[2];
            truth(f * IMU_PER_FRAME * kDt, &x);
            seen = seen && observe(&x, &ext, g_pts[i], xn);
        }
        if (seen) track = i;
    }
    assert_true(track >= 0);
    g_track_test = 1;
    run_result_t r;
    run_flight(11, 20.0, JAC_OBSERVABILITY, track, 120, &r);
    g_track_test = 0;
    const double alpha = 0.01, rate = (double)g_tt.alarms / (double)g_tt.tests;
    const double n_eff = (double)g_tt.tests / 3.0;
    const double half = 2.576 * sqrt(alpha * (1.0 - alpha) / n_eff);
    const double mean_ratio = g_tt.sum_ratio / (double)g_tt.tests;
    printf(
        "  %ld tests of clean tracks: alarm rate %.4f (alpha %.2f, 99%% interval +-%.4f), "
        "mean gamma/dof %.3f; jump at 120 flagged at 120..123: %d %d %d %d\n",
        g_tt.tests, rate, alpha, half, mean_ratio, g_tt.jump_alarm[0], g_tt.jump_alarm[1],
        g_tt.jump_alarm[2], g_tt.jump_alarm[3]);
    assert_true(g_tt.tests > 8000);
    assert_true(fabs(rate - alpha) <= half);
    assert_true(fabs(mean_ratio - 1.0) < 0.05);
    assert_int_equal(g_tt.jump_alarm[0], 1);
    assert_int_equal(g_tt.jump_alarm[1], 1);
    assert_int_equal(g_tt.jump_alarm[2], 0); /* all three frames after the jump: consistent */
    const double nested_rate = (double)g_tt.nested_alarms / (double)g_tt.nested;
    const double nested_half = 2.576 * sqrt(alpha * (1.0 - alpha) / ((double)g_tt.nested / 3.0));
    printf(
        "  nested (5 frames, inner 3): %ld tests, inner alarm rate %.4f (99%% interval +-%.4f), "
        "%ld alarms differ from the 3-frame test's, largest |dgamma|/(1+gamma) %.2e, "
        "%ld 5-frame statistics differ from sfd_window_test_track's\n",
        g_tt.nested, nested_rate, nested_half, g_tt.nested_disagree, g_tt.nested_worst,
        g_tt.nested_outer_differ);
    assert_true(g_tt.nested > 5000);
    assert_int_equal(g_tt.nested_outer_differ, 0);
    assert_true(fabs(nested_rate - alpha) <= nested_half);
    assert_true(g_tt.nested_disagree * 100 <= g_tt.nested); /* measured: 0 */
    assert_true(g_tt.nested_worst < 0.05);                  /* measured: 1.1e-2 */
    /* the ramp test from the same factorization: chi2(2) on clean tracks */
    const double ramp_rate = (double)g_tt.ramp_alarms / (double)g_tt.ramp_tests;
    const double ramp_half = 2.576 * sqrt(alpha * (1.0 - alpha) / ((double)g_tt.ramp_tests / 3.0));
    const double ramp_mean = g_tt.ramp_sum / (double)g_tt.ramp_tests;
    printf(
        "  ramp (sfd_window_test_track_evidence, 5 frames): %ld tests, alarm rate %.4f at "
        "chi2(2, 0.99) (99%% interval +-%.4f), mean %.3f (chi2(2): 2); %ld results differ from the "
        "nested test's; largest |GLR - dense reference|/(1+GLR) %.1e\n",
        g_tt.ramp_tests, ramp_rate, ramp_half, ramp_mean, g_tt.ev_differ, g_tt.ramp_worst);
    assert_int_equal(g_tt.ev_differ, 0);
    assert_true(g_tt.ramp_worst < 1e-6);
    assert_true(g_tt.ramp_tests > 5000);
    assert_true(fabs(ramp_rate - alpha) <= ramp_half);
    assert_true(fabs(ramp_mean - 2.0) < 0.1);
    /* the motion's fit: the same tests, the dense reference's fit, and along a direction fixed
     * in advance z is N(0, 1) on clean tracks (its 10 % upper point: the 99 % binomial interval,
     * a third of the statistics independent; mean within 0.05) */
    const double z_rate = (double)g_tt.motion_z_alarms / (double)g_tt.motion_z_tests;
    const double z_half = 2.576 * sqrt(0.1 * 0.9 / ((double)g_tt.motion_z_tests / 3.0));
    const double z_mean = g_tt.motion_z_sum / (double)g_tt.motion_z_tests;
    printf(
        "  motion (sfd_window_test_track_motion, 3 frames and inner 3 of 5): %ld fits, %ld "
        "results differ from the tests'; largest difference from the dense fit %.1e; z along x "
        "and y: above N(0,1)'s 10 %% point %.4f of %ld (99%% interval +-%.4f), mean %.4f\n",
        g_tt.motion_fits, g_tt.motion_differ, g_tt.motion_worst, z_rate, g_tt.motion_z_tests,
        z_half, z_mean);
    assert_int_equal(g_tt.motion_differ, 0);
    assert_true(g_tt.motion_fits > 10000);
    assert_true(g_tt.motion_worst < 1e-6);
    assert_true(fabs(z_rate - 0.1) <= z_half);
    assert_true(fabs(z_mean) < 0.05);
    /* inner outside 2..m - 1: refused, nothing written */
    sfd_window_test_obs_t o;
    memset(&o, 0, sizeof o);
    o.frames = 3;
    double g2[2] = {-1.0, -1.0};
    int32_t d2[2] = {-1, -1};
    assert_status(sfd_window_test_track_nested(&g_w, &ext, &o, 3, &g_ws, g2, d2), SFD_ERR_INVAL);
    assert_status(sfd_window_test_track_nested(&g_w, &ext, &o, 1, &g_ws, g2, d2), SFD_ERR_INVAL);
    assert_status(sfd_window_test_track_nested(&g_w, &ext, &o, 2, NULL, g2, d2), SFD_ERR_INVAL);
    {
        double g3[3] = {-1.0, -1.0, -1.0};
        int32_t d3[3] = {-1, -1, -1};
        assert_status(sfd_window_test_track_evidence(&g_w, &ext, &o, 3, &g_ws, g3, d3),
                      SFD_ERR_INVAL);
        assert_status(sfd_window_test_track_evidence(&g_w, &ext, &o, 2, NULL, g3, d3),
                      SFD_ERR_INVAL);
        assert_true(g3[0] == -1.0 && g3[2] == -1.0 && d3[0] == -1 && d3[2] == -1);
        /* the motion's call: inner 1 or m, a ramp without a nested test or not 0/1 */
        sfd_window_motion_t mo;
        memset(&mo, 0x5a, sizeof mo);
        const sfd_window_motion_t untouched = mo;
        assert_status(sfd_window_test_track_motion(&g_w, &ext, &o, 3, 0, &g_ws, g3, d3, &mo),
                      SFD_ERR_INVAL);
        assert_status(sfd_window_test_track_motion(&g_w, &ext, &o, 1, 0, &g_ws, g3, d3, &mo),
                      SFD_ERR_INVAL);
        assert_status(sfd_window_test_track_motion(&g_w, &ext, &o, 0, 1, &g_ws, g3, d3, &mo),
                      SFD_ERR_INVAL);
        assert_status(sfd_window_test_track_motion(&g_w, &ext, &o, 2, 2, &g_ws, g3, d3, &mo),
                      SFD_ERR_INVAL);
        assert_status(sfd_window_test_track_motion(&g_w, &ext, &o, 0, 0, NULL, g3, d3, &mo),
                      SFD_ERR_INVAL);
        assert_true(g3[0] == -1.0 && g3[2] == -1.0 && d3[0] == -1 && d3[2] == -1);
        assert_memory_equal(&mo, &untouched, sizeof mo);
    }
    assert_true(g2[0] == -1.0 && g2[1] == -1.0 && d2[0] == -1 && d2[1] == -1);
}

/* GIVEN the same 10 s flight from rest twice WHEN the second builds every frame's observations in
 * the scratch's u.obs, the memory the update's work space reuses THEN the filter ends bit for bit
 * the same (sfd_window_frame reads every observation before the update writes there) */
static void observations_built_in_the_scratch_give_the_same_filter(void **state) {
    (void)state;
    run_result_t a, b;
    static sfd_window_t first;
    g_obs_in_scratch = 0;
    run_flight_from(11, 10.0, JAC_OBSERVABILITY, -1, 0, 1, &a);
    first = g_w;
    g_obs_in_scratch = 1;
    run_flight_from(11, 10.0, JAC_OBSERVABILITY, -1, 0, 1, &b);
    g_obs_in_scratch = 0;
    assert_true(a.used > 100); /* updates happened, so the work space was written */
    assert_int_equal(a.used, b.used);
    assert_memory_equal(first.P, g_w.P, sizeof g_w.P);
    assert_memory_equal(first.p_IinW_m, g_w.p_IinW_m, sizeof g_w.p_IinW_m);
    assert_memory_equal(first.q_ItoW, g_w.q_ItoW, sizeof g_w.q_ItoW);
    assert_memory_equal(first.clones, g_w.clones, sizeof g_w.clones);
}

static void flagged_tracks_are_dropped_and_capacities_hold(void **state) {
    (void)state;
    sfd_window_params_t prm;
    sfd_window_params_default(&prm);
    assert_status(sfd_window_init(&g_w, &prm), SFD_OK);
    sfd_extrinsics_t ext;
    extrinsics(&ext);
    sfd_window_result_t res;
    sfd_window_obs_t obs[SFD_WINDOW_MAX_TRACKS];
    memset(obs, 0, sizeof obs);
    /* not started */
    assert_status(sfd_window_frame(&g_w, 1, obs, 0, &ext, &g_ws, &res), SFD_ERR_STATE);
    const double z[3] = {0, 0, 0}, q[4] = {1, 0, 0, 0};
    assert_status(sfd_window_start_at(&g_w, 0, z, z, q, z, z), SFD_OK);
    assert_status(sfd_window_frame(&g_w, 1, NULL, 1, &ext, &g_ws, &res), SFD_ERR_INVAL);
    assert_status(sfd_window_frame(&g_w, 1, obs, 0, &ext, NULL, &res), SFD_ERR_INVAL);
    assert_status(sfd_window_frame(&g_w, 1, obs, SFD_WINDOW_MAX_TRACKS + 1, &ext, &g_ws, &res),
                  SFD_ERR_INVAL);
    for (int i = 0; i < SFD_WINDOW_MAX_TRACKS; ++i) {
        obs[i].track_id = i;
        obs[i].xn[0] = 0.001 * i;
        obs[i].cov_xn[0] = obs[i].cov_xn[2] = 1e-6;
    }
    obs[3].track_id = 2;    /* duplicate id: counted, ignored */
    obs[5].cov_xn[0] = NAN; /* bad value: counted, ignored */
    /* valid in double, not in the tracks' float storage: counted, ignored */
    obs[9].xn[1] = 1e39;                           /* beyond float's range */
    obs[11].cov_xn[0] = obs[11].cov_xn[2] = 1e-50; /* positive definite, 0 in float */
    assert_status(sfd_window_frame(&g_w, 1, obs, SFD_WINDOW_MAX_TRACKS, &ext, &g_ws, &res), SFD_OK);
    assert_int_equal(res.added, SFD_WINDOW_MAX_TRACKS - 4);
    assert_int_equal(res.overflow, 4);
    assert_int_equal(g_w.num_tracks, SFD_WINDOW_MAX_TRACKS - 4);
    /* frame 2: track 7 flagged, the others seen again */
    obs[7].drop = 1;
    assert_status(sfd_window_frame(&g_w, 2, obs, SFD_WINDOW_MAX_TRACKS, &ext, &g_ws, &res), SFD_OK);
    assert_int_equal(res.dropped, 1);
    assert_int_equal(g_w.num_tracks, SFD_WINDOW_MAX_TRACKS - 5);
    /* the window never exceeds L clones, P's dimension stays 15 + 6 L */
    obs[7].drop = 0;
    for (int f = 3; f < 20; ++f) {
        assert_status(sfd_window_frame(&g_w, f, obs, SFD_WINDOW_MAX_TRACKS, &ext, &g_ws, &res),
                      SFD_OK);
        assert_true(g_w.num_clones <= prm.window);
    }
    /* no motion at all: every due track is refused for lack of parallax, never used */
    assert_int_equal(res.used, 0);
    /* bad parameters */
    prm.window = SFD_MAX_WINDOW + 1;
    assert_status(sfd_window_init(&g_w, &prm), SFD_ERR_INVAL);
    sfd_window_params_default(&prm);
    prm.gate_alpha = 0.0;
    assert_status(sfd_window_init(&g_w, &prm), SFD_ERR_INVAL);
    sfd_window_params_default(&prm);
    prm.noise.accel_noise_m_s2_rthz = NAN;
    assert_status(sfd_window_init(&g_w, &prm), SFD_ERR_INVAL);
}

/* CTest runs this file as two executables (tests/CMakeLists.txt, tests/m7/CMakeLists.txt):
 * unit.window (SFD_TEST_WINDOW_PART 1: every test but the last two) and unit.window_start_nees
 * (part 2: the two Monte Carlo runs from rest), so that `ctest -j2` runs the two halves side by
 * side: whole, this file took 650 s on the emulated Cortex-M7 and 580 s under qemu-aarch64, the
 * longest test of either preset. Without the definition every test runs. */
#ifndef SFD_TEST_WINDOW_PART
#define SFD_TEST_WINDOW_PART 0
#endif
#if SFD_TEST_WINDOW_PART < 0 || SFD_TEST_WINDOW_PART > 2
#error "SFD_TEST_WINDOW_PART is 0 (every test), 1 or 2"
#endif
enum { kStartNeesTests = 2 };

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(flight_stays_close_to_the_truth),
        cmocka_unit_test(pose_nees_is_inside_its_chi_square_band),
        cmocka_unit_test(keyframes_span_more_motion_and_stay_consistent),
        cmocka_unit_test(sequence_numbers_wrap_without_changing_the_filter),
        cmocka_unit_test(the_newest_depth_prior_is_a_second_measurement),
        cmocka_unit_test(correlated_anisotropic_pixel_noise_is_whitened),
        cmocka_unit_test(a_track_without_its_first_prior_starts_from_its_newest),
        cmocka_unit_test(a_flagged_observation_ends_its_track),
        cmocka_unit_test(unobservable_directions_stay_unobservable),
        cmocka_unit_test(a_jumped_track_is_gated_and_does_not_pull),
        cmocka_unit_test(the_track_test_with_the_filters_covariance_is_calibrated),
        cmocka_unit_test(observations_built_in_the_scratch_give_the_same_filter),
        cmocka_unit_test(flagged_tracks_are_dropped_and_capacities_hold),
        /* part 2 */
        cmocka_unit_test(pose_nees_from_a_start_at_rest),
        cmocka_unit_test(pose_nees_with_ten_times_the_initial_uncertainty),
    };
    const size_t n = sizeof tests / sizeof tests[0];
    const size_t first = SFD_TEST_WINDOW_PART == 2 ? n - kStartNeesTests : 0;
    const size_t count = SFD_TEST_WINDOW_PART == 0   ? n
                         : SFD_TEST_WINDOW_PART == 1 ? n - kStartNeesTests
                                                     : (size_t)kStartNeesTests;
    /* the function behind cmocka_run_group_tests, for a slice of the table */
    return _cmocka_run_group_tests(SFD_TEST_WINDOW_PART == 2 ? "window_start_nees" : "window",
                                   tests + first, count, NULL, NULL);
}
