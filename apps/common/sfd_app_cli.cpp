// SPDX-License-Identifier: MIT
#include "sfd_app_cli.hpp"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <type_traits>

namespace sfdapp {

namespace {

// How a key's text is read (the file's rules, sfd_app_config.cpp's Reader).
enum class Kind { kMethod, kReal, kInt, kMicros, kSeed, kVec3, kString };

struct KeyInfo {
    ConfigKey doc;
    Kind kind;
    void *(*dst)(AppConfig &);  // where the value goes (kMethod: unused)
};

static_assert(std::is_same<int, int32_t>::value, "integer keys are int32_t and int alike");

// NOLINTNEXTLINE(bugprone-macro-parentheses): a lambda around a member path, not an expression
#define SFD_DST(expr) [](AppConfig &c) -> void * { return &(c.expr); }

// In the order of apps/config/sfd.yaml (integration.cli_convention checks the two against each
// other, and docs/deploy.md's table against both).
const KeyInfo kKeys[] = {
    {{"method", "M", "none | parity | oprf | ransac1 | ransacf | both"}, Kind::kMethod, nullptr},
    {{"false_alarm_rate", "A", "false-alarm rate of the chi-square tests, (0, 0.5]"},
     Kind::kReal,
     SFD_DST(node.params.false_alarm_rate)},
    {{"pixel_sigma_px", "PX", "pixel noise per axis (px), > 0"},
     Kind::kReal,
     SFD_DST(node.params.pixel_sigma_px)},
    {{"window_frames", "L", "parity window (frames), 2..SFD_MAX_WINDOW"},
     Kind::kInt,
     SFD_DST(node.params.window_frames)},
    {{"group_size", "n", "parity group size, 1..SFD_MAX_GROUP"},
     Kind::kInt,
     SFD_DST(node.params.group_size)},
    {{"translation_known", "0|1", "1: translation from the window filter; 0: eliminated"},
     Kind::kInt,
     SFD_DST(node.params.translation_known)},
    {{"exact_depth_covariance", "0|1", "1: depth-noise covariance of eq. (22); 0: (28)"},
     Kind::kInt,
     SFD_DST(node.params.exact_depth_covariance)},
    {{"parity_isolation", "0|1", "1: isolate spurious features in failing groups"},
     Kind::kInt,
     SFD_DST(node.params.parity_isolation)},
    {{"pixel_noise_adapt", "0|1", "1: the pixel noise variance scaled by an online estimate"},
     Kind::kInt,
     SFD_DST(node.params.pixel_noise_adapt)},
    {{"evidence_frames", "N", "frames of the evidence test over a track's life, 0..SFD_MAX_WINDOW"},
     Kind::kInt,
     SFD_DST(node.params.evidence_frames)},
    {{"both_parity_share", "S", "method both: parity's share of false_alarm_rate, (0, 1)"},
     Kind::kReal,
     SFD_DST(node.params.both_parity_share)},
    {{"alarm_hold_ratio", "R",
      "threshold factor after alarm_hold_frames alarms in a row on a track, (0, 1]; 1: off"},
     Kind::kReal,
     SFD_DST(node.params.alarm_hold_ratio)},
    {{"alarm_hold_frames", "N", "alarms in a row that start the alarm hold, 1..100"},
     Kind::kInt,
     SFD_DST(node.params.alarm_hold_frames)},
    {{"alarm_hold_max_statistic", "K",
      "an alarm above K times its threshold (a step) does not start the hold, [1, 1e6]"},
     Kind::kReal,
     SFD_DST(node.params.alarm_hold_max_statistic)},
    {{"alarm_hold_min_statistic", "K",
      "a held alarm below K times the full threshold ends the hold, [0, 1]; 0: every held "
      "alarm continues it"},
     Kind::kReal,
     SFD_DST(node.params.alarm_hold_min_statistic)},
    {{"alarm_hold_alpha_scale", "S",
      "with the hold on, the window test's share of false_alarm_rate is scaled by S (the "
      "evidence test keeps alpha/2), (0, 1]"},
     Kind::kReal,
     SFD_DST(node.params.alarm_hold_alpha_scale)},
    {{"alarm_hold_direction_alpha", "A",
      "a held track with a fitted motion is tested one-sided along its direction at level A "
      "instead of against the lowered threshold, [0, 0.5); 0: off"},
     Kind::kReal,
     SFD_DST(node.params.alarm_hold_direction_alpha)},
    {{"evidence_ramp_share", "S",
      "the ramp test's share of the evidence test's alpha/2 (the omnibus keeps the rest), [0, 1]; "
      "0: off"},
     Kind::kReal,
     SFD_DST(node.params.evidence_ramp_share)},
    {{"default_depth_m", "M", "depth prior of features without one (m), > 0"},
     Kind::kReal,
     SFD_DST(node.params.default_depth_m)},
    {{"default_depth_var_m2", "V", "variance of that prior (m^2), >= 0"},
     Kind::kReal,
     SFD_DST(node.params.default_depth_var_m2)},
    {{"max_imu_gap_us", "US", "largest IMU gap inside a frame interval (us), > 0"},
     Kind::kMicros,
     SFD_DST(node.params.max_imu_gap_us)},
    {{"time_horizon_us", "US", "time-glitch horizon (us), > 0"},
     Kind::kMicros,
     SFD_DST(node.time.horizon_us)},
    {{"time_resync_messages", "N", "jumped messages that restart a stream, 2..1000"},
     Kind::kInt,
     SFD_DST(node.time.resync_messages)},
    {{"gyro_bias_rad_s", "X,Y,Z", "gyro bias subtracted (rad/s, IMU frame)"},
     Kind::kVec3,
     SFD_DST(node.params.gyro_bias_rad_s[0])},
    {{"max_hypotheses", "N", "hypothesis budget per frame, 1..SFD_MAX_HYPOTHESES"},
     Kind::kInt,
     SFD_DST(node.params.max_hypotheses)},
    {{"ransac_confidence", "P", "probability p of eq. (27), (0, 1)"},
     Kind::kReal,
     SFD_DST(node.params.ransac_confidence)},
    {{"seed", "S", "seed of the hypothesis draws, 0..2^53"},
     Kind::kSeed,
     SFD_DST(node.params.seed)},
    {{"filter.enabled", "0|1", "1: run the EKF (SFD_STATE)"},
     Kind::kInt,
     SFD_DST(node.nav.enabled)},
    {{"filter.gyro_noise_rad_s_rthz", "D", "gyro noise density, >= 0"},
     Kind::kReal,
     SFD_DST(node.nav.noise.gyro_noise_rad_s_rthz)},
    {{"filter.accel_noise_m_s2_rthz", "D", "accelerometer noise density, >= 0"},
     Kind::kReal,
     SFD_DST(node.nav.noise.accel_noise_m_s2_rthz)},
    {{"filter.gyro_bias_rw_rad_s2_rthz", "D", "gyro bias random walk, >= 0"},
     Kind::kReal,
     SFD_DST(node.nav.noise.gyro_bias_rw_rad_s2_rthz)},
    {{"filter.accel_bias_rw_m_s3_rthz", "D", "accelerometer bias random walk, >= 0"},
     Kind::kReal,
     SFD_DST(node.nav.noise.accel_bias_rw_m_s3_rthz)},
    {{"filter.gravity_m_s2", "G", "gravity (m/s^2), > 0"},
     Kind::kReal,
     SFD_DST(node.nav.noise.gravity_m_s2)},
    {{"filter.window_filter", "0|1", "1: sliding-window filter; 0: single-state EKF"},
     Kind::kInt,
     SFD_DST(node.nav.window_filter)},
    {{"filter.window_size", "N", "poses of the window filter, 2..SFD_MAX_WINDOW"},
     Kind::kInt,
     SFD_DST(node.nav.window_size)},
    {{"filter.window_depth_priors", "0|1|2",
      "depth priors per track used: none, the first, the first and newest"},
     Kind::kInt,
     SFD_DST(node.nav.window_depth_priors)},
    {{"filter.window_flagged_earlier", "0|1",
      "1: a flagged track's earlier observations used through the gate (not after an evidence "
      "flag); 0: deleted"},
     Kind::kInt,
     SFD_DST(node.nav.window_flagged_earlier)},
    {{"filter.window_gate_alpha", "A", "false-alarm rate of the window gate, (0, 0.5]"},
     Kind::kReal,
     SFD_DST(node.nav.window_gate_alpha)},
    {{"filter.first_estimates", "0|1", "1: first-estimate Jacobians"},
     Kind::kInt,
     SFD_DST(node.nav.first_estimates)},
    {{"filter.observability_constrained", "0|1", "1: observability-constrained Jacobians"},
     Kind::kInt,
     SFD_DST(node.nav.observability_constrained)},
    {{"filter.keyframe_parallax_rad", "R",
      "0: the oldest pose leaves the window; > 0: poses moving less leave (keyframes)"},
     Kind::kReal,
     SFD_DST(node.nav.keyframe_parallax_rad)},
    {{"filter.init_rest_s", "S", "IMU at rest averaged at start (s), (0, 60)"},
     Kind::kReal,
     SFD_DST(node.nav.init_rest_s)},
    {{"filter.init_from_truth", "0|1", "1: start from TRUTH (evaluation only)"},
     Kind::kInt,
     SFD_DST(node.nav.init_from_truth)},
    {{"filter.init_accel_bias_m_s2", "X,Y,Z", "accelerometer bias with init_from_truth"},
     Kind::kVec3,
     SFD_DST(node.nav.init_accel_bias_m_s2[0])},
    {{"filter.consider_position", "0|1", "1: camera updates leave the position alone"},
     Kind::kInt,
     SFD_DST(node.nav.consider_position)},
    {{"filter.gyro_bias_at_rest", "0|1", "1: the mean gyro at rest is the initial bias"},
     Kind::kInt,
     SFD_DST(node.nav.gyro_bias_at_rest)},
    {{"filter.landmark_depth_var_m2", "V", "depth variance without a prior (m^2), >= 0"},
     Kind::kReal,
     SFD_DST(node.nav.landmark_depth_var_m2)},
    {{"filter.landmark_max_age_s", "S", "landmarks unseen this long are dropped (s)"},
     Kind::kReal,
     SFD_DST(node.nav.landmark_max_age_s)},
    {{"filter.landmark_gate_alpha", "A", "false-alarm rate of the landmark gate, (0, 1)"},
     Kind::kReal,
     SFD_DST(node.nav.landmark_gate_alpha)},
    {{"filter.min_parallax_px", "PX", "OPRF: least parallax for epipolar tests (px)"},
     Kind::kReal,
     SFD_DST(node.nav.min_parallax_px)},
    {{"camera_id", "ID", "camera to follow; -1: the first CAMERA_INFO's"},
     Kind::kInt,
     SFD_DST(node.camera_id)},
    {{"publish_timing", "0|1", "1: publish SFD_TIMING after every frame"},
     Kind::kInt,
     SFD_DST(node.publish_timing)},
    {{"lcm_url", "URL", "LCM provider (sfd-node; sfd-replay reads a file)"},
     Kind::kString,
     SFD_DST(lcm_url)},
    {{"channels.imu", "NAME", "IMU channel"}, Kind::kString, SFD_DST(channels.imu)},
    {{"channels.camera_info", "NAME", "CAMERA_INFO channel"},
     Kind::kString,
     SFD_DST(channels.camera_info)},
    {{"channels.features", "NAME", "FEATURES channel"}, Kind::kString, SFD_DST(channels.features)},
    {{"channels.verdict", "NAME", "SFD_VERDICT channel"}, Kind::kString, SFD_DST(channels.verdict)},
    {{"channels.timing", "NAME", "SFD_TIMING channel"}, Kind::kString, SFD_DST(channels.timing)},
    {{"channels.state", "NAME", "SFD_STATE channel"}, Kind::kString, SFD_DST(channels.state)},
    {{"channels.truth", "NAME", "TRUTH channel"}, Kind::kString, SFD_DST(channels.truth)},
};

#undef SFD_DST

const KeyInfo *find_key(const std::string &key) {
    for (const KeyInfo &k : kKeys) {
        if (key == k.doc.key) return &k;
    }
    return nullptr;
}

// The deprecated spellings of sfd 0.1: {old flag, new flag}.
const char *const kAliases[][2] = {
    {"alpha", "false-alarm-rate"},
    {"window", "window-frames"},
    {"group", "group-size"},
    {"pixel-sigma", "pixel-sigma-px"},
    {"depth-default", "default-depth-m"},
    {"imu-channel", "channels.imu"},
    {"camera-info-channel", "channels.camera_info"},
    {"features-channel", "channels.features"},
    {"verdict-channel", "channels.verdict"},
    {"timing-channel", "channels.timing"},
    {"state-channel", "channels.state"},
    {"truth-channel", "channels.truth"},
};

}  // namespace

const std::vector<ConfigKey> &config_keys() {
    static const std::vector<ConfigKey> keys = [] {
        std::vector<ConfigKey> v;
        for (const KeyInfo &k : kKeys) v.push_back(k.doc);
        return v;
    }();
    return keys;
}

std::string flag_of(const std::string &key) {
    std::string f = "--" + key;
    for (char &c : f) {
        if (c == '_') c = '-';
    }
    return f;
}

bool set_key(const std::string &key, const std::string &text, const std::string &origin,
             AppConfig *cfg, std::string *why) {
    const KeyInfo *k = find_key(key);
    if (k == nullptr) {
        *why = "is not a key of the configuration";
        return false;
    }
    switch (k->kind) {
        case Kind::kMethod: {
            std::string err;
            if (!set_method(text, cfg, &err)) {
                *why = "is " + err;
                return false;
            }
            break;
        }
        case Kind::kReal: {
            // Any number strtod reads whole, nan and inf included: the range is validate()'s,
            // as for the file.
            const char *b = text.c_str();
            char *end = nullptr;
            const double v = std::strtod(b, &end);
            if (text.empty() || end == b || *end != '\0') {
                *why = "is not a number";
                return false;
            }
            *static_cast<double *>(k->dst(*cfg)) = v;
            break;
        }
        case Kind::kInt: {
            long long v = 0;
            if (!sfdcli::parse_int(text, std::numeric_limits<int32_t>::min(),
                                   std::numeric_limits<int32_t>::max(), &v, why)) {
                if (*why != "is not an integer") *why = "is outside the 32-bit integer range";
                return false;
            }
            *static_cast<int32_t *>(k->dst(*cfg)) = static_cast<int32_t>(v);
            break;
        }
        case Kind::kMicros: {
            double v = 0.0;
            if (!sfdcli::parse_real(text, -9.0e15, 9.0e15, &v, why) || v != std::floor(v)) {
                *why = "is not a whole number of microseconds (|value| <= 9e15)";
                return false;
            }
            *static_cast<int64_t *>(k->dst(*cfg)) = static_cast<int64_t>(v);
            break;
        }
        case Kind::kSeed: {
            double v = 0.0;
            if (!sfdcli::parse_real(text, 0.0, 9007199254740992.0, &v, why) || v != std::floor(v)) {
                *why = "is not an unsigned integer (0..2^53)";
                return false;
            }
            *static_cast<uint64_t *>(k->dst(*cfg)) = static_cast<uint64_t>(v);
            break;
        }
        case Kind::kVec3:
            if (!sfdcli::parse_vec3(text, static_cast<double *>(k->dst(*cfg)), why)) return false;
            break;
        case Kind::kString:
            *static_cast<std::string *>(k->dst(*cfg)) = text;
            break;
    }
    cfg->origin[key] = origin;
    return true;
}

void ConfigCommandLine::add_to(sfdcli::Parser *parser) {
    parser->section(
        "Configuration (apps/config/sfd.yaml documents every key; a flag is the key with '_'\n"
        "written '-', a nested key keeping its dot; flags override the --config files)");
    parser->value("config", "F",
                  "YAML configuration; several: later keys win (all\n"
                  "read before the flags)",
                  [this](const std::string &v, std::string *) {
                      files_.push_back(v);
                      return true;
                  });
    for (const KeyInfo &k : kKeys) {
        const std::string key = k.doc.key, flag = flag_of(key);
        parser->value(flag.substr(2), k.doc.metavar, k.doc.help,
                      [this, key, flag](const std::string &v, std::string *why) {
                          AppConfig scratch;  // the type is checked now, the range after the files
                          if (!set_key(key, v, flag, &scratch, why)) return false;
                          settings_.push_back(Setting{key, v, flag});
                          return true;
                      });
    }
    for (const auto &a : kAliases) parser->alias(a[0], std::string(flag_of(a[1])).substr(2));
    sfdcli::Option no_iso;
    no_iso.name = "no-isolation";
    no_iso.alias_of = "parity-isolation 0";
    no_iso.set = [this](const std::string &, std::string *) {
        settings_.push_back(Setting{"parity_isolation", "0", "--no-isolation"});
        return true;
    };
    parser->add(no_iso);
}

int ConfigCommandLine::load(const std::string &prog, AppConfig *cfg) const {
    std::string err;
    for (const std::string &f : files_) {
        if (!read_config(f, cfg, &err)) {
            std::fprintf(stderr, "%s: %s\n", prog.c_str(), err.c_str());
            return sfdcli::kExitUsage;
        }
    }
    for (const Setting &s : settings_) {
        if (!set_key(s.key, s.text, s.flag, cfg, &err)) {  // checked when parsed: not reached
            std::fprintf(stderr, "%s: %s: %s %s\n", prog.c_str(), s.flag.c_str(), s.text.c_str(),
                         err.c_str());
            return sfdcli::kExitUsage;
        }
    }
    if (!validate(*cfg, &err)) {
        std::fprintf(stderr, "%s: %s\n", prog.c_str(), err.c_str());
        return sfdcli::kExitUsage;
    }
    return 0;
}

}  // namespace sfdapp
