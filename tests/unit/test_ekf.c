/* SPDX-License-Identifier: MIT */
/* unit.ekf: the error-state EKF (Kilic 2014 eqs. (14)-(22)): equals a linear Kalman filter on a
 * linear case, its batch camera update equals the textbook eqs. (19)-(21), its Jacobian equals
 * numerical differentiation, it is consistent (NEES over Monte Carlo runs inside the chi-square
 * bounds), and it refuses bad input without changing. */
#include "sfd_test.h"
#include "test_dense.h"

#include <string.h>

#include <sfd/sfd_ekf.h>
#include <sfd/sfd_prng.h>
#include <sfd/sfd_rotation.h>

enum { NX = SFD_EKF_DIM };

/* C = A B with A (n x k), B (k x m). */
static void matmul(int n, int k, int m, const double *A, const double *B, double *C) {
    for (int i = 0; i < n; ++i) {
        for (int j = 0; j < m; ++j) {
            double s = 0.0;
            for (int l = 0; l < k; ++l) s += A[i * k + l] * B[l * m + j];
            C[i * m + j] = s;
        }
    }
}

static void transpose(int n, int m, const double *A, double *At) {
    for (int i = 0; i < n; ++i) {
        for (int j = 0; j < m; ++j) At[j * n + i] = A[i * m + j];
    }
}

/* Quadratic form e^T P^-1 e. */
static double mahalanobis(int n, const double *P, const double *e) {
    double x[NX] = {0};
    assert_true(test_solve_dense(n, 1, P, e, x));
    double s = 0.0;
    for (int i = 0; i < n; ++i) s += e[i] * x[i];
    return s;
}

/* True when the symmetric matrix is positive definite (Cholesky succeeds). */
static int is_spd(int n, const double *P) {
    double L[NX * NX];
    memset(L, 0, sizeof L);
    for (int j = 0; j < n; ++j) {
        double s = P[j * n + j];
        for (int k = 0; k < j; ++k) s -= L[j * n + k] * L[j * n + k];
        if (!(s > 0.0)) return 0;
        L[j * n + j] = sqrt(s);
        for (int i = j + 1; i < n; ++i) {
            double t = P[i * n + j];
            for (int k = 0; k < j; ++k) t -= L[i * n + k] * L[j * n + k];
            L[i * n + j] = t / L[j * n + j];
        }
    }
    return 1;
}

static void rotmat_of(const sfd_ekf_t *e, double R[9]) {
    sfd_quat_to_rotmat(e->q_ItoW, R);
}

/* Local orientation error Log(R_est^T R_true). */
static void rotation_error(const double R_est[9], const double R_true[9], double dth[3]) {
    double Rt[9], D[9];
    transpose(3, 3, R_est, Rt);
    matmul(3, 3, 3, Rt, R_true, D);
    sfd_so3_log(D, dth);
}

static sfd_ekf_camera_t forward_camera(void) {
    /* Camera looking along the IMU x axis: camera z = IMU x, camera x = -IMU y, y = -IMU z. */
    sfd_ekf_camera_t cam;
    memset(&cam, 0, sizeof cam);
    const double T[16] = {0, 0, 1, 0.05, -1, 0, 0, 0.01, 0, -1, 0, -0.02, 0, 0, 0, 1};
    assert_status(sfd_extrinsics_from_matrix(&cam.ext, T), SFD_OK);
    cam.fx_px = 400.0;
    cam.fy_px = 410.0;
    cam.cx_px = 320.0;
    cam.cy_px = 240.0;
    cam.pixel_sigma_px = 1.0;
    return cam;
}

/* GIVEN zero gyro, no rotation/bias uncertainty and position fixes WHEN running 50 steps THEN
 * position, velocity and their covariance equal a textbook 6-state linear Kalman filter
 * (eqs. (9)-(13)) to rounding. */
