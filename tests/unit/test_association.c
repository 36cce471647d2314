/* SPDX-License-Identifier: MIT */
/* unit.association: OPRF (Kilic 2014 Section 3.2, Table 1), 1-point RANSAC, fundamental-matrix
 * RANSAC and no association, on synthetic frame pairs with known outliers: detection, the kept
 * inliers, the hypothesis budget, determinism, degenerate motion and argument checks. */
#include "sfd_test.h"

#include <string.h>

#include <sfd/sfd_assoc.h>
#include <sfd/sfd_parity.h>
#include <sfd/sfd_prng.h>
#include <sfd/sfd_rotation.h>

#include "euroc_calib.h"
#include "sfd_pair_sim.h"

typedef struct {
    long tp, fp, tn, fn, untested;
} counts_t;

/* the association's work space, shared by every association of this file (one call at a time) */
static sfd_assoc_work_t g_aw;

static void tally(const sim_pair_t *pr, const sfd_assoc_result_t *r, counts_t *c) {
    for (int i = 0; i < pr->n; ++i) {
        if (r->status[i] == SFD_VERDICT_UNTESTED) {
            c->untested++;
        } else if (r->status[i] == SFD_VERDICT_SPURIOUS) {
            if (pr->outlier[i])
                c->tp++;
            else
                c->fp++;
        } else {
            if (pr->outlier[i])
                c->fn++;
            else
                c->tn++;
        }
    }
}

static sfd_assoc_result_t res; /* large: keep it off the stack */
static sim_pair_t pair;

static counts_t run_trials(int method, const sim_pair_opts_t *o, int trials, double *pos_err_prior,
                           double *pos_err_post, int *max_hyp) {
    counts_t c = {0, 0, 0, 0, 0};
    static sfd_assoc_t assoc;
    sfd_assoc_params_t ap;
    sfd_assoc_params_default(&ap);
    ap.method = method;
    assert_status(sfd_assoc_init(&assoc, &ap), SFD_OK);
    double e0 = 0, e1 = 0;
    int hmax = 0;
    for (int t = 0; t < trials; ++t) {
        assert_int_equal(sim_pair_make(&pair, o, 1000U + (uint64_t)t), 0);
        for (int k = 0; k < 3; ++k) {
            const double d = pair.ekf.p_IinW_m[k] - pair.true_p_I[k];
            e0 += d * d;
        }
        assert_status(sfd_assoc_run(&assoc, &g_aw, &pair.ekf, &pair.cam, pair.prev_R_CtoW,
                                    pair.prev_p_C, pair.m, pair.n, &res),
                      SFD_OK);
        assert_status(res.update_status, SFD_OK);
        for (int k = 0; k < 3; ++k) {
            const double d = pair.ekf.p_IinW_m[k] - pair.true_p_I[k];
            e1 += d * d;
        }
        if (res.hypotheses_used > hmax) hmax = res.hypotheses_used;
        tally(&pair, &res, &c);
    }
    if (pos_err_prior) *pos_err_prior = sqrt(e0 / trials);
    if (pos_err_post) *pos_err_post = sqrt(e1 / trials);
    if (max_hyp) *max_hyp = hmax;
    return c;
}

static double precision(const counts_t *c) {
    return c->tp + c->fp ? (double)c->tp / (double)(c->tp + c->fp) : 1.0;
}
static double recall(const counts_t *c) {
    return c->tp + c->fn ? (double)c->tp / (double)(c->tp + c->fn) : 1.0;
}

/* GIVEN 20 frame pairs of 200 matches with 30% random outliers (1 px noise, IMU prior 5 cm /
 * 0.3 deg) WHEN running OPRF THEN precision and recall of SPURIOUS are >= 0.97, at most a few
 * hypotheses are drawn (eq. (27) at 70% inliers asks for 4), and the update with the accepted
 * matches reduces the position error of the prior. */
