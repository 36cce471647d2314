/* SPDX-License-Identifier: MIT */
/* unit.imu_ring: the drivers' fixed-capacity IMU ring buffer and frame-motion assembly. */
#include "sfd_test.h"

#include "euroc_calib.h"

#include <math.h>
#include <string.h>

#include <sfd/sfd_imu_ring.h>

static sfd_imu_ring_t g_ring;
static sfd_imu_sample_t g_scratch[SFD_MAX_IMU_SAMPLES];

static sfd_imu_sample_t sample(int64_t t, double wx, double wy, double wz) {
    sfd_imu_sample_t s;
    memset(&s, 0, sizeof s);
    s.t_us = t;
    s.gyro_rad_s[0] = wx;
    s.gyro_rad_s[1] = wy;
    s.gyro_rad_s[2] = wz;
    s.accel_m_s2[2] = 9.81;
    return s;
}

/* GIVEN samples WHEN pushed out of order THEN ORDER and not stored; WHEN the ring is full and a
 * frame needs its oldest sample THEN that sample is overwritten, counted, and IMU_OVERFLOW
 * returned while the new one is kept. */
static void imu_ring_order_and_overflow(void **state) {
    (void)state;
    SFD_REQ("SFD-LCM-004");
    sfd_imu_ring_init(&g_ring);
    assert_true(sfd_imu_ring_newest(&g_ring) == INT64_MIN);
    sfd_imu_sample_t s = sample(100, 0, 0, 0);
    assert_int_equal(sfd_imu_ring_push(&g_ring, &s), SFD_REJECT_NONE);
    assert_int_equal(sfd_imu_ring_push(&g_ring, &s), SFD_REJECT_ORDER);
    s.t_us = 50;
    assert_int_equal(sfd_imu_ring_push(&g_ring, &s), SFD_REJECT_ORDER);
    assert_int_equal(g_ring.count, 1);
    for (int i = 1; i < SFD_IMU_RING_CAPACITY; ++i) {
        s.t_us = 100 + 5000 * (int64_t)i;
        assert_int_equal(sfd_imu_ring_push(&g_ring, &s), SFD_REJECT_NONE);
    }
    sfd_imu_ring_set_needed(&g_ring, 100); /* a frame's interval starts at the first sample */
    s.t_us += 5000;
    assert_int_equal(sfd_imu_ring_push(&g_ring, &s), SFD_REJECT_IMU_OVERFLOW);
    assert_int_equal(g_ring.count, SFD_IMU_RING_CAPACITY);
    assert_true(g_ring.overwritten == 1);
    assert_true(sfd_imu_ring_newest(&g_ring) == s.t_us);
    int32_t n = 0;
    /* the first sample (t = 100) is gone: an interval starting there is a gap */
    assert_int_equal(sfd_imu_ring_window(&g_ring, 100, 20000, g_scratch, SFD_MAX_IMU_SAMPLES, &n),
                     SFD_REJECT_IMU_GAP);
    assert_int_equal(sfd_imu_ring_window(&g_ring, 5100, 20000, g_scratch, SFD_MAX_IMU_SAMPLES, &n),
                     SFD_REJECT_NONE);
}

/* GIVEN a full ring WHEN nothing was declared needed yet THEN a drop is no loss; WHEN the
 * dropped sample lies before the last one at or before the time declared needed THEN it is
 * counted in `overwritten` only; WHEN it is that last sample (an interval starting at the mark
 * begins there) or newer THEN it is a loss: IMU_OVERFLOW and `lost`; a lowered mark makes a
 * newer sample needed again. */
