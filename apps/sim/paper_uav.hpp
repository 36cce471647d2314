// SPDX-License-Identifier: MIT
// sfd-sim scenarios reproducing the papers' simulations.
#ifndef SFD_SIM_PAPER_UAV_HPP
#define SFD_SIM_PAPER_UAV_HPP

#include <cstdint>
#include <string>

namespace sfdsim {

struct PaperOptions {
    uint64_t seed = 1;
    int windows = 10000;    // Monte Carlo windows per case
    int window_frames = 2;  // L (the paper's figures: L = 2)
    int group_size = 3;     // n (the paper: groups of three)
    std::string out_dir;    // CSV output directory ("" = none)
};

/// Tornqvist et al. 2008 Section IV: Figure 1 (scatter of Zhat y), Figures 2-3 (ROC, known and
/// unknown translation, Cov(zhat) in {0, 3^2}, k in {0, 0.02, 0.03}). Prints a summary table
/// and writes paper_fig1.csv, paper_roc.csv. Returns a process exit code.
int run_paper_uav(const PaperOptions &opt);

struct IsolationOptions {
    uint64_t seed = 1;
    int frames = 200;
    int features = 240;
    double outlier_ratio = 0.1;
    double jump_px = 8.0;
    std::string out_dir;
};

/// Detector-level comparison of sfd's isolation against the paper's discard-the-group rule on a
/// simulated flight with mistracked features: sweeps alpha, reports the fraction of consistent
/// features kept at equal detection probability. Writes isolation.csv.
int run_isolation(const IsolationOptions &opt);

}  // namespace sfdsim

#endif