static void oprf_detects_random_outliers_and_improves_the_pose(void **state) {
    (void)state;
    SFD_REQ("SFD-OPRF-001");
    const sim_pair_opts_t o = sim_pair_default_opts();
    double e0, e1;
    int hmax;
    const counts_t c = run_trials(SFD_METHOD_OPRF, &o, 20, &e0, &e1, &hmax);
    print_message(
        "OPRF: tp %ld fp %ld tn %ld fn %ld untested %ld; precision %.4f recall %.4f; "
        "position error prior %.4f m, posterior %.4f m; max hypotheses %d\n",
        c.tp, c.fp, c.tn, c.fn, c.untested, precision(&c), recall(&c), e0, e1, hmax);
    assert_true(precision(&c) >= 0.97);
    assert_true(recall(&c) >= 0.97);
    assert_true(e1 < 0.5 * e0);
    assert_true(hmax <= 10);
}

/* GIVEN the same frames WHEN running 1-point RANSAC (reprojection distance) THEN it detects them
 * as well (it is the baseline the thesis starts from). */
static void ransac1_detects_random_outliers(void **state) {
    (void)state;
    SFD_REQ("SFD-OPRF-002");
    const sim_pair_opts_t o = sim_pair_default_opts();
    double e0, e1;
    const counts_t c = run_trials(SFD_METHOD_RANSAC1, &o, 20, &e0, &e1, NULL);
    print_message("RANSAC1: precision %.4f recall %.4f; position error %.4f -> %.4f m\n",
                  precision(&c), recall(&c), e0, e1);
    assert_true(precision(&c) >= 0.95);
    assert_true(recall(&c) >= 0.95);
    assert_true(e1 < 0.5 * e0);
}

/* GIVEN the same frames WHEN running the fundamental-matrix RANSAC (Table 2) THEN it detects
 * random outliers from the pixels alone. Its precision is lower than the IMU-aided methods':
 * its F is fitted to the same noisy pixels it judges, which inflates the inliers' Sampson
 * distances (false-alarm rate about 1.9% at alpha = 1%, see zero_outliers_keep_every_match). */
static void ransacf_detects_random_outliers(void **state) {
    (void)state;
    SFD_REQ("SFD-OPRF-003");
    const sim_pair_opts_t o = sim_pair_default_opts();
    const counts_t c = run_trials(SFD_METHOD_RANSACF, &o, 10, NULL, NULL, NULL);
    print_message("RANSACF: precision %.4f recall %.4f\n", precision(&c), recall(&c));
    assert_true(precision(&c) >= 0.90);
    assert_true(recall(&c) >= 0.95);
}

/* GIVEN 0% outliers WHEN running each method THEN every match is kept when the data are
 * noise-free, and with 1 px noise the false alarms of the IMU-aided methods stay within the
 * binomial 99.9% bound of alpha = 0.01 over 4000 matches (at most 61). The fundamental-matrix
 * RANSAC fits its model to the judged pixels, so its rate is above alpha: bound 3%. */
static void zero_outliers_keep_every_match(void **state) {
    (void)state;
    SFD_REQ("SFD-OPRF-004");
    const int methods[4] = {SFD_METHOD_NONE, SFD_METHOD_OPRF, SFD_METHOD_RANSAC1,
                            SFD_METHOD_RANSACF};
    for (int k = 0; k < 4; ++k) {
        sim_pair_opts_t o = sim_pair_default_opts();
        o.outlier_ratio = 0.0;
        o.sigma_px = 0.0;
        counts_t c = run_trials(methods[k], &o, 5, NULL, NULL, NULL);
        assert_int_equal(c.fp, 0);
        assert_int_equal(c.untested, 0);
        o.sigma_px = 1.0;
        c = run_trials(methods[k], &o, 20, NULL, NULL, NULL);
        print_message("method %d, 0%% outliers, 1 px: %ld false alarms of %ld\n", methods[k], c.fp,
                      c.fp + c.tn);
        assert_true(c.fp <= (methods[k] == SFD_METHOD_RANSACF ? 120 : 61));
    }
}

/* GIVEN 100% outliers WHEN running the RANSAC methods with a budget of 37 THEN no run draws more
 * than 37 hypotheses and every run reports the budget exhausted. */