static void imu_ring_overwrite_of_consumed_samples_is_not_a_loss(void **state) {
    (void)state;
    SFD_REQ("SFD-LCM-004");
    sfd_imu_ring_init(&g_ring);
    sfd_imu_sample_t s = sample(0, 0, 0, 0);
    for (int i = 0; i < SFD_IMU_RING_CAPACITY; ++i) { /* t = 0, 5000, 10000, ... */
        s.t_us = 5000 * (int64_t)i;
        assert_int_equal(sfd_imu_ring_push(&g_ring, &s), SFD_REJECT_NONE);
    }
    s.t_us += 5000;
    assert_int_equal(sfd_imu_ring_push(&g_ring, &s), SFD_REJECT_NONE); /* drops 0: no need yet */
    assert_true(g_ring.overwritten == 1 && g_ring.lost == 0);
    sfd_imu_ring_set_needed(&g_ring, 5000); /* an interval would start at the sample t = 5000 */
    s.t_us += 5000;
    assert_int_equal(sfd_imu_ring_push(&g_ring, &s), SFD_REJECT_IMU_OVERFLOW); /* drops 5000 */
    assert_true(g_ring.overwritten == 2 && g_ring.lost == 1);
    sfd_imu_ring_set_needed(&g_ring, 22000); /* intervals start at the sample t = 20000 */
    s.t_us += 5000;
    assert_int_equal(sfd_imu_ring_push(&g_ring, &s), SFD_REJECT_NONE); /* drops 10000 */
    assert_true(g_ring.overwritten == 3 && g_ring.lost == 1);
    sfd_imu_ring_set_needed(&g_ring, 16000); /* lowered: intervals start at 15000 */
    int32_t n = 0;
    assert_int_equal(sfd_imu_ring_window(&g_ring, 16000, 30000, g_scratch, SFD_MAX_IMU_SAMPLES, &n),
                     SFD_REJECT_NONE);
    s.t_us += 5000;
    assert_int_equal(sfd_imu_ring_push(&g_ring, &s), SFD_REJECT_IMU_OVERFLOW); /* drops 15000 */
    assert_true(g_ring.overwritten == 4 && g_ring.lost == 2);
    assert_int_equal(sfd_imu_ring_window(&g_ring, 16000, 30000, g_scratch, SFD_MAX_IMU_SAMPLES, &n),
                     SFD_REJECT_IMU_GAP);
}

/* GIVEN 200 Hz samples WHEN asking for [t0, t1] THEN the copy starts at the last sample <= t0 and
 * ends at the first >= t1; a t1 past the newest sample is LATE; too many samples is CAPACITY. */
static void imu_ring_window_bounds(void **state) {
    (void)state;
    SFD_REQ("SFD-LCM-004");
    sfd_imu_ring_init(&g_ring);
    for (int i = 0; i < 100; ++i) {
        sfd_imu_sample_t s = sample(1000000 + 5000 * (int64_t)i, 0.1, 0, 0);
        sfd_imu_ring_push(&g_ring, &s);
    }
    int32_t n = 0;
    assert_int_equal(sfd_imu_ring_window(&g_ring, 1012000, 1063000, g_scratch, 64, &n),
                     SFD_REJECT_NONE);
    assert_int_equal(n, 12);
    assert_true(g_scratch[0].t_us == 1010000);
    assert_true(g_scratch[n - 1].t_us == 1065000);
    assert_int_equal(sfd_imu_ring_window(&g_ring, 1010000, 1065000, g_scratch, 64, &n),
                     SFD_REJECT_NONE);
    assert_int_equal(n, 12);
    assert_int_equal(sfd_imu_ring_window(&g_ring, 1400000, 1495001, g_scratch, 64, &n),
                     SFD_REJECT_IMU_LATE);
    assert_int_equal(sfd_imu_ring_window(&g_ring, 999999, 1010000, g_scratch, 64, &n),
                     SFD_REJECT_IMU_GAP);
    assert_int_equal(sfd_imu_ring_window(&g_ring, 1000000, 1400000, g_scratch, 10, &n),
                     SFD_REJECT_CAPACITY);
}

/* GIVEN a constant body rate and EuRoC's camera-IMU extrinsics WHEN assembling the motion between
 * two frame times THEN R_CcurToCprev = R_CtoI^T exp(w dt) R_CtoI to 1e-12; a gap inside the
 * interval larger than the limit is IMU_GAP. */
