/* SPDX-License-Identifier: MIT */
/* unit.msckf: the window filter's measurement side (sfd_msckf.h, core/docs/msckf.md): the
 * projected residual is orthogonal to the landmark Jacobian and has 3 rows fewer; the gate
 * statistic equals the statistic with the landmark eliminated by weighted least squares (the
 * parity-space statistic with known translation); it is chi2(rows - 3) for consistent tracks
 * whatever the landmark error (Monte Carlo with a binomial interval); the QR-compressed update
 * equals the textbook Kalman update with every projected row; folding an unprojected unit-noise
 * track equals projecting, then folding; bad sizes and rank-deficient landmarks are status
 * codes. */
#include "sfd_test.h"
#include "test_dense.h"

#include <string.h>

#include <sfd/sfd_chi2.h>
#include <sfd/sfd_msckf.h>
#include <sfd/sfd_prng.h>

enum { D = SFD_MSCKF_DIM, TR = SFD_MSCKF_TRACK_ROWS, BIG = 6 * TR };
_Static_assert(BIG <= TEST_DENSE_MAX && D <= TEST_DENSE_MAX, "test_dense.h's capacity");

static sfd_msckf_track_t g_track, g_copy, g_before;
static sfd_msckf_stack_t g_stack;
static sfd_msckf_work_t g_work;
static double g_P[D * D], g_P2[D * D];

/* ---- helpers of the test ---- */

/* A random SPD n x n matrix into P (stride D): M M^T / n + 0.1 I, entries O(1). */
static void random_spd(sfd_prng_t *rng, int n, double *P) {
    static double M[D * D];
    for (int i = 0; i < n * n; ++i) M[i] = sfd_prng_gaussian(rng);
    for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
            double v = 0.0;
            for (int k = 0; k < n; ++k) v += M[i * n + k] * M[j * n + k];
            P[i * D + j] = v / n + (i == j ? 0.1 : 0.0);
        }
    }
}

/* A track of `rows` rows on an n-dimensional state: random Jacobians, block-diagonal 2x2 pixel
 * noise (a distortion Jacobian's shape: anisotropic, correlated), the last row of an odd count a
 * depth prior with its own variance. r is left 0. */
static void random_track(sfd_prng_t *rng, int rows, int n, sfd_msckf_track_t *t) {
    memset(t, 0, sizeof *t);
    t->rows = rows;
    t->n = n;
    for (int i = 0; i < rows; ++i) {
        for (int j = 0; j < n; ++j) t->Hx[i][j] = sfd_prng_gaussian(rng);
        for (int j = 0; j < 3; ++j) t->Hf[i][j] = 3.0 * sfd_prng_gaussian(rng);
    }
    for (int i = 0; i + 1 < rows; i += 2) {
        const double a = 0.5 + sfd_prng_uniform(rng), b = 0.5 + 2.0 * sfd_prng_uniform(rng);
        const double c = 0.4 * sqrt(a * b) * (2.0 * sfd_prng_uniform(rng) - 1.0);
        t->R[i][i] = a;
        t->R[i + 1][i + 1] = b;
        t->R[i][i + 1] = t->R[i + 1][i] = c;
    }
    if (rows % 2 == 1) t->R[rows - 1][rows - 1] = 0.3;
}

/* ---- tests ---- */

static void projected_residual_is_orthogonal_to_the_landmark_jacobian(void **state) {
    (void)state;
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 11);
    for (int rows = 4; rows <= TR; ++rows) {
        random_track(&rng, rows, 20, &g_track);
        /* The first 3 columns of Hx are H_f itself: their projection must vanish (N^T H_f = 0);
         * r is a pure landmark error H_f dp: its projection must vanish too. */
        const double dp[3] = {0.3, -1.2, 0.7};
        for (int i = 0; i < rows; ++i) {
            g_track.r[i] = 0.0;
            for (int j = 0; j < 3; ++j) {
                g_track.Hx[i][j] = g_track.Hf[i][j];
                g_track.r[i] += g_track.Hf[i][j] * dp[j];
            }
        }
        /* Isotropic noise stays isotropic under an orthonormal N. */
        for (int i = 0; i < rows; ++i) {
            for (int j = 0; j < rows; ++j) g_track.R[i][j] = i == j ? 2.25 : 0.0;
        }
        g_copy = g_track;
        assert_int_equal(sfd_msckf_track_project(&g_track), SFD_OK);
        assert_int_equal(g_track.rows, rows - 3);
        assert_int_equal(g_track.projected, 1);
        for (int i = 0; i < rows - 3; ++i) {
            for (int j = 0; j < 3; ++j) assert_true(fabs(g_track.Hx[i][j]) < 1e-12);
            assert_true(fabs(g_track.r[i]) < 1e-12);
            for (int j = 0; j < rows - 3; ++j) {
                assert_true(fabs(g_track.R[i][j] - (i == j ? 2.25 : 0.0)) < 1e-12);
            }
        }
        /* Norms are kept: sum of squares of a column of Hx outside H_f's range does not grow. */
        double before = 0.0, after = 0.0;
        for (int i = 0; i < rows; ++i) before += g_copy.Hx[i][5] * g_copy.Hx[i][5];
        for (int i = 0; i < rows - 3; ++i) after += g_track.Hx[i][5] * g_track.Hx[i][5];
        assert_true(after <= before + 1e-12);
        assert_int_equal(sfd_msckf_track_project(&g_track), SFD_ERR_INVAL); /* not twice */
    }
}