static void hypotheses_never_exceed_the_budget(void **state) {
    (void)state;
    SFD_REQ("SFD-OPRF-005");
    const int methods[3] = {SFD_METHOD_OPRF, SFD_METHOD_RANSAC1, SFD_METHOD_RANSACF};
    static sfd_assoc_t assoc;
    for (int k = 0; k < 3; ++k) {
        sfd_assoc_params_t ap;
        sfd_assoc_params_default(&ap);
        ap.method = methods[k];
        ap.max_hypotheses = 37;
        assert_status(sfd_assoc_init(&assoc, &ap), SFD_OK);
        sim_pair_opts_t o = sim_pair_default_opts();
        o.outlier_ratio = 1.0;
        for (int t = 0; t < 5; ++t) {
            sim_pair_make(&pair, &o, 50U + (uint64_t)t);
            assert_status(sfd_assoc_run(&assoc, &g_aw, &pair.ekf, &pair.cam, pair.prev_R_CtoW,
                                        pair.prev_p_C, pair.m, pair.n, &res),
                          SFD_OK);
            assert_true(res.hypotheses_used <= 37);
            assert_int_equal(res.budget_exhausted, 1);
        }
    }
}

/* GIVEN the same seed and input WHEN running twice THEN verdicts, statistics and the posterior
 * are bit-identical; a different seed draws different hypotheses. */
static void same_seed_gives_identical_verdicts(void **state) {
    (void)state;
    SFD_REQ("SFD-OPRF-006");
    static sfd_assoc_t a1, a2;
    static sfd_assoc_result_t r1, r2;
    static sim_pair_t p1, p2;
    sfd_assoc_params_t ap;
    sfd_assoc_params_default(&ap);
    ap.seed = 77;
    const sim_pair_opts_t o = sim_pair_default_opts();
    sim_pair_make(&p1, &o, 9);
    sim_pair_copy(&p2, &p1);
    assert_status(sfd_assoc_init(&a1, &ap), SFD_OK);
    assert_status(sfd_assoc_init(&a2, &ap), SFD_OK);
    assert_status(
        sfd_assoc_run(&a1, &g_aw, &p1.ekf, &p1.cam, p1.prev_R_CtoW, p1.prev_p_C, p1.m, p1.n, &r1),
        SFD_OK);
    assert_status(
        sfd_assoc_run(&a2, &g_aw, &p2.ekf, &p2.cam, p2.prev_R_CtoW, p2.prev_p_C, p2.m, p2.n, &r2),
        SFD_OK);
    assert_memory_equal(&r1, &r2, sizeof r1);
    assert_memory_equal(&p1.ekf, &p2.ekf, sizeof p1.ekf);
}

/* The pixels of an exact pair (sigma_px 0: exact pixels and landmarks) seen through the EuRoC cam0
 * radtan distortion: each undistorted pixel is distorted, gets isotropic N(0, sigma^2) raw-pixel
 * noise and is undistorted again; the match carries its noise through the distortion Jacobian
 * (sfd_camera_pixel_noise) when @p jacobian is 1, else none (isotropic in undistorted pixels,
 * the former model). edge[i] = 1 when the current observation's undistorted noise variance,
 * tr(C_curr) / 2, is at least 1.4 sigma^2 (the stretched border of the image). */
static void distort_pair(sim_pair_t *pr, double sigma, uint64_t seed, int jacobian, uint8_t *edge) {
    sfd_camera_t cam;
    assert_status(sfd_camera_init(&cam, SFD_DISTORTION_RADTAN, 752, 480, kEurocFx, kEurocFy,
                                  kEurocCx, kEurocCy, kEurocRadtan),
                  SFD_OK);
    sfd_prng_t rng;
    sfd_prng_seed(&rng, seed);
    pr->cam.pixel_sigma_px = sigma;
    for (int i = 0; i < pr->n; ++i) {
        sfd_match_t *m = &pr->m[i];
        double *uv[2] = {m->prev_uv_px, m->uv_px};
        float *dc[2] = {m->noise.prev_dC, m->noise.curr_dC};
        for (int f = 0; f < 2; ++f) {
            const double xn[2] = {(uv[f][0] - kEurocCx) / kEurocFx,
                                  (uv[f][1] - kEurocCy) / kEurocFy};
            double raw[2], xn2[2];
            assert_status(sfd_camera_distort(&cam, xn, raw, NULL), SFD_OK);
            raw[0] += sigma * sfd_prng_gaussian(&rng);
            raw[1] += sigma * sfd_prng_gaussian(&rng);
            assert_status(sfd_camera_undistort(&cam, raw, xn2, NULL), SFD_OK);
            uv[f][0] = kEurocFx * xn2[0] + kEurocCx;
            uv[f][1] = kEurocFy * xn2[1] + kEurocCy;
            assert_status(sfd_camera_pixel_noise(&cam, xn2, dc[f]), SFD_OK);
        }
        edge[i] = (uint8_t)(1.0 + 0.5 * (m->noise.curr_dC[0] + m->noise.curr_dC[2]) >= 1.4);
        if (!jacobian) memset(&m->noise, 0, sizeof m->noise);
    }
}