static void imu_assemble_motion_matches_closed_form(void **state) {
    (void)state;
    SFD_REQ("SFD-LCM-005");
    const double *T = kEurocTimuCam;
    sfd_extrinsics_t ext;
    assert_int_equal(sfd_extrinsics_from_matrix(&ext, T), SFD_OK);
    /* rates whose sums with the bias are exact in float (the ring stores floats) */
    const double w[3] = {0.3125, -0.5, 0.8125}, bias[3] = {0.0078125, 0.015625, -0.03125};
    sfd_imu_ring_init(&g_ring);
    for (int i = 0; i < 100; ++i) {
        sfd_imu_sample_t s =
            sample(5000 * (int64_t)i, w[0] + bias[0], w[1] + bias[1], w[2] + bias[2]);
        sfd_imu_ring_push(&g_ring, &s);
    }
    sfd_frame_motion_t mo;
    const int64_t t0 = 101234, t1 = 151234;
    assert_int_equal(sfd_assemble_motion(&g_ring, &ext, bias, t0, t1, 20000, &mo), SFD_REJECT_NONE);
    double phi[3], RI[9], expect[9];
    for (int k = 0; k < 3; ++k) phi[k] = w[k] * (t1 - t0) * 1e-6;
    sfd_so3_exp(phi, RI);
    sfd_extrinsics_camera_rotation(&ext, RI, expect);
    for (int k = 0; k < 9; ++k) assert_near(mo.R_CcurToCprev[k], expect[k], 1e-12);
    assert_int_equal(mo.translation_known, 0);
    /* a 30 ms hole inside the next interval */
    sfd_imu_ring_init(&g_ring);
    for (int i = 0; i < 100; ++i) {
        if (i >= 30 && i < 36) continue;
        sfd_imu_sample_t s = sample(5000 * (int64_t)i, 0, 0, 0.1);
        sfd_imu_ring_push(&g_ring, &s);
    }
    assert_int_equal(sfd_assemble_motion(&g_ring, &ext, bias, 140000, 190000, 20000, &mo),
                     SFD_REJECT_IMU_GAP);
    assert_int_equal(sfd_assemble_motion(&g_ring, &ext, bias, 190000, 140000, 20000, &mo),
                     SFD_REJECT_ORDER);
}

/* GIVEN a ring whose array has wrapped WHEN asking for an interval across the wrap THEN the span
 * is two pieces, read in place, with the same samples as the copy; gyro integration over the span
 * equals integration over the copy bit for bit; an interval inside one piece is one piece. */
static void imu_ring_span_across_the_wrap_equals_the_copy(void **state) {
    (void)state;
    SFD_REQ("SFD-LCM-004");
    sfd_imu_ring_init(&g_ring);
    const int total = SFD_IMU_RING_CAPACITY + 37; /* the array wraps 37 samples in */
    for (int i = 0; i < total; ++i) {
        sfd_imu_sample_t s = sample(5000 * (int64_t)i, 0.2 + 1e-3 * i, -0.1, 0.05 * (i % 7));
        assert_int_equal(sfd_imu_ring_push(&g_ring, &s), SFD_REJECT_NONE);
    }
    const int64_t t0 = 5000 * (int64_t)(total - 60) + 1234, t1 = 5000 * (int64_t)(total - 10) + 17;
    sfd_imu_span_t span;
    assert_int_equal(sfd_imu_ring_span(&g_ring, t0, t1, SFD_MAX_IMU_SAMPLES, &span),
                     SFD_REJECT_NONE);
    assert_true(span.count[0] > 0 && span.count[1] > 0); /* crosses the end of the array */
    assert_true(span.packed[1] == &g_ring.samples[0]);
    int32_t n = 0;
    assert_int_equal(sfd_imu_ring_window(&g_ring, t0, t1, g_scratch, SFD_MAX_IMU_SAMPLES, &n),
                     SFD_REJECT_NONE);
    assert_int_equal(sfd_imu_span_count(&span), n);
    assert_int_equal(n, 52);
    for (int32_t i = 0; i < n; ++i) {
        const sfd_imu_sample_t s = sfd_imu_span_at(&span, i);
        assert_memory_equal(&s, &g_scratch[i], sizeof g_scratch[i]);
    }
    const double bias[3] = {0.01, -0.02, 0.003};
    double q_span[4], q_copy[4];
    assert_status(sfd_gyro_integrate_span(&span, t0, t1, bias, 20000, q_span), SFD_OK);
    assert_status(sfd_gyro_integrate(g_scratch, (size_t)n, t0, t1, bias, 20000, q_copy), SFD_OK);
    assert_memory_equal(q_span, q_copy, sizeof q_span);
    /* inside the last 37 samples: one piece */
    assert_int_equal(sfd_imu_ring_span(&g_ring, 5000 * (int64_t)(total - 20),
                                       5000 * (int64_t)(total - 5), SFD_MAX_IMU_SAMPLES, &span),
                     SFD_REJECT_NONE);
    assert_int_equal(span.count[1], 0);
    assert_int_equal(span.count[0], 16);
    /* a malformed span is refused, not read */
    span.count[1] = 3;
    span.packed[1] = NULL;
    assert_status(sfd_gyro_integrate_span(&span, t0, t1, bias, 0, q_span), SFD_ERR_INVAL);
    span.count[1] = -1;
    assert_status(sfd_gyro_integrate_span(&span, t0, t1, bias, 0, q_span), SFD_ERR_INVAL);
}

