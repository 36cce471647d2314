/* SPDX-License-Identifier: MIT */
/* unit.time_guard: the time-glitch policy of one input stream (sfd/sfd_time_guard.h). */
#include "sfd_test.h"

#include <sfd/sfd_time_guard.h>

static sfd_time_guard_t g_a, g_b;

static void init_both(int64_t horizon_us, int32_t n) {
    sfd_time_guard_params_t prm = {horizon_us, n};
    assert_status(sfd_time_guard_init(&g_a, &prm), SFD_OK);
    assert_status(sfd_time_guard_init(&g_b, &prm), SFD_OK);
}

/* GIVEN a stream at t = 10 s, H = 0.5 s, N = 3 WHEN messages come in order, duplicated, a little
 * back, far back or far ahead THEN accept / order / order / jump / jump, and a refused message
 * never moves the reference. */
static void in_step_duplicate_reordered_and_jumped_messages(void **state) {
    (void)state;
    init_both(500000, 3);
    assert_int_equal(sfd_time_guard_check(&g_a, 10000000, NULL), SFD_TIME_ACCEPT);
    assert_int_equal(sfd_time_guard_check(&g_a, 10005000, NULL), SFD_TIME_ACCEPT);
    assert_int_equal(sfd_time_guard_check(&g_a, 10005000, NULL), SFD_TIME_ORDER);
    assert_int_equal(sfd_time_guard_check(&g_a, 9505001, NULL), SFD_TIME_ORDER);   /* H - 1 back */
    assert_int_equal(sfd_time_guard_check(&g_a, 9505000, NULL), SFD_TIME_JUMP);    /* H back */
    assert_int_equal(sfd_time_guard_check(&g_a, 10505000, NULL), SFD_TIME_ACCEPT); /* H ahead */
    assert_int_equal(sfd_time_guard_check(&g_a, 11005001, NULL), SFD_TIME_JUMP);   /* H + 1 */
    assert_int_equal(sfd_time_guard_check(&g_a, INT64_MAX, NULL), SFD_TIME_JUMP);
    assert_int_equal(sfd_time_guard_check(&g_a, INT64_MIN, NULL), SFD_TIME_JUMP);
    assert_true(g_a.ref_us == 10505000);
    assert_int_equal(sfd_time_guard_check(&g_a, 10510000, NULL), SFD_TIME_ACCEPT);
}

/* GIVEN a stream at 100 s WHEN it restarts at 0 and sends N = 3 messages 5 ms apart THEN the
 * first two are jumps and the third is the new time base (RESYNC), after which the stream goes
 * on; a run is broken by an accepted message, by a message not after the run's last, and by a
 * gap larger than H inside it. */
static void a_sustained_jump_is_a_new_time_base_after_n_consistent_messages(void **state) {
    (void)state;
    init_both(500000, 3);
    assert_int_equal(sfd_time_guard_check(&g_a, 100000000, NULL), SFD_TIME_ACCEPT);
    assert_int_equal(sfd_time_guard_check(&g_a, 0, NULL), SFD_TIME_JUMP);
    assert_int_equal(sfd_time_guard_check(&g_a, 5000, NULL), SFD_TIME_JUMP);
    assert_int_equal(sfd_time_guard_check(&g_a, 10000, NULL), SFD_TIME_RESYNC);
    assert_true(g_a.ref_us == 10000);
    assert_int_equal(sfd_time_guard_check(&g_a, 15000, NULL), SFD_TIME_ACCEPT);
    /* broken by an accepted message in between */
    assert_int_equal(sfd_time_guard_check(&g_a, 50000000, NULL), SFD_TIME_JUMP);
    assert_int_equal(sfd_time_guard_check(&g_a, 50005000, NULL), SFD_TIME_JUMP);
    assert_int_equal(sfd_time_guard_check(&g_a, 20000, NULL), SFD_TIME_ACCEPT);
    assert_int_equal(sfd_time_guard_check(&g_a, 50010000, NULL), SFD_TIME_JUMP);
    assert_int_equal(g_a.run, 1);
    /* broken by a message not after the run's last, and by a gap larger than H */
    assert_int_equal(sfd_time_guard_check(&g_a, 50010000, NULL), SFD_TIME_JUMP);
    assert_int_equal(g_a.run, 1);
    assert_int_equal(sfd_time_guard_check(&g_a, 50510001, NULL), SFD_TIME_JUMP);
    assert_int_equal(g_a.run, 1);
    assert_int_equal(sfd_time_guard_check(&g_a, 50515000, NULL), SFD_TIME_JUMP);
    assert_int_equal(sfd_time_guard_check(&g_a, 50520000, NULL), SFD_TIME_RESYNC);
    /* INT64_MAX glitches never form a run (none is after the previous) */
    for (int i = 0; i < 10; ++i) {
        assert_int_equal(sfd_time_guard_check(&g_a, INT64_MAX, NULL), SFD_TIME_JUMP);
    }
}

