/* SPDX-License-Identifier: MIT */
/* Unit tests of the chi-square module (sfd_chi2.h). Requirements: core/docs/chi_square.md.
 *
 * Reference values: "published" ones are the 4-decimal entries of the standard chi-square tables
 * (e.g. Abramowitz & Stegun table 26.8, NIST/SEMATECH e-Handbook 1.3.6.7.4), each re-checked
 * with scipy.stats.chi2. The 12+ digit ones were computed with scipy 1.11
 * (scipy.stats.chi2.isf / .cdf / .sf, scipy.stats.ncx2.cdf) and agree with a 40-digit mpmath
 * evaluation to better than 1e-14 relative, except where noted. */
#include "sfd_test.h"

#include <string.h>

#include "sfd/sfd_chi2.h"

#define ARRAY_LEN(a) (sizeof(a) / sizeof((a)[0]))

/* Relative tolerance of the quantile and CDF against the high-precision references. The
 * header promises ~1e-12; measured worst case over the supported range is ~6e-15. */
#define REL_TOL_QUANTILE 1e-12
#define REL_TOL_CDF 1e-12

/* Bit-exact comparison of two doubles (for "output untouched" and "table equals quantile"). */
static int same_bits(double a, double b) {
    uint64_t ba, bb;
    memcpy(&ba, &a, sizeof ba);
    memcpy(&bb, &b, sizeof bb);
    return ba == bb;
}

static double quantile_or_fail(double alpha, int dof) {
    double x = -1.0;
    assert_status(sfd_chi2_quantile_upper(alpha, dof, &x), SFD_OK);
    return x;
}

/* ---- SFD-CHI-002: quantile --------------------------------------------------------------- */

typedef struct {
    double alpha; /* upper-tail probability */
    int dof;
    double table; /* published 4-decimal value */
    double ref;   /* scipy.stats.chi2.isf(alpha, dof), 16-17 digits */
} quantile_case_t;

/* Lower-tail table columns chi2_p(k) are entered as alpha = 1 - p. */
static const quantile_case_t kQuantileCases[] = {
    {0.01, 2, 9.2103, 9.21034037197618},      /* chi2_0.99(2)  */
    {0.01, 3, 11.3449, 11.344866730144373},   /* chi2_0.99(3)  */
    {0.05, 6, 12.5916, 12.591587243743977},   /* chi2_0.95(6)  */
    {0.001, 1, 10.8276, 10.827566170662733},  /* chi2_0.999(1) */
    {0.05, 1, 3.8415, 3.841458820694124},     /* chi2_0.95(1)  */
    {0.05, 2, 5.9915, 5.991464547107979},     /* chi2_0.95(2)  */
    {0.10, 20, 28.4120, 28.41198058430563},   /* chi2_0.90(20) */
    {0.005, 30, 53.6720, 53.671961930240585}, /* chi2_0.995(30) */
    {0.05, 50, 67.5048, 67.5048065495412},    /* chi2_0.95(50) */
    {0.01, 64, 93.2169, 93.21685966023843},   /* chi2_0.99(64) */
    {0.99, 10, 2.5582, 2.5582121601872066},   /* chi2_0.01(10), lower quantile */
    {0.99, 64, 40.6486, 40.648562828972494},  /* chi2_0.01(64), lower quantile */
    {0.995, 5, 0.4117, 0.41174190383249899},  /* chi2_0.005(5), lower quantile */
    {0.95, 1, 0.0039, 0.0039321400000195297}, /* chi2_0.05(1), lower quantile */
};

static void chi2_quantile_published_table_matches_4_decimals(void **state) {
    (void)state;
    SFD_REQ("SFD-CHI-002");
    /* GIVEN the published table entries (rounded to 4 decimals)
     * WHEN the upper-alpha quantile is computed
     * THEN it rounds to the published value (|error| <= 0.5e-4) */
    for (size_t i = 0; i < ARRAY_LEN(kQuantileCases); ++i) {
        const quantile_case_t *c = &kQuantileCases[i];
        assert_near(quantile_or_fail(c->alpha, c->dof), c->table, 0.5e-4 + 1e-12);
    }
}

