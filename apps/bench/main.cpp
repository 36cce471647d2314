// SPDX-License-Identifier: MIT
// sfd-bench: side-by-side benchmarks: `parity` (issue 3) and `assoc` (issue 5, sfd's association
// methods against OpenCV's findFundamentalMat/findEssentialMat; assoc.cpp).
//
// sfd-bench links a core built with SFD_MAX_FEATURES = 512 (the wire capacity) so that it can run
// N = 500; the per-frame cost depends on the features present, not on the capacity.
//
// parity: per-frame wall time of sfd_parity_push_frame (median, p99, max over --frames frames
// after the window is full) on the simulated flight of drivers/sim (1 px noise, 10% of features
// mistracking by 8 px per window), for N in {50, 100, 200, 500}, L in {2, 3, 5}, n in {3, 4},
// known and unknown translation. Instruction counts come from tools/bench_parity_callgrind.sh,
// which runs this program under callgrind with --single (one configuration).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "sfd/sfd.h"
#include "sfd_cli.hpp"
#include "sfd_opencv_quiet.hpp"
#include "sfd_eval.hpp"
#include "sfd_scene_sim.h"

int bench_assoc(int argc, char **argv);  // assoc.cpp

namespace {

sfd_frame_t g_frame;
sfd_verdict_t g_out;
scene_t g_scene;
sfd_parity_t g_det;

struct Result {
    double median_us, p99_us, max_us, spurious_frac;
};

bool run(int N, int L, int n, int known, int frames, uint64_t seed, Result *res) {
    scene_init(&g_scene, seed, N, 1.0);
    g_scene.respawn = 1;
    sfd_params_t p;
    sfd_params_default(&p);
    p.window_frames = L;
    p.group_size = n;
    p.translation_known = known;
    if (sfd_parity_init(&g_det, &p, &g_scene.cam) != SFD_OK) return false;
    sfd_prng_t rng;
    sfd_prng_seed(&rng, seed + 1);
    std::vector<double> times;
    times.reserve(size_t(frames));
    long spurious = 0, judged = 0;
    for (int f = 0; f < frames + L; ++f) {
        for (int i = 0; i < g_scene.n; ++i) {
            if (sfd_prng_uniform(&rng) < 0.1 / (L - 1)) {
                g_scene.offset_px[i][0] += 8.0;
            }
        }
        sfd_frame_motion_t mo;
        scene_step(&g_scene, &g_frame, &mo, 0.0);
        if (!known) mo.translation_known = 0;
        const auto t0 = std::chrono::steady_clock::now();
        const sfd_status_t st = sfd_parity_push_frame(&g_det, &g_frame, &mo, &g_out);
        const auto t1 = std::chrono::steady_clock::now();
        if (st != SFD_OK) return false;
        if (f >= L) {
            times.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
            spurious += g_out.num_spurious;
            judged += g_out.num_spurious + g_out.num_consistent;
        }
    }
    std::sort(times.begin(), times.end());
    res->median_us = sfdeval::percentile_sorted(times, 0.5);
    res->p99_us = sfdeval::percentile_sorted(times, 0.99);  // nearest rank, as every sfd tool
    res->max_us = times.back();
    res->spurious_frac = judged ? double(spurious) / double(judged) : 0.0;
    return true;
}

int run_parity(int argc, char **argv) {
    int frames = 2000;
    uint64_t seed = 1;
    std::string csv_path;
    const char *csv = nullptr;
    int single[4] = {200, 3, 3, 0};  // --features, --window-frames, --group-size, known
    bool is_single = false;
    // argv[0] is "parity" (the subcommand): its own options and help.
    sfdcli::Parser cli(
        "sfd-bench", "sfd-bench parity",
        "[--frames N] [--seed S] [--csv FILE]\n"
        "       sfd-bench parity --single [--features N] [--window-frames L] [--group-size n]\n"
        "                        [--translation-known 0|1] [--frames F]",
        "  Per-frame time of the parity detector over the grid N {50,100,200,500} x\n"
        "  L {2,3,5} x n {3,4} x {known, unknown translation}; a markdown table.");
    const auto int_opt = [](int *dst, long long lo, long long hi) -> sfdcli::Setter {
        return [dst, lo, hi](const std::string &v, std::string *why) {
            long long x = 0;
            if (!sfdcli::parse_int(v, lo, hi, &x, why)) return false;
            *dst = static_cast<int>(x);
            return true;
        };
    };
    cli.value("frames", "N", "measured frames per configuration, 1..10000000 (2000)",
              int_opt(&frames, 1, 10000000));
    cli.value("seed", "S", "seed (1)", [&seed](const std::string &v, std::string *why) {
        long long x = 0;
        if (!sfdcli::parse_int(v, 0, 9007199254740992LL, &x, why)) return false;
        seed = static_cast<uint64_t>(x);
        return true;
    });
    cli.value("csv", "FILE", "also write the table as CSV",
              [&csv_path, &csv](const std::string &v, std::string *) {
                  csv_path = v;
                  csv = csv_path.c_str();
                  return true;
              });
    cli.section("One configuration (for callgrind: tools/bench_parity_callgrind.sh)");
    cli.flag("single", "run one configuration instead of the grid",
             [&is_single] { is_single = true; });
    cli.value("features", "N", "features, 1..SFD_MAX_FEATURES (200)",
              int_opt(&single[0], 1, SFD_MAX_FEATURES));
    cli.value("window-frames", "L", "window, 2..SFD_MAX_WINDOW (3)",
              int_opt(&single[1], 2, SFD_MAX_WINDOW));
    cli.value("group-size", "n", "group size, 1..SFD_MAX_GROUP (3)",
              int_opt(&single[2], 1, SFD_MAX_GROUP));
    cli.value("translation-known", "0|1", "1: known translation (0)", int_opt(&single[3], 0, 1));
    cli.epilog("Exit: 0 ok, 2 bad usage, 1 internal failure.");
    std::vector<std::string> positional;
    if (const int rc = cli.parse(argc, argv, &positional); rc >= 0) return rc;
    if (!positional.empty()) return cli.fail("unexpected argument " + positional[0]);
    if (is_single) {
        Result r;
        if (!run(single[0], single[1], single[2], single[3] != 0, frames, seed, &r)) return 1;
        std::printf("N=%d L=%d n=%d known=%d frames=%d median_us=%.2f p99_us=%.2f max_us=%.2f\n",
                    single[0], single[1], single[2], single[3], frames, r.median_us, r.p99_us,
                    r.max_us);
        return 0;
    }
    FILE *fc = nullptr;
    if (csv != nullptr) {
        fc = std::fopen(csv, "w");
        if (fc == nullptr) {
            std::fprintf(stderr, "sfd-bench: cannot write %s\n", csv);
            return 2;
        }
        std::fprintf(fc, "features,L,n,translation,median_us,p99_us,max_us,spurious_fraction\n");
    }
    std::printf("sfd-bench parity: %d frames per configuration, seed %llu, SFD_MAX_FEATURES=%d\n\n",
                frames, static_cast<unsigned long long>(seed), SFD_MAX_FEATURES);
    std::printf(
        "| N | L | n | translation | median (us) | p99 (us) | max (us) | judged spurious |\n");
    std::printf("|---|---|---|---|---|---|---|---|\n");
    for (int N : {50, 100, 200, 500}) {
        for (int L : {2, 3, 5}) {
            for (int n : {3, 4}) {
                for (int known : {0, 1}) {
                    Result r;
                    if (N > SFD_MAX_FEATURES || L > SFD_MAX_WINDOW || n > SFD_MAX_GROUP) continue;
                    if (!run(N, L, n, known, frames, seed, &r)) {
                        std::fprintf(stderr, "sfd-bench: run failed (N=%d L=%d n=%d)\n", N, L, n);
                        return 1;
                    }
                    const char *tr = known ? "known" : "unknown";
                    std::printf("| %d | %d | %d | %s | %.1f | %.1f | %.1f | %.3f |\n", N, L, n, tr,
                                r.median_us, r.p99_us, r.max_us, r.spurious_frac);
                    if (fc != nullptr) {
                        std::fprintf(fc, "%d,%d,%d,%s,%.3f,%.3f,%.3f,%.5f\n", N, L, n, tr,
                                     r.median_us, r.p99_us, r.max_us, r.spurious_frac);
                    }
                }
            }
        }
    }
    if (fc != nullptr) std::fclose(fc);
    return 0;
}

}  // namespace

int main(int argc, char **argv) {
    sfdapp::quiet_opencv();
    // Subcommands parity and assoc, each with its own options and --help.
    sfdcli::Parser cli("sfd-bench", "sfd-bench", "SUBCOMMAND [options]",
                       "  Side-by-side benchmarks. Subcommands (sfd-bench SUBCOMMAND --help):\n"
                       "  parity    per-frame time of the parity detector over a grid\n"
                       "  assoc     sfd association methods against OpenCV");
    cli.epilog("Exit: 0 ok, 2 bad usage, 1 internal failure.");
    if (argc < 2 || argv[1][0] == '-') {
        std::vector<std::string> positional;
        if (const int rc = cli.parse(argc, argv, &positional); rc >= 0) return rc;
        return cli.fail("missing SUBCOMMAND (parity or assoc; sfd-bench --help)");
    }
    if (std::strcmp(argv[1], "assoc") == 0) return bench_assoc(argc - 1, argv + 1);
    if (std::strcmp(argv[1], "parity") == 0) return run_parity(argc - 1, argv + 1);
    return cli.fail(std::string("unknown subcommand ") + argv[1] + " (parity or assoc)");
}
