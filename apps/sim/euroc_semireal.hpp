// SPDX-License-Identifier: MIT
// sfd-sim euroc-semireal: a semi-real sensor log from a EuRoC sequence without images (real IMU,
// real motion from the ground truth, simulated landmarks projected through cam0).
#ifndef SFD_SIM_EUROC_SEMIREAL_HPP
#define SFD_SIM_EUROC_SEMIREAL_HPP

#include <cstdint>
#include <cstdio>
#include <string>

namespace sfdsim {

struct SemirealOptions {
    std::string euroc_dir;   // folder holding mav0/ (or mav0 itself)
    std::string out_path;    // .lcmlog
    std::string config_out;  // optional: sfd-replay configuration for this log
    uint64_t seed = 1;
    int features = 200;              // tracks kept in view per frame
    double camera_hz = 20.0;         // simulated camera rate (Hz)
    double spurious_fraction = 0.1;  // target fraction of spurious (feature, frame) pairs
    double pixel_sigma_px = 0.5;     // pixel noise per axis (px)
    double depth_var_m2 = 0.01;      // variance of the depth priors written (m^2)
    double jump_px = 8.0;            // mistracking: jump size (px)
    double drift_px = 1.5;           // mistracking: drift per frame (px)
    int drift_frames = 5;            // mistracking: frames a drift lasts
    double mover_speed_m_s = 0.5;    // moving object: speed of the group (m/s)
    double track_loss = 0.02;        // probability per frame that a track ends (tracker loss)
    int truth_window = 2;            // frames a step of a track is labelled spurious (L - 1)
};

/// Help text of the scenario's options.
void semireal_help(FILE *out);

/// Reads the EuRoC folder and writes the log (and the configuration). Returns a process exit
/// code: 0, 2 for bad input (a message naming the file and line/field), 1 for a write failure.
int write_semireal_log(const SemirealOptions &opt);

}  // namespace sfdsim

#endif
