// SPDX-License-Identifier: MIT
#include "sfd_app_config.hpp"

#include <opencv2/core.hpp>

#include <cerrno>
#include <cstdlib>
#include <set>

namespace sfdapp {

AppConfig::AppConfig() {
    sfd_node_config_default(&node);
}

bool set_method(const std::string &name, AppConfig *cfg, std::string *error) {
    if (name == "none") {
        cfg->node.params.method = SFD_METHOD_NONE;
    } else if (name == "parity") {
        cfg->node.params.method = SFD_METHOD_PARITY;
    } else if (name == "oprf") {
        cfg->node.params.method = SFD_METHOD_OPRF;
    } else if (name == "ransac1") {
        cfg->node.params.method = SFD_METHOD_RANSAC1;
    } else if (name == "ransacf") {
        cfg->node.params.method = SFD_METHOD_RANSACF;
    } else if (name == "both") {
        cfg->node.params.method = SFD_METHOD_BOTH;
    } else {
        *error = "unknown method " + name + " (none, parity, oprf, ransac1, ransacf, both)";
        return false;
    }
    cfg->method = name;
    return true;
}

namespace {

bool read_number(const cv::FileNode &n, const std::string &where, double *out, std::string *err) {
    if (!n.isReal() && !n.isInt()) {
        *err = where + ": expected a number";
        return false;
    }
    *out = static_cast<double>(n);
    return true;
}

bool read_int(const cv::FileNode &n, const std::string &where, int *out, std::string *err) {
    if (!n.isInt()) {
        *err = where + ": expected an integer";
        return false;
    }
    *out = static_cast<int>(n);
    return true;
}

bool read_string(const cv::FileNode &n, const std::string &where, std::string *out,
                 std::string *err) {
    if (!n.isString()) {
        *err = where + ": expected a string";
        return false;
    }
    *out = static_cast<std::string>(n);
    return true;
}

}  // namespace

bool load_config(const std::string &path, AppConfig *cfg, std::string *error) {
    cv::FileStorage fs;
    try {
        if (!fs.open(path, cv::FileStorage::READ | cv::FileStorage::FORMAT_YAML)) {
            *error = path + ": cannot open";
            return false;
        }
    } catch (const cv::Exception &e) {
        *error = path + ": not valid YAML (" + e.msg + ")";
        return false;
    }
    const cv::FileNode root = fs.root();
    if (!root.isMap()) {
        *error = path + ": top level is not a map";
        return false;
    }
    static const std::set<std::string> known = {"method",
                                                "false_alarm_rate",
                                                "pixel_sigma_px",
                                                "window_frames",
                                                "group_size",
                                                "translation_known",
                                                "exact_depth_covariance",
                                                "parity_isolation",
                                                "default_depth_m",
                                                "default_depth_var_m2",
                                                "max_imu_gap_us",
                                                "time_horizon_us",
                                                "time_resync_messages",
                                                "gyro_bias_rad_s",
                                                "camera_id",
                                                "publish_timing",
                                                "lcm_url",
                                                "channels",
                                                "max_hypotheses",
                                                "ransac_confidence",
                                                "seed",
                                                "filter"};
    for (const std::string &key : root.keys()) {
        if (known.count(key) == 0) {
            *error = path;
            error->append(": unknown key ").append(key);
            return false;
        }
    }
    sfd_params_t &p = cfg->node.params;
    auto where = [&](const std::string &key) { return path + ": " + key; };
    double d = 0;
    int i = 0;
    std::string s;
    if (!root["method"].empty()) {
        if (!read_string(root["method"], where("method"), &s, error)) return false;
        if (!set_method(s, cfg, error)) {
            *error = where("method") + ": " + *error;
            return false;
        }
    }
    struct NumKey {
        const char *name;
        double *dst;
    } nums[] = {{"false_alarm_rate", &p.false_alarm_rate},
                {"pixel_sigma_px", &p.pixel_sigma_px},
                {"default_depth_m", &p.default_depth_m},
                {"default_depth_var_m2", &p.default_depth_var_m2},
                {"ransac_confidence", &p.ransac_confidence}};
    for (const NumKey &k : nums) {
        if (root[k.name].empty()) continue;
        if (!read_number(root[k.name], where(k.name), &d, error)) return false;
        *k.dst = d;
    }
    struct IntKey {
        const char *name;
        int *dst;
    } ints[] = {{"window_frames", &p.window_frames},
                {"group_size", &p.group_size},
                {"translation_known", &p.translation_known},
                {"exact_depth_covariance", &p.exact_depth_covariance},
                {"parity_isolation", &p.parity_isolation},
                {"max_hypotheses", &p.max_hypotheses},
                {"publish_timing", &cfg->node.publish_timing}};
    for (const IntKey &k : ints) {
        if (root[k.name].empty()) continue;
        if (!read_int(root[k.name], where(k.name), &i, error)) return false;
        *k.dst = i;
    }
    if (!root["camera_id"].empty()) {
        if (!read_int(root["camera_id"], where("camera_id"), &i, error)) return false;
        cfg->node.camera_id = i;
    }
    if (!root["max_imu_gap_us"].empty()) {
        if (!read_number(root["max_imu_gap_us"], where("max_imu_gap_us"), &d, error)) return false;
        p.max_imu_gap_us = static_cast<int64_t>(d);
    }
    if (!root["time_horizon_us"].empty()) {
        if (!read_number(root["time_horizon_us"], where("time_horizon_us"), &d, error))
            return false;
        if (!(d > 0.0 && d <= 9.0e15) || d != static_cast<double>(static_cast<int64_t>(d))) {
            *error = where("time_horizon_us") + ": " + std::to_string(d) +
                     " is not a whole number of microseconds > 0";
            return false;
        }
        cfg->node.time.horizon_us = static_cast<int64_t>(d);
    }
    if (!root["time_resync_messages"].empty()) {
        if (!read_int(root["time_resync_messages"], where("time_resync_messages"), &i, error)) {
            return false;
        }
        if (i < 2 || i > 1000) {
            *error =
                where("time_resync_messages") + ": " + std::to_string(i) + " is not in 2..1000";
            return false;
        }
        cfg->node.time.resync_messages = i;
    }
    const cv::FileNode bias = root["gyro_bias_rad_s"];
    if (!bias.empty()) {
        if (!bias.isSeq() || bias.size() != 3) {
            *error = where("gyro_bias_rad_s") + ": expected a list of 3 numbers";
            return false;
        }
        for (int k = 0; k < 3; ++k) {
            if (!read_number(bias[k], where("gyro_bias_rad_s"), &d, error)) return false;
            p.gyro_bias_rad_s[k] = d;
        }
    }
    if (!root["seed"].empty()) {
        if (!read_int(root["seed"], where("seed"), &i, error)) return false;
        if (i < 0) {
            *error = where("seed") + ": expected a non-negative integer";
            return false;
        }
        p.seed = static_cast<uint64_t>(i);
    }
    const cv::FileNode flt = root["filter"];
    if (!flt.empty()) {
        if (!flt.isMap()) {
            *error = where("filter") + ": expected a map";
            return false;
        }
        sfd_nav_config_t &nv = cfg->node.nav;
        struct FKey {
            const char *name;
            double *dst;
        } fnums[] = {{"gyro_noise_rad_s_rthz", &nv.noise.gyro_noise_rad_s_rthz},
                     {"accel_noise_m_s2_rthz", &nv.noise.accel_noise_m_s2_rthz},
                     {"gyro_bias_rw_rad_s2_rthz", &nv.noise.gyro_bias_rw_rad_s2_rthz},
                     {"accel_bias_rw_m_s3_rthz", &nv.noise.accel_bias_rw_m_s3_rthz},
                     {"gravity_m_s2", &nv.noise.gravity_m_s2},
                     {"init_rest_s", &nv.init_rest_s},
                     {"landmark_depth_var_m2", &nv.landmark_depth_var_m2},
                     {"landmark_max_age_s", &nv.landmark_max_age_s},
                     {"landmark_gate_alpha", &nv.landmark_gate_alpha},
                     {"min_parallax_px", &nv.min_parallax_px},
                     {"window_gate_alpha", &nv.window_gate_alpha}};
        const char *fints[] = {"enabled",           "gyro_bias_at_rest", "init_from_truth",
                               "consider_position", "window_filter",     "window_size",
                               "first_estimates"};
        int32_t *fint_dst[] = {&nv.enabled,           &nv.gyro_bias_at_rest, &nv.init_from_truth,
                               &nv.consider_position, &nv.window_filter,     &nv.window_size,
                               &nv.first_estimates};
        constexpr int kNumFints = static_cast<int>(sizeof fints / sizeof fints[0]);
        for (const std::string &key : flt.keys()) {
            bool found = key == "init_accel_bias_m_s2";
            for (const FKey &k : fnums) found = found || key == k.name;
            for (const char *k : fints) found = found || key == k;
            if (!found) {
                *error = where("filter");
                error->append(": unknown key ").append(key);
                return false;
            }
        }
        for (const FKey &k : fnums) {
            if (flt[k.name].empty()) continue;
            if (!read_number(flt[k.name], where(std::string("filter.") + k.name), &d, error)) {
                return false;
            }
            *k.dst = d;
        }
        const cv::FileNode ab = flt["init_accel_bias_m_s2"];
        if (!ab.empty()) {
            const std::string w = where("filter.init_accel_bias_m_s2");
            if (!ab.isSeq() || ab.size() != 3) {
                *error = w + ": expected a list of 3 numbers";
                return false;
            }
            for (int k = 0; k < 3; ++k) {
                if (!read_number(ab[k], w, &d, error)) return false;
                nv.init_accel_bias_m_s2[k] = d;
            }
        }
        for (int k = 0; k < kNumFints; ++k) {
            if (flt[fints[k]].empty()) continue;
            if (!read_int(flt[fints[k]], where(std::string("filter.") + fints[k]), &i, error)) {
                return false;
            }
            *fint_dst[k] = i;
        }
    }
    if (!root["lcm_url"].empty() &&
        !read_string(root["lcm_url"], where("lcm_url"), &cfg->lcm_url, error)) {
        return false;
    }
    const cv::FileNode ch = root["channels"];
    if (!ch.empty()) {
        if (!ch.isMap()) {
            *error = where("channels") + ": expected a map";
            return false;
        }
        std::string *dst[] = {&cfg->channels.imu,      &cfg->channels.camera_info,
                              &cfg->channels.features, &cfg->channels.verdict,
                              &cfg->channels.timing,   &cfg->channels.state,
                              &cfg->channels.truth};
        const char *names[] = {"imu",    "camera_info", "features", "verdict",
                               "timing", "state",       "truth"};
        for (const std::string &key : ch.keys()) {
            bool found = false;
            for (int k = 0; k < 7; ++k) found = found || key == names[k];
            if (!found) {
                *error = where("channels");
                error->append(": unknown key ").append(key);
                return false;
            }
        }
        for (int k = 0; k < 7; ++k) {
            if (ch[names[k]].empty()) continue;
            if (!read_string(ch[names[k]], where(std::string("channels.") + names[k]), dst[k],
                             error)) {
                return false;
            }
        }
    }
    return validate(*cfg, error) || (*error = path + ": " + *error, false);
}

bool validate(const AppConfig &cfg, std::string *error) {
    const sfd_status_t st = sfd_params_validate(&cfg.node.params);
    if (st == SFD_OK) return true;
    *error = std::string("invalid detector parameters (") + sfd_status_str(st) +
             "): check false_alarm_rate (0, 0.5], pixel_sigma_px > 0, window_frames 2.." +
             std::to_string(SFD_MAX_WINDOW) + ", group_size 1.." + std::to_string(SFD_MAX_GROUP) +
             ", default_depth_m > 0, default_depth_var_m2 >= 0, max_imu_gap_us > 0, 0/1 flags";
    return false;
}

bool parse_long(const char *s, long lo, long hi, long *out) {
    char *end = nullptr;
    errno = 0;
    const long v = std::strtol(s, &end, 10);
    if (end == s || *end != '\0' || errno != 0 || v < lo || v > hi) return false;
    *out = v;
    return true;
}

}  // namespace sfdapp