/* gamma = r^T N (N^T S N)^-1 N^T r equals r^T (S^-1 - S^-1 Hf (Hf^T S^-1 Hf)^-1 Hf^T S^-1) r,
 * S = Hx P Hx^T + R: the landmark eliminated by weighted least squares. */
static void gate_equals_the_landmark_eliminated_statistic(void **state) {
    (void)state;
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 12);
    const int n = 27;
    for (int trial = 0; trial < 20; ++trial) {
        const int rows = 4 + (int)sfd_prng_uniform_index(&rng, (uint32_t)(TR - 3));
        random_spd(&rng, n, g_P);
        random_track(&rng, rows, n, &g_track);
        for (int i = 0; i < rows; ++i) g_track.r[i] = 2.0 * sfd_prng_gaussian(&rng);
        /* Reference: S, then S^-1 r and S^-1 Hf. */
        double S[TR * TR] = {0}, SiR[TR] = {0}, SiF[TR * 3] = {0}, rhs[TR * 4] = {0};
        for (int i = 0; i < rows; ++i) {
            for (int j = 0; j < rows; ++j) {
                double v = 0.0;
                for (int k = 0; k < n; ++k) {
                    for (int l = 0; l < n; ++l)
                        v += g_track.Hx[i][k] * g_P[k * D + l] * g_track.Hx[j][l];
                }
                S[i * rows + j] = v + g_track.R[i][j];
            }
            rhs[i * 4 + 0] = g_track.r[i];
            for (int j = 0; j < 3; ++j) rhs[i * 4 + 1 + j] = g_track.Hf[i][j];
        }
        double X[TR * 4] = {0};
        assert_true(test_solve_dense(rows, 4, S, rhs, X));
        for (int i = 0; i < rows; ++i) {
            SiR[i] = X[i * 4 + 0];
            for (int j = 0; j < 3; ++j) SiF[i * 3 + j] = X[i * 4 + 1 + j];
        }
        double FtSiF[9] = {0}, FtSiR[3] = {0}, rSiR = 0.0;
        for (int i = 0; i < rows; ++i) {
            rSiR += g_track.r[i] * SiR[i];
            for (int a = 0; a < 3; ++a) {
                FtSiR[a] += g_track.Hf[i][a] * SiR[i];
                for (int b = 0; b < 3; ++b) FtSiF[a * 3 + b] += g_track.Hf[i][a] * SiF[i * 3 + b];
            }
        }
        double y[3] = {0.0, 0.0, 0.0};
        assert_true(test_solve_dense(3, 1, FtSiF, FtSiR, y));
        const double ref = rSiR - (FtSiR[0] * y[0] + FtSiR[1] * y[1] + FtSiR[2] * y[2]);
        /* The same statistic without N: R replaced by S, Hx not read. */
        g_copy = g_track;
        for (int i = 0; i < rows; ++i) {
            for (int j = 0; j < rows; ++j) g_copy.R[i][j] = S[i * rows + j];
        }
        assert_int_equal(sfd_msckf_track_project(&g_track), SFD_OK);
        double gamma = -1.0;
        int32_t dof = 0;
        assert_int_equal(sfd_msckf_track_gate(&g_track, g_P, &gamma, &dof), SFD_OK);
        assert_int_equal(dof, rows - 3);
        assert_true(fabs(gamma - ref) <= 1e-9 * (1.0 + fabs(ref)));
        double gamma_gls = -1.0;
        int32_t dof_gls = 0;
        g_before = g_copy;
        assert_int_equal(
            sfd_msckf_track_statistic(&g_copy, (const double(*)[TR])g_copy.R, &gamma_gls, &dof_gls),
            SFD_OK);
        assert_memory_equal(&g_copy, &g_before, sizeof g_copy); /* the track is only read */
        assert_int_equal(dof_gls, rows - 3);
        assert_true(fabs(gamma_gls - ref) <= 1e-9 * (1.0 + fabs(ref)));
        /* Only S's lower triangle is read: the upper one poisoned, the same statistic. */
        for (int i = 0; i < rows; ++i) {
            for (int j = i + 1; j < rows; ++j) g_copy.R[i][j] = NAN;
        }
        double gamma_lower = -1.0;
        int32_t dof_lower = 0;
        assert_int_equal(sfd_msckf_track_statistic(&g_copy, (const double(*)[TR])g_copy.R,
                                                   &gamma_lower, &dof_lower),
                         SFD_OK);
        assert_true(gamma_lower == gamma_gls && dof_lower == dof_gls);
    }
}

