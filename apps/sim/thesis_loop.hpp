// SPDX-License-Identifier: MIT
// sfd-sim thesis-loop: Kilic 2014 Chapter IV, the association methods in an EKF localization loop.
// Design and definitions: the header comment of thesis_loop.cpp and apps/sim/THESIS_LOOP.md.
#ifndef SFD_SIM_THESIS_LOOP_HPP
#define SFD_SIM_THESIS_LOOP_HPP

#include <cstdint>
#include <cstdio>
#include <string>

namespace sfdsim {

struct ThesisOptions {
    uint64_t seed = 1;    // base seed: run r uses streams derived from (seed, r)
    int frames = 800;     // camera frames (20 Hz) per run: 800 = one 40 s loop
    int runs = 5;         // Monte Carlo runs per sweep point
    bool quick = false;   // two levels per sweep (CI, tests)
    std::string out_dir;  // CSV output directory ("" = none)
};

/// Runs the three sweeps (measurement noise, control input noise, mismatch ratio) for every
/// association method, prints a markdown summary and the verdict on the thesis's claim, writes
/// thesis_rmse.csv (deterministic) and thesis_time.csv (wall clock). Returns an exit code.
int run_thesis_loop(const ThesisOptions &opt);

/// The unit definitions, for sfd-sim --help.
void thesis_loop_help(FILE *out);

}  // namespace sfdsim

#endif