static void ekf_linear_case_equals_kalman_filter(void **state) {
    (void)state;
    SFD_REQ("SFD-EKF-001");
    sfd_ekf_noise_t nz;
    sfd_ekf_noise_default(&nz);
    nz.gyro_noise_rad_s_rthz = 0.0;
    nz.gyro_bias_rw_rad_s2_rthz = 0.0;
    nz.accel_bias_rw_m_s3_rthz = 0.0;
    nz.accel_noise_m_s2_rthz = 0.05;
    const double p0[3] = {1, 2, 3}, v0[3] = {0.5, -0.2, 0.1}, q0[4] = {1, 0, 0, 0};
    const double zero[3] = {0, 0, 0};
    double P0[NX] = {0};
    for (int k = 0; k < 3; ++k) {
        P0[SFD_EKF_IDX_P + k] = 0.3;
        P0[SFD_EKF_IDX_V + k] = 0.2;
    }
    sfd_ekf_t ekf;
    assert_status(sfd_ekf_init(&ekf, &nz, p0, v0, q0, zero, zero, P0), SFD_OK);

    /* reference: x = (p, v), A = [I dt I; 0 I], B u = (dt^2/2 a_W, dt a_W) */
    double x[6], P[36];
    memset(P, 0, sizeof P);
    for (int k = 0; k < 3; ++k) {
        x[k] = p0[k];
        x[3 + k] = v0[k];
        P[k * 6 + k] = 0.3;
        P[(3 + k) * 6 + 3 + k] = 0.2;
    }
    const double dt = 0.01, qa = 0.05 * 0.05, r = 0.04;
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 11);
    for (int step = 0; step < 50; ++step) {
        const double acc[3] = {0.3 * sin(0.1 * step), -0.2, 9.81 + 0.1 * cos(0.2 * step)};
        const double gyro[3] = {0, 0, 0};
        assert_status(sfd_ekf_propagate(&ekf, gyro, acc, dt), SFD_OK);
        double A[36] = {0}, Q[36] = {0}, AP[36], At[36], APAt[36];
        for (int k = 0; k < 6; ++k) A[k * 6 + k] = 1.0;
        for (int k = 0; k < 3; ++k) {
            const double aw = acc[k] + (k == 2 ? -9.81 : 0.0);
            x[k] += x[3 + k] * dt + 0.5 * dt * dt * aw;
            x[3 + k] += dt * aw;
            A[k * 6 + 3 + k] = dt;
            Q[k * 6 + k] = qa * dt * dt * dt / 3.0;
            Q[k * 6 + 3 + k] = Q[(3 + k) * 6 + k] = qa * dt * dt / 2.0;
            Q[(3 + k) * 6 + 3 + k] = qa * dt;
        }
        matmul(6, 6, 6, A, P, AP);
        transpose(6, 6, A, At);
        matmul(6, 6, 6, AP, At, APAt);
        for (int k = 0; k < 36; ++k) P[k] = APAt[k] + Q[k];
        if (step % 5 == 4) { /* position fix z = p + noise */
            double z[3], res[3], H[3 * NX] = {0}, R[9] = {0};
            for (int k = 0; k < 3; ++k) {
                z[k] = x[k] + 0.2 * sfd_prng_gaussian(&rng);
                res[k] = z[k] - ekf.p_IinW_m[k];
                H[k * NX + SFD_EKF_IDX_P + k] = 1.0;
                R[k * 3 + k] = r;
            }
            assert_status(sfd_ekf_update_linear(&ekf, H, res, R, 3), SFD_OK);
            /* reference eqs. (11)-(13): K = P C^T (C P C^T + R)^-1 with C = [I 0] */
            double S[9], PCt[18], Kt[18] = {0}, K[18];
            for (int i = 0; i < 3; ++i) {
                for (int j = 0; j < 3; ++j) S[i * 3 + j] = P[i * 6 + j] + (i == j ? r : 0.0);
            }
            for (int i = 0; i < 6; ++i) {
                for (int j = 0; j < 3; ++j) PCt[i * 3 + j] = P[i * 6 + j];
            }
            double PCt_T[18];
            transpose(6, 3, PCt, PCt_T);
            assert_true(test_solve_dense(3, 6, S, PCt_T, Kt)); /* S^-1 (P C^T)^T = K^T */
            transpose(3, 6, Kt, K);
            double innov[3];
            for (int k = 0; k < 3; ++k) innov[k] = z[k] - x[k];
            for (int i = 0; i < 6; ++i) {
                for (int k = 0; k < 3; ++k) x[i] += K[i * 3 + k] * innov[k];
            }
            double KC[36] = {0}, IKC[36], Pn[36];
            for (int i = 0; i < 6; ++i) {
                for (int j = 0; j < 3; ++j) KC[i * 6 + j] = K[i * 3 + j];
            }
            for (int k = 0; k < 36; ++k) IKC[k] = (k % 7 == 0 ? 1.0 : 0.0) - KC[k];
            matmul(6, 6, 6, IKC, P, Pn);
            memcpy(P, Pn, sizeof P);
        }
    }
    for (int k = 0; k < 3; ++k) {
        assert_near(ekf.p_IinW_m[k], x[k], 1e-9);
        assert_near(ekf.v_IinW_m_s[k], x[3 + k], 1e-9);
    }
    const int map[6] = {0, 1, 2, 3, 4, 5};
    for (int i = 0; i < 6; ++i) {
        for (int j = 0; j < 6; ++j) {
            assert_near(ekf.P[map[i] * NX + map[j]], P[i * 6 + j], 1e-10);
        }
    }
    /* the rotation never moved: its covariance and the quaternion are exact */
    assert_near(ekf.q_ItoW[0], 1.0, 1e-15);
    assert_near(ekf.P[SFD_EKF_IDX_THETA * NX + SFD_EKF_IDX_THETA], 0.0, 0.0);
}

/* A filter with a full, random SPD covariance and a generic pose. */
static void random_filter(sfd_ekf_t *ekf, sfd_prng_t *rng) {
    sfd_ekf_noise_t nz;
    sfd_ekf_noise_default(&nz);
    const double p[3] = {0.3, -0.2, 1.0}, v[3] = {1, 0, 0}, bg[3] = {0.01, 0, -0.01};
    const double ba[3] = {0.05, 0.02, 0};
    double rv[3] = {0.1, -0.2, 0.3}, q[4];
    sfd_quat_from_rotvec(rv, q);
    double P0[NX];
    for (int i = 0; i < NX; ++i) P0[i] = 1.0;
    assert_status(sfd_ekf_init(ekf, &nz, p, v, q, bg, ba, P0), SFD_OK);
    double G[NX * NX], Gt[NX * NX], GGt[NX * NX];
    for (int i = 0; i < NX * NX; ++i) G[i] = 0.1 * sfd_prng_gaussian(rng);
    transpose(NX, NX, G, Gt);
    matmul(NX, NX, NX, G, Gt, GGt);
    for (int i = 0; i < NX * NX; ++i) ekf->P[i] = GGt[i] + ((i % (NX + 1)) == 0 ? 0.01 : 0.0);
}