/* GIVEN an IMU stream (b) at 10 s WHEN the frame stream (a) has no reference THEN its first
 * message is in step within H of the IMU either way and a jump otherwise; a frame stream whose
 * own reference is old (a camera pause longer than H while the IMU runs) accepts a frame within
 * H of the IMU. */
static void a_stream_without_reference_is_judged_by_the_other(void **state) {
    (void)state;
    init_both(500000, 3);
    assert_int_equal(sfd_time_guard_check(&g_b, 10000000, NULL), SFD_TIME_ACCEPT);
    assert_int_equal(sfd_time_guard_check(&g_a, 10600000, &g_b), SFD_TIME_JUMP);
    assert_int_equal(sfd_time_guard_check(&g_a, 9400000, &g_b), SFD_TIME_JUMP);
    assert_int_equal(sfd_time_guard_check(&g_a, 9600000, &g_b), SFD_TIME_ACCEPT);
    /* the camera pauses 2 s while the IMU runs */
    assert_int_equal(sfd_time_guard_check(&g_b, 10400000, &g_a), SFD_TIME_ACCEPT);
    assert_int_equal(sfd_time_guard_check(&g_b, 10800000, &g_a), SFD_TIME_ACCEPT);
    assert_int_equal(sfd_time_guard_check(&g_b, 11200000, &g_a), SFD_TIME_ACCEPT);
    assert_int_equal(sfd_time_guard_check(&g_b, 11600000, &g_a), SFD_TIME_ACCEPT);
    assert_int_equal(sfd_time_guard_check(&g_a, 11650000, &g_b), SFD_TIME_ACCEPT);
    /* without the IMU, the same pause would have been a jump */
    sfd_time_guard_reset(&g_a);
    assert_int_equal(sfd_time_guard_check(&g_a, 9600000, NULL), SFD_TIME_ACCEPT);
    assert_int_equal(sfd_time_guard_check(&g_a, 11650000, NULL), SFD_TIME_JUMP);
}

/* GIVEN parameters out of range THEN init refuses them and leaves the guard alone. */
static void parameters_out_of_range_are_refused(void **state) {
    (void)state;
    sfd_time_guard_params_t prm;
    sfd_time_guard_params_default(&prm);
    assert_true(prm.horizon_us == 500000);
    assert_int_equal(prm.resync_messages, 5);
    assert_status(sfd_time_guard_params_validate(&prm), SFD_OK);
    assert_status(sfd_time_guard_params_validate(NULL), SFD_ERR_INVAL);
    sfd_time_guard_params_t bad = prm;
    bad.horizon_us = 0;
    assert_status(sfd_time_guard_init(&g_a, &bad), SFD_ERR_INVAL);
    bad = prm;
    bad.resync_messages = 1;
    assert_status(sfd_time_guard_init(&g_a, &bad), SFD_ERR_INVAL);
    bad.resync_messages = 1001;
    assert_status(sfd_time_guard_init(&g_a, &bad), SFD_ERR_INVAL);
    assert_status(sfd_time_guard_init(NULL, &prm), SFD_ERR_INVAL);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(in_step_duplicate_reordered_and_jumped_messages),
        cmocka_unit_test(a_sustained_jump_is_a_new_time_base_after_n_consistent_messages),
        cmocka_unit_test(a_stream_without_reference_is_judged_by_the_other),
        cmocka_unit_test(parameters_out_of_range_are_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
