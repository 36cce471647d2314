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

#include "sfd_pair_sim.h"

typedef struct {
    long tp, fp, tn, fn, untested;
} counts_t;

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
        assert_status(sfd_assoc_run(&assoc, &pair.ekf, &pair.cam, pair.prev_R_CtoW, pair.prev_p_C,
                                    pair.m, pair.n, &res),
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
            assert_status(sfd_assoc_run(&assoc, &pair.ekf, &pair.cam, pair.prev_R_CtoW,
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
    p2 = p1;
    assert_status(sfd_assoc_init(&a1, &ap), SFD_OK);
    assert_status(sfd_assoc_init(&a2, &ap), SFD_OK);
    assert_status(
        sfd_assoc_run(&a1, &p1.ekf, &p1.cam, p1.prev_R_CtoW, p1.prev_p_C, p1.m, p1.n, &r1), SFD_OK);
    assert_status(
        sfd_assoc_run(&a2, &p2.ekf, &p2.cam, p2.prev_R_CtoW, p2.prev_p_C, p2.m, p2.n, &r2), SFD_OK);
    assert_memory_equal(&r1, &r2, sizeof r1);
    assert_memory_equal(&p1.ekf, &p2.ekf, sizeof p1.ekf);
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
        assert_status(sfd_assoc_run(&assoc, &pair.ekf, &pair.cam, pair.prev_R_CtoW, pair.prev_p_C,
                                    pair.m, pair.n, &res),
                      SFD_OK);
        assert_int_equal(res.degenerate_motion, 1);
        tally(&pair, &res, &c);
    }
    print_message("degenerate: precision %.4f recall %.4f\n", precision(&c), recall(&c));
    assert_true(precision(&c) >= 0.95 && recall(&c) >= 0.95);
}

/* GIVEN a match whose landmark is behind the camera and one with a NaN pixel WHEN running THEN
 * both are UNTESTED and the others are judged; bad arguments give status codes. */
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
        pair.m[0].obs.landmark_W_m[k] = 2.0 * pair.prev_p_C[k] - pair.m[0].obs.landmark_W_m[k];
    }
    pair.m[1].obs.uv_px[0] = NAN;
    assert_status(sfd_assoc_run(&assoc, &pair.ekf, &pair.cam, pair.prev_R_CtoW, pair.prev_p_C,
                                pair.m, pair.n, &res),
                  SFD_OK);
    assert_int_equal(res.status[0], SFD_VERDICT_UNTESTED);
    assert_int_equal(res.status[1], SFD_VERDICT_UNTESTED);
    assert_int_equal(res.num_untested, 2);
    assert_int_equal(res.num_consistent + res.num_spurious, pair.n - 2);
    assert_status(sfd_assoc_run(&assoc, &pair.ekf, &pair.cam, pair.prev_R_CtoW, pair.prev_p_C,
                                pair.m, SFD_MAX_FEATURES + 1, &res),
                  SFD_ERR_INVAL);
    assert_status(sfd_assoc_run(&assoc, &pair.ekf, &pair.cam, NULL, pair.prev_p_C, pair.m, 3, &res),
                  SFD_ERR_INVAL);
    ap.method = SFD_METHOD_PARITY;
    assert_status(sfd_assoc_init(&assoc, &ap), SFD_ERR_INVAL);
    ap.method = SFD_METHOD_OPRF;
    ap.max_hypotheses = SFD_MAX_HYPOTHESES + 1;
    assert_status(sfd_assoc_init(&assoc, &ap), SFD_ERR_CAPACITY);
    static sfd_assoc_t fresh;
    memset(&fresh, 0, sizeof fresh);
    assert_status(sfd_assoc_run(&fresh, &pair.ekf, &pair.cam, pair.prev_R_CtoW, pair.prev_p_C,
                                pair.m, 3, &res),
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
    p2 = p1;
    assert_status(sfd_assoc_init(&a1, &ap), SFD_OK);
    assert_status(sfd_assoc_init(&a2, &ap), SFD_OK);
    assert_status(
        sfd_assoc_run(&a1, &p1.ekf, &p1.cam, p1.prev_R_CtoW, p1.prev_p_C, p1.m, p1.n, &r1), SFD_OK);
    assert_status(sfd_assoc_apply(&a2, &p2.ekf, &p2.cam, p2.m, p2.n, &r2), SFD_ERR_STATE);
    assert_status(
        sfd_assoc_select(&a2, &p2.ekf, &p2.cam, p2.prev_R_CtoW, p2.prev_p_C, p2.m, p2.n, &r2),
        SFD_OK);
    /* the provisional verdicts are set 1: every match judged, none untested */
    assert_int_equal(r2.num_consistent + r2.num_spurious, p2.n);
    assert_status(sfd_assoc_apply(&a2, &p2.ekf, &p2.cam, p2.m, p2.n - 1, &r2), SFD_ERR_STATE);
    sfd_ekf_t moved = p2.ekf;
    moved.p_IinW_m[0] += 1e-9;
    assert_status(sfd_assoc_apply(&a2, &moved, &p2.cam, p2.m, p2.n, &r2), SFD_ERR_STATE);
    assert_status(sfd_assoc_apply(&a2, &p2.ekf, &p2.cam, p2.m, p2.n, &r2), SFD_OK);
    assert_memory_equal(&r1, &r2, sizeof r1);
    assert_memory_equal(&p1.ekf, &p2.ekf, sizeof p1.ekf);
    /* a second apply needs a new selection */
    assert_status(sfd_assoc_apply(&a2, &p2.ekf, &p2.cam, p2.m, p2.n, &r2), SFD_ERR_STATE);
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
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
