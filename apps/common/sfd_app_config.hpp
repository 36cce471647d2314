// SPDX-License-Identifier: MIT
// Configuration of sfd-node and sfd-replay: YAML through cv::FileStorage (apps/config/sfd.yaml
// documents every key), then command-line overrides, then one validation (validate()) that both
// tools run, so that they accept and refuse exactly the same configurations.
#ifndef SFD_APP_CONFIG_HPP
#define SFD_APP_CONFIG_HPP

#include <map>
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
    /// Where each key's value was set last, by its YAML name ("filter.window_size"): the path of
    /// the config file or the command-line option ("--window"). Keys absent keep their default.
    std::map<std::string, std::string> origin;
    AppConfig();
    /// The origin of `key` ("gyro_bias_rad_s[1]" is looked up as "gyro_bias_rad_s"), or "default".
    std::string origin_of(const std::string &key) const;
};

/// Reads `path` into `cfg` (keys absent from the file keep their values) and records `path` as
/// the origin of every key it sets. Checks syntax, key names and types only (an integer key
/// holds an integer within 32 bits, written in decimal; a number key a number; a microsecond
/// key a whole number); the ranges are validate()'s, to be called once the command-line
/// overrides are applied (sfd-node, sfd-replay). On failure returns false with a one-line
/// reason "PATH: KEY: VALUE is not ...".
bool read_config(const std::string &path, AppConfig *cfg, std::string *error);

/// read_config() then validate(), for a tool that overrides no key of the file (sfd-hil).
bool load_config(const std::string &path, AppConfig *cfg, std::string *error);

/// Sets the method by name; false with the reason "not one of none, parity, ..." for others.
bool set_method(const std::string &name, AppConfig *cfg, std::string *error);

/// Checks every key against its range (the core's validators' ranges: sfd_params_validate,
/// sfd_nav_init, sfd_window_init, sfd_rest_init, sfd_assoc_init, sfd_time_guard_params_validate;
/// plus the flags 0/1, camera_id, the channels and lcm_url), in the order of apps/config/sfd.yaml.
/// On the first bad one returns false with "ORIGIN: KEY: VALUE is not ..." (ORIGIN: the file or
/// the option that set it). A configuration it accepts is accepted by sfd_node_init().
bool validate(const AppConfig &cfg, std::string *error);

/// A command-line integer: the whole of s in base 10, within [lo, hi]; false otherwise.
bool parse_long(const char *s, long lo, long hi, long *out);

/// A number as the error messages print it: the shortest text that reads back the same ("-9.81",
/// "1e-300", "nan", "inf"); with `mark_real` a whole value keeps a decimal point ("5.0", as a
/// YAML real it was written as), else not ("5").
std::string format_double(double v, bool mark_real = false);

}  // namespace sfdapp

#endif