/* Set-1 false alarms (sfd_assoc_select) of @p method among the edge matches of @p trials clean
 * distorted pairs (distort_pair); the totals in *n_edge / *n_all, flagged in *fa_all. */
static long edge_false_alarms(int method, int jacobian, int trials, long *n_edge, long *n_all,
                              long *fa_all) {
    static sfd_assoc_t assoc;
    static uint8_t edge[SIM_PAIR_MAX];
    sfd_assoc_params_t ap;
    sfd_assoc_params_default(&ap);
    ap.method = method;
    assert_status(sfd_assoc_init(&assoc, &ap), SFD_OK);
    sim_pair_opts_t o = sim_pair_default_opts();
    o.outlier_ratio = 0.0;
    o.sigma_px = 0.0;         /* exact pixels and landmarks: the noise is added by distort_pair */
    o.prior_p_sigma_m = 1e-4; /* a prior close to the truth: the statistic is the noise's */
    o.prior_th_sigma_rad = 1e-5;
    long fa = 0;
    *n_edge = *n_all = *fa_all = 0;
    for (int t = 0; t < trials; ++t) {
        assert_int_equal(sim_pair_make(&pair, &o, 5000U + (uint64_t)t), 0);
        distort_pair(&pair, 1.0, 9000U + (uint64_t)t, jacobian, edge);
        assert_status(sfd_assoc_select(&assoc, &g_aw, &pair.ekf, &pair.cam, pair.prev_R_CtoW,
                                       pair.prev_p_C, pair.m, pair.n, &res),
                      SFD_OK);
        for (int i = 0; i < pair.n; ++i) {
            assert_int_not_equal(res.status[i], SFD_VERDICT_UNTESTED);
            const long flagged = res.status[i] == SFD_VERDICT_SPURIOUS;
            *n_all += 1;
            *fa_all += flagged;
            if (edge[i]) {
                *n_edge += 1;
                fa += flagged;
            }
        }
    }
    return fa;
}

/* GIVEN clean frame pairs through the EuRoC cam0 radtan distortion with 1 px isotropic noise in
 * raw pixels (fixed seeds) and a prior close to the truth WHEN OPRF (Sampson) and 1-point RANSAC
 * (reprojection) select THEN the false-alarm rate among the matches at the stretched image border
 * (undistorted noise variance >= 1.4 sigma^2) is inside the 99 % binomial interval of alpha = 1 %
 * with the noise carried through the distortion Jacobian, and above it with isotropic noise in
 * undistorted pixels (the former model), so the test can fail. Measured on 17089 edge matches:
 * OPRF 1.14 % (isotropic 1.80 %: its per-frame noise scale absorbs part of it), RANSAC1 1.05 %
 * (isotropic 7.05 %). */
static void distorted_edge_false_alarms_are_calibrated_with_the_jacobian(void **state) {
    (void)state;
    const int methods[2] = {SFD_METHOD_OPRF, SFD_METHOD_RANSAC1};
    const char *names[2] = {"oprf", "ransac1"};
    const double alpha = 0.01;
    for (int k = 0; k < 2; ++k) {
        long ne = 0, na = 0, fa_all = 0, ne0 = 0, na0 = 0, fa_all0 = 0;
        const long fa = edge_false_alarms(methods[k], 1, 240, &ne, &na, &fa_all);
        const long fa0 = edge_false_alarms(methods[k], 0, 240, &ne0, &na0, &fa_all0);
        assert_int_equal(ne, ne0);
        const double half = 2.576 * sqrt(alpha * (1.0 - alpha) / (double)ne);
        const double rate = (double)fa / (double)ne;
        const double rate0 = (double)fa0 / (double)ne0;
        print_message(
            "%s edge matches %ld (of %ld): Jacobian %.4f (all %.4f), isotropic %.4f "
            "(all %.4f); 99%% interval %.4f..%.4f\n",
            names[k], ne, na, rate, (double)fa_all / (double)na, rate0,
            (double)fa_all0 / (double)na0, alpha - half, alpha + half);
        assert_true(ne > 5000);
        assert_true(fabs(rate - alpha) <= half);
        assert_true(rate0 > alpha + half);
    }
}

