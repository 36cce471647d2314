// SPDX-License-Identifier: MIT
// sfd-sim log writer: simulated sensor logs (IMU, CAMERA_INFO, FEATURES, TRUTH) in LCM's log
// format, written through LCM's own lcm_eventlog API.
#ifndef SFD_SIM_FLIGHT_LOG_HPP
#define SFD_SIM_FLIGHT_LOG_HPP

#include <cstdint>
#include <string>

namespace sfdsim {

struct FlightOptions {
    std::string scenario;  // paper-uav, mistracking, moving-object
    std::string out_path;  // .lcmlog
    uint64_t seed = 1;
    int frames = 400;    // 20 Hz camera frames
    int features = 200;  // features in view per frame
    double outlier_ratio = 0.1;
    double fault_magnitude = 0.02;  // paper-uav: k of k(-1, 1)^T in normalized coordinates
    double jump_px = 8.0;           // mistracking: jump size (px)
    double depth_var = 0.0;         // variance of the depth priors written (m^2)
    double pixel_noise_px = 1.0;
    double gyro_noise = 1.7e-4;             // rad/s/sqrt(Hz)
    double gyro_bias[3] = {0.0, 0.0, 0.0};  // rad/s
    int truth_window = 2;  // frames a mistracked track is labelled spurious (L - 1)
};

/// Writes the log; returns a process exit code (2: bad path).
int write_flight_log(const FlightOptions &opt);

}  // namespace sfdsim

#endif
