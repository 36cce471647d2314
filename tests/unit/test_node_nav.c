/* SPDX-License-Identifier: MIT */
/* unit.node_nav: the node's navigation side (drivers/lcm/sfd_node_nav.h), its start from TRUTH. */
#include "sfd_test.h"

#include <string.h>

#include "sfd_node_nav.h"

static sfd_nav_t g_nav;

/* GIVEN init_from_truth, a configured gyro bias and init_accel_bias_m_s2
 * WHEN two TRUTH poses arrive 50 ms apart
 * THEN the filter starts at the second pose, with the velocity of the difference and exactly the
 *      configured gyro and accelerometer biases. */
static void nav_truth_start_takes_configured_biases(void **state) {
    (void)state;
    sfd_nav_config_t cfg;
    sfd_nav_config_default(&cfg);
    cfg.init_from_truth = 1;
    cfg.init_accel_bias_m_s2[0] = -0.013337;
    cfg.init_accel_bias_m_s2[1] = 0.103464;
    cfg.init_accel_bias_m_s2[2] = 0.093086;
    sfd_params_t params;
    sfd_params_default(&params);
    params.gyro_bias_rad_s[0] = -0.002153;
    params.gyro_bias_rad_s[1] = 0.020744;
    params.gyro_bias_rad_s[2] = 0.075806;
    assert_status(sfd_nav_init(&g_nav, &cfg, &params), SFD_OK);
    const double q[4] = {1, 0, 0, 0}, p0[3] = {1, 2, 3}, p1[3] = {1.05, 2, 3};
    sfd_nav_truth(&g_nav, 1000000, p0, q);
    assert_int_equal(g_nav.ready, 0);
    sfd_nav_truth(&g_nav, 1050000, p1, q);
    assert_int_equal(g_nav.ready, 1);
    assert_near(g_nav.ekf.p_IinW_m[0], 1.05, 1e-15);
    assert_near(g_nav.ekf.v_IinW_m_s[0], 1.0, 1e-12);
    for (int k = 0; k < 3; ++k) {
        assert_near(g_nav.ekf.ba_m_s2[k], cfg.init_accel_bias_m_s2[k], 0.0);
        assert_near(g_nav.ekf.bg_rad_s[k], params.gyro_bias_rad_s[k], 0.0);
    }
}

/* GIVEN a non-finite init_accel_bias_m_s2 WHEN the navigation side is initialized THEN INVAL. */
static void nav_init_nonfinite_accel_bias_refused(void **state) {
    (void)state;
    sfd_nav_config_t cfg;
    sfd_nav_config_default(&cfg);
    for (int k = 0; k < 3; ++k) assert_near(cfg.init_accel_bias_m_s2[k], 0.0, 0.0);
    cfg.init_accel_bias_m_s2[1] = NAN;
    sfd_params_t params;
    sfd_params_default(&params);
    assert_status(sfd_nav_init(&g_nav, &cfg, &params), SFD_ERR_INVAL);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(nav_truth_start_takes_configured_biases),
        cmocka_unit_test(nav_init_nonfinite_accel_bias_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