static void chi2_quantile_reference_points_match_to_1e_12_relative(void **state) {
    (void)state;
    SFD_REQ("SFD-CHI-002");
    /* GIVEN 16-digit reference quantiles, including large dof and lower quantiles
     * WHEN the quantile is computed
     * THEN the relative error is below 1e-12 */
    for (size_t i = 0; i < ARRAY_LEN(kQuantileCases); ++i) {
        const quantile_case_t *c = &kQuantileCases[i];
        assert_near(quantile_or_fail(c->alpha, c->dof), c->ref, REL_TOL_QUANTILE * c->ref);
    }
}

static void chi2_quantile_extreme_alpha_matches_reference(void **state) {
    (void)state;
    SFD_REQ("SFD-CHI-002");
    /* GIVEN false-alarm rates down to 1e-299 and lower quantiles with p = 2^-40
     * WHEN the quantile is computed
     * THEN it matches the high-precision reference to 1e-12 relative */
    static const struct {
        double alpha;
        int dof;
        double ref;
    } cases[] = {
        {1e-10, 4, 52.66796321106174},   /* scipy chi2.isf */
        {1e-6, 32, 85.23155071709897},   /* scipy chi2.isf */
        {1e-100, 3, 466.2143575712913},  /* scipy chi2.isf */
        {1e-299, 1, 1369.2708113083495}, /* scipy chi2.isf */
        {0.5, 1, 0.45493642311957275},   /* median, mpmath (scipy: ...572) */
        {0.5, 64, 63.334582023531966},   /* median, mpmath */
        /* p = 2^-40: x ~ (pi/2) p^2. mpmath 1.2993322677942484e-24 (scipy's chi2.ppf gives
         * ...2528e-24, 3.4e-15 off). */
        {1.0 - 9.094947017729282e-13, 1, 1.2993322677942484e-24},
    };
    for (size_t i = 0; i < ARRAY_LEN(cases); ++i) {
        assert_near(quantile_or_fail(cases[i].alpha, cases[i].dof), cases[i].ref,
                    REL_TOL_QUANTILE * cases[i].ref);
    }
}

static void chi2_quantile_then_cdf_round_trip_returns_alpha(void **state) {
    (void)state;
    SFD_REQ("SFD-CHI-002");
    SFD_REQ("SFD-CHI-001");
    /* GIVEN every dof in [1, SFD_CHI2_MAX_DOF] and alphas from 1e-200 to 1 - 1e-12
     * WHEN x = quantile(alpha) and then (P, Q) = cdf(x)
     * THEN Q(x) = alpha (upper quantiles) or P(x) = 1 - alpha (lower quantiles), to 1e-11
     *      relative (the tail's sensitivity to x is ~x/2 for large x, hence the margin) */
    static const double alphas[] = {1e-200, 1e-50, 1e-12, 1e-6, 1e-3,  0.01,       0.05,       0.3,
                                    0.5,    0.7,   0.95,  0.99, 0.999, 1.0 - 1e-6, 1.0 - 1e-12};
    for (int dof = 1; dof <= SFD_CHI2_MAX_DOF; ++dof) {
        for (size_t i = 0; i < ARRAY_LEN(alphas); ++i) {
            const double alpha = alphas[i];
            const double x = quantile_or_fail(alpha, dof);
            double p = -1.0;
            double q = -1.0;
            assert_status(sfd_chi2_cdf(x, dof, &p, &q), SFD_OK);
            if (alpha <= 0.5) {
                assert_near(q, alpha, 1e-11 * alpha);
            } else {
                assert_near(p, 1.0 - alpha, 1e-11 * (1.0 - alpha));
            }
        }
    }
}

static void chi2_quantile_increasing_in_dof_and_decreasing_in_alpha(void **state) {
    (void)state;
    SFD_REQ("SFD-CHI-002");
    /* GIVEN a fixed alpha
     * WHEN the quantile is computed for increasing dof (and for a smaller alpha)
     * THEN the thresholds increase strictly */
    double prev = 0.0;
    for (int dof = 1; dof <= SFD_CHI2_MAX_DOF; ++dof) {
        const double x = quantile_or_fail(0.01, dof);
        assert_true(x > prev);
        assert_true(quantile_or_fail(0.001, dof) > x);
        prev = x;
    }
}

/* ---- SFD-CHI-001: central CDF and upper tail ---------------------------------------------- */