/* Consistent tracks: dx ~ N(0, P), noise ~ N(0, R), any landmark error: gamma ~ chi2(rows - 3).
 * 4000 tracks of 9 rows (dof 6): the mean within 4 standard errors of 6, and the fraction above
 * the 1 % quantile inside its 99.9 % binomial interval. */
static void gate_is_chi_square_for_consistent_tracks_whatever_the_landmark_error(void **state) {
    (void)state;
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 13);
    const int n = 21, rows = 9, trials = 4000;
    random_spd(&rng, n, g_P);
    double Lp[D * D] = {0}; /* Cholesky factor of P (test-side, plain loops) */
    for (int j = 0; j < n; ++j) {
        double s = g_P[j * D + j];
        for (int k = 0; k < j; ++k) s -= Lp[j * D + k] * Lp[j * D + k];
        Lp[j * D + j] = sqrt(s);
        for (int i = j + 1; i < n; ++i) {
            double t = g_P[i * D + j];
            for (int k = 0; k < j; ++k) t -= Lp[i * D + k] * Lp[j * D + k];
            Lp[i * D + j] = t / Lp[j * D + j];
        }
    }
    double q99 = 0.0;
    assert_int_equal(sfd_chi2_quantile_upper(0.01, rows - 3, &q99), SFD_OK);
    double sum = 0.0;
    int above = 0;
    for (int t = 0; t < trials; ++t) {
        random_track(&rng, rows, n, &g_track);
        double e[D], dx[D];
        for (int i = 0; i < n; ++i) e[i] = sfd_prng_gaussian(&rng);
        for (int i = 0; i < n; ++i) {
            dx[i] = 0.0;
            for (int k = 0; k <= i; ++k) dx[i] += Lp[i * D + k] * e[k];
        }
        const double dp[3] = {50.0 * sfd_prng_gaussian(&rng), 50.0 * sfd_prng_gaussian(&rng),
                              50.0 * sfd_prng_gaussian(&rng)};
        for (int i = 0; i < rows; i += 2) { /* noise with the 2x2 blocks' covariance */
            if (i + 1 < rows) {
                const double a = g_track.R[i][i], c = g_track.R[i][i + 1],
                             b = g_track.R[i + 1][i + 1];
                const double l11 = sqrt(a), l21 = c / l11, l22 = sqrt(b - l21 * l21);
                const double u = sfd_prng_gaussian(&rng), v = sfd_prng_gaussian(&rng);
                g_track.r[i] = l11 * u;
                g_track.r[i + 1] = l21 * u + l22 * v;
            } else {
                g_track.r[i] = sqrt(g_track.R[i][i]) * sfd_prng_gaussian(&rng);
            }
        }
        for (int i = 0; i < rows; ++i) {
            for (int k = 0; k < n; ++k) g_track.r[i] += g_track.Hx[i][k] * dx[k];
            for (int k = 0; k < 3; ++k) g_track.r[i] += g_track.Hf[i][k] * dp[k];
        }
        assert_int_equal(sfd_msckf_track_project(&g_track), SFD_OK);
        double gamma = 0.0;
        int32_t dof = 0;
        assert_int_equal(sfd_msckf_track_gate(&g_track, g_P, &gamma, &dof), SFD_OK);
        sum += gamma;
        above += gamma > q99;
    }
    const double mean = sum / trials, se = sqrt(2.0 * (rows - 3) / trials);
    assert_true(fabs(mean - (rows - 3)) < 4.0 * se);
    /* Binomial(4000, 0.01): sd 6.3; 99.9 % interval about [21, 61]. */
    assert_true(above >= 21 && above <= 61);
}

/* The compressed update equals the Kalman filter with every projected row stacked:
 * S = H P H^T + R (block diagonal), K = P H^T S^-1, dx = K r, P' = (I - K H) P. */
/* The compressed update against the textbook Kalman update with every projected row stacked.
 * gauge = 1: the rows never touch the first 6 columns (as a track never touches the IMU state)
 * and are orthogonal to one direction of the others (as the window's gauge), so the normal
 * equations are singular and the compression must drop those directions. */
