// SPDX-License-Identifier: MIT
// Isolation gain: sfd's isolation inside failing groups against the paper's rule (discard the
// whole group), at equal detection probability, on a simulated flight with mistracked features.
//
// Scenario (drivers/sim/sfd_scene_sim.h): camera over landmarks at 30-50 m, 1 px pixel noise,
// per frame rotation N(0, 0.01^2) rad per axis and ~0.45 m translation, unknown translation in the
// test, L = 3, n = 3. Each frame, each feature mistracks with probability outlier_ratio / (L - 1):
// its track jumps by jump_px in a random direction and stays on the wrong point. Truth: a
// feature is spurious in a window when a jump happened inside it (the newest L - 1 frames).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

#include "paper_uav.hpp"
#include "sfd/sfd.h"
#include "sfd_scene_sim.h"

namespace sfdsim {
namespace {

struct Point {
    double alpha, recall, kept;
};

// Static: the frame, verdict and scene are large (tens of KiB).
sfd_frame_t g_frame;
sfd_verdict_t g_out;
scene_t g_scene;
sfd_parity_t g_det;

Point run_once(const IsolationOptions &opt, int isolation, double alpha) {
    scene_init(&g_scene, opt.seed, std::min(opt.features, SFD_MAX_FEATURES), 1.0);
    sfd_params_t p;
    sfd_params_default(&p);
    p.translation_known = 0;
    p.parity_isolation = isolation;
    p.false_alarm_rate = alpha;
    p.window_frames = 3;
    p.group_size = 3;
    if (sfd_parity_init(&g_det, &p, &g_scene.cam) != SFD_OK) return {alpha, -1, -1};
    std::vector<int> last_jump(size_t(g_scene.n), -1000);
    sfd_prng_t jump_rng;
    sfd_prng_seed(&jump_rng, opt.seed + 17);
    const double p_jump = opt.outlier_ratio / (p.window_frames - 1);
    long pos = 0, tp = 0, neg = 0, keep = 0;
    for (int f = 0; f < opt.frames; ++f) {
        if (f > 0) {
            for (int i = 0; i < g_scene.n; ++i) {
                if (sfd_prng_uniform(&jump_rng) < p_jump) {
                    const double a = 6.283185307179586 * sfd_prng_uniform(&jump_rng);
                    g_scene.offset_px[i][0] += opt.jump_px * std::cos(a);
                    g_scene.offset_px[i][1] += opt.jump_px * std::sin(a);
                    last_jump[size_t(i)] = f;
                }
            }
        }
        sfd_frame_motion_t mo;
        scene_step(&g_scene, &g_frame, &mo, 0.0);
        mo.translation_known = 0;
        if (sfd_parity_push_frame(&g_det, &g_frame, &mo, &g_out) != SFD_OK) return {alpha, -1, -1};
        for (int k = 0; k < g_frame.num_features; ++k) {
            const sfd_feature_result_t &v = g_out.features[k];
            if (v.status == SFD_VERDICT_UNTESTED) continue;
            const int i = int(g_frame.features[k].track_id - 1000);
            const bool spurious = f - last_jump[size_t(i)] < p.window_frames - 1;
            if (spurious) {
                ++pos;
                tp += v.status == SFD_VERDICT_SPURIOUS;
            } else {
                ++neg;
                keep += v.status == SFD_VERDICT_CONSISTENT;
            }
        }
    }
    return {alpha, pos ? double(tp) / pos : 0.0, neg ? double(keep) / neg : 0.0};
}

// Kept fraction of `curve` at detection rate `recall`, linear in recall between neighbours.
double kept_at(const std::vector<Point> &curve, double recall) {
    for (size_t i = 1; i < curve.size(); ++i) {
        const Point &a = curve[i - 1], &b = curve[i];
        if ((a.recall - recall) * (b.recall - recall) <= 0.0 && a.recall != b.recall) {
            const double t = (recall - a.recall) / (b.recall - a.recall);
            return a.kept + t * (b.kept - a.kept);
        }
    }
    return NAN;
}

}  // namespace

int run_isolation(const IsolationOptions &opt) {
    std::vector<Point> iso, pap;
    for (int e = 0; e <= 16; ++e) {
        const double alpha = std::pow(10.0, -5.0 + 4.0 * e / 16.0);  // 1e-5 .. 0.1
        iso.push_back(run_once(opt, 1, alpha));
        pap.push_back(run_once(opt, 0, alpha));
        if (iso.back().recall < 0 || pap.back().recall < 0) {
            std::fprintf(stderr, "sfd-sim: detector failed\n");
            return 1;
        }
    }
    auto by_recall = [](const Point &a, const Point &b) { return a.recall < b.recall; };
    std::vector<Point> iso_sorted = iso;
    std::sort(iso_sorted.begin(), iso_sorted.end(), by_recall);
    if (!opt.out_dir.empty()) {
        const std::string path = opt.out_dir + "/isolation.csv";
        FILE *f = std::fopen(path.c_str(), "w");
        if (f == nullptr) {
            std::fprintf(stderr, "sfd-sim: cannot write %s\n", path.c_str());
            return 1;
        }
        std::fprintf(f, "method,alpha,recall,consistent_kept\n");
        for (const Point &p : iso)
            std::fprintf(f, "isolation,%.6g,%.6f,%.6f\n", p.alpha, p.recall, p.kept);
        for (const Point &p : pap)
            std::fprintf(f, "paper,%.6g,%.6f,%.6f\n", p.alpha, p.recall, p.kept);
        std::fclose(f);
    }
    std::printf(
        "sfd-sim isolation: %d frames, %d features, outlier ratio %.2f, jump %.1f px, "
        "L = 3, n = 3, unknown translation, seed %llu\n",
        opt.frames, opt.features, opt.outlier_ratio, opt.jump_px,
        static_cast<unsigned long long>(opt.seed));
    std::printf("%-10s %-14s %-16s %-22s\n", "alpha", "recall(paper)", "kept(paper rule)",
                "kept(sfd isolation) at same recall");
    const double iso_max = iso_sorted.back().recall;
    for (const Point &p : pap) {
        const double k = kept_at(iso_sorted, p.recall);
        char cell[64];
        if (std::isnan(k)) {
            std::snprintf(cell, sizeof cell, "n/a (sfd recall <= %.4f)", iso_max);
        } else {
            std::snprintf(cell, sizeof cell, "%.4f", k);
        }
        std::printf("%-10.2g %-14.4f %-16.4f %s\n", p.alpha, p.recall, p.kept, cell);
    }
    return 0;
}

}  // namespace sfdsim