/* GIVEN a filter with a dense random covariance, a rotating, accelerating IMU sample and biases
 * WHEN propagated one step THEN P' equals the dense F P F^T + Q of eqs. (17)-(18), with F built
 * here entry by entry (the core multiplies over F's nonzero blocks only) */
static void ekf_propagated_covariance_equals_dense_transition(void **state) {
    (void)state;
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 77);
    sfd_ekf_t ekf;
    random_filter(&ekf, &rng);
    const double gyro[3] = {0.3, -0.5, 0.8}, accel[3] = {1.5, -0.7, 9.3}, dt = 0.005;
    double P0[NX * NX], R[9];
    memcpy(P0, ekf.P, sizeof P0);
    rotmat_of(&ekf, R);
    double w[3], a[3], mdtw[3];
    for (int k = 0; k < 3; ++k) {
        w[k] = gyro[k] - ekf.bg_rad_s[k];
        a[k] = accel[k] - ekf.ba_m_s2[k];
        mdtw[k] = -dt * w[k];
    }
    const double ax[9] = {0, -a[2], a[1], a[2], 0, -a[0], -a[1], a[0], 0};
    double Rax[9], Rw[9];
    matmul(3, 3, 3, R, ax, Rax);
    assert_status(sfd_so3_exp(mdtw, Rw), SFD_OK);
    enum {
        P_ = SFD_EKF_IDX_P,
        V_ = SFD_EKF_IDX_V,
        T_ = SFD_EKF_IDX_THETA,
        G_ = SFD_EKF_IDX_BG,
        A_ = SFD_EKF_IDX_BA
    };
    double F[NX * NX];
    memset(F, 0, sizeof F);
    for (int i = 0; i < NX; ++i) F[i * NX + i] = 1.0;
    for (int r = 0; r < 3; ++r) {
        F[(P_ + r) * NX + V_ + r] = dt;
        F[(T_ + r) * NX + G_ + r] = -dt;
        for (int c = 0; c < 3; ++c) {
            F[(P_ + r) * NX + T_ + c] = -0.5 * dt * dt * Rax[3 * r + c];
            F[(P_ + r) * NX + A_ + c] = -0.5 * dt * dt * R[3 * r + c];
            F[(V_ + r) * NX + T_ + c] = -dt * Rax[3 * r + c];
            F[(V_ + r) * NX + A_ + c] = -dt * R[3 * r + c];
            F[(T_ + r) * NX + T_ + c] = Rw[3 * r + c];
        }
    }
    double FP[NX * NX], Ft[NX * NX], Pd[NX * NX];
    matmul(NX, NX, NX, F, P0, FP);
    transpose(NX, NX, F, Ft);
    matmul(NX, NX, NX, FP, Ft, Pd);
    const sfd_ekf_noise_t *nz = &ekf.noise;
    const double qa = nz->accel_noise_m_s2_rthz * nz->accel_noise_m_s2_rthz;
    for (int k = 0; k < 3; ++k) {
        Pd[(P_ + k) * NX + P_ + k] += qa * dt * dt * dt / 3.0;
        Pd[(P_ + k) * NX + V_ + k] += qa * dt * dt / 2.0;
        Pd[(V_ + k) * NX + P_ + k] += qa * dt * dt / 2.0;
        Pd[(V_ + k) * NX + V_ + k] += qa * dt;
        Pd[(T_ + k) * NX + T_ + k] += nz->gyro_noise_rad_s_rthz * nz->gyro_noise_rad_s_rthz * dt;
        Pd[(G_ + k) * NX + G_ + k] +=
            nz->gyro_bias_rw_rad_s2_rthz * nz->gyro_bias_rw_rad_s2_rthz * dt;
        Pd[(A_ + k) * NX + A_ + k] +=
            nz->accel_bias_rw_m_s3_rthz * nz->accel_bias_rw_m_s3_rthz * dt;
    }
    assert_status(sfd_ekf_propagate(&ekf, gyro, accel, dt), SFD_OK);
    for (int i = 0; i < NX * NX; ++i) assert_near(ekf.P[i], Pd[i], 1e-12);
}

static sfd_ekf_obs_t observation_ahead(const sfd_ekf_t *ekf, const sfd_ekf_camera_t *cam,
                                       sfd_prng_t *rng, double depth) {
    double R_CtoW[9], p_C[3];
    sfd_ekf_camera_pose(ekf, &cam->ext, R_CtoW, p_C);
    const double xc = 0.4 * (sfd_prng_uniform(rng) - 0.5), yc = 0.3 * (sfd_prng_uniform(rng) - 0.5);
    const double c[3] = {xc * depth, yc * depth, depth};
    sfd_ekf_obs_t o;
    memset(&o, 0, sizeof o);
    for (int r = 0; r < 3; ++r) {
        o.landmark_W_m[r] = p_C[r];
        for (int k = 0; k < 3; ++k) o.landmark_W_m[r] += R_CtoW[3 * r + k] * c[k];
    }
    o.uv_px[0] = cam->fx_px * xc + cam->cx_px + 3.0 * sfd_prng_gaussian(rng);
    o.uv_px[1] = cam->fy_px * yc + cam->cy_px + 3.0 * sfd_prng_gaussian(rng);
    for (int k = 0; k < 3; ++k) o.landmark_cov_m2[(size_t)4 * (size_t)k] = 0.01 * (k + 1);
    o.landmark_cov_m2[1] = o.landmark_cov_m2[3] = 0.003;
    return o;
}

