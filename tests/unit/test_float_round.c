/* SPDX-License-Identifier: MIT */
/* unit.float_round: sfd_float_round_trip (core/src/float_round.h), the rounding of a double to
 * what float storage keeps, which the checks "still valid once stored as float" of the parity
 * detector, the window filter and the navigation rely on. */
#include "sfd_test.h"

#include <float.h>

#include "float_round.h"

/* Values the test cannot know at compile time (so nothing is folded before run time). */
static volatile double g_in[2] = {1.0 / 3.0, -0.30806395596568226};

/* A plain round trip written the way GCC 12.2's SLP vectorizer pairs it (in place; not inlined,
 * so that the shape the miscompile needs does not depend on the caller). */
__attribute__((noinline)) static void plain_round_trip_pair(double x[2]) {
    x[0] = (double)(float)x[0];
    x[1] = (double)(float)x[1];
}

static void round_trip_pair(double x[2]) {
    x[0] = sfd_float_round_trip(x[0]);
    x[1] = sfd_float_round_trip(x[1]);
}

/* GIVEN doubles that are not floats WHEN rounded in place as a pair THEN each becomes the float
 * nearest to it, read back exactly: within half a float ulp, never the unrounded double. The
 * plain conversion is compiled and run beside it and its outcome printed (GCC 12.2 at -O2/-O3
 * returns the unrounded doubles), without asserting on it: it is the compiler's, not ours. */
static void a_pair_rounded_in_place_is_the_nearest_floats(void **state) {
    (void)state;
    double x[2] = {g_in[0], g_in[1]};
    round_trip_pair(x);
    for (int k = 0; k < 2; ++k) {
        const float f = (float)g_in[k]; /* scalar: converted at run time */
        assert_true(x[k] == (double)f);
        assert_true(x[k] != g_in[k]);
        assert_true(x[k] - g_in[k] <= 0.5 * FLT_EPSILON * (g_in[k] < 0 ? -g_in[k] : g_in[k]));
        assert_true(g_in[k] - x[k] <= 0.5 * FLT_EPSILON * (g_in[k] < 0 ? -g_in[k] : g_in[k]));
    }
    double y[2] = {g_in[0], g_in[1]};
    plain_round_trip_pair(y);
    print_message("plain (double)(float) pair in place: %s\n",
                  (y[0] != g_in[0] && y[1] != g_in[1]) ? "rounded" : "NOT rounded (compiler)");
}

/* GIVEN values float holds exactly, beyond float's range and NaN WHEN rounded THEN the exact
 * ones are unchanged, the large ones become infinite and NaN stays NaN. */
static void exact_values_stay_and_out_of_range_ones_overflow(void **state) {
    (void)state;
    assert_true(sfd_float_round_trip(0.5) == 0.5);
    assert_true(sfd_float_round_trip(-3.0) == -3.0);
    assert_true(sfd_float_round_trip((double)FLT_MAX) == (double)FLT_MAX);
    const double big = g_in[0] * 3e39;
    assert_true(sfd_float_round_trip(big) > (double)FLT_MAX);
    const double nan = g_in[0] * 0.0 / 0.0;
    const double r = sfd_float_round_trip(nan);
    assert_true(r != r);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(a_pair_rounded_in_place_is_the_nearest_floats),
        cmocka_unit_test(exact_values_stay_and_out_of_range_ones_overflow),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
