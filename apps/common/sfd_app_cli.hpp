// SPDX-License-Identifier: MIT
// The command line of sfd-node and sfd-replay: one parser (sfd_cli.hpp) with the same flags on
// both, one per key of apps/config/sfd.yaml. A key's flag is "--" + the key with every '_'
// written '-'; a nested key keeps its dot: pixel_sigma_px is --pixel-sigma-px,
// filter.window_size is --filter.window-size, channels.imu is --channels.imu. Values follow the
// file's type rules (an integer key takes a decimal integer within 32 bits, a list of 3 numbers
// is written X,Y,Z); the ranges are validate()'s, judged once the files and the flags are in.
#ifndef SFD_APP_CLI_HPP
#define SFD_APP_CLI_HPP

#include <string>
#include <vector>

#include "sfd_app_config.hpp"
#include "sfd_cli.hpp"

namespace sfdapp {

/// One key of the configuration as the command line sets it.
struct ConfigKey {
    const char *key;      ///< its YAML name ("filter.window_size")
    const char *metavar;  ///< the value's placeholder in the help
    const char *help;     ///< one line; apps/config/sfd.yaml documents the key in full
};

/// Every key of apps/config/sfd.yaml, in the file's order.
const std::vector<ConfigKey> &config_keys();

/// The flag of `key`: "--pixel-sigma-px", "--filter.window-size".
std::string flag_of(const std::string &key);

/// Sets `key` from command-line text by the file's type rules and records `origin` as where the
/// key was set. False with `why` ("is not an integer") for a value of the wrong type.
bool set_key(const std::string &key, const std::string &text, const std::string &origin,
             AppConfig *cfg, std::string *why);

/// The configuration part of a command line: --config files and the flags over them.
class ConfigCommandLine {
  public:
    /// Adds --config and one flag per key (config_keys()) to `parser`, plus the deprecated
    /// spellings of sfd 0.1 (--alpha, --window, --group, --pixel-sigma, --depth-default,
    /// --no-isolation, --imu-channel, ...).
    void add_to(sfdcli::Parser *parser);
    /// Once the command line is parsed: the --config files in order (later keys win), then the
    /// flags in order, then validate(). 0, or kExitUsage after printing "PROG: REASON".
    int load(const std::string &prog, AppConfig *cfg) const;
    /// The --config paths given (inputs that no output may overwrite).
    const std::vector<std::string> &files() const { return files_; }

  private:
    struct Setting {
        std::string key, text, flag;
    };
    std::vector<std::string> files_;
    std::vector<Setting> settings_;
};

}  // namespace sfdapp

#endif