/* The dense textbook quantities of eqs. (19)-(22) for M observations: stacked H (2M x 15), the
 * block-diagonal R, the innovation nu, S = H P H^T + R and the gain K = P H^T S^-1. */
enum { TB_M = 5 };
static void textbook_system(const sfd_ekf_t *ekf, const sfd_ekf_camera_t *cam,
                            const sfd_ekf_obs_t *obs, double *H, double *R, double *nu, double *S,
                            double *K) {
    enum { M = TB_M };
    memset(H, 0, sizeof(double) * 2 * M * NX);
    memset(R, 0, sizeof(double) * 4 * M * M);
    for (int i = 0; i < M; ++i) {
        double uv[2], Hp[12], Ri[4];
        assert_status(sfd_ekf_predict_observation(ekf, cam, &obs[i], uv, Hp, Ri), SFD_OK);
        for (int r = 0; r < 2; ++r) {
            nu[2 * i + r] = obs[i].uv_px[r] - uv[r];
            for (int k = 0; k < 3; ++k) {
                H[(2 * i + r) * NX + SFD_EKF_IDX_P + k] = Hp[6 * r + k];
                H[(2 * i + r) * NX + SFD_EKF_IDX_THETA + k] = Hp[6 * r + 3 + k];
            }
            for (int c = 0; c < 2; ++c) R[(2 * i + r) * 2 * M + 2 * i + c] = Ri[2 * r + c];
        }
    }
    double Ht[NX * 2 * M], PHt[NX * 2 * M], PHt_T[2 * M * NX], Kt[2 * M * NX] = {0};
    transpose(2 * M, NX, H, Ht);
    matmul(NX, NX, 2 * M, ekf->P, Ht, PHt);
    matmul(2 * M, NX, 2 * M, H, PHt, S);
    for (int i = 0; i < 4 * M * M; ++i) S[i] += R[i];
    transpose(NX, 2 * M, PHt, PHt_T);
    assert_true(test_solve_dense(2 * M, NX, S, PHt_T, Kt));
    transpose(2 * M, NX, Kt, K);
}

/* GIVEN a random SPD prior and 5 observations WHEN updating THEN state and covariance equal the
 * dense textbook eqs. (19)-(21), K = P H^T (H P H^T + R)^-1, P+ = (I - K H) P, to rounding. */
static void ekf_camera_update_equals_textbook_equations(void **state) {
    (void)state;
    SFD_REQ("SFD-EKF-002");
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 5);
    sfd_ekf_t ekf;
    random_filter(&ekf, &rng);
    const sfd_ekf_camera_t cam = forward_camera();
    enum { M = TB_M };
    sfd_ekf_obs_t obs[M];
    for (int i = 0; i < M; ++i) obs[i] = observation_ahead(&ekf, &cam, &rng, 4.0 + i);
    /* dense H (2M x 15), R (2M x 2M), residual */
    double H[2 * M * NX], R[4 * M * M], nu[2 * M], S[4 * M * M], K[NX * 2 * M];
    textbook_system(&ekf, &cam, obs, H, R, nu, S, K);
    double dx[NX], KH[NX * NX], IKH[NX * NX], Pref[NX * NX];
    matmul(NX, 2 * M, 1, K, nu, dx);
    matmul(NX, 2 * M, NX, K, H, KH);
    for (int i = 0; i < NX * NX; ++i) IKH[i] = ((i % (NX + 1)) == 0 ? 1.0 : 0.0) - KH[i];
    matmul(NX, NX, NX, IKH, ekf.P, Pref);
    double nis_ref = 0.0, Sinv_nu[2 * M] = {0};
    assert_true(test_solve_dense(2 * M, 1, S, nu, Sinv_nu));
    for (int i = 0; i < 2 * M; ++i) nis_ref += nu[i] * Sinv_nu[i];

    sfd_ekf_t before = ekf;
    sfd_ekf_update_info_t info;
    assert_status(sfd_ekf_update_camera(&ekf, &cam, obs, NULL, M, &info), SFD_OK);
    assert_int_equal(info.used, M);
    assert_int_equal(info.skipped, 0);
    assert_near(info.nis, nis_ref, 1e-9 * nis_ref);
    for (int k = 0; k < 3; ++k) {
        assert_near(ekf.p_IinW_m[k] - before.p_IinW_m[k], dx[SFD_EKF_IDX_P + k], 1e-10);
        assert_near(ekf.v_IinW_m_s[k] - before.v_IinW_m_s[k], dx[SFD_EKF_IDX_V + k], 1e-10);
        assert_near(ekf.bg_rad_s[k] - before.bg_rad_s[k], dx[SFD_EKF_IDX_BG + k], 1e-10);
        assert_near(ekf.ba_m_s2[k] - before.ba_m_s2[k], dx[SFD_EKF_IDX_BA + k], 1e-10);
    }
    double R0[9], R1[9], dth[3];
    rotmat_of(&before, R0);
    rotmat_of(&ekf, R1);
    rotation_error(R0, R1, dth);
    for (int k = 0; k < 3; ++k) assert_near(dth[k], dx[SFD_EKF_IDX_THETA + k], 1e-10);
    /* Joseph and (I - K H) P agree for the optimal gain */
    for (int i = 0; i < NX * NX; ++i) assert_near(ekf.P[i], Pref[i], 1e-10);
    assert_true(is_spd(NX, ekf.P));
}