static void check_update_against_kalman(uint64_t seed, int gauge) {
    sfd_prng_t rng;
    sfd_prng_seed(&rng, seed);
    const int n = 21, tracks = 6;
    random_spd(&rng, n, g_P);
    memcpy(g_P2, g_P, sizeof g_P);
    assert_int_equal(sfd_msckf_stack_reset(&g_stack, n), SFD_OK);
    static double H[BIG * D], r[BIG], R[BIG * BIG];
    memset(R, 0, sizeof R);
    int m = 0;
    for (int t = 0; t < tracks; ++t) {
        random_track(&rng, 6 + t, n, &g_track);
        for (int i = 0; gauge && i < g_track.rows; ++i) {
            double dot = 0.0; /* v: 1 at columns 6, 9, ..., 18 */
            for (int j = 0; j < 6; ++j) g_track.Hx[i][j] = 0.0;
            for (int j = 6; j < n; j += 3) dot += g_track.Hx[i][j];
            for (int j = 6; j < n; j += 3) g_track.Hx[i][j] -= dot / 5.0;
        }
        for (int i = 0; i < g_track.rows; ++i) g_track.r[i] = sfd_prng_gaussian(&rng);
        assert_int_equal(sfd_msckf_track_project(&g_track), SFD_OK);
        assert_int_equal(sfd_msckf_stack_fold(&g_stack, &g_track), SFD_OK);
        for (int i = 0; i < g_track.rows; ++i) {
            for (int j = 0; j < n; ++j) H[(m + i) * n + j] = g_track.Hx[i][j];
            r[m + i] = g_track.r[i];
            for (int j = 0; j < g_track.rows; ++j) R[(m + i) * BIG + m + j] = g_track.R[i][j];
        }
        m += g_track.rows;
    }
    assert_int_equal(g_stack.folded, m);
    assert_true(m > n); /* more rows than states: the compression drops rows */
    /* Reference Kalman update. */
    static double PHt[D * BIG], S[BIG * BIG], Kt[BIG * D], HP[BIG * D];
    for (int i = 0; i < n; ++i) {
        for (int j = 0; j < m; ++j) {
            double v = 0.0;
            for (int l = 0; l < n; ++l) v += g_P2[i * D + l] * H[j * n + l];
            PHt[i * m + j] = v;
        }
    }
    for (int i = 0; i < m; ++i) {
        for (int j = 0; j < m; ++j) {
            double v = 0.0;
            for (int l = 0; l < n; ++l) v += H[i * n + l] * PHt[l * m + j];
            S[i * m + j] = v + R[i * BIG + j];
        }
        for (int j = 0; j < n; ++j) HP[i * n + j] = PHt[j * m + i];
    }
    assert_true(test_solve_dense(m, n, S, HP, Kt)); /* K^T = S^-1 H P */
    double dx_ref[D];
    for (int i = 0; i < n; ++i) {
        dx_ref[i] = 0.0;
        for (int j = 0; j < m; ++j) dx_ref[i] += Kt[j * n + i] * r[j];
    }
    double dx[D];
    assert_int_equal(sfd_msckf_update(&g_stack, g_P, dx, &g_work), SFD_OK);
    for (int i = 0; i < n; ++i)
        assert_true(fabs(dx[i] - dx_ref[i]) < 1e-9 * (1.0 + fabs(dx_ref[i])));
    for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
            double kh = 0.0; /* (K H P)_ij = sum_l K_il (H P)_lj */
            for (int l = 0; l < m; ++l) kh += Kt[l * n + i] * HP[l * n + j];
            const double ref = g_P2[i * D + j] - kh;
            assert_true(fabs(g_P[i * D + j] - ref) < 1e-9 * (1.0 + fabs(ref)));
            assert_true(g_P[i * D + j] == g_P[j * D + i]);
        }
    }
    /* An empty stack leaves P and gives dx = 0. */
    memcpy(g_P2, g_P, sizeof g_P);
    assert_int_equal(sfd_msckf_stack_reset(&g_stack, n), SFD_OK);
    assert_int_equal(sfd_msckf_update(&g_stack, g_P, dx, &g_work), SFD_OK);
    assert_memory_equal(g_P, g_P2, sizeof g_P);
    for (int i = 0; i < n; ++i) assert_true(dx[i] == 0.0);
}

static void compressed_update_equals_the_kalman_filter(void **state) {
    (void)state;
    check_update_against_kalman(14, 0);
}

/* GIVEN rows that leave the IMU columns untouched and share an unobserved direction (the
 * normal equations are singular) WHEN compressed and updated THEN the result still equals the
 * Kalman filter: the unobserved directions are dropped, not inverted. */
static void compressed_update_equals_the_kalman_filter_when_directions_are_unobserved(
    void **state) {
    (void)state;
    check_update_against_kalman(15, 1);
}

