/* SPDX-License-Identifier: MIT */
/* unit.params: defaults are valid; every out-of-range field is rejected with the right code. */
#include "sfd_test.h"

#include <sfd/sfd_params.h>

/* GIVEN defaults THEN they validate and hold the documented values. */
static void params_default_valid(void **state) {
    (void)state;
    SFD_REQ("SFD-API-002");
    sfd_params_t p;
    assert_status(sfd_params_default(&p), SFD_OK);
    assert_status(sfd_params_validate(&p), SFD_OK);
    assert_int_equal(p.method, SFD_METHOD_PARITY);
    assert_int_equal(p.window_frames, 3);
    assert_int_equal(p.group_size, 3);
    assert_near(p.false_alarm_rate, 0.01, 0.0);
}

/* GIVEN null pointers THEN SFD_ERR_INVAL. */
static void params_null_rejected(void **state) {
    (void)state;
    SFD_REQ("SFD-API-002");
    assert_status(sfd_params_default(NULL), SFD_ERR_INVAL);
    assert_status(sfd_params_validate(NULL), SFD_ERR_INVAL);
}

#define EXPECT_FIELD(field, value, status)               \
    do {                                                 \
        sfd_params_t p_;                                 \
        sfd_params_default(&p_);                         \
        p_.field = (value);                              \
        assert_status(sfd_params_validate(&p_), status); \
    } while (0)

/* GIVEN one field out of range at a time THEN the matching status; capacities give CAPACITY. */
static void params_out_of_range_rejected(void **state) {
    (void)state;
    SFD_REQ("SFD-API-002");
    EXPECT_FIELD(method, -1, SFD_ERR_INVAL);
    EXPECT_FIELD(method, 6, SFD_ERR_INVAL);
    EXPECT_FIELD(pixel_sigma_px, 0.0, SFD_ERR_INVAL);
    EXPECT_FIELD(pixel_sigma_px, NAN, SFD_ERR_INVAL);
    EXPECT_FIELD(pixel_sigma_px, INFINITY, SFD_ERR_INVAL);
    EXPECT_FIELD(false_alarm_rate, 0.0, SFD_ERR_INVAL);
    EXPECT_FIELD(false_alarm_rate, 0.6, SFD_ERR_INVAL);
    EXPECT_FIELD(false_alarm_rate, NAN, SFD_ERR_INVAL);
    EXPECT_FIELD(window_frames, 1, SFD_ERR_INVAL);
    EXPECT_FIELD(window_frames, SFD_MAX_WINDOW + 1, SFD_ERR_CAPACITY);
    EXPECT_FIELD(group_size, 0, SFD_ERR_INVAL);
    EXPECT_FIELD(group_size, SFD_MAX_GROUP + 1, SFD_ERR_CAPACITY);
    EXPECT_FIELD(max_hypotheses, 0, SFD_ERR_INVAL);
    EXPECT_FIELD(max_hypotheses, SFD_MAX_HYPOTHESES + 1, SFD_ERR_CAPACITY);
    EXPECT_FIELD(translation_known, 2, SFD_ERR_INVAL);
    EXPECT_FIELD(exact_depth_covariance, -1, SFD_ERR_INVAL);
    EXPECT_FIELD(parity_isolation, 2, SFD_ERR_INVAL);
    EXPECT_FIELD(default_depth_m, -1.0, SFD_ERR_INVAL);
    EXPECT_FIELD(default_depth_m, 1e39, SFD_ERR_INVAL);  /* beyond float: stored as float */
    EXPECT_FIELD(default_depth_m, 1e-40, SFD_ERR_INVAL); /* subnormal in float */
    EXPECT_FIELD(default_depth_var_m2, -0.5, SFD_ERR_INVAL);
    EXPECT_FIELD(default_depth_var_m2, 1e39, SFD_ERR_INVAL);
    EXPECT_FIELD(ransac_confidence, 1.0, SFD_ERR_INVAL);
    EXPECT_FIELD(gyro_bias_rad_s[1], NAN, SFD_ERR_INVAL);
    EXPECT_FIELD(max_imu_gap_us, 0, SFD_ERR_INVAL);
    EXPECT_FIELD(both_parity_share, 0.0, SFD_ERR_INVAL);
    EXPECT_FIELD(both_parity_share, 1.0, SFD_ERR_INVAL);
    EXPECT_FIELD(both_parity_share, NAN, SFD_ERR_INVAL);
    EXPECT_FIELD(alarm_hold_ratio, 0.0, SFD_ERR_INVAL);
    EXPECT_FIELD(alarm_hold_ratio, 1.0000001, SFD_ERR_INVAL);
    EXPECT_FIELD(alarm_hold_ratio, NAN, SFD_ERR_INVAL);
    EXPECT_FIELD(alarm_hold_frames, 0, SFD_ERR_INVAL);
    EXPECT_FIELD(alarm_hold_frames, SFD_ALARM_HOLD_MAX_FRAMES + 1, SFD_ERR_INVAL);
    EXPECT_FIELD(alarm_hold_max_statistic, 0.999, SFD_ERR_INVAL);
    EXPECT_FIELD(alarm_hold_max_statistic, INFINITY, SFD_ERR_INVAL);
    EXPECT_FIELD(alarm_hold_alpha_scale, 0.0, SFD_ERR_INVAL);
    EXPECT_FIELD(alarm_hold_alpha_scale, 1.0000001, SFD_ERR_INVAL);
    EXPECT_FIELD(alarm_hold_alpha_scale, NAN, SFD_ERR_INVAL);
    EXPECT_FIELD(evidence_ramp_share, -1e-9, SFD_ERR_INVAL);
    EXPECT_FIELD(evidence_ramp_share, 1.0000001, SFD_ERR_INVAL);
    EXPECT_FIELD(evidence_ramp_share, NAN, SFD_ERR_INVAL);
    EXPECT_FIELD(alarm_hold_min_statistic, -1e-9, SFD_ERR_INVAL);
    EXPECT_FIELD(alarm_hold_min_statistic, 1.0000001, SFD_ERR_INVAL);
    EXPECT_FIELD(alarm_hold_min_statistic, NAN, SFD_ERR_INVAL);
    EXPECT_FIELD(alarm_hold_direction_alpha, -1e-9, SFD_ERR_INVAL);
    EXPECT_FIELD(alarm_hold_direction_alpha, 0.5, SFD_ERR_INVAL);
    EXPECT_FIELD(alarm_hold_direction_alpha, NAN, SFD_ERR_INVAL);
}