/* Mean OPRF noise scale (sfd_assoc_t.sampson_scale) and the outliers' recall over @p trials
 * frame pairs of @p o (1 px noise, pixel_sigma_px = 1 px: the true scale is 1). */
static double mean_oprf_scale(const sim_pair_opts_t *o, int trials, double *recall) {
    static sfd_assoc_t assoc;
    sfd_assoc_params_t ap;
    sfd_assoc_params_default(&ap);
    ap.method = SFD_METHOD_OPRF;
    assert_status(sfd_assoc_init(&assoc, &ap), SFD_OK);
    counts_t c = {0, 0, 0, 0, 0};
    double sum = 0.0;
    for (int t = 0; t < trials; ++t) {
        assert_int_equal(sim_pair_make(&pair, o, 7000U + (uint64_t)t), 0);
        assert_status(sfd_assoc_run(&assoc, &g_aw, &pair.ekf, &pair.cam, pair.prev_R_CtoW,
                                    pair.prev_p_C, pair.m, pair.n, &res),
                      SFD_OK);
        sum += assoc.sampson_scale;
        tally(&pair, &res, &c);
    }
    *recall = (c.tp + c.fn) > 0 ? (double)c.tp / (double)(c.tp + c.fn) : 0.0;
    return sum / (double)trials;
}

/* GIVEN frame pairs with 1 px noise, pixel_sigma_px = 1 px and a prior close to the truth (true
 * noise scale 1), without outliers, with 30 % random outliers (>= 20 px off) and with 30 %
 * structured ones (one 3-15 px shift) WHEN OPRF selects THEN its noise scale stays near 1: the
 * median over all matches alone gave 0.990, 2.412 and 2.048 (30 % far outliers read the chi2(1)
 * median at its 0.71 quantile); with the refinement over the gate 0.990, 0.963 and 1.273 (the
 * structured outliers inside the gate still count), structured recall 0.838 -> 0.869. */
static void oprf_noise_scale_is_not_inflated_by_outliers(void **state) {
    (void)state;
    sim_pair_opts_t o = sim_pair_default_opts();
    o.n = 200;
    o.sigma_px = 1.0;
    o.prior_p_sigma_m = 1e-4; /* a prior close to the truth: the distances are the noise's */
    o.prior_th_sigma_rad = 1e-5;
    double recall = 0.0;
    o.outlier_ratio = 0.0;
    const double s_clean = mean_oprf_scale(&o, 40, &recall);
    o.outlier_ratio = 0.3;
    const double s_random = mean_oprf_scale(&o, 40, &recall);
    o.structured = 1;
    const double s_structured = mean_oprf_scale(&o, 40, &recall);
    print_message(
        "oprf noise scale: clean %.3f, 30%% random %.3f, 30%% structured %.3f "
        "(structured recall %.3f)\n",
        s_clean, s_random, s_structured, recall);
    assert_true(s_clean > 0.8 && s_clean < 1.25);
    assert_true(s_random > 0.8 && s_random < 1.25);
    assert_true(s_structured > 0.8 && s_structured < 1.5);
}

/* GIVEN no translation between the frames WHEN running OPRF THEN it flags degenerate motion and
 * still separates random outliers with the rotation-only transfer check. */