static void bad_sizes_and_degenerate_landmarks_are_status_codes(void **state) {
    (void)state;
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 15);
    random_track(&rng, 6, 10, &g_track);
    g_copy = g_track;
    g_track.rows = TR + 1; /* over capacity */
    assert_int_equal(sfd_msckf_track_project(&g_track), SFD_ERR_INVAL);
    g_track.rows = 3; /* fewer rows than the landmark's 3 dof: nothing left to test */
    assert_int_equal(sfd_msckf_track_project(&g_track), SFD_ERR_INVAL);
    g_track.rows = 6;
    g_track.n = D + 1;
    assert_int_equal(sfd_msckf_track_project(&g_track), SFD_ERR_INVAL);
    g_track.n = 10;
    assert_memory_equal(&g_track, &g_copy, sizeof g_track); /* nothing written */
    g_track.r[2] = NAN;
    assert_int_equal(sfd_msckf_track_project(&g_track), SFD_ERR_INVAL);
    g_track.r[2] = 0.0;
    assert_int_equal(sfd_msckf_track_project(NULL), SFD_ERR_INVAL);
    double gamma = 0.0;
    int32_t dof = 0;
    random_spd(&rng, 10, g_P);
    assert_int_equal(sfd_msckf_track_gate(&g_track, g_P, &gamma, &dof), SFD_ERR_INVAL);
    assert_int_equal(sfd_msckf_stack_reset(&g_stack, 10), SFD_OK);
    assert_int_equal(sfd_msckf_stack_fold(&g_stack, &g_track), SFD_ERR_INVAL); /* unprojected */
    /* The statistic without N: sizes, null, a projected track, and what it overwrites. */
    g_copy = g_track;
    g_copy.rows = TR + 1;
    assert_int_equal(
        sfd_msckf_track_statistic(&g_copy, (const double(*)[TR])g_copy.R, &gamma, &dof),
        SFD_ERR_INVAL);
    g_copy.rows = 3;
    assert_int_equal(
        sfd_msckf_track_statistic(&g_copy, (const double(*)[TR])g_copy.R, &gamma, &dof),
        SFD_ERR_INVAL);
    g_copy.rows = 6;
    assert_int_equal(sfd_msckf_track_statistic(NULL, (const double(*)[TR])g_copy.R, &gamma, &dof),
                     SFD_ERR_INVAL);
    assert_int_equal(sfd_msckf_track_statistic(&g_copy, NULL, &gamma, &dof), SFD_ERR_INVAL);
    assert_int_equal(sfd_msckf_track_statistic(&g_copy, (const double(*)[TR])g_copy.R, NULL, &dof),
                     SFD_ERR_INVAL);
    g_copy.projected = 1;
    assert_int_equal(
        sfd_msckf_track_statistic(&g_copy, (const double(*)[TR])g_copy.R, &gamma, &dof),
        SFD_ERR_INVAL);
    g_copy.projected = 0;
    g_copy.r[1] = NAN;
    assert_int_equal(
        sfd_msckf_track_statistic(&g_copy, (const double(*)[TR])g_copy.R, &gamma, &dof),
        SFD_ERR_NUMERIC);
    g_copy = g_track;
    g_copy.R[0][0] = -1.0; /* not positive definite */
    assert_int_equal(
        sfd_msckf_track_statistic(&g_copy, (const double(*)[TR])g_copy.R, &gamma, &dof),
        SFD_ERR_NUMERIC);
    /* Rank 2 (no parallax: every row's landmark direction in one plane). */
    for (int i = 0; i < 6; ++i) g_track.Hf[i][2] = 2.0 * g_track.Hf[i][0] - g_track.Hf[i][1];
    g_copy = g_track;
    assert_int_equal(
        sfd_msckf_track_statistic(&g_copy, (const double(*)[TR])g_copy.R, &gamma, &dof),
        SFD_ERR_NUMERIC);
    assert_int_equal(sfd_msckf_track_project(&g_track), SFD_ERR_NUMERIC);
    assert_int_equal(g_track.projected, 0);
    /* Fold into a stack of another dimension. */
    random_track(&rng, 6, 10, &g_track);
    assert_int_equal(sfd_msckf_track_project(&g_track), SFD_OK);
    assert_int_equal(sfd_msckf_stack_reset(&g_stack, 12), SFD_OK);
    assert_int_equal(sfd_msckf_stack_fold(&g_stack, &g_track), SFD_ERR_INVAL);
    assert_int_equal(sfd_msckf_stack_reset(&g_stack, D + 1), SFD_ERR_INVAL);
    /* A non-positive-definite projected noise is refused and leaves the stack as it was. */
    assert_int_equal(sfd_msckf_stack_reset(&g_stack, 10), SFD_OK);
    g_track.R[0][0] = -1.0;
    assert_int_equal(sfd_msckf_stack_fold(&g_stack, &g_track), SFD_ERR_NUMERIC);
    assert_int_equal(g_stack.folded, 0);
}