/* GIVEN the ring stores float samples WHEN a sample is pushed THEN it reads back as its floats
 * (a relative 6e-8 of each value); WHEN a value is NaN, infinite or beyond float's range THEN
 * NONFINITE and nothing is stored. */
static void imu_ring_stores_floats_and_refuses_what_float_cannot_hold(void **state) {
    (void)state;
    SFD_REQ("SFD-LCM-004");
    sfd_imu_ring_init(&g_ring);
    sfd_imu_sample_t s = sample(1000, 0.1, -0.2, 0.3);
    s.accel_m_s2[0] = 1.0 / 3.0;
    assert_int_equal(sfd_imu_ring_push(&g_ring, &s), SFD_REJECT_NONE);
    const double bad[] = {NAN, INFINITY, -INFINITY, 1e39, -1e39};
    for (size_t b = 0; b < sizeof bad / sizeof bad[0]; ++b) {
        for (int k = 0; k < 6; ++k) {
            sfd_imu_sample_t x = sample(2000 + (int64_t)(6 * b + k), 0.0, 0.0, 0.0);
            if (k < 3) {
                x.gyro_rad_s[k] = bad[b];
            } else {
                x.accel_m_s2[k - 3] = bad[b];
            }
            assert_int_equal(sfd_imu_ring_push(&g_ring, &x), SFD_REJECT_NONFINITE);
        }
    }
    assert_int_equal(g_ring.count, 1);
    sfd_imu_sample_t t = sample(5000, 0.1, -0.2, 0.3);
    assert_int_equal(sfd_imu_ring_push(&g_ring, &t), SFD_REJECT_NONE);
    sfd_imu_span_t span;
    assert_int_equal(sfd_imu_ring_span(&g_ring, 1000, 5000, 8, &span), SFD_REJECT_NONE);
    assert_int_equal(sfd_imu_span_count(&span), 2);
    const sfd_imu_sample_t r = sfd_imu_span_at(&span, 0);
    assert_true(r.t_us == 1000);
    assert_true(r.gyro_rad_s[1] == (double)(float)-0.2);
    assert_true(r.accel_m_s2[0] == (double)(float)(1.0 / 3.0));
    assert_true(fabs(r.accel_m_s2[0] - 1.0 / 3.0) <= 6e-8 / 3.0);
    assert_true(r.accel_m_s2[0] != 1.0 / 3.0); /* stored as float, not double */
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(imu_ring_order_and_overflow),
        cmocka_unit_test(imu_ring_overwrite_of_consumed_samples_is_not_a_loss),
        cmocka_unit_test(imu_ring_window_bounds),
        cmocka_unit_test(imu_assemble_motion_matches_closed_form),
        cmocka_unit_test(imu_ring_span_across_the_wrap_equals_the_copy),
        cmocka_unit_test(imu_ring_stores_floats_and_refuses_what_float_cannot_hold),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
