// SPDX-License-Identifier: MIT
// unit.app_config: the configuration of sfd-node and sfd-replay (apps/common/sfd_app_config.hpp).
//  - the shipped apps/config/sfd.yaml loads, validates and starts a node;
//  - validate() refuses one bad value per key (NaN, infinity, negative, zero where > 0 is needed,
//    out of range, not 0/1) with "ORIGIN: KEY: VALUE is not ...", naming that key only;
//  - every configuration it accepts (the boundaries of every range) is accepted by
//    sfd_node_init(), so the node cannot fail on a configuration validate() passed;
//  - read_config() refuses wrong types, non-integers, integers beyond 32 bits (which
//    cv::FileStorage would wrap), octal and hexadecimal literals and unknown keys, naming the
//    file, the key and the value; ranges are judged after the command-line overrides;
//  - the command-line numbers are parsed whole ("--window 2.5: not an integer").
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <limits>
#include <string>
#include <unistd.h>
#include <vector>

#include "sfd_app_cli.hpp"
#include "sfd_app_config.hpp"

// cmocka last: its macros clash with the C++ standard headers.
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

extern "C" {
#include <cmocka.h>
}

namespace {

using sfdapp::AppConfig;

sfd_node_t g_node;           // ~0.3 MiB: static
std::string g_shipped_yaml;  // apps/config/sfd.yaml (the first argument)

void no_publish(void *, sfd_node_output_t, const void *, int32_t, int64_t) {}

void expect_equal(const std::string &actual, const std::string &expected, const char *what) {
    if (actual != expected) {
        fail_msg("%s:\n  got      '%s'\n  expected '%s'", what, actual.c_str(), expected.c_str());
    }
}

// ---- validate(): one bad value per key ---------------------------------------------------------

struct BadValue {
    const char *key;  // the YAML key, given the origin "F" below
    std::function<void(AppConfig &)> set;
    const char *message;  // expected after "F: "
};

const double kNan = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

std::vector<BadValue> bad_values() {
    using C = AppConfig;
    return {
        {"method", [](C &c) { c.node.params.method = 9; },
         "method: \"parity\" is not one of none, parity, oprf, ransac1, ransacf, both"},
        {"false_alarm_rate", [](C &c) { c.node.params.false_alarm_rate = 0.0; },
         "false_alarm_rate: 0 is not in (0, 0.5]"},
        {"false_alarm_rate", [](C &c) { c.node.params.false_alarm_rate = 0.51; },
         "false_alarm_rate: 0.51 is not in (0, 0.5]"},
        {"false_alarm_rate", [](C &c) { c.node.params.false_alarm_rate = kNan; },
         "false_alarm_rate: nan is not finite"},
        {"pixel_sigma_px", [](C &c) { c.node.params.pixel_sigma_px = 0.0; },
         "pixel_sigma_px: 0 is not > 0"},
        {"pixel_sigma_px", [](C &c) { c.node.params.pixel_sigma_px = kInf; },
         "pixel_sigma_px: inf is not finite"},
        {"window_frames", [](C &c) { c.node.params.window_frames = 1; },
         "window_frames: 1 is not in 2..5"},
        {"window_frames", [](C &c) { c.node.params.window_frames = SFD_MAX_WINDOW + 1; },
         "window_frames: 6 is not in 2..5"},
        {"group_size", [](C &c) { c.node.params.group_size = 0; }, "group_size: 0 is not in 1..4"},
        {"group_size", [](C &c) { c.node.params.group_size = SFD_MAX_GROUP + 1; },
         "group_size: 5 is not in 1..4"},
        {"translation_known", [](C &c) { c.node.params.translation_known = 2; },
         "translation_known: 2 is not 0 or 1"},
        {"exact_depth_covariance", [](C &c) { c.node.params.exact_depth_covariance = -1; },
         "exact_depth_covariance: -1 is not 0 or 1"},
        {"parity_isolation", [](C &c) { c.node.params.parity_isolation = 7; },
         "parity_isolation: 7 is not 0 or 1"},
        {"default_depth_m", [](C &c) { c.node.params.default_depth_m = -10.0; },
         "default_depth_m: -10 is not in [1.17549e-38, 3.40282e+38]"},
        {"default_depth_m", [](C &c) { c.node.params.default_depth_m = 1e39; },
         "default_depth_m: 1e+39 is not in [1.17549e-38, 3.40282e+38]"},
        {"default_depth_var_m2", [](C &c) { c.node.params.default_depth_var_m2 = -0.5; },
         "default_depth_var_m2: -0.5 is not in [0, 3.40282e+38]"},
        {"default_depth_var_m2", [](C &c) { c.node.params.default_depth_var_m2 = kNan; },
         "default_depth_var_m2: nan is not finite"},
        {"max_imu_gap_us", [](C &c) { c.node.params.max_imu_gap_us = 0; },
         "max_imu_gap_us: 0 is not > 0"},
        {"time_horizon_us", [](C &c) { c.node.time.horizon_us = -1; },
         "time_horizon_us: -1 is not > 0"},
        {"time_resync_messages", [](C &c) { c.node.time.resync_messages = 1; },
         "time_resync_messages: 1 is not in 2..1000"},
        {"time_resync_messages", [](C &c) { c.node.time.resync_messages = 1001; },
         "time_resync_messages: 1001 is not in 2..1000"},
        {"gyro_bias_rad_s", [](C &c) { c.node.params.gyro_bias_rad_s[2] = -kInf; },
         "gyro_bias_rad_s[2]: -inf is not finite"},
        {"max_hypotheses", [](C &c) { c.node.params.max_hypotheses = 0; },
         "max_hypotheses: 0 is not in 1..256"},
        {"max_hypotheses", [](C &c) { c.node.params.max_hypotheses = SFD_MAX_HYPOTHESES + 1; },
         "max_hypotheses: 257 is not in 1..256"},
        {"ransac_confidence", [](C &c) { c.node.params.ransac_confidence = 1.0; },
         "ransac_confidence: 1 is not in (0, 1)"},
        {"alarm_hold_ratio", [](C &c) { c.node.params.alarm_hold_ratio = 0.0; },
         "alarm_hold_ratio: 0 is not in (0, 1]"},
        {"alarm_hold_ratio", [](C &c) { c.node.params.alarm_hold_ratio = 1.5; },
         "alarm_hold_ratio: 1.5 is not in (0, 1]"},
        {"alarm_hold_frames", [](C &c) { c.node.params.alarm_hold_frames = 0; },
         "alarm_hold_frames: 0 is not in 1..100"},
        {"alarm_hold_frames", [](C &c) { c.node.params.alarm_hold_frames = 101; },
         "alarm_hold_frames: 101 is not in 1..100"},
        {"alarm_hold_max_statistic", [](C &c) { c.node.params.alarm_hold_max_statistic = 0.5; },
         "alarm_hold_max_statistic: 0.5 is not in [1, 1e+06]"},
        {"alarm_hold_min_statistic", [](C &c) { c.node.params.alarm_hold_min_statistic = -0.1; },
         "alarm_hold_min_statistic: -0.1 is not in [0, 1]"},
        {"alarm_hold_min_statistic", [](C &c) { c.node.params.alarm_hold_min_statistic = 1.5; },
         "alarm_hold_min_statistic: 1.5 is not in [0, 1]"},
        {"alarm_hold_alpha_scale", [](C &c) { c.node.params.alarm_hold_alpha_scale = 0.0; },
         "alarm_hold_alpha_scale: 0 is not in (0, 1]"},
        {"alarm_hold_alpha_scale", [](C &c) { c.node.params.alarm_hold_alpha_scale = 1.5; },
         "alarm_hold_alpha_scale: 1.5 is not in (0, 1]"},
        {"alarm_hold_direction_alpha",
         [](C &c) { c.node.params.alarm_hold_direction_alpha = -0.1; },
         "alarm_hold_direction_alpha: -0.1 is not in [0, 0.5)"},
        {"alarm_hold_direction_alpha", [](C &c) { c.node.params.alarm_hold_direction_alpha = 0.5; },
         "alarm_hold_direction_alpha: 0.5 is not in [0, 0.5)"},
        {"evidence_ramp_share", [](C &c) { c.node.params.evidence_ramp_share = -0.1; },
         "evidence_ramp_share: -0.1 is not in [0, 1]"},
        {"evidence_ramp_share", [](C &c) { c.node.params.evidence_ramp_share = 1.5; },
         "evidence_ramp_share: 1.5 is not in [0, 1]"},
        {"filter.enabled", [](C &c) { c.node.nav.enabled = 7; }, "filter.enabled: 7 is not 0 or 1"},
        {"filter.gyro_noise_rad_s_rthz",
         [](C &c) { c.node.nav.noise.gyro_noise_rad_s_rthz = -1e-4; },
         "filter.gyro_noise_rad_s_rthz: -0.0001 is not >= 0"},
        {"filter.accel_noise_m_s2_rthz",
         [](C &c) { c.node.nav.noise.accel_noise_m_s2_rthz = kNan; },
         "filter.accel_noise_m_s2_rthz: nan is not finite"},
        {"filter.gyro_bias_rw_rad_s2_rthz",
         [](C &c) { c.node.nav.noise.gyro_bias_rw_rad_s2_rthz = -3.9e-5; },
         "filter.gyro_bias_rw_rad_s2_rthz: -3.9e-05 is not >= 0"},
        {"filter.accel_bias_rw_m_s3_rthz",
         [](C &c) { c.node.nav.noise.accel_bias_rw_m_s3_rthz = kInf; },
         "filter.accel_bias_rw_m_s3_rthz: inf is not finite"},
        {"filter.gravity_m_s2", [](C &c) { c.node.nav.noise.gravity_m_s2 = -9.81; },
         "filter.gravity_m_s2: -9.81 is not > 0"},
        {"filter.gravity_m_s2", [](C &c) { c.node.nav.noise.gravity_m_s2 = 0.0; },
         "filter.gravity_m_s2: 0 is not > 0"},
        {"filter.window_filter", [](C &c) { c.node.nav.window_filter = 2; },
         "filter.window_filter: 2 is not 0 or 1"},
        {"filter.window_size", [](C &c) { c.node.nav.window_size = SFD_MAX_WINDOW + 1; },
         "filter.window_size: 6 is not in 2..5"},
        {"filter.window_size", [](C &c) { c.node.nav.window_size = 1; },
         "filter.window_size: 1 is not in 2..5"},
        {"filter.window_depth_priors", [](C &c) { c.node.nav.window_depth_priors = 3; },
         "filter.window_depth_priors: 3 is not in 0..2"},
        {"filter.window_depth_priors", [](C &c) { c.node.nav.window_depth_priors = -1; },
         "filter.window_depth_priors: -1 is not in 0..2"},
        {"filter.window_flagged_earlier", [](C &c) { c.node.nav.window_flagged_earlier = 2; },
         "filter.window_flagged_earlier: 2 is not 0 or 1"},
        {"filter.window_gate_alpha", [](C &c) { c.node.nav.window_gate_alpha = 0.6; },
         "filter.window_gate_alpha: 0.6 is not in (0, 0.5]"},
        {"filter.window_gate_alpha", [](C &c) { c.node.nav.window_gate_alpha = 0.0; },
         "filter.window_gate_alpha: 0 is not in (0, 0.5]"},
        {"filter.first_estimates", [](C &c) { c.node.nav.first_estimates = -1; },
         "filter.first_estimates: -1 is not 0 or 1"},
        {"filter.observability_constrained", [](C &c) { c.node.nav.observability_constrained = 2; },
         "filter.observability_constrained: 2 is not 0 or 1"},
        {"filter.keyframe_parallax_rad", [](C &c) { c.node.nav.keyframe_parallax_rad = -0.01; },
         "filter.keyframe_parallax_rad: -0.01 is not >= 0"},
        {"filter.keyframe_parallax_rad", [](C &c) { c.node.nav.keyframe_parallax_rad = kNan; },
         "filter.keyframe_parallax_rad: nan is not finite"},
        {"filter.keyframe_parallax_rad",
         [](C &c) {
             c.node.nav.keyframe_parallax_rad = 0.02;
             c.node.nav.window_size = 3;
         },
         "filter.keyframe_parallax_rad: 0.02 needs filter.window_size >= window_frames + 1 (4)"},
        {"filter.init_rest_s", [](C &c) { c.node.nav.init_rest_s = 0.0; },
         "filter.init_rest_s: 0 is not in (0, 60)"},
        {"filter.init_rest_s", [](C &c) { c.node.nav.init_rest_s = 60.0; },
         "filter.init_rest_s: 60 is not in (0, 60)"},
        {"filter.init_from_truth", [](C &c) { c.node.nav.init_from_truth = 2; },
         "filter.init_from_truth: 2 is not 0 or 1"},
        {"filter.init_accel_bias_m_s2", [](C &c) { c.node.nav.init_accel_bias_m_s2[0] = kNan; },
         "filter.init_accel_bias_m_s2[0]: nan is not finite"},
        {"filter.consider_position", [](C &c) { c.node.nav.consider_position = 3; },
         "filter.consider_position: 3 is not 0 or 1"},
        {"filter.gyro_bias_at_rest", [](C &c) { c.node.nav.gyro_bias_at_rest = -2; },
         "filter.gyro_bias_at_rest: -2 is not 0 or 1"},
        {"filter.landmark_depth_var_m2", [](C &c) { c.node.nav.landmark_depth_var_m2 = -1.0; },
         "filter.landmark_depth_var_m2: -1 is not >= 0"},
        {"filter.landmark_max_age_s", [](C &c) { c.node.nav.landmark_max_age_s = 0.0; },
         "filter.landmark_max_age_s: 0 is not in (0, 9e+09]"},
        {"filter.landmark_max_age_s", [](C &c) { c.node.nav.landmark_max_age_s = 1e300; },
         "filter.landmark_max_age_s: 1e+300 is not in (0, 9e+09]"},
        {"filter.landmark_gate_alpha", [](C &c) { c.node.nav.landmark_gate_alpha = 1.0; },
         "filter.landmark_gate_alpha: 1 is not in (0, 1)"},
        {"filter.min_parallax_px", [](C &c) { c.node.nav.min_parallax_px = -0.5; },
         "filter.min_parallax_px: -0.5 is not >= 0"},
        {"filter.max_dt_s", [](C &c) { c.node.nav.noise.max_dt_s = 0.0; },
         "filter.max_dt_s: 0 is not > 0"},
        {"filter.p0_diag", [](C &c) { c.node.nav.p0_diag[4] = -1e-4; },
         "filter.p0_diag[4]: -0.0001 is not >= 0"},
        {"camera_id", [](C &c) { c.node.camera_id = -2; },
         "camera_id: -2 is not -1 or in 0..2147483647"},
        {"publish_timing", [](C &c) { c.node.publish_timing = 2; },
         "publish_timing: 2 is not 0 or 1"},
        {"lcm_url", [](C &c) { c.lcm_url.clear(); }, "lcm_url: \"\" is empty"},
        {"channels.imu", [](C &c) { c.channels.imu.clear(); }, "channels.imu: \"\" is empty"},
        {"channels.features", [](C &c) { c.channels.features = "IMU"; },
         "channels.features: \"IMU\" is the same as channels.imu"},
        {"channels.verdict", [](C &c) { c.channels.verdict = "FEATURES"; },
         "channels.verdict: \"FEATURES\" is the same as channels.features"},
        {"channels.truth", [](C &c) { c.channels.truth = "SFD_STATE"; },
         "channels.truth: \"SFD_STATE\" is the same as channels.state"},
        {"channels.state", [](C &c) { c.channels.state = std::string(64, 'S'); },
         "channels.state: \"SSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSS\" is "
         "longer than 63 characters (LCM's limit)"},
        {"channels.timing", [](C &c) { c.channels.timing = "SFD TIMING"; },
         "channels.timing: \"SFD TIMING\" contains ' ' (a channel name is matched exactly: no "
         "blanks, control or regular-expression characters)"},
        {"channels.camera_info", [](C &c) { c.channels.camera_info = "CAM.*"; },
         "channels.camera_info: \"CAM.*\" contains '.' (a channel name is matched exactly: no "
         "blanks, control or regular-expression characters)"},
        {"method",
         [](C &c) {
             std::string e;
             assert_true(sfdapp::set_method("ransac1", &c, &e));
             c.node.nav.enabled = 0;
         },
         "method: \"ransac1\" needs filter.enabled: 1 (it is 0, from F)"},
    };
}

// GIVEN the defaults with one value out of its range, set from a file "F" THEN validate() refuses
// the configuration with "F: KEY: VALUE is not ..." naming that key and value.
void one_bad_value_per_key_is_named(void **) {
    AppConfig good;
    std::string err;
    assert_true(sfdapp::validate(good, &err));
    for (const BadValue &b : bad_values()) {
        AppConfig cfg;
        b.set(cfg);
        cfg.origin[b.key] = "F";
        cfg.origin["filter.enabled"] = "F";
        err.clear();
        assert_false(sfdapp::validate(cfg, &err));
        expect_equal(err, std::string("F: ") + b.message, b.key);
    }
}

// GIVEN each bad value THEN the message is the same whatever else is valid (the first bad key in
// the order of sfd.yaml is named, not a list of every key).
void only_the_bad_key_is_named(void **) {
    AppConfig cfg;
    cfg.node.nav.noise.gravity_m_s2 = -9.81;
    cfg.node.publish_timing = 5;
    cfg.origin["filter.gravity_m_s2"] = "sfd.yaml";
    cfg.origin["publish_timing"] = "--other";
    std::string err;
    assert_false(sfdapp::validate(cfg, &err));
    expect_equal(err, "sfd.yaml: filter.gravity_m_s2: -9.81 is not > 0", "first bad key");
    cfg.node.nav.noise.gravity_m_s2 = 9.81;
    assert_false(sfdapp::validate(cfg, &err));
    expect_equal(err, "--other: publish_timing: 5 is not 0 or 1", "second bad key");
}

// GIVEN the boundaries of every range THEN validate() accepts them and so does sfd_node_init()
// (a configuration validate() passes can never make the node fail at start).
void accepted_configurations_start_a_node(void **) {
    using C = AppConfig;
    const std::vector<std::function<void(C &)>> good = {
        [](C &) {},
        [](C &c) { c.node.params.false_alarm_rate = 0.5; },
        [](C &c) { c.node.params.false_alarm_rate = 1e-12; },
        [](C &c) { c.node.params.window_frames = 2; },
        [](C &c) { c.node.params.window_frames = SFD_MAX_WINDOW; },
        [](C &c) { c.node.params.group_size = 1; },
        [](C &c) { c.node.params.group_size = SFD_MAX_GROUP; },
        [](C &c) { c.node.params.default_depth_var_m2 = 0.0; },
        [](C &c) { c.node.params.max_hypotheses = 1; },
        [](C &c) { c.node.params.max_hypotheses = SFD_MAX_HYPOTHESES; },
        [](C &c) { c.node.params.ransac_confidence = 0.999999; },
        [](C &c) { c.node.params.alarm_hold_ratio = 1.0; },
        [](C &c) { c.node.params.alarm_hold_frames = SFD_ALARM_HOLD_MAX_FRAMES; },
        [](C &c) {
            c.node.params.alarm_hold_ratio = 1e-6;
            c.node.params.alarm_hold_frames = 1;
            c.node.params.alarm_hold_max_statistic = 1e6;
            c.node.params.alarm_hold_alpha_scale = 1e-6;
        },
        [](C &c) { c.node.params.alarm_hold_alpha_scale = 1.0; },
        [](C &c) { c.node.params.alarm_hold_direction_alpha = 0.0; },
        [](C &c) { c.node.params.alarm_hold_direction_alpha = std::nextafter(0.5, 0.0); },
        [](C &c) { c.node.params.alarm_hold_min_statistic = 0.0; },
        [](C &c) {  // every held alarm ends the hold (the hold lasts one observation)
            c.node.params.alarm_hold_min_statistic = 1.0;
            c.node.params.alarm_hold_ratio = 1e-6;
        },
        [](C &c) { c.node.params.evidence_ramp_share = 0.0; },
        [](C &c) { c.node.params.evidence_ramp_share = 1.0; },
        [](C &c) {  // the omnibus evidence test at the smallest share above 0
            c.node.params.evidence_ramp_share = std::nextafter(1.0, 0.0);
            c.node.params.false_alarm_rate = 1e-12;
        },
        [](C &c) {  // the ramp's alpha underflows: its threshold is infinite, it never flags
            c.node.params.evidence_ramp_share = 4.9e-324;
        },
        [](C &c) { c.node.params.max_imu_gap_us = 1; },
        [](C &c) { c.node.params.seed = UINT64_MAX; },
        [](C &c) { c.node.time.horizon_us = 1; },
        [](C &c) { c.node.time.resync_messages = 2; },
        [](C &c) { c.node.time.resync_messages = 1000; },
        [](C &c) {
            c.node.nav.noise.gyro_noise_rad_s_rthz = 0.0;
            c.node.nav.noise.accel_noise_m_s2_rthz = 0.0;
            c.node.nav.noise.gyro_bias_rw_rad_s2_rthz = 0.0;
            c.node.nav.noise.accel_bias_rw_m_s3_rthz = 0.0;
        },
        [](C &c) { c.node.nav.noise.gravity_m_s2 = 1e-3; },
        [](C &c) { c.node.nav.window_size = 2; },
        [](C &c) { c.node.nav.window_size = SFD_MAX_WINDOW; },
        [](C &c) { c.node.nav.window_gate_alpha = 0.5; },
        [](C &c) { c.node.nav.window_gate_alpha = 1e-12; },
        [](C &c) { c.node.nav.first_estimates = 1; },
        [](C &c) { c.node.nav.observability_constrained = 0; },
        [](C &c) { c.node.nav.keyframe_parallax_rad = 0.02; },
        [](C &c) { c.node.nav.window_depth_priors = 0; },
        [](C &c) { c.node.nav.window_depth_priors = 2; },
        [](C &c) { c.node.nav.window_flagged_earlier = 0; },
        [](C &c) {
            c.node.nav.keyframe_parallax_rad = 0.02;
            c.node.nav.window_size = 4;
        },
        [](C &c) { c.node.nav.init_rest_s = 59.9; },
        [](C &c) {
            c.node.nav.window_filter = 0;
            c.node.nav.window_size = 2;
        },
        [](C &c) { c.node.nav.landmark_depth_var_m2 = 0.0; },
        [](C &c) { c.node.nav.landmark_max_age_s = 9e9; },
        [](C &c) { c.node.nav.landmark_gate_alpha = 0.999; },
        [](C &c) { c.node.nav.min_parallax_px = 0.0; },
        [](C &c) {
            c.node.nav.enabled = 0;
            c.node.params.method = SFD_METHOD_PARITY;
        },
        [](C &c) {
            c.node.nav.enabled = 0;
            std::string e;
            assert_true(sfdapp::set_method("none", &c, &e));
        },
        [](C &c) {
            std::string e;
            assert_true(sfdapp::set_method("both", &c, &e));
        },
        [](C &c) { c.node.camera_id = 0; },
        [](C &c) { c.node.camera_id = std::numeric_limits<int32_t>::max(); },
        [](C &c) { c.node.publish_timing = 0; },
        [](C &c) { c.channels.imu = std::string(63, 'I'); },
    };
    for (size_t k = 0; k < good.size(); ++k) {
        AppConfig cfg;
        good[k](cfg);
        std::string err;
        if (!sfdapp::validate(cfg, &err)) fail_msg("case %zu refused: %s", k, err.c_str());
        if (sfd_node_init(&g_node, &cfg.node, no_publish, nullptr, nullptr) != SFD_OK) {
            fail_msg("case %zu: validate() accepted it, sfd_node_init() refused it", k);
        }
    }
}

// ---- read_config(): the file ------------------------------------------------------------------

// Writes a YAML file with `body` under the header and returns its path.
std::string write_yaml(const std::string &body) {
    char path[] = "/tmp/sfd_test_app_config_XXXXXX";
    const int fd = mkstemp(path);
    assert_true(fd >= 0);
    const std::string text = "%YAML:1.0\n---\n" + body + "\n";
    assert_int_equal(write(fd, text.data(), text.size()), static_cast<ssize_t>(text.size()));
    close(fd);
    return path;
}

// read_config() then validate() on a file with `body`: "" when both accept it, else the error
// with the file's path replaced by "F".
std::string file_error(const std::string &body, AppConfig *out = nullptr) {
    const std::string path = write_yaml(body);
    AppConfig cfg;
    std::string err;
    const bool ok = sfdapp::read_config(path, &cfg, &err) && sfdapp::validate(cfg, &err);
    std::remove(path.c_str());
    if (out != nullptr) *out = cfg;
    if (ok) return "";
    for (size_t p = err.find(path); p != std::string::npos; p = err.find(path)) {
        err.replace(p, path.size(), "F");
    }
    return err;
}

// GIVEN the shipped apps/config/sfd.yaml THEN it loads, validates, states the defaults and starts
// a node.
void shipped_config_is_valid(void **) {
    const std::string &path = g_shipped_yaml;
    AppConfig cfg;
    std::string err;
    if (!sfdapp::read_config(path, &cfg, &err)) fail_msg("%s", err.c_str());
    if (!sfdapp::validate(cfg, &err)) fail_msg("%s", err.c_str());
    assert_int_equal(sfd_node_init(&g_node, &cfg.node, no_publish, nullptr, nullptr), SFD_OK);
    // "a missing key keeps the default shown here": the file states the defaults exactly
    const AppConfig def;
    assert_memory_equal(&cfg.node, &def.node, sizeof cfg.node);
    expect_equal(cfg.method, def.method, "method");
    expect_equal(cfg.lcm_url, def.lcm_url, "lcm_url");
    expect_equal(
        cfg.channels.imu + cfg.channels.camera_info + cfg.channels.features + cfg.channels.verdict +
            cfg.channels.timing + cfg.channels.state + cfg.channels.truth,
        def.channels.imu + def.channels.camera_info + def.channels.features + def.channels.verdict +
            def.channels.timing + def.channels.state + def.channels.truth,
        "channels");
    expect_equal(cfg.origin_of("filter.gravity_m_s2"), path, "origin of a key of the file");
    expect_equal(cfg.origin_of("gyro_bias_rad_s[1]"), path, "origin of a list element");
}

// GIVEN one bad value per key in a file THEN the message names the file, the key and the value.
void file_values_are_named(void **) {
    const std::vector<std::pair<std::string, std::string>> cases = {
        // the defects of issue 18
        {"filter:\n   gyro_noise_rad_s_rthz: -3.4e-4",
         "F: filter.gyro_noise_rad_s_rthz: -0.00034 is not >= 0"},
        {"filter:\n   accel_noise_m_s2_rthz: .nan",
         "F: filter.accel_noise_m_s2_rthz: nan is not finite"},
        {"filter:\n   gravity_m_s2: -9.81", "F: filter.gravity_m_s2: -9.81 is not > 0"},
        {"filter:\n   enabled: 7", "F: filter.enabled: 7 is not 0 or 1"},
        {"channels:\n   verdict: \"IMU\"",
         "F: channels.verdict: \"IMU\" is the same as channels.imu"},
        {"channels:\n   imu: SFD_TIMING",
         "F: channels.imu: \"SFD_TIMING\" is the same as channels.timing"},
        {"camera_id: 123456789012",
         "F: camera_id: 123456789012 is outside the 32-bit integer range"},
        {"camera_id: -2147483649", "F: camera_id: -2147483649 is outside the 32-bit integer range"},
        {"camera_id: 4294967297", "F: camera_id: 4294967297 is outside the 32-bit integer range"},
        {"camera_id: -7", "F: camera_id: -7 is not -1 or in 0..2147483647"},
        // types
        {"window_frames: 2.5", "F: window_frames: 2.5 is not an integer"},
        {"window_frames: 3.0", "F: window_frames: 3.0 is not an integer"},
        {"window_frames: \"3\"", "F: window_frames: \"3\" is not an integer"},
        {"window_frames: 03",
         "F: window_frames: 03 has a leading 0 (cv::FileStorage would read it as octal)"},
        {"window_frames: 0x3", "F: window_frames: 0x3 is not a decimal number"},
        {"group_size: [ 1, 2 ]", "F: group_size: [1, 2] is not an integer"},
        {"false_alarm_rate: abc", "F: false_alarm_rate: \"abc\" is not a number"},
        {"false_alarm_rate: nan", "F: false_alarm_rate: \"nan\" is not a number"},
        {"pixel_sigma_px: .inf", "F: pixel_sigma_px: inf is not finite"},
        {"pixel_sigma_px: 1e999", "F: pixel_sigma_px: inf is not finite"},
        {"default_depth_m: -.inf", "F: default_depth_m: -inf is not finite"},
        {"method: 3", "F: method: 3 is not a string"},
        {"method: parity2",
         "F: method: \"parity2\" is not one of none, parity, oprf, ransac1, ransacf, both"},
        {"filter:\n   enabled: true", "F: filter.enabled: \"true\" is not an integer"},
        {"filter: 1", "F: filter: 1 is not a map"},
        {"channels: [ a ]", "F: channels: [\"a\"] is not a map"},
        {"channels:\n   imu: 5", "F: channels.imu: 5 is not a string"},
        {"lcm_url: 7667", "F: lcm_url: 7667 is not a string"},
        {"lcm_url: \"\"", "F: lcm_url: \"\" is empty"},
        {"gyro_bias_rad_s: [ 0.0, 0.0 ]",
         "F: gyro_bias_rad_s: [0.0, 0.0] is not a list of 3 numbers"},
        {"gyro_bias_rad_s: [ 0.0, x, 0.0 ]", "F: gyro_bias_rad_s[1]: \"x\" is not a number"},
        {"gyro_bias_rad_s: [ 0.0, 0.0, .nan ]", "F: gyro_bias_rad_s[2]: nan is not finite"},
        {"gyro_bias_rad_s: [ 0, 0, 99999999999 ]",
         "F: gyro_bias_rad_s[2]: 99999999999 is outside the 32-bit integer range"},
        {"filter:\n   init_accel_bias_m_s2: [ 0.1, 0.2 ]",
         "F: filter.init_accel_bias_m_s2: [0.1, 0.2] is not a list of 3 numbers"},
        {"filter: { window_size: 07 }",
         "F: filter.window_size: 07 has a leading 0 (cv::FileStorage would read it as octal)"},
        // microseconds and the seed
        {"max_imu_gap_us: 2.5", "F: max_imu_gap_us: 2.5 is not a whole number of microseconds"},
        {"max_imu_gap_us: -5", "F: max_imu_gap_us: -5 is not > 0"},
        {"max_imu_gap_us: 5000000000",
         "F: max_imu_gap_us: 5000000000 is outside the 32-bit integer range"},
        {"max_imu_gap_us: 1e16", "F: max_imu_gap_us: 1e+16 is beyond 9e15 microseconds"},
        {"max_imu_gap_us: .nan", "F: max_imu_gap_us: nan is not a whole number of microseconds"},
        {"time_horizon_us: 0", "F: time_horizon_us: 0 is not > 0"},
        {"time_horizon_us: 0.5", "F: time_horizon_us: 0.5 is not a whole number of microseconds"},
        {"time_resync_messages: 1", "F: time_resync_messages: 1 is not in 2..1000"},
        {"time_resync_messages: 5.5", "F: time_resync_messages: 5.5 is not an integer"},
        {"seed: -1", "F: seed: -1 is not an unsigned integer (0..2^53)"},
        {"seed: 1.5", "F: seed: 1.5 is not an unsigned integer (0..2^53)"},
        {"seed: \"1\"", "F: seed: \"1\" is not an unsigned integer"},
        // the filter's ranges
        {"filter:\n   window_size: 6", "F: filter.window_size: 6 is not in 2..5"},
        {"filter:\n   window_gate_alpha: 0.75",
         "F: filter.window_gate_alpha: 0.75 is not in (0, 0.5]"},
        {"filter:\n   init_rest_s: 0", "F: filter.init_rest_s: 0 is not in (0, 60)"},
        {"filter:\n   landmark_gate_alpha: 0", "F: filter.landmark_gate_alpha: 0 is not in (0, 1)"},
        {"filter:\n   landmark_max_age_s: -2",
         "F: filter.landmark_max_age_s: -2 is not in (0, 9e+09]"},
        {"filter:\n   landmark_depth_var_m2: -1",
         "F: filter.landmark_depth_var_m2: -1 is not >= 0"},
        {"filter:\n   min_parallax_px: -1", "F: filter.min_parallax_px: -1 is not >= 0"},
        {"filter:\n   gyro_bias_at_rest: 2", "F: filter.gyro_bias_at_rest: 2 is not 0 or 1"},
        // keys
        {"no_such_key: 3", "F: unknown key no_such_key"},
        {"filter:\n   gravity: 9.81", "F: unknown key filter.gravity"},
        {"channels:\n   imu2: \"X\"", "F: unknown key channels.imu2"},
        // across keys
        {"method: oprf\nfilter:\n   enabled: 0",
         "F: method: \"oprf\" needs filter.enabled: 1 (it is 0, from F)"},
    };
    for (const auto &c : cases) expect_equal(file_error(c.first), c.second, c.first.c_str());
    // the values a microsecond key or the seed takes beyond 32 bits, written as reals
    AppConfig cfg;
    expect_equal(file_error("max_imu_gap_us: 5e9\nseed: 4.5e15\ntime_horizon_us: 2.0e6", &cfg), "",
                 "reals for the 64-bit keys");
    assert_true(cfg.node.params.max_imu_gap_us == 5000000000LL);
    assert_true(cfg.node.params.seed == 4500000000000000ULL);
    assert_true(cfg.node.time.horizon_us == 2000000LL);
    // integers that fit, comments and quoted strings holding digits are not literals to refuse
    expect_equal(file_error("camera_id: 2147483647 # 0123\nchannels:\n   imu: \"0123\"\n"
                            "lcm_url: \"udpm://239.255.76.67:7667?ttl=0\"",
                            &cfg),
                 "", "literals that fit");
    assert_int_equal(cfg.node.camera_id, 2147483647);
    expect_equal(cfg.channels.imu, "0123", "a quoted channel of digits");
    // a missing file and a file that is not YAML
    AppConfig c2;
    std::string err;
    assert_false(sfdapp::read_config("/nonexistent/sfd.yaml", &c2, &err));
    expect_equal(err, "/nonexistent/sfd.yaml: cannot open (No such file or directory)",
                 "missing file");
    assert_false(sfdapp::read_config("/tmp", &c2, &err));
    expect_equal(err, "/tmp: not a regular file", "a directory");
    expect_equal(file_error("seed: 1\ngyro_bias_rad_s: [ 1"),
                 "F:4: not valid YAML (Missing , between the elements)", "not YAML");
    // outside the YAML subset of sfd.yaml: refused before cv::FileStorage, which never returns
    // on these two (found by fuzz.config), and a control byte
    const std::string subset =
        ": not a 'key: value' line (the configuration is the YAML subset of apps/config/sfd.yaml)";
    expect_equal(file_error("   gravity_m_s2: 9.81\n   # c\n-\n-"), "F:5" + subset,
                 "block list items (a cv::FileStorage hang)");
    expect_equal(file_error("# c\n   f%%irst qL:1.0\n--/-"), "F:4" + subset,
                 "a key with '%' (a cv::FileStorage hang)");
    expect_equal(file_error("seed: 1\x01"),
                 "F:3: a control character or a non-ASCII byte outside a comment", "control byte");
    expect_equal(file_error("# \xc3\xa9t\xc3\xa9\nseed: 1"), "", "UTF-8 in a comment");
    // plain YAML without the %YAML:1.0 line (cv::FileStorage: "Input file is invalid"), and a
    // comment, a blank line or a trailing space on line 1 (the same)
    const std::string header =
        "F:1: the first line must be %YAML:1.0 (cv::FileStorage, which reads the configuration, "
        "takes no file without it)";
    for (const char *text : {"seed: 1\n", "---\nseed: 1\n", "# c\n%YAML:1.0\nseed: 1\n",
                             "\nseed: 1\n", "\n%YAML:1.0\nseed: 1\n", "%YAML:1.0 \nseed: 1\n"}) {
        char plain[] = "/tmp/sfd_test_app_config_XXXXXX";
        const int pfd = mkstemp(plain);
        assert_true(pfd >= 0);
        const size_t len = std::strlen(text);
        assert_int_equal(write(pfd, text, len), static_cast<ssize_t>(len));
        close(pfd);
        assert_false(sfdapp::read_config(plain, &c2, &err));
        expect_equal(err, std::string(plain) + header.substr(1), text);
        std::remove(plain);
    }
    // a YAML escape that makes a line break in a value, or in a key, stays one line in the
    // message (found by fuzz.config)
    const std::string nl = file_error("channels:\n   imu: \"a\\nb\"");
    assert_true(nl.find('\n') == std::string::npos);
    assert_true(nl.find("channels.imu: \"a\\nb\"") != std::string::npos);
    const std::string nk = file_error("filter: { \"a\\nb\": 1 }");
    expect_equal(nk, "F: unknown key filter.\"a\\nb\"", "an escaped key");
    // an empty file (cv::FileStorage asserts on it, with a two-line message)
    char empty[] = "/tmp/sfd_test_app_config_XXXXXX";
    const int fd = mkstemp(empty);
    assert_true(fd >= 0);
    close(fd);
    assert_false(sfdapp::read_config(empty, &c2, &err));
    expect_equal(err, std::string(empty) + ": empty file, not a YAML configuration", "empty");
    std::remove(empty);
}

// GIVEN load_config() (read_config() then validate(), for sfd-hil, which overrides no key) THEN
// a range error of the file is refused with the same message.
void load_config_validates(void **) {
    const std::string path = write_yaml("filter:\n   gravity_m_s2: -9.81");
    AppConfig cfg;
    std::string err;
    assert_true(sfdapp::read_config(path, &cfg, &err));
    assert_false(sfdapp::load_config(path, &cfg, &err));
    std::remove(path.c_str());
    expect_equal(err, path + ": filter.gravity_m_s2: -9.81 is not > 0", "load_config");
    AppConfig shipped;
    assert_true(sfdapp::load_config(g_shipped_yaml, &shipped, &err));
}

// GIVEN a bad value in the file and a good one on the command line (or the reverse) THEN the
// configuration after the overrides is judged, and the message names the flag that set the key.
void overrides_are_validated_after_the_file(void **) {
    AppConfig cfg;
    assert_string_equal(file_error("method: oprf\nfilter:\n   enabled: 0", &cfg).c_str(),
                        "F: method: \"oprf\" needs filter.enabled: 1 (it is 0, from F)");
    std::string err;
    assert_true(sfdapp::set_method("parity", &cfg, &err));  // --method parity
    cfg.origin["method"] = "--method";
    assert_true(sfdapp::validate(cfg, &err));
    // --window-frames 9 (sfd_app_cli.hpp: the flag of a key sets it, the range is validate()'s)
    assert_true(sfdapp::set_key("window_frames", "9", "--window-frames", &cfg, &err));
    assert_false(sfdapp::validate(cfg, &err));
    expect_equal(err, "--window-frames: window_frames: 9 is not in 2..5",
                 "an override out of range");
}

// GIVEN a key's flag value THEN it is read whole by the file's type rules: 2.5 is not an
// integer, 5x not a number; the range is left to validate() (nan included).
void command_line_values_follow_the_file_rules(void **) {
    AppConfig cfg;
    std::string why;
    assert_true(sfdapp::set_key("window_frames", "-4", "--window-frames", &cfg, &why));
    assert_int_equal(cfg.node.params.window_frames, -4);
    expect_equal(cfg.origin_of("window_frames"), "--window-frames", "origin");
    const std::vector<std::pair<const char *, const char *>> bad_ints = {
        {"2.5", "is not an integer"},
        {"", "is not an integer"},
        {"3x", "is not an integer"},
        {"1e3", "is not an integer"},
        {"99999999999", "is outside the 32-bit integer range"},
    };
    for (const auto &b : bad_ints) {
        assert_false(sfdapp::set_key("window_frames", b.first, "--window-frames", &cfg, &why));
        expect_equal(why, b.second, b.first);
    }
    assert_true(sfdapp::set_key("false_alarm_rate", "nan", "--false-alarm-rate", &cfg, &why));
    assert_true(std::isnan(cfg.node.params.false_alarm_rate));
    assert_false(sfdapp::set_key("false_alarm_rate", "0.05x", "--false-alarm-rate", &cfg, &why));
    expect_equal(why, "is not a number", "junk after a number");
    assert_false(sfdapp::set_key("max_imu_gap_us", "2.5", "--max-imu-gap-us", &cfg, &why));
    assert_true(
        sfdapp::set_key("gyro_bias_rad_s", "0.1,-0.2,3e-3", "--gyro-bias-rad-s", &cfg, &why));
    assert_true(cfg.node.params.gyro_bias_rad_s[1] == -0.2);
    assert_false(sfdapp::set_key("gyro_bias_rad_s", "1,2", "--gyro-bias-rad-s", &cfg, &why));
    assert_false(sfdapp::set_key("method", "ransac", "--method", &cfg, &why));
    expect_equal(why, "is not one of none, parity, oprf, ransac1, ransacf, both", "method");
    assert_true(sfdapp::set_key("channels.imu", "IMU2", "--channels.imu", &cfg, &why));
    expect_equal(cfg.channels.imu, "IMU2", "a channel");
    expect_equal(sfdapp::flag_of("filter.window_size"), "--filter.window-size", "a nested key");
    expect_equal(sfdapp::flag_of("pixel_sigma_px"), "--pixel-sigma-px", "a top-level key");
}

void numbers_are_printed_as_written(void **) {
    expect_equal(sfdapp::format_double(-9.81), "-9.81", "-9.81");
    expect_equal(sfdapp::format_double(0.1), "0.1", "0.1");
    expect_equal(sfdapp::format_double(5.0), "5", "5");
    expect_equal(sfdapp::format_double(5.0, true), "5.0", "5.0 as a real");
    expect_equal(sfdapp::format_double(3.4e-4), "0.00034", "3.4e-4");
    expect_equal(sfdapp::format_double(1e-300), "1e-300", "1e-300");
    expect_equal(sfdapp::format_double(-kInf), "-inf", "-inf");
    expect_equal(sfdapp::format_double(-kNan), "nan", "nan");
}

}  // namespace

int main(int argc, char **argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: test_app_config PATH/apps/config/sfd.yaml\n");
        return 2;
    }
    g_shipped_yaml = argv[1];
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(shipped_config_is_valid),
        cmocka_unit_test(one_bad_value_per_key_is_named),
        cmocka_unit_test(only_the_bad_key_is_named),
        cmocka_unit_test(accepted_configurations_start_a_node),
        cmocka_unit_test(file_values_are_named),
        cmocka_unit_test(load_config_validates),
        cmocka_unit_test(overrides_are_validated_after_the_file),
        cmocka_unit_test(command_line_values_follow_the_file_rules),
        cmocka_unit_test(numbers_are_printed_as_written),
    };
    return cmocka_run_group_tests(tests, nullptr, nullptr);
}