/* GIVEN tracks with unit noise (R = I), dense or with the window filter's block sparsity (each
 * observation's two rows on one clone's six columns, the depth row on one clone's) WHEN folded
 * unprojected (the Schur complement: H_x^T H_x - Z^T Z with Z = Q_1^T H_x) THEN the normal
 * equations equal those of projecting, then folding, to rounding: every entry of Y and b, the
 * touched columns, the folded row count and the residual's square; and the update from them
 * is the same. */
static void unprojected_fold_equals_projecting_then_folding(void **state) {
    (void)state;
    static sfd_msckf_stack_t other;
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 21);
    const int n = 27; /* 15 + 2 clones of 6 */
    for (int sparse = 0; sparse <= 1; ++sparse) {
        assert_int_equal(sfd_msckf_stack_reset(&g_stack, n), SFD_OK);
        assert_int_equal(sfd_msckf_stack_reset(&other, n), SFD_OK);
        for (int rows = 4; rows <= TR; ++rows) {
            random_track(&rng, rows, n, &g_track);
            for (int i = 0; i < rows; ++i) {
                for (int j = 0; j < rows; ++j) g_track.R[i][j] = (i == j) ? 1.0 : 0.0;
                g_track.r[i] = sfd_prng_gaussian(&rng);
                /* frame of row i: clones of 6 columns after the 15 IMU ones, 1 or 2 in turn */
                const int clone = 15 + 6 * ((i / 2) % 2);
                for (int j = 0; sparse && j < n; ++j) {
                    if (j < clone || j >= clone + 6) g_track.Hx[i][j] = 0.0;
                }
            }
            g_copy = g_track;
            g_before = g_track;
            assert_int_equal(sfd_msckf_stack_fold_unprojected(&g_stack, &g_track), SFD_OK);
            assert_memory_equal(&g_track, &g_before, sizeof g_track); /* the track is read only */
            assert_int_equal(sfd_msckf_track_project(&g_copy), SFD_OK);
            assert_int_equal(sfd_msckf_stack_fold(&other, &g_copy), SFD_OK);
            double scale = 0.0;
            for (int a = 0; a < n; ++a) {
                for (int c = a; c <= n; ++c) scale = fmax(scale, fabs(other.Tq[a][c]));
            }
            for (int a = 0; a < n; ++a) {
                assert_int_equal(g_stack.used[a], other.used[a]);
                for (int c = a; c <= n; ++c) {
                    assert_true(fabs(g_stack.Tq[a][c] - other.Tq[a][c]) <= 1e-12 * scale);
                }
            }
            assert_int_equal(g_stack.folded, other.folded);
            assert_true(fabs(g_stack.residual_ss - other.residual_ss) <=
                        1e-12 * (1.0 + other.residual_ss));
        }
        if (sparse) {
            for (int a = 0; a < 15; ++a) assert_int_equal(g_stack.used[a], 0); /* IMU columns */
        }
        random_spd(&rng, n, g_P);
        memcpy(g_P2, g_P, sizeof g_P);
        double dx[D], dx2[D];
        assert_int_equal(sfd_msckf_update(&g_stack, g_P, dx, &g_work), SFD_OK);
        assert_int_equal(sfd_msckf_update(&other, g_P2, dx2, &g_work), SFD_OK);
        for (int i = 0; i < n; ++i) {
            assert_true(fabs(dx[i] - dx2[i]) <= 1e-9 * (1.0 + fabs(dx2[i])));
            for (int j = 0; j < n; ++j) {
                assert_true(fabs(g_P[i * D + j] - g_P2[i * D + j]) <=
                            1e-9 * (1.0 + fabs(g_P2[i * D + j])));
            }
        }
    }
}

/* A window filter's track, whitened: L = 5 clones (identity attitude, positions along x at
 * speed_m_s, 20 Hz) see the point p (m) with 1.5 px noise at 458 px focal length; rows 2k, 2k + 1
 * touch clone k's columns 15 + 6k .. + 5 (dp, dtheta). */
static void window_track(const double p[3], double speed_m_s, sfd_msckf_track_t *t) {
    const double sigma = 1.5 / 458.0;
    memset(t, 0, sizeof *t);
    t->rows = 10;
    t->n = D;
    for (int k = 0; k < 5; ++k) {
        const double pc[3] = {p[0] - speed_m_s * 0.05 * k, p[1], p[2]};
        const double iz = 1.0 / pc[2];
        const double J[2][3] = {{iz, 0.0, -pc[0] * iz * iz}, {0.0, iz, -pc[1] * iz * iz}};
        const double sk[3][3] = {{0.0, -pc[2], pc[1]}, {pc[2], 0.0, -pc[0]}, {-pc[1], pc[0], 0.0}};
        for (int a = 0; a < 2; ++a) {
            double *h = &t->Hx[2 * k + a][15 + 6 * k];
            for (int j = 0; j < 3; ++j) {
                double js = 0.0;
                for (int b = 0; b < 3; ++b) js += J[a][b] * sk[b][j];
                h[j] = -J[a][j] / sigma;
                h[3 + j] = js / sigma;
                t->Hf[2 * k + a][j] = J[a][j] / sigma;
            }
        }
    }
    for (int i = 0; i < 10; ++i) t->R[i][i] = 1.0;
}

