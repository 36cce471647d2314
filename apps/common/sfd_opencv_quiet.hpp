// SPDX-License-Identifier: MIT
// OpenCV's own log lines ("[ WARN:0@0.001] global persistence.cpp:531 open Can't open file ...")
// silenced in the tools that use OpenCV: each failure is reported once, by sfd, in one line that
// names the file (docs/deploy.md, "Command line").
#ifndef SFD_OPENCV_QUIET_HPP
#define SFD_OPENCV_QUIET_HPP

#include <opencv2/core/utils/logger.hpp>

namespace sfdapp {

inline void quiet_opencv() {
    cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
}

}  // namespace sfdapp

#endif