/* GIVEN position marked as a consider state WHEN updating with 5 observations THEN the position
 * is not corrected and P equals the Joseph form of the textbook gain with its position rows zeroed,
 * (I - K'H) P (I - K'H)^T + K' R K'^T, to rounding (a suboptimal gain keeps P exact). */
static void ekf_consider_states_are_not_corrected_and_p_stays_exact(void **state) {
    (void)state;
    SFD_REQ("SFD-EKF-007");
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 15);
    sfd_ekf_t ekf;
    random_filter(&ekf, &rng);
    for (int k = 0; k < 3; ++k) ekf.consider[SFD_EKF_IDX_P + k] = 1;
    const sfd_ekf_camera_t cam = forward_camera();
    enum { M = TB_M };
    sfd_ekf_obs_t obs[M];
    for (int i = 0; i < M; ++i) obs[i] = observation_ahead(&ekf, &cam, &rng, 4.0 + i);
    double H[2 * M * NX], R[4 * M * M], nu[2 * M], S[4 * M * M], K[NX * 2 * M];
    textbook_system(&ekf, &cam, obs, H, R, nu, S, K);
    for (int k = 0; k < 3; ++k) {
        for (int c = 0; c < 2 * M; ++c) K[(SFD_EKF_IDX_P + k) * 2 * M + c] = 0.0;
    }
    double KH[NX * NX], IKH[NX * NX], IKHt[NX * NX], A[NX * NX], Pref[NX * NX];
    double KR[NX * 2 * M], Ktr[2 * M * NX], KRKt[NX * NX];
    matmul(NX, 2 * M, NX, K, H, KH);
    for (int i = 0; i < NX * NX; ++i) IKH[i] = ((i % (NX + 1)) == 0 ? 1.0 : 0.0) - KH[i];
    transpose(NX, NX, IKH, IKHt);
    matmul(NX, NX, NX, IKH, ekf.P, A);
    matmul(NX, NX, NX, A, IKHt, Pref);
    matmul(NX, 2 * M, 2 * M, K, R, KR);
    transpose(NX, 2 * M, K, Ktr);
    matmul(NX, 2 * M, NX, KR, Ktr, KRKt);
    for (int i = 0; i < NX * NX; ++i) Pref[i] += KRKt[i];
    const sfd_ekf_t before = ekf;
    assert_status(sfd_ekf_update_camera(&ekf, &cam, obs, NULL, M, NULL), SFD_OK);
    assert_memory_equal(ekf.p_IinW_m, before.p_IinW_m, sizeof ekf.p_IinW_m);
    for (int i = 0; i < NX * NX; ++i) assert_near(ekf.P[i], Pref[i], 1e-10);
    assert_true(is_spd(NX, ekf.P));
    /* the other states are corrected by K' nu */
    double dx[NX];
    matmul(NX, 2 * M, 1, K, nu, dx);
    for (int k = 0; k < 3; ++k) {
        assert_near(ekf.v_IinW_m_s[k] - before.v_IinW_m_s[k], dx[SFD_EKF_IDX_V + k], 1e-10);
        assert_near(ekf.ba_m_s2[k] - before.ba_m_s2[k], dx[SFD_EKF_IDX_BA + k], 1e-10);
    }
}

/* GIVEN a generic pose WHEN perturbing position and orientation (R^ Exp(dtheta)) THEN the
 * predicted pixel changes as H_pose says, to second order. */
static void ekf_camera_jacobian_matches_numerical_derivative(void **state) {
    (void)state;
    SFD_REQ("SFD-EKF-003");
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 9);
    sfd_ekf_t ekf;
    random_filter(&ekf, &rng);
    const sfd_ekf_camera_t cam = forward_camera();
    const sfd_ekf_obs_t o = observation_ahead(&ekf, &cam, &rng, 3.0);
    double uv0[2], Hp[12], Ri[4];
    assert_status(sfd_ekf_predict_observation(&ekf, &cam, &o, uv0, Hp, Ri), SFD_OK);
    const double h = 1e-6;
    for (int col = 0; col < 6; ++col) {
        sfd_ekf_t e = ekf;
        if (col < 3) {
            e.p_IinW_m[col] += h;
        } else {
            double R[9], dR[9], Rn[9], phi[3] = {0, 0, 0};
            phi[col - 3] = h;
            rotmat_of(&ekf, R);
            sfd_so3_exp(phi, dR);
            matmul(3, 3, 3, R, dR, Rn);
            sfd_rotmat_to_quat(Rn, e.q_ItoW);
        }
        double uv1[2];
        assert_status(sfd_ekf_predict_observation(&e, &cam, &o, uv1, NULL, NULL), SFD_OK);
        for (int r = 0; r < 2; ++r) {
            const double num = (uv1[r] - uv0[r]) / h;
            assert_near(Hp[6 * r + col], num, 1e-4 * (1.0 + fabs(num)));
        }
    }
    /* R = sigma^2 I + J_L C_L J_L^T is larger than sigma^2 I */
    assert_true(Ri[0] > 1.0 && Ri[3] > 1.0);
}