/* GIVEN window-filter geometry from hovering to fast and from near to far points (the Schur
 * complement subtracts Z^T Z from H_x^T H_x, so rounding is relative to H_x^T H_x, not to what
 * the projection keeps) WHEN 40 tracks are folded unprojected and, separately, projected then
 * folded, and each stack updates the same covariance THEN the compression keeps and drops the
 * same pivots (the window's gauge and what the rows do not observe) and the updates agree. */
static void unprojected_fold_keeps_the_projections_pivots_from_hover_to_fast_flight(void **state) {
    (void)state;
    static sfd_msckf_stack_t other;
    static double P[D * D];
    const double speeds[3] = {0.01, 0.2, 5.0};
    const double depth_lo[3] = {2.0, 20.0, 200.0};
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 23);
    int dropped_total = 0;
    for (int si = 0; si < 3; ++si) {
        for (int di = 0; di < 3; ++di) {
            assert_int_equal(sfd_msckf_stack_reset(&g_stack, D), SFD_OK);
            assert_int_equal(sfd_msckf_stack_reset(&other, D), SFD_OK);
            for (int tr = 0; tr < 40; ++tr) {
                const double z = depth_lo[di] * (1.0 + 2.0 * sfd_prng_uniform(&rng));
                const double p[3] = {z * (sfd_prng_uniform(&rng) - 0.5),
                                     0.8 * z * (sfd_prng_uniform(&rng) - 0.5), z};
                window_track(p, speeds[si], &g_track);
                for (int i = 0; i < 10; ++i) g_track.r[i] = sfd_prng_gaussian(&rng);
                g_copy = g_track;
                assert_int_equal(sfd_msckf_stack_fold_unprojected(&g_stack, &g_track), SFD_OK);
                assert_int_equal(sfd_msckf_track_project(&g_copy), SFD_OK);
                assert_int_equal(sfd_msckf_stack_fold(&other, &g_copy), SFD_OK);
            }
            random_spd(&rng, D, P);
            memcpy(g_P, P, sizeof P);
            memcpy(g_P2, P, sizeof P);
            double dx[D], dx2[D];
            assert_int_equal(sfd_msckf_update(&g_stack, g_P, dx, &g_work), SFD_OK);
            assert_int_equal(sfd_msckf_update(&other, g_P2, dx2, &g_work), SFD_OK);
            for (int c = 0; c < D; ++c) {
                assert_int_equal(g_stack.used[c], other.used[c]); /* the pivots kept */
                if (c >= 15 && other.used[c] == 0) ++dropped_total;
                assert_true(fabs(dx[c] - dx2[c]) <= 1e-8 * (1.0 + fabs(dx2[c])));
                for (int j = 0; j < D; ++j) {
                    assert_true(fabs(g_P[c * D + j] - g_P2[c * D + j]) <=
                                1e-8 * (1.0 + fabs(P[c * D + j])));
                }
            }
        }
    }
    assert_true(dropped_total >= 9 * 6); /* at least the gauge's 6 pivots in every case */
}

/* GIVEN tracks the unprojected fold cannot take WHEN folded THEN a status code and an unchanged
 * stack: a noise that is not exactly the identity, a projected track, sizes, a non-finite entry,
 * another dimension (SFD_ERR_INVAL); an H_f of rank 2 (SFD_ERR_NUMERIC, as the projection). */