/* GIVEN boundary values THEN they are accepted. */
static void params_boundaries_accepted(void **state) {
    (void)state;
    SFD_REQ("SFD-API-002");
    EXPECT_FIELD(window_frames, 2, SFD_OK);
    EXPECT_FIELD(window_frames, SFD_MAX_WINDOW, SFD_OK);
    EXPECT_FIELD(group_size, 1, SFD_OK);
    EXPECT_FIELD(group_size, SFD_MAX_GROUP, SFD_OK);
    EXPECT_FIELD(max_hypotheses, SFD_MAX_HYPOTHESES, SFD_OK);
    EXPECT_FIELD(false_alarm_rate, 0.5, SFD_OK);
    EXPECT_FIELD(default_depth_var_m2, 0.0, SFD_OK);
    EXPECT_FIELD(alarm_hold_ratio, 1.0, SFD_OK);
    EXPECT_FIELD(alarm_hold_frames, SFD_ALARM_HOLD_MAX_FRAMES, SFD_OK);
    EXPECT_FIELD(alarm_hold_max_statistic, 1.0, SFD_OK);
    EXPECT_FIELD(alarm_hold_alpha_scale, 1.0, SFD_OK);
    EXPECT_FIELD(alarm_hold_alpha_scale, 1e-6, SFD_OK);
    EXPECT_FIELD(evidence_ramp_share, 0.0, SFD_OK);
    EXPECT_FIELD(evidence_ramp_share, 1.0, SFD_OK);
    EXPECT_FIELD(alarm_hold_min_statistic, 0.0, SFD_OK);
    EXPECT_FIELD(alarm_hold_min_statistic, 1.0, SFD_OK);
    EXPECT_FIELD(alarm_hold_direction_alpha, 0.0, SFD_OK);
    EXPECT_FIELD(alarm_hold_direction_alpha, 0.4999999, SFD_OK);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(params_default_valid),
        cmocka_unit_test(params_null_rejected),
        cmocka_unit_test(params_out_of_range_rejected),
        cmocka_unit_test(params_boundaries_accepted),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