/* ---- Monte Carlo consistency ---- */

typedef struct {
    double p[3], v[3], R[9], bg[3], ba[3];
} truth_t;

/* Truth propagation with the true IMU signal (same discretization as the filter's mean). */
static void truth_step(truth_t *t, const double w[3], const double f[3], double dt) {
    double a_W[3], dR[9], Rn[9], phi[3];
    for (int r = 0; r < 3; ++r) {
        a_W[r] = (r == 2) ? -9.81 : 0.0;
        for (int k = 0; k < 3; ++k) a_W[r] += t->R[3 * r + k] * f[k];
    }
    for (int k = 0; k < 3; ++k) {
        t->p[k] += t->v[k] * dt + 0.5 * dt * dt * a_W[k];
        t->v[k] += dt * a_W[k];
        phi[k] = w[k] * dt;
    }
    sfd_so3_exp(phi, dR);
    matmul(3, 3, 3, t->R, dR, Rn);
    memcpy(t->R, Rn, sizeof Rn);
}

static double nees_of(const sfd_ekf_t *e, const truth_t *t) {
    double err[NX], Re[9], dth[3];
    rotmat_of(e, Re);
    rotation_error(Re, t->R, dth);
    for (int k = 0; k < 3; ++k) {
        err[SFD_EKF_IDX_P + k] = t->p[k] - e->p_IinW_m[k];
        err[SFD_EKF_IDX_V + k] = t->v[k] - e->v_IinW_m_s[k];
        err[SFD_EKF_IDX_THETA + k] = dth[k];
        err[SFD_EKF_IDX_BG + k] = t->bg[k] - e->bg_rad_s[k];
        err[SFD_EKF_IDX_BA + k] = t->ba[k] - e->ba_m_s2[k];
    }
    return mahalanobis(NX, e->P, err);
}

/* Wilson-Hilferty quantile of chi2(k) at the standard normal quantile z. */
static double chi2_wh(double k, double z) {
    const double c = 2.0 / (9.0 * k);
    const double b = 1.0 - c + z * sqrt(c);
    return k * b * b * b;
}

/* GIVEN 60 Monte Carlo runs of a 4 s flight (IMU 200 Hz with white noise and bias random walk,
 * 20 Hz camera seeing 12 mapped landmarks with 1 px noise, initial errors drawn from P0) WHEN
 * filtering THEN the run-averaged NEES (15 dof) at 2 s and 4 s lies inside the two-sided 99%
 * chi-square interval, and P stays symmetric positive definite throughout. */