static void unprojected_fold_refuses_what_it_cannot_fold(void **state) {
    (void)state;
    static sfd_msckf_stack_t before;
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 22);
    random_track(&rng, 7, 10, &g_track);
    for (int i = 0; i < 7; ++i) {
        for (int j = 0; j < 7; ++j) g_track.R[i][j] = (i == j) ? 1.0 : 0.0;
    }
    assert_int_equal(sfd_msckf_stack_reset(&g_stack, 10), SFD_OK);
    assert_int_equal(sfd_msckf_stack_fold_unprojected(&g_stack, &g_track), SFD_OK);
    before = g_stack;
    g_copy = g_track;
    g_copy.R[1][2] = 1e-300; /* not the identity */
    assert_int_equal(sfd_msckf_stack_fold_unprojected(&g_stack, &g_copy), SFD_ERR_INVAL);
    g_copy = g_track;
    g_copy.R[3][3] = 2.0;
    assert_int_equal(sfd_msckf_stack_fold_unprojected(&g_stack, &g_copy), SFD_ERR_INVAL);
    g_copy = g_track;
    g_copy.projected = 1;
    assert_int_equal(sfd_msckf_stack_fold_unprojected(&g_stack, &g_copy), SFD_ERR_INVAL);
    g_copy = g_track;
    g_copy.rows = 3;
    assert_int_equal(sfd_msckf_stack_fold_unprojected(&g_stack, &g_copy), SFD_ERR_INVAL);
    g_copy.rows = TR + 1;
    assert_int_equal(sfd_msckf_stack_fold_unprojected(&g_stack, &g_copy), SFD_ERR_INVAL);
    g_copy = g_track;
    g_copy.n = 9;
    assert_int_equal(sfd_msckf_stack_fold_unprojected(&g_stack, &g_copy), SFD_ERR_INVAL);
    g_copy = g_track;
    g_copy.Hx[2][4] = NAN;
    assert_int_equal(sfd_msckf_stack_fold_unprojected(&g_stack, &g_copy), SFD_ERR_INVAL);
    assert_int_equal(sfd_msckf_stack_fold_unprojected(NULL, &g_track), SFD_ERR_INVAL);
    assert_int_equal(sfd_msckf_stack_fold_unprojected(&g_stack, NULL), SFD_ERR_INVAL);
    g_copy = g_track;
    for (int i = 0; i < 7; ++i) g_copy.Hf[i][2] = 2.0 * g_copy.Hf[i][0] - g_copy.Hf[i][1];
    assert_int_equal(sfd_msckf_stack_fold_unprojected(&g_stack, &g_copy), SFD_ERR_NUMERIC);
    assert_memory_equal(&g_stack, &before, sizeof g_stack);
}

/* One unit-noise row w = [1 0] with residual 0.5 in a 2-state stack (Y = [1 0; 0 0], b = [0.5 0]):
 * T = [1 0], q = 0.5. */
static void fold_one_unit_row(void) {
    assert_int_equal(sfd_msckf_stack_reset(&g_stack, 2), SFD_OK);
    g_stack.used[0] = 1;
    g_stack.Tq[0][0] = 1.0;
    g_stack.Tq[0][1] = 0.0;
    g_stack.Tq[0][2] = 0.5;
    g_stack.folded = 1;
}

/* GIVEN a covariance that is not positive semi-definite (rounding gone wrong upstream) WHEN the
 * update would make a variance negative THEN it refuses with a status code and leaves P and dx
 * unchanged (the check that replaces the Joseph form's guarantee). */
static void update_refuses_a_negative_variance(void **state) {
    (void)state;
    fold_one_unit_row();
    g_P[0] = 1.0; /* P = [1 10; 10 1]: indefinite */
    g_P[1] = 10.0;
    g_P[D] = 10.0;
    g_P[D + 1] = 1.0;
    double dx[2] = {7.0, 7.0};
    /* P'_22 = 1 - 10^2 / 2 < 0 */
    assert_int_equal(sfd_msckf_update(&g_stack, g_P, dx, &g_work), SFD_ERR_NUMERIC);
    assert_true(g_P[0] == 1.0 && g_P[1] == 10.0 && g_P[D] == 10.0 && g_P[D + 1] == 1.0);
    assert_true(dx[0] == 7.0 && dx[1] == 7.0);
    g_P[1] = g_P[D] = 0.5; /* positive definite: the same row updates */
    fold_one_unit_row();   /* the update consumed the stack */
    assert_int_equal(sfd_msckf_update(&g_stack, g_P, dx, &g_work), SFD_OK);
    assert_near(g_P[0], 0.5, 1e-15);             /* 1 - 1 / 2 */
    assert_near(g_P[D + 1], 1.0 - 0.125, 1e-15); /* 1 - 0.5^2 / 2 */
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(projected_residual_is_orthogonal_to_the_landmark_jacobian),
        cmocka_unit_test(gate_equals_the_landmark_eliminated_statistic),
        cmocka_unit_test(gate_is_chi_square_for_consistent_tracks_whatever_the_landmark_error),
        cmocka_unit_test(compressed_update_equals_the_kalman_filter),
        cmocka_unit_test(compressed_update_equals_the_kalman_filter_when_directions_are_unobserved),
        cmocka_unit_test(bad_sizes_and_degenerate_landmarks_are_status_codes),
        cmocka_unit_test(unprojected_fold_equals_projecting_then_folding),
        cmocka_unit_test(unprojected_fold_refuses_what_it_cannot_fold),
        cmocka_unit_test(unprojected_fold_keeps_the_projections_pivots_from_hover_to_fast_flight),
        cmocka_unit_test(update_refuses_a_negative_variance),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