static void chi2_cdf_reference_points_match_to_1e_12_relative(void **state) {
    (void)state;
    SFD_REQ("SFD-CHI-001");
    /* GIVEN reference values of P and Q (mpmath, 20 digits)
     * WHEN sfd_chi2_cdf is evaluated
     * THEN both tails match to 1e-12 relative, including a lower tail of 2.6e-15 */
    static const struct {
        double x;
        int dof;
        double p;
        double q;
    } cases[] = {
        {1.0, 1, 0.68268949213708589717, 0.31731050786291410283},
        {3.0, 4, 0.44217459962892542767, 0.55782540037107457233},
        {64.0, 64, 0.52351169452374141096, 0.47648830547625858904},
        {1e-3, 8, 2.603125216982890512e-15, 0.99999999999999739687},
        {50.0, 1, 0.99999999999846254021, 1.5374597944280348502e-12},
        {300.0, 10, 1.0, 1.554674754380318106e-58},
    };
    for (size_t i = 0; i < ARRAY_LEN(cases); ++i) {
        double p = -1.0;
        double q = -1.0;
        assert_status(sfd_chi2_cdf(cases[i].x, cases[i].dof, &p, &q), SFD_OK);
        assert_near(p, cases[i].p, REL_TOL_CDF * cases[i].p);
        assert_near(q, cases[i].q, REL_TOL_CDF * cases[i].q);
    }
}

static void chi2_cdf_far_upper_tail_keeps_relative_precision(void **state) {
    (void)state;
    SFD_REQ("SFD-CHI-001");
    /* GIVEN x far in the upper tail, where 1 - P would be exactly 0
     * WHEN the upper tail is computed
     * THEN Q(200; 2) = exp(-100) and Q(1400; 1) = erfc(sqrt(700)) = 2.101e-306 to 1e-12 */
    double p = -1.0;
    double q = -1.0;
    assert_status(sfd_chi2_cdf(200.0, 2, &p, &q), SFD_OK);
    assert_near(q, exp(-100.0), 1e-13 * exp(-100.0));
    assert_near(p, 1.0, 0.0);
    assert_status(sfd_chi2_cdf(1400.0, 1, &p, &q), SFD_OK);
    assert_near(q, 2.101014516264217495e-306, 1e-12 * 2.101014516264217495e-306);
    /* dof = 2 has the closed form Q = exp(-x/2) everywhere */
    for (int i = 1; i <= 70; ++i) {
        const double x = 10.0 * (double)i;
        assert_status(sfd_chi2_cdf(x, 2, NULL, &q), SFD_OK);
        assert_near(q, exp(-0.5 * x), 1e-13 * exp(-0.5 * x));
    }
}

static void chi2_cdf_tails_are_complementary_and_monotone(void **state) {
    (void)state;
    SFD_REQ("SFD-CHI-001");
    /* GIVEN a grid of x for every dof
     * WHEN P and Q are computed
     * THEN P + Q = 1 (to 2 ulp), 0 <= P, Q <= 1, and P is non-decreasing in x */
    for (int dof = 1; dof <= SFD_CHI2_MAX_DOF; ++dof) {
        double prev = 0.0;
        for (int i = 0; i <= 200; ++i) {
            const double x = 0.01 * (double)(i * i) * (1.0 + 0.05 * (double)dof);
            double p = -1.0;
            double q = -1.0;
            assert_status(sfd_chi2_cdf(x, dof, &p, &q), SFD_OK);
            assert_true(p >= 0.0 && p <= 1.0 && q >= 0.0 && q <= 1.0);
            assert_near(p + q, 1.0, 4.5e-16);
            assert_true(p >= prev);
            prev = p;
        }
    }
}

static void chi2_cdf_zero_x_gives_zero_cdf(void **state) {
    (void)state;
    SFD_REQ("SFD-CHI-001");
    /* GIVEN x = 0
     * WHEN the CDF is computed (outputs are nullable)
     * THEN P = 0 and Q = 1; passing NULL for either output is accepted */
    double p = -1.0;
    double q = -1.0;
    assert_status(sfd_chi2_cdf(0.0, 3, &p, &q), SFD_OK);
    assert_true(same_bits(p, 0.0));
    assert_true(same_bits(q, 1.0));
    assert_status(sfd_chi2_cdf(5.0, 3, NULL, NULL), SFD_OK);
    assert_status(sfd_chi2_cdf(5.0, 3, &p, NULL), SFD_OK);
    assert_status(sfd_chi2_cdf(5.0, 3, NULL, &q), SFD_OK);
    assert_near(p + q, 1.0, 2.3e-16);
}