static void oprf_falls_back_to_rotation_only_without_translation(void **state) {
    (void)state;
    SFD_REQ("SFD-OPRF-007");
    sim_pair_opts_t o = sim_pair_default_opts();
    o.translation_m = 0.0;
    o.prior_p_sigma_m = 0.002;
    static sfd_assoc_t assoc;
    sfd_assoc_params_t ap;
    sfd_assoc_params_default(&ap);
    assert_status(sfd_assoc_init(&assoc, &ap), SFD_OK);
    counts_t c = {0, 0, 0, 0, 0};
    for (int t = 0; t < 5; ++t) {
        sim_pair_make(&pair, &o, 300U + (uint64_t)t);
        assert_status(sfd_assoc_run(&assoc, &g_aw, &pair.ekf, &pair.cam, pair.prev_R_CtoW,
                                    pair.prev_p_C, pair.m, pair.n, &res),
                      SFD_OK);
        assert_int_equal(res.degenerate_motion, 1);
        tally(&pair, &res, &c);
    }
    print_message("degenerate: precision %.4f recall %.4f\n", precision(&c), recall(&c));
    assert_true(precision(&c) >= 0.95 && recall(&c) >= 0.95);
}

/* GIVEN matches whose landmark is behind the camera or missing, with a NaN pixel, a landmark
 * covariance not finite, or a pixel noise excess dC not finite or with I + dC not positive
 * definite WHEN running THEN those are UNTESTED and the others (one with a valid anisotropic
 * excess) are judged; bad arguments give status codes. */
static void invalid_matches_are_untested_and_bad_arguments_rejected(void **state) {
    (void)state;
    SFD_REQ("SFD-OPRF-008");
    static sfd_assoc_t assoc;
    sfd_assoc_params_t ap;
    sfd_assoc_params_default(&ap);
    assert_status(sfd_assoc_init(&assoc, &ap), SFD_OK);
    sim_pair_opts_t o = sim_pair_default_opts();
    o.n = 30;
    sim_pair_make(&pair, &o, 4);
    for (int k = 0; k < 3; ++k) {
        pair.landmark_W_m[0][k] = 2.0 * pair.prev_p_C[k] - pair.landmark_W_m[0][k];
    }
    pair.m[1].uv_px[0] = NAN;
    pair.m[2].landmark_W_m = NULL; /* no landmark: unusable, as one behind the camera */
    pair.m[3].landmark_cov_m2 = NULL;
    pair.landmark_cov_m2[4][8] = NAN; /* a landmark covariance not finite */
    /* pixel noise excess: not finite in either frame, or I + dC not positive definite */
    pair.m[5].noise.prev_dC[1] = NAN;
    pair.m[6].noise.curr_dC[2] = INFINITY;
    pair.m[7].noise.prev_dC[0] = -1.5F;                             /* xx = -0.5 */
    pair.m[8].noise.curr_dC[0] = pair.m[8].noise.curr_dC[2] = 1.0F; /* det = 4 - 9 < 0 */
    pair.m[8].noise.curr_dC[1] = 3.0F;
    pair.m[9].noise.prev_dC[0] = pair.m[9].noise.curr_dC[2] = 0.5F; /* a valid excess */
    pair.m[9].noise.prev_dC[1] = -0.25F;
    assert_status(sfd_assoc_run(&assoc, &g_aw, &pair.ekf, &pair.cam, pair.prev_R_CtoW,
                                pair.prev_p_C, pair.m, pair.n, &res),
                  SFD_OK);
    for (int i = 0; i < 9; ++i) assert_int_equal(res.status[i], SFD_VERDICT_UNTESTED);
    assert_int_not_equal(res.status[9], SFD_VERDICT_UNTESTED);
    assert_int_equal(res.num_untested, 9);
    assert_int_equal(res.num_consistent + res.num_spurious, pair.n - 9);
    assert_status(sfd_assoc_run(&assoc, &g_aw, &pair.ekf, &pair.cam, pair.prev_R_CtoW,
                                pair.prev_p_C, pair.m, SFD_MAX_FEATURES + 1, &res),
                  SFD_ERR_INVAL);
    assert_status(
        sfd_assoc_run(&assoc, &g_aw, &pair.ekf, &pair.cam, NULL, pair.prev_p_C, pair.m, 3, &res),
        SFD_ERR_INVAL);
    assert_status(sfd_assoc_run(&assoc, NULL, &pair.ekf, &pair.cam, pair.prev_R_CtoW, pair.prev_p_C,
                                pair.m, 3, &res),
                  SFD_ERR_INVAL); /* no work space */
    ap.method = SFD_METHOD_PARITY;
    assert_status(sfd_assoc_init(&assoc, &ap), SFD_ERR_INVAL);
    ap.method = SFD_METHOD_OPRF;
    ap.max_hypotheses = SFD_MAX_HYPOTHESES + 1;
    assert_status(sfd_assoc_init(&assoc, &ap), SFD_ERR_CAPACITY);
    static sfd_assoc_t fresh;
    memset(&fresh, 0, sizeof fresh);
    assert_status(sfd_assoc_run(&fresh, &g_aw, &pair.ekf, &pair.cam, pair.prev_R_CtoW,
                                pair.prev_p_C, pair.m, 3, &res),
                  SFD_ERR_STATE);
}

