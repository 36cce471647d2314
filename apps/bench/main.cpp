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

void usage(FILE *out) {
    std::fprintf(out,
                 "usage: sfd-bench parity [--frames N] [--seed S] [--csv FILE]\n"
                 "       sfd-bench parity --single N L n known [--frames F]\n"
                 "       sfd-bench assoc [--trials T] [--seed S] [--csv FILE] [--quick]\n"
                 "  assoc     sfd association methods against OpenCV (sfd-bench assoc --help)\n"
                 "  parity    per-frame time of the parity detector over the grid\n"
                 "            N {50,100,200,500} x L {2,3,5} x n {3,4} x {known, unknown}\n"
                 "  --single  one configuration (for callgrind: tools/bench_parity_callgrind.sh)\n"
                 "  --frames  measured frames per configuration (default 2000)\n"
                 "  --csv     also write the table as CSV\n"
                 "Exit: 0 ok, 2 bad usage, 1 internal failure.\n");
}

}  // namespace

int main(int argc, char **argv) {
    if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h")) {
        usage(argc < 2 ? stderr : stdout);
        return argc < 2 ? 2 : 0;
    }
    if (std::strcmp(argv[1], "assoc") == 0) return bench_assoc(argc, argv);
    if (std::strcmp(argv[1], "parity") != 0) {
        std::fprintf(stderr, "sfd-bench: unknown mode: %s (available: parity, assoc)\n", argv[1]);
        return 2;
    }
    int frames = 2000;
    uint64_t seed = 1;
    const char *csv = nullptr;
    int single[4] = {0, 0, 0, 0};
    bool is_single = false;
    for (int i = 2; i < argc; ++i) {
        const char *a = argv[i];
        if (!std::strcmp(a, "--frames") && i + 1 < argc) {
            char *end = nullptr;
            const long v = std::strtol(argv[++i], &end, 10);
            frames = (*end == '\0' && v >= 1 && v <= 10000000) ? int(v) : -1;
            if (frames < 1) {
                std::fprintf(stderr, "sfd-bench: --frames: expected 1..10000000\n");
                return 2;
            }
        } else if (!std::strcmp(a, "--seed") && i + 1 < argc) {
            seed = std::strtoull(argv[++i], nullptr, 10);
        } else if (!std::strcmp(a, "--csv") && i + 1 < argc) {
            csv = argv[++i];
        } else if (!std::strcmp(a, "--single") && i + 4 < argc) {
            for (int k = 0; k < 4; ++k) {
                char *end = nullptr;
                const long v = std::strtol(argv[++i], &end, 10);
                single[k] = (*end == '\0' && v >= 0 && v <= 100000) ? int(v) : -1;
            }
            is_single = true;
        } else {
            std::fprintf(stderr, "sfd-bench: unknown or incomplete option: %s\n", a);
            usage(stderr);
            return 2;
        }
    }
    if (is_single) {
        if (single[3] < 0 || single[0] < 1 || single[0] > SFD_MAX_FEATURES || single[1] < 2 ||
            single[1] > SFD_MAX_WINDOW || single[2] < 1 || single[2] > SFD_MAX_GROUP) {
            std::fprintf(stderr, "sfd-bench: --single: N 1..%d, L 2..%d, n 1..%d\n",
                         SFD_MAX_FEATURES, SFD_MAX_WINDOW, SFD_MAX_GROUP);
            return 2;
        }
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