static void ekf_nees_is_consistent_over_monte_carlo(void **state) {
    (void)state;
    SFD_REQ("SFD-EKF-004");
    enum { RUNS = 60, STEPS = 800, CAM_EVERY = 10, NOBS = 12 };
    const double dt = 0.005;
    sfd_ekf_noise_t nz;
    sfd_ekf_noise_default(&nz);
    nz.gyro_noise_rad_s_rthz = 2e-3;
    nz.accel_noise_m_s2_rthz = 2e-2;
    nz.gyro_bias_rw_rad_s2_rthz = 1e-4;
    nz.accel_bias_rw_m_s3_rthz = 1e-3;
    const sfd_ekf_camera_t cam = forward_camera();
    double P0[NX];
    for (int k = 0; k < 3; ++k) {
        P0[SFD_EKF_IDX_P + k] = 0.05 * 0.05;
        P0[SFD_EKF_IDX_V + k] = 0.05 * 0.05;
        P0[SFD_EKF_IDX_THETA + k] = 0.02 * 0.02;
        P0[SFD_EKF_IDX_BG + k] = 0.005 * 0.005;
        P0[SFD_EKF_IDX_BA + k] = 0.05 * 0.05;
    }
    double nees_mid = 0.0, nees_end = 0.0;
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 2024);
    for (int run = 0; run < RUNS; ++run) {
        truth_t t;
        memset(&t, 0, sizeof t);
        t.R[0] = t.R[4] = t.R[8] = 1.0;
        t.v[0] = 0.5;
        for (int k = 0; k < 3; ++k) {
            t.bg[k] = sqrt(P0[SFD_EKF_IDX_BG + k]) * sfd_prng_gaussian(&rng);
            t.ba[k] = sqrt(P0[SFD_EKF_IDX_BA + k]) * sfd_prng_gaussian(&rng);
        }
        /* filter starts at truth + error drawn from P0 */
        double p[3], v[3], q[4], dth[3], Rt[9], dR[9], Re[9];
        const double zero[3] = {0, 0, 0};
        for (int k = 0; k < 3; ++k) {
            p[k] = t.p[k] - sqrt(P0[SFD_EKF_IDX_P + k]) * sfd_prng_gaussian(&rng);
            v[k] = t.v[k] - sqrt(P0[SFD_EKF_IDX_V + k]) * sfd_prng_gaussian(&rng);
            dth[k] = -sqrt(P0[SFD_EKF_IDX_THETA + k]) * sfd_prng_gaussian(&rng);
        }
        memcpy(Rt, t.R, sizeof Rt);
        sfd_so3_exp(dth, dR);
        matmul(3, 3, 3, Rt, dR, Re);
        sfd_rotmat_to_quat(Re, q);
        sfd_ekf_t ekf;
        assert_status(sfd_ekf_init(&ekf, &nz, p, v, q, zero, zero, P0), SFD_OK);
        for (int s = 1; s <= STEPS; ++s) {
            const double tt = s * dt;
            const double w[3] = {0.3 * sin(1.3 * tt), 0.2 * cos(0.9 * tt), 0.15};
            const double f_true[3] = {0.4 * cos(tt), 0.3 * sin(1.7 * tt), 9.81 + 0.2 * sin(tt)};
            double wm[3], fm[3];
            for (int k = 0; k < 3; ++k) {
                wm[k] =
                    w[k] + t.bg[k] + nz.gyro_noise_rad_s_rthz / sqrt(dt) * sfd_prng_gaussian(&rng);
                fm[k] = f_true[k] + t.ba[k] +
                        nz.accel_noise_m_s2_rthz / sqrt(dt) * sfd_prng_gaussian(&rng);
            }
            assert_status(sfd_ekf_propagate(&ekf, wm, fm, dt), SFD_OK);
            /* truth: attitude held level by the f_true choice; move with the true signals */
            truth_step(&t, w, f_true, dt);
            for (int k = 0; k < 3; ++k) {
                t.bg[k] += nz.gyro_bias_rw_rad_s2_rthz * sqrt(dt) * sfd_prng_gaussian(&rng);
                t.ba[k] += nz.accel_bias_rw_m_s3_rthz * sqrt(dt) * sfd_prng_gaussian(&rng);
            }
            if (s % CAM_EVERY == 0) {
                /* landmarks placed in front of the true camera, observed with 1 px noise */
                sfd_ekf_t te = ekf; /* truth pose in a filter struct for the projection */
                memcpy(te.p_IinW_m, t.p, sizeof t.p);
                sfd_rotmat_to_quat(t.R, te.q_ItoW);
                sfd_ekf_obs_t obs[NOBS];
                for (int i = 0; i < NOBS; ++i) {
                    double R_CtoW[9], p_C[3];
                    sfd_ekf_camera_pose(&te, &cam.ext, R_CtoW, p_C);
                    const double depth = 3.0 + 6.0 * sfd_prng_uniform(&rng);
                    const double xc = 0.8 * (sfd_prng_uniform(&rng) - 0.5);
                    const double yc = 0.6 * (sfd_prng_uniform(&rng) - 0.5);
                    const double c[3] = {xc * depth, yc * depth, depth};
                    memset(&obs[i], 0, sizeof obs[i]);
                    for (int r = 0; r < 3; ++r) {
                        obs[i].landmark_W_m[r] = p_C[r];
                        for (int k = 0; k < 3; ++k)
                            obs[i].landmark_W_m[r] += R_CtoW[3 * r + k] * c[k];
                    }
                    obs[i].uv_px[0] = cam.fx_px * xc + cam.cx_px + sfd_prng_gaussian(&rng);
                    obs[i].uv_px[1] = cam.fy_px * yc + cam.cy_px + sfd_prng_gaussian(&rng);
                }
                assert_status(sfd_ekf_update_camera(&ekf, &cam, obs, NULL, NOBS, NULL), SFD_OK);
                assert_true(is_spd(NX, ekf.P));
            }
            if (s == STEPS / 2) nees_mid += nees_of(&ekf, &t);
            if (s == STEPS) nees_end += nees_of(&ekf, &t);
        }
    }
    const double k = (double)(NX * RUNS);
    const double lo = chi2_wh(k, -2.5758) / RUNS, hi = chi2_wh(k, 2.5758) / RUNS;
    print_message(
        "NEES averaged over %d runs: %.3f at 2 s, %.3f at 4 s; 99%% interval [%.3f, %.3f]\n", RUNS,
        nees_mid / RUNS, nees_end / RUNS, lo, hi);
    assert_true(nees_mid / RUNS > lo && nees_mid / RUNS < hi);
    assert_true(nees_end / RUNS > lo && nees_end / RUNS < hi);
}

/* GIVEN a tilted IMU at rest WHEN starting from gravity THEN roll/pitch map the specific force to
 * +z, yaw is 0, and 2 s of propagation at rest keep the position within millimetres. */