/* ---- SFD-CHI-003: non-central CDF --------------------------------------------------------- */

static void ncchi2_cdf_reference_points_match_scipy(void **state) {
    (void)state;
    SFD_REQ("SFD-CHI-003");
    /* GIVEN scipy.stats.ncx2.cdf values (lambda from 1e-6 to the 1000 limit)
     * WHEN the non-central CDF is computed
     * THEN it matches to 1e-12 relative (mpmath agrees with scipy to ~1e-15 here) */
    static const struct {
        double x;
        int dof;
        double lambda;
        double ref;
    } cases[] = {
        {5.0, 2, 1e-6, 0.9179148987698466},      {3.0, 1, 2.0, 0.6238689492782098},
        {1.0, 2, 3.0, 0.12182549722936442},      {10.0, 4, 5.0, 0.6382288595823113},
        {60.0, 8, 40.0, 0.8214518427271369},     {120.0, 64, 80.0, 0.12503915415419564},
        {30.0, 64, 10.0, 5.27193075115025e-06},  {50.0, 3, 100.0, 0.0011535247854982166},
        {900.0, 16, 900.0, 0.40127604148244},    {800.0, 6, 1000.0, 0.00031073020773496595},
        {1500.0, 2, 1000.0, 0.9999999999993443},
    };
    for (size_t i = 0; i < ARRAY_LEN(cases); ++i) {
        double cdf = -1.0;
        assert_status(sfd_ncchi2_cdf(cases[i].x, cases[i].dof, cases[i].lambda, &cdf), SFD_OK);
        assert_near(cdf, cases[i].ref, 1e-12 * cases[i].ref);
    }
}

static void ncchi2_cdf_zero_lambda_equals_central(void **state) {
    (void)state;
    SFD_REQ("SFD-CHI-003");
    /* GIVEN lambda = 0
     * WHEN the non-central CDF is computed
     * THEN it equals the central CDF exactly, e.g. 0.9179150013761012 at x = 5, dof = 2 */
    for (int dof = 1; dof <= SFD_CHI2_MAX_DOF; dof += 7) {
        for (int i = 1; i <= 20; ++i) {
            const double x = 0.37 * (double)(i * dof);
            double nc = -1.0;
            double p = -2.0;
            assert_status(sfd_ncchi2_cdf(x, dof, 0.0, &nc), SFD_OK);
            assert_status(sfd_chi2_cdf(x, dof, &p, NULL), SFD_OK);
            assert_true(same_bits(nc, p));
        }
    }
    double nc = -1.0;
    assert_status(sfd_ncchi2_cdf(5.0, 2, 0.0, &nc), SFD_OK);
    assert_near(nc, 0.9179150013761012, 1e-15);
}

static void ncchi2_cdf_decreases_with_lambda(void **state) {
    (void)state;
    SFD_REQ("SFD-CHI-003");
    /* GIVEN a fixed threshold x
     * WHEN lambda grows (a stronger fault)
     * THEN the CDF (missed-detection probability) decreases, stays in [0, 1], and is 0 at x = 0 */
    double prev = 1.0;
    for (int i = 0; i <= 100; ++i) {
        const double lambda = 10.0 * (double)i;
        double cdf = -1.0;
        assert_status(sfd_ncchi2_cdf(40.0, 6, lambda, &cdf), SFD_OK);
        assert_true(cdf >= 0.0 && cdf <= prev);
        prev = cdf;
    }
    double cdf = -1.0;
    assert_status(sfd_ncchi2_cdf(0.0, 6, 50.0, &cdf), SFD_OK);
    assert_true(same_bits(cdf, 0.0));
}

/* ---- SFD-CHI-004: threshold table --------------------------------------------------------- */

