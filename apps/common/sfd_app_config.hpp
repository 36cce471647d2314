// SPDX-License-Identifier: MIT
// Configuration of sfd-node and sfd-replay: YAML through cv::FileStorage (apps/config/sfd.yaml
// documents every key), then command-line overrides.
#ifndef SFD_APP_CONFIG_HPP
#define SFD_APP_CONFIG_HPP

#include <string>

#include "sfd_node_core.h"

namespace sfdapp {

struct Channels {
    std::string imu = "IMU";
    std::string camera_info = "CAMERA_INFO";
    std::string features = "FEATURES";
    std::string verdict = "SFD_VERDICT";
    std::string timing = "SFD_TIMING";
    std::string state = "SFD_STATE";
    std::string truth = "TRUTH";  // subscribed by sfd-node only with filter.init_from_truth
};

struct AppConfig {
    sfd_node_config_t node{};
    std::string method = "parity";
    std::string lcm_url = "udpm://239.255.76.67:7667?ttl=0";
    Channels channels;
    AppConfig();
};

/// Reads `path` into `cfg` (keys absent from the file keep their values). On failure returns
/// false with a one-line reason naming the file and the key.
bool load_config(const std::string &path, AppConfig *cfg, std::string *error);

/// Sets the method by name (none, parity); false with a reason for others.
bool set_method(const std::string &name, AppConfig *cfg, std::string *error);

/// Validates the detector parameters; false with a reason naming the first bad one.
bool validate(const AppConfig &cfg, std::string *error);

/// A command-line integer: the whole of s in base 10, within [lo, hi]; false otherwise.
bool parse_long(const char *s, long lo, long hi, long *out);

}  // namespace sfdapp

#endif
