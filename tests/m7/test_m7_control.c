/* SPDX-License-Identifier: MIT */
/* The target harness's own test (m7.harness, m7.harness_positive_control): passing assertions
 * of every kind the runner implements, skip(), and, built with -DSFD_M7_DELIBERATE_FAILURE, one
 * assertion that fails, which must reach QEMU's exit status through the runner (1 failed test),
 * newlib's exit and semihosting's SYS_EXIT_EXTENDED. */
#include "sfd_test.h"

#include <string.h>

static void m7_assertions_pass(void **state) {
    (void)state;
    const unsigned char a[4] = {1, 2, 3, 4};
    unsigned char b[4];
    memcpy(b, a, sizeof b);
    int x = 42;
    assert_true(x == 42);
    assert_false(x != 42);
    assert_non_null(&x);
    assert_null(NULL);
    assert_int_equal(-1, -1);
    assert_int_not_equal(-1, 1);
    assert_status(3, 3);
    assert_in_range(5, 0, 9);
    assert_string_equal("m7", "m7");
    assert_memory_equal(a, b, sizeof a);
    assert_near(sqrt(2.0) * sqrt(2.0), 2.0, 1e-15);
    /* Hard-float double arithmetic and newlib's printf of a double and a 64-bit integer. */
    char text[64];
    (void)snprintf(text, sizeof text, "%.17g %llx", 0.1 + 0.2, 0x123456789abcdefULL);
    assert_string_equal(text, "0.30000000000000004 123456789abcdef");
    print_message("m7: assertions pass\n");
}

static void m7_skip_is_not_a_failure(void **state) {
    (void)state;
    skip();
}

#ifdef SFD_M7_DELIBERATE_FAILURE
static void m7_deliberate_failure(void **state) {
    (void)state;
    assert_int_equal(1 + 1, 3);
    print_message("m7: not reached\n");
}
#endif

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(m7_assertions_pass),
        cmocka_unit_test(m7_skip_is_not_a_failure),
#ifdef SFD_M7_DELIBERATE_FAILURE
        cmocka_unit_test(m7_deliberate_failure),
#endif
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