static void chi2_table_init_valid_alpha_fills_every_dof(void **state) {
    (void)state;
    SFD_REQ("SFD-CHI-004");
    /* GIVEN alpha = 0.01
     * WHEN the table is initialized
     * THEN alpha is stored, threshold[0] = 0 and threshold[k] equals the quantile bit for bit */
    static sfd_chi2_table_t table;
    memset(&table, 0xA5, sizeof table);
    assert_status(sfd_chi2_table_init(&table, 0.01), SFD_OK);
    assert_true(same_bits(table.alpha, 0.01));
    assert_true(same_bits(table.threshold[0], 0.0));
    for (int k = 1; k <= SFD_CHI2_MAX_DOF; ++k) {
        assert_true(same_bits(table.threshold[k], quantile_or_fail(0.01, k)));
    }
    assert_near(table.threshold[2], 9.2103, 0.5e-4);
    if (SFD_CHI2_MAX_DOF >= 64) {
        assert_near(table.threshold[64], 93.2169, 0.5e-4);
    }
}

static void chi2_table_init_invalid_arguments_rejected(void **state) {
    (void)state;
    SFD_REQ("SFD-CHI-004");
    SFD_REQ("SFD-CHI-005");
    /* GIVEN a null table, or alpha outside (1e-300, 1) or NaN
     * WHEN the table is initialized
     * THEN SFD_ERR_INVAL is returned and the table is left untouched */
    static sfd_chi2_table_t table;
    static sfd_chi2_table_t before;
    memset(&table, 0x5A, sizeof table);
    memcpy(&before, &table, sizeof table);
    assert_status(sfd_chi2_table_init(NULL, 0.01), SFD_ERR_INVAL);
    static const double bad_alphas[] = {0.0, 1.0, -0.01, 1.5, 1e-300};
    for (size_t i = 0; i < ARRAY_LEN(bad_alphas); ++i) {
        assert_status(sfd_chi2_table_init(&table, bad_alphas[i]), SFD_ERR_INVAL);
    }
    assert_status(sfd_chi2_table_init(&table, NAN), SFD_ERR_INVAL);
    assert_status(sfd_chi2_table_init(&table, INFINITY), SFD_ERR_INVAL);
    assert_memory_equal(&table, &before, sizeof table);
}

/* ---- SFD-CHI-005: invalid arguments ------------------------------------------------------- */

static void chi2_cdf_invalid_arguments_rejected_outputs_untouched(void **state) {
    (void)state;
    SFD_REQ("SFD-CHI-005");
    /* GIVEN dof 0, SFD_CHI2_MAX_DOF + 1, negative dof, negative x, NaN or infinite x
     * WHEN sfd_chi2_cdf is called
     * THEN SFD_ERR_INVAL is returned and the outputs keep their values */
    double p = 7.0;
    double q = 8.0;
    assert_status(sfd_chi2_cdf(1.0, 0, &p, &q), SFD_ERR_INVAL);
    assert_status(sfd_chi2_cdf(1.0, SFD_CHI2_MAX_DOF + 1, &p, &q), SFD_ERR_INVAL);
    assert_status(sfd_chi2_cdf(1.0, -3, &p, &q), SFD_ERR_INVAL);
    assert_status(sfd_chi2_cdf(-1e-300, 2, &p, &q), SFD_ERR_INVAL);
    assert_status(sfd_chi2_cdf(-1.0, 2, &p, &q), SFD_ERR_INVAL);
    assert_status(sfd_chi2_cdf(NAN, 2, &p, &q), SFD_ERR_INVAL);
    assert_status(sfd_chi2_cdf(INFINITY, 2, &p, &q), SFD_ERR_INVAL);
    assert_status(sfd_chi2_cdf(-INFINITY, 2, &p, &q), SFD_ERR_INVAL);
    assert_true(same_bits(p, 7.0));
    assert_true(same_bits(q, 8.0));
    /* the boundaries themselves are valid */
    assert_status(sfd_chi2_cdf(1.0, 1, &p, &q), SFD_OK);
    assert_status(sfd_chi2_cdf(1.0, SFD_CHI2_MAX_DOF, &p, &q), SFD_OK);
}