static void ekf_starts_from_gravity_at_rest(void **state) {
    (void)state;
    SFD_REQ("SFD-EKF-005");
    sfd_ekf_noise_t nz;
    sfd_ekf_noise_default(&nz);
    const double phi[3] = {0.2, -0.1, 0.0};
    double R[9];
    sfd_so3_exp(phi, R); /* a body orientation with some yaw coupling is fine: only f is used */
    double f[3];
    for (int k = 0; k < 3; ++k) f[k] = R[3 * 2 + k] * 9.81; /* R^T (0,0,g) */
    const double zero[3] = {0, 0, 0};
    double P0[NX];
    for (int i = 0; i < NX; ++i) P0[i] = 1e-4;
    sfd_ekf_t ekf;
    assert_status(sfd_ekf_init_from_gravity(&ekf, &nz, f, zero, P0), SFD_OK);
    double Re[9];
    rotmat_of(&ekf, Re);
    double up[3] = {0, 0, 0};
    for (int r = 0; r < 3; ++r) {
        for (int k = 0; k < 3; ++k) up[r] += Re[3 * r + k] * f[k];
    }
    assert_near(up[0], 0.0, 1e-12);
    assert_near(up[1], 0.0, 1e-12);
    assert_near(up[2], 9.81, 1e-12);
    assert_near(Re[3 * 1 + 0], 0.0, 1e-12); /* yaw 0: body x has no world-y component */
    for (int s = 0; s < 400; ++s) assert_status(sfd_ekf_propagate(&ekf, zero, f, 0.005), SFD_OK);
    for (int k = 0; k < 3; ++k) assert_near(ekf.p_IinW_m[k], 0.0, 1e-9);
    const double moving[3] = {0, 0, 14.0};
    assert_status(sfd_ekf_init_from_gravity(&ekf, &nz, moving, zero, P0), SFD_ERR_DOMAIN);
}

/* GIVEN bad arguments WHEN calling THEN status codes, and the filter is unchanged. */
static void ekf_rejects_bad_input_and_stays_unchanged(void **state) {
    (void)state;
    SFD_REQ("SFD-EKF-006");
    sfd_ekf_t ekf;
    memset(&ekf, 0, sizeof ekf);
    const double g[3] = {0, 0, 0}, a[3] = {0, 0, 9.81};
    assert_status(sfd_ekf_propagate(&ekf, g, a, 0.01), SFD_ERR_STATE);
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 3);
    random_filter(&ekf, &rng);
    const sfd_ekf_t before = ekf;
    assert_status(sfd_ekf_propagate(&ekf, g, a, 0.0), SFD_ERR_INVAL);
    assert_status(sfd_ekf_propagate(&ekf, g, a, 0.2), SFD_ERR_INVAL);
    const double nan3[3] = {0, NAN, 0};
    assert_status(sfd_ekf_propagate(&ekf, nan3, a, 0.01), SFD_ERR_INVAL);
    assert_status(sfd_ekf_propagate(NULL, g, a, 0.01), SFD_ERR_INVAL);
    const sfd_ekf_camera_t cam = forward_camera();
    sfd_ekf_obs_t o = observation_ahead(&ekf, &cam, &rng, 5.0);
    assert_status(sfd_ekf_update_camera(&ekf, &cam, &o, NULL, -1, NULL), SFD_ERR_INVAL);
    assert_status(sfd_ekf_update_camera(&ekf, &cam, &o, NULL, SFD_MAX_FEATURES + 1, NULL),
                  SFD_ERR_INVAL);
    /* a landmark behind the camera is skipped and counted, nothing applied */
    sfd_ekf_obs_t behind = o;
    double R_CtoW[9], p_C[3];
    sfd_ekf_camera_pose(&ekf, &cam.ext, R_CtoW, p_C);
    for (int r = 0; r < 3; ++r) behind.landmark_W_m[r] = 2.0 * p_C[r] - o.landmark_W_m[r];
    sfd_ekf_update_info_t info;
    assert_status(sfd_ekf_update_camera(&ekf, &cam, &behind, NULL, 1, &info), SFD_OK);
    assert_int_equal(info.used, 0);
    assert_int_equal(info.skipped, 1);
    /* use flags: nothing selected, nothing applied */
    const uint8_t none = 0;
    assert_status(sfd_ekf_update_camera(&ekf, &cam, &o, &none, 1, &info), SFD_OK);
    assert_int_equal(info.used, 0);
    double H[NX] = {0}, res = 1.0, Rneg = -5.0;
    H[0] = 1.0;
    ekf.P[0] = 1.0;
    const sfd_ekf_t before2 = ekf;
    assert_status(sfd_ekf_update_linear(&ekf, H, &res, &Rneg, 1), SFD_ERR_NUMERIC);
    assert_memory_equal(&ekf.P, &before2.P, sizeof ekf.P);
    assert_int_equal(ekf.numeric_faults, before.numeric_faults + 1U);
    assert_status(sfd_ekf_update_linear(&ekf, H, &res, &Rneg, 7), SFD_ERR_INVAL);
    assert_memory_equal(ekf.p_IinW_m, before.p_IinW_m, sizeof ekf.p_IinW_m);
    assert_memory_equal(ekf.q_ItoW, before.q_ItoW, sizeof ekf.q_ItoW);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(ekf_linear_case_equals_kalman_filter),
        cmocka_unit_test(ekf_propagated_covariance_equals_dense_transition),
        cmocka_unit_test(ekf_camera_update_equals_textbook_equations),
        cmocka_unit_test(ekf_camera_jacobian_matches_numerical_derivative),
        cmocka_unit_test(ekf_consider_states_are_not_corrected_and_p_stays_exact),
        cmocka_unit_test(ekf_nees_is_consistent_over_monte_carlo),
        cmocka_unit_test(ekf_starts_from_gravity_at_rest),
        cmocka_unit_test(ekf_rejects_bad_input_and_stays_unchanged),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
