// SPDX-License-Identifier: MIT
// OpenCV's own log lines ("[ WARN:0@0.001] global persistence.cpp:531 open Can't open file ...")
// silenced in the tools that use OpenCV: each failure is reported once, by sfd, in one line that
// names the file (docs/deploy.md, "Command line").
#ifndef SFD_OPENCV_QUIET_HPP
#define SFD_OPENCV_QUIET_HPP

#include <opencv2/core.hpp>
#include <opencv2/core/utils/logger.hpp>
#include <string>

namespace sfdapp {

inline void quiet_opencv() {
    cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
}

// The one-line reason for a cv::FileStorage exception on the YAML file PATH:
// "PATH:LINE: not valid YAML (reason)" for a parse error (OpenCV 4 puts "PATH(LINE): reason" in
// e.func), else "PATH: not valid YAML (reason)" with OpenCV's bare reason (e.err), never e.msg's
// "OpenCV(4.6.0) ./modules/core/src/persistence.cpp:692: error: (-5:Bad argument) ..." and its
// line break. The sfd configuration (sfd_app_config.cpp) and EuRoC's sensor.yaml (euroc_io.cpp).
inline std::string opencv_yaml_error(const std::string &path, const cv::Exception &e) {
    const std::size_t close = e.func.find("): ");
    if (e.func.rfind(path + "(", 0) == 0 && close != std::string::npos) {
        return path + ":" + e.func.substr(path.size() + 1, close - path.size() - 1) +
               ": not valid YAML (" + e.func.substr(close + 3) + ")";
    }
    std::string reason = e.err.empty() ? e.msg : e.err;
    for (char &c : reason) {
        if (c == '\n' || c == '\r') c = ' ';
    }
    while (!reason.empty() && reason.back() == ' ') reason.pop_back();
    return path + ": not valid YAML (" + reason + ")";
}

}  // namespace sfdapp

#endif