static void chi2_quantile_invalid_arguments_rejected_output_untouched(void **state) {
    (void)state;
    SFD_REQ("SFD-CHI-005");
    /* GIVEN alpha 0, 1, <= 1e-300, > 1, NaN, dof out of range, or a null output
     * WHEN the quantile is requested
     * THEN SFD_ERR_INVAL is returned and the output keeps its value */
    double x = 3.0;
    static const double bad_alphas[] = {0.0, 1.0, 1e-300, 1e-310, -0.5, 2.0};
    for (size_t i = 0; i < ARRAY_LEN(bad_alphas); ++i) {
        assert_status(sfd_chi2_quantile_upper(bad_alphas[i], 4, &x), SFD_ERR_INVAL);
    }
    assert_status(sfd_chi2_quantile_upper(NAN, 4, &x), SFD_ERR_INVAL);
    assert_status(sfd_chi2_quantile_upper(INFINITY, 4, &x), SFD_ERR_INVAL);
    assert_status(sfd_chi2_quantile_upper(0.01, 0, &x), SFD_ERR_INVAL);
    assert_status(sfd_chi2_quantile_upper(0.01, SFD_CHI2_MAX_DOF + 1, &x), SFD_ERR_INVAL);
    assert_status(sfd_chi2_quantile_upper(0.01, 4, NULL), SFD_ERR_INVAL);
    assert_true(same_bits(x, 3.0));
}

static void ncchi2_cdf_invalid_arguments_rejected_output_untouched(void **state) {
    (void)state;
    SFD_REQ("SFD-CHI-005");
    /* GIVEN dof out of range, negative or non-finite x, lambda < 0, > 1000 or NaN, null output
     * WHEN the non-central CDF is requested
     * THEN SFD_ERR_INVAL is returned and the output keeps its value */
    double cdf = 5.0;
    assert_status(sfd_ncchi2_cdf(1.0, 0, 1.0, &cdf), SFD_ERR_INVAL);
    assert_status(sfd_ncchi2_cdf(1.0, SFD_CHI2_MAX_DOF + 1, 1.0, &cdf), SFD_ERR_INVAL);
    assert_status(sfd_ncchi2_cdf(-1.0, 2, 1.0, &cdf), SFD_ERR_INVAL);
    assert_status(sfd_ncchi2_cdf(NAN, 2, 1.0, &cdf), SFD_ERR_INVAL);
    assert_status(sfd_ncchi2_cdf(INFINITY, 2, 1.0, &cdf), SFD_ERR_INVAL);
    assert_status(sfd_ncchi2_cdf(1.0, 2, -1e-9, &cdf), SFD_ERR_INVAL);
    assert_status(sfd_ncchi2_cdf(1.0, 2, 1000.0001, &cdf), SFD_ERR_INVAL);
    assert_status(sfd_ncchi2_cdf(1.0, 2, NAN, &cdf), SFD_ERR_INVAL);
    assert_status(sfd_ncchi2_cdf(1.0, 2, INFINITY, &cdf), SFD_ERR_INVAL);
    assert_status(sfd_ncchi2_cdf(1.0, 2, 1.0, NULL), SFD_ERR_INVAL);
    assert_true(same_bits(cdf, 5.0));
    assert_status(sfd_ncchi2_cdf(1.0, 2, 1000.0, &cdf), SFD_OK); /* the limit is valid */
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(chi2_cdf_reference_points_match_to_1e_12_relative),
        cmocka_unit_test(chi2_cdf_far_upper_tail_keeps_relative_precision),
        cmocka_unit_test(chi2_cdf_tails_are_complementary_and_monotone),
        cmocka_unit_test(chi2_cdf_zero_x_gives_zero_cdf),
        cmocka_unit_test(chi2_quantile_published_table_matches_4_decimals),
        cmocka_unit_test(chi2_quantile_reference_points_match_to_1e_12_relative),
        cmocka_unit_test(chi2_quantile_extreme_alpha_matches_reference),
        cmocka_unit_test(chi2_quantile_then_cdf_round_trip_returns_alpha),
        cmocka_unit_test(chi2_quantile_increasing_in_dof_and_decreasing_in_alpha),
        cmocka_unit_test(ncchi2_cdf_reference_points_match_scipy),
        cmocka_unit_test(ncchi2_cdf_zero_lambda_equals_central),
        cmocka_unit_test(ncchi2_cdf_decreases_with_lambda),
        cmocka_unit_test(chi2_table_init_valid_alpha_fills_every_dof),
        cmocka_unit_test(chi2_table_init_invalid_arguments_rejected),
        cmocka_unit_test(chi2_cdf_invalid_arguments_rejected_outputs_untouched),
        cmocka_unit_test(chi2_quantile_invalid_arguments_rejected_output_untouched),
        cmocka_unit_test(ncchi2_cdf_invalid_arguments_rejected_output_untouched),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
