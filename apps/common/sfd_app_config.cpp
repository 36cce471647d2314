// SPDX-License-Identifier: MIT
#include "sfd_app_config.hpp"

#include <opencv2/core.hpp>

#include <set>

namespace sfdapp {

AppConfig::AppConfig() {
    sfd_params_default(&node.params);
    node.camera_id = -1;
    node.publish_timing = 1;
}

bool set_method(const std::string &name, AppConfig *cfg, std::string *error) {
    if (name == "none") {
        cfg->node.params.method = SFD_METHOD_NONE;
    } else if (name == "parity") {
        cfg->node.params.method = SFD_METHOD_PARITY;
    } else if (name == "oprf" || name == "ransac1" || name == "ransacf" || name == "both") {
        *error = "method " + name +
                 " is not in this build yet (arrives with the EKF); available: "
                 "none, parity";
        return false;
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
                                                "gyro_bias_rad_s",
                                                "camera_id",
                                                "publish_timing",
                                                "lcm_url",
                                                "channels"};
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
                {"default_depth_var_m2", &p.default_depth_var_m2}};
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
        std::string *dst[] = {&cfg->channels.imu, &cfg->channels.camera_info,
                              &cfg->channels.features, &cfg->channels.verdict,
                              &cfg->channels.timing};
        const char *names[] = {"imu", "camera_info", "features", "verdict", "timing"};
        for (const std::string &key : ch.keys()) {
            bool found = false;
            for (int k = 0; k < 5; ++k) found = found || key == names[k];
            if (!found) {
                *error = where("channels");
                error->append(": unknown key ").append(key);
                return false;
            }
        }
        for (int k = 0; k < 5; ++k) {
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

}  // namespace sfdapp