/* GIVEN a selection WHEN applying THEN select + apply equals sfd_assoc_run bit for bit; apply
 * without a selection, with another match count, or after the filter moved is refused
 * (SFD_ERR_STATE) and changes nothing. */
static void select_then_apply_equals_run_and_checks_its_sequence(void **state) {
    (void)state;
    SFD_REQ("SFD-OPRF-009");
    static sfd_assoc_t a1, a2;
    static sfd_assoc_result_t r1, r2;
    static sim_pair_t p1, p2;
    sfd_assoc_params_t ap;
    sfd_assoc_params_default(&ap);
    const sim_pair_opts_t o = sim_pair_default_opts();
    assert_int_equal(sim_pair_make(&p1, &o, 21), 0);
    sim_pair_copy(&p2, &p1);
    assert_status(sfd_assoc_init(&a1, &ap), SFD_OK);
    assert_status(sfd_assoc_init(&a2, &ap), SFD_OK);
    assert_status(
        sfd_assoc_run(&a1, &g_aw, &p1.ekf, &p1.cam, p1.prev_R_CtoW, p1.prev_p_C, p1.m, p1.n, &r1),
        SFD_OK);
    assert_status(sfd_assoc_apply(&a2, &g_aw, &p2.ekf, &p2.cam, p2.m, p2.n, &r2), SFD_ERR_STATE);
    assert_status(sfd_assoc_select(&a2, &g_aw, &p2.ekf, &p2.cam, p2.prev_R_CtoW, p2.prev_p_C, p2.m,
                                   p2.n, &r2),
                  SFD_OK);
    /* the provisional verdicts are set 1: every match judged, none untested */
    assert_int_equal(r2.num_consistent + r2.num_spurious, p2.n);
    assert_status(sfd_assoc_apply(&a2, &g_aw, &p2.ekf, &p2.cam, p2.m, p2.n - 1, &r2),
                  SFD_ERR_STATE);
    sfd_ekf_t moved = p2.ekf;
    moved.p_IinW_m[0] += 1e-9;
    assert_status(sfd_assoc_apply(&a2, &g_aw, &moved, &p2.cam, p2.m, p2.n, &r2), SFD_ERR_STATE);
    assert_status(sfd_assoc_apply(&a2, &g_aw, &p2.ekf, &p2.cam, p2.m, p2.n, &r2), SFD_OK);
    assert_memory_equal(&r1, &r2, sizeof r1);
    assert_memory_equal(&p1.ekf, &p2.ekf, sizeof p1.ekf);
    /* a second apply needs a new selection */
    assert_status(sfd_assoc_apply(&a2, &g_aw, &p2.ekf, &p2.cam, p2.m, p2.n, &r2), SFD_ERR_STATE);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(oprf_detects_random_outliers_and_improves_the_pose),
        cmocka_unit_test(ransac1_detects_random_outliers),
        cmocka_unit_test(ransacf_detects_random_outliers),
        cmocka_unit_test(zero_outliers_keep_every_match),
        cmocka_unit_test(hypotheses_never_exceed_the_budget),
        cmocka_unit_test(same_seed_gives_identical_verdicts),
        cmocka_unit_test(oprf_falls_back_to_rotation_only_without_translation),
        cmocka_unit_test(invalid_matches_are_untested_and_bad_arguments_rejected),
        cmocka_unit_test(select_then_apply_equals_run_and_checks_its_sequence),
        cmocka_unit_test(distorted_edge_false_alarms_are_calibrated_with_the_jacobian),
        cmocka_unit_test(oprf_noise_scale_is_not_inflated_by_outliers),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
