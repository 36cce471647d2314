/* SPDX-License-Identifier: MIT */
/* unit.ransac_common: the adaptive hypothesis count of Kilic 2014 eq. (27). */
#include "sfd_test.h"

#include <sfd/sfd_ransac.h>

/* GIVEN p, inlier ratio and sample size WHEN counting hypotheses THEN the value is
 * ceil(log(1-p)/log(1-(1-eps)^m)) as computed independently (Python math.log1p). */
static void hypothesis_count_matches_eq27(void **state) {
    (void)state;
    assert_int_equal(sfd_ransac_hypothesis_count(0.99, 0.7, 1, 256), 4);
    assert_int_equal(sfd_ransac_hypothesis_count(0.99, 0.5, 1, 256), 7);
    assert_int_equal(sfd_ransac_hypothesis_count(0.99, 0.7, 8, 256), 78);
    assert_int_equal(sfd_ransac_hypothesis_count(0.999, 0.9, 1, 256), 3);
    assert_int_equal(sfd_ransac_hypothesis_count(0.99, 0.01, 1, 1000), 459);
}

/* GIVEN a count above the budget WHEN counting THEN the budget is returned, never more. */
static void hypothesis_count_never_exceeds_budget(void **state) {
    (void)state;
    assert_int_equal(sfd_ransac_hypothesis_count(0.99, 0.5, 8, 256), 256); /* eq. 27: 1177 */
    assert_int_equal(sfd_ransac_hypothesis_count(0.99, 0.01, 1, 100), 100);
    assert_int_equal(sfd_ransac_hypothesis_count(0.99, 0.7, 1, 3), 3);
    assert_int_equal(sfd_ransac_hypothesis_count(0.99, 0.7, 1, 0), 1);
}

/* GIVEN the edge cases where eq. (27) has no finite value WHEN counting THEN all-inlier gives
 * one hypothesis and no inliers / bad arguments give the budget. */
static void hypothesis_count_edge_cases(void **state) {
    (void)state;
    assert_int_equal(sfd_ransac_hypothesis_count(0.99, 1.0, 1, 50), 1);
    assert_int_equal(sfd_ransac_hypothesis_count(0.99, 0.0, 1, 50), 50);
    assert_int_equal(sfd_ransac_hypothesis_count(0.99, -0.5, 1, 50), 50);
    assert_int_equal(sfd_ransac_hypothesis_count(0.99, 0.5, 0, 50), 50);
    assert_int_equal(sfd_ransac_hypothesis_count(0.99, 0.5, 65, 50), 50);
    assert_int_equal(sfd_ransac_hypothesis_count(1.0, 0.5, 1, 50), 50);
    assert_int_equal(sfd_ransac_hypothesis_count(0.0, 0.5, 1, 50), 50);
    assert_int_equal(sfd_ransac_hypothesis_count(0.99, 0.0 / 0.0, 1, 50), 50);
    /* (1-eps)^m underflows: 1e-5^64 < DBL_MIN */
    assert_int_equal(sfd_ransac_hypothesis_count(0.99, 1e-5, 64, 50), 50);
    /* barely any outliers: a single hypothesis suffices */
    assert_int_equal(sfd_ransac_hypothesis_count(0.5, 0.9999, 1, 50), 1);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(hypothesis_count_matches_eq27),
        cmocka_unit_test(hypothesis_count_never_exceeds_budget),
        cmocka_unit_test(hypothesis_count_edge_cases),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
