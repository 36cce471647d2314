// SPDX-License-Identifier: MIT
// sfd-bench assoc: per-frame time and outlier precision/recall/F1 of sfd's association methods
// (OPRF, 1-point RANSAC, fundamental-matrix RANSAC, none) against OpenCV's findFundamentalMat
// (FM_RANSAC, FM_LMEDS, USAC_DEFAULT, USAC_FAST, USAC_ACCURATE, USAC_MAGSAC) and
// findEssentialMat (RANSAC, USAC_MAGSAC) on the same correspondences (drivers/sim/sfd_pair_sim.h),
// at OpenCV thresholds of 1 px and 3 px. An outlier is "detected" when sfd says SPURIOUS or
// OpenCV's mask says 0.
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "sfd/sfd.h"
#include "sfd_cli.hpp"
#include "sfd_eval.hpp"
#include "sfd_pair_sim.h"

namespace {

sim_pair_t g_pair;
sim_pair_t g_work;
sfd_assoc_t g_assoc;
sfd_assoc_work_t g_assoc_work;
sfd_assoc_result_t g_res;

struct Stats {
    std::vector<double> us;        // association (sfd: sfd_assoc_select; OpenCV: the call)
    std::vector<double> total_us;  // sfd: select + apply (the EKF update and the rescue)
    std::vector<double> hyps;      // sfd OPRF / RANSAC1 / RANSACF: hypotheses drawn per frame
    long exhausted = 0;            // frames where eq. (27) asked for the whole budget
    long tp = 0, fp = 0, fn = 0, tn = 0;
    void add(double t_us, double t_total_us, const std::vector<uint8_t> &flagged,
             const sim_pair_t &pr) {
        us.push_back(t_us);
        total_us.push_back(t_total_us);
        for (int i = 0; i < pr.n; ++i) {
            const bool out = pr.outlier[i] != 0;
            const bool f = flagged[size_t(i)] != 0;
            tp += (out && f);
            fp += (!out && f);
            fn += (out && !f);
            tn += (!out && !f);
        }
    }
    // The one percentile rule of every sfd tool (sfd_eval.hpp: nearest rank).
    static double pct_of(const std::vector<double> &v, double q) {
        std::vector<double> s = v;
        std::sort(s.begin(), s.end());
        return sfdeval::percentile_sorted(s, q);
    }
    double pct(double q) const { return pct_of(us, q); }
    std::string hyp_text() const {
        if (hyps.empty()) return "-";
        char b[64];
        std::snprintf(b, sizeof b, "%.0f / %.0f", pct_of(hyps, 0.5), pct_of(hyps, 1.0));
        return b;
    }
    double pct_total(double q) const { return pct_of(total_us, q); }
    // Scores by sfd_eval's rule (every match is tested here: strict and lenient recall agree);
    // undefined (NaN, printed "nan") where the denominator is empty, never a made-up 1.0.
    sfdeval::DetectionScores scores() const {
        sfdeval::DetectionCounts c;
        c.tp = tp;
        c.fp = fp;
        c.fn = fn;
        c.tn = tn;
        return sfdeval::score(c);
    }
    double precision() const { return scores().precision; }
    double recall() const { return scores().recall; }
    double f1() const { return scores().f1; }
};

struct Method {
    std::string name;
    int sfd_method;  // >= 0: sfd
    int cv_kind;     // 0: findFundamentalMat, 1: findEssentialMat
    int cv_method;
    double thr_px;
};

double now_us() {
    return double(std::chrono::duration_cast<std::chrono::nanoseconds>(
                      std::chrono::steady_clock::now().time_since_epoch())
                      .count()) /
           1000.0;
}

bool run_method(const Method &m, const sim_pair_t &pr, uint64_t seed, Stats *st) {
    std::vector<uint8_t> flagged(size_t(pr.n), 0);
    if (m.sfd_method >= 0) {
        sfd_assoc_params_t ap;
        sfd_assoc_params_default(&ap);
        ap.method = m.sfd_method;
        ap.seed = seed;
        if (sfd_assoc_init(&g_assoc, &ap) != SFD_OK) return false;
        g_work.ekf = pr.ekf;  // the run updates the filter: start each from the same prior
        const double t0 = now_us();
        const sfd_status_t s = sfd_assoc_select(&g_assoc, &g_assoc_work, &g_work.ekf, &pr.cam,
                                                pr.prev_R_CtoW, pr.prev_p_C, pr.m, pr.n, &g_res);
        const double t1 = now_us();
        const sfd_status_t s2 =
            sfd_assoc_apply(&g_assoc, &g_assoc_work, &g_work.ekf, &pr.cam, pr.m, pr.n, &g_res);
        const double t2 = now_us();
        if (s != SFD_OK || s2 != SFD_OK) return false;
        for (int i = 0; i < pr.n; ++i) {
            flagged[size_t(i)] = (g_res.status[i] == SFD_VERDICT_SPURIOUS);
        }
        st->add(t1 - t0, t2 - t0, flagged, pr);
        if (m.sfd_method != SFD_METHOD_NONE) {
            st->hyps.push_back(double(g_res.hypotheses_used));
            st->exhausted += g_res.budget_exhausted;
        }
        return true;
    }
    std::vector<cv::Point2f> a(size_t(pr.n)), b(size_t(pr.n));
    for (int i = 0; i < pr.n; ++i) {
        a[size_t(i)] = cv::Point2f(float(pr.m[i].prev_uv_px[0]), float(pr.m[i].prev_uv_px[1]));
        b[size_t(i)] = cv::Point2f(float(pr.m[i].uv_px[0]), float(pr.m[i].uv_px[1]));
    }
    cv::Mat mask;
    cv::theRNG().state = seed;  // OpenCV's RANSAC draws from its global RNG
    const cv::Matx33d K(pr.cam.fx_px, 0, pr.cam.cx_px, 0, pr.cam.fy_px, pr.cam.cy_px, 0, 0, 1);
    const double t0 = now_us();
    cv::Mat F;
    if (m.cv_kind == 0) {
        F = cv::findFundamentalMat(a, b, m.cv_method, m.thr_px, 0.99, mask);
    } else {
        F = cv::findEssentialMat(a, b, K, m.cv_method, 0.99, m.thr_px, mask);
    }
    const double t1 = now_us();
    for (int i = 0; i < pr.n; ++i) {
        flagged[size_t(i)] = mask.empty() ? 1 : (mask.at<uint8_t>(i) == 0);
    }
    st->add(t1 - t0, t1 - t0, flagged, pr);
    return true;
}

}  // namespace

int bench_assoc(int argc, char **argv) {
    int trials = 50;
    uint64_t seed = 1;
    const char *csv = nullptr;
    bool quick = false;
    bool worst = false;     // SFD_MAX_FEATURES matches, all outliers
    bool sfd_only = false;  // skip OpenCV (profiling sfd under callgrind)
    std::string only;       // keep the methods whose name contains this
    // argv[0] is "assoc" (the subcommand): its own options and help.
    sfdcli::Parser cli(
        "sfd-bench", "sfd-bench assoc",
        "[--trials T] [--seed S] [--csv FILE] [--quick | --worst-case]\n"
        "                       [--sfd-only] [--only STR]",
        "  sfd's association methods against OpenCV's findFundamentalMat / findEssentialMat.\n"
        "  Same correspondences for every method; N in {50,100,200,500}, outlier ratio\n"
        "  {0,0.1,0.3,0.5}, pixel noise {0.5,1} px, random and structured outliers. Prints a\n"
        "  markdown table; --csv writes every row.");
    cli.value("trials", "T", "trials per configuration, 1..100000 (50)",
              [&trials](const std::string &v, std::string *why) {
                  long long x = 0;
                  if (!sfdcli::parse_int(v, 1, 100000, &x, why)) return false;
                  trials = static_cast<int>(x);
                  return true;
              });
    cli.value("seed", "S", "seed (1)", [&seed](const std::string &v, std::string *why) {
        long long x = 0;
        if (!sfdcli::parse_int(v, 0, 9007199254740992LL, &x, why)) return false;
        seed = static_cast<uint64_t>(x);
        return true;
    });
    std::string csv_path;
    cli.value("csv", "FILE", "also write every row as CSV",
              [&csv_path, &csv](const std::string &v, std::string *) {
                  csv_path = v;
                  csv = csv_path.c_str();
                  return true;
              });
    cli.flag("quick", "only N=200, 30% outliers, 1 px (the SPEC's headline case)",
             [&quick] { quick = true; });
    cli.flag("worst-case",
             "N=SFD_MAX_FEATURES, 100% random outliers, 1 px: the hypothesis\n"
             "budget is spent every frame (column 'hypotheses': median / max)",
             [&worst] { worst = true; });
    cli.flag("sfd-only", "sfd's methods only", [&sfd_only] { sfd_only = true; });
    cli.value("only", "STR",
              "methods whose name contains STR (for profiling, e.g.\n"
              "valgrind --tool=callgrind ... --only OPRF)",
              [&only](const std::string &v, std::string *) {
                  only = v;
                  return true;
              });
    cli.epilog("Exit: 0 ok, 2 bad usage, 1 internal failure.");
    std::vector<std::string> positional;
    if (const int rc = cli.parse(argc, argv, &positional); rc >= 0) return rc;
    if (!positional.empty()) return cli.fail("unexpected argument " + positional[0]);
    std::vector<Method> methods = {
        {"sfd OPRF", SFD_METHOD_OPRF, 0, 0, 0},
        {"sfd RANSAC1", SFD_METHOD_RANSAC1, 0, 0, 0},
        {"sfd RANSACF", SFD_METHOD_RANSACF, 0, 0, 0},
        {"sfd none", SFD_METHOD_NONE, 0, 0, 0},
    };
    for (double thr : {1.0, 3.0}) {
        if (sfd_only) break;
        const std::string t = (thr < 2) ? " @1px" : " @3px";
        methods.push_back({"cv F FM_RANSAC" + t, -1, 0, cv::FM_RANSAC, thr});
        methods.push_back({"cv F USAC_DEFAULT" + t, -1, 0, cv::USAC_DEFAULT, thr});
        methods.push_back({"cv F USAC_FAST" + t, -1, 0, cv::USAC_FAST, thr});
        methods.push_back({"cv F USAC_ACCURATE" + t, -1, 0, cv::USAC_ACCURATE, thr});
        methods.push_back({"cv F USAC_MAGSAC" + t, -1, 0, cv::USAC_MAGSAC, thr});
        methods.push_back({"cv E RANSAC" + t, -1, 1, cv::RANSAC, thr});
        methods.push_back({"cv E USAC_MAGSAC" + t, -1, 1, cv::USAC_MAGSAC, thr});
    }
    if (!sfd_only) methods.push_back({"cv F FM_LMEDS", -1, 0, cv::FM_LMEDS, 0.0});
    if (!only.empty()) {
        std::vector<Method> kept;
        for (const Method &m : methods) {
            if (m.name.find(only) != std::string::npos) kept.push_back(m);
        }
        methods = kept;
    }

    FILE *fc = nullptr;
    if (csv != nullptr) {
        fc = std::fopen(csv, "w");
        if (fc == nullptr) {
            std::fprintf(stderr, "sfd-bench: cannot write %s\n", csv);
            return 2;
        }
        std::fprintf(fc,
                     "N,outlier_ratio,sigma_px,outliers,method,median_us,p99_us,"
                     "median_with_update_us,precision,recall,f1,hyp_median,hyp_max,"
                     "budget_exhausted_frames\n");
    }
    std::printf("sfd-bench assoc: %d trials per configuration, seed %llu, OpenCV %s\n", trials,
                static_cast<unsigned long long>(seed), CV_VERSION);
    std::printf(
        "Times are association only (sfd: sfd_assoc_select; OpenCV: the call). The\n"
        "'+ update' column adds sfd_assoc_apply: EKF update with set 1, rescue, set 2.\n\n");
    std::printf(
        "| N | outliers | sigma | kind | method | median (us) | p99 (us) | + update median "
        "(us) | precision | recall | F1 | hypotheses |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    std::vector<int> Ns = quick ? std::vector<int>{200} : std::vector<int>{50, 100, 200, 500};
    std::vector<double> ratios =
        quick ? std::vector<double>{0.3} : std::vector<double>{0.0, 0.1, 0.3, 0.5};
    std::vector<double> sigmas = quick ? std::vector<double>{1.0} : std::vector<double>{0.5, 1.0};
    if (worst) {
        Ns = {SFD_MAX_FEATURES};
        ratios = {1.0};
        sigmas = {1.0};
    }
    for (int N : Ns) {
        if (N > SFD_MAX_FEATURES) continue;
        for (double ratio : ratios) {
            for (double sigma : sigmas) {
                for (int structured : {0, 1}) {
                    if (structured && (ratio == 0.0 || worst)) continue;
                    std::vector<Stats> st(methods.size());
                    for (int t = 0; t < trials; ++t) {
                        sim_pair_opts_t o = sim_pair_default_opts();
                        o.n = N;
                        o.outlier_ratio = ratio;
                        o.sigma_px = sigma;
                        o.structured = structured;
                        const uint64_t s = seed * 1000003ULL + uint64_t(t);
                        if (sim_pair_make(&g_pair, &o, s) != 0 || g_pair.n != N) {
                            std::fprintf(stderr, "sfd-bench: scene generation failed\n");
                            return 1;
                        }
                        for (size_t k = 0; k < methods.size(); ++k) {
                            if (!run_method(methods[k], g_pair, s, &st[k])) {
                                std::fprintf(stderr, "sfd-bench: %s failed\n",
                                             methods[k].name.c_str());
                                return 1;
                            }
                        }
                    }
                    const char *kind = structured ? "structured" : "random";
                    for (size_t k = 0; k < methods.size(); ++k) {
                        Stats &x = st[k];
                        std::printf(
                            "| %d | %.0f%% | %.1f | %s | %s | %.1f | %.1f | %.1f | %.3f | "
                            "%.3f | %.3f | %s |\n",
                            N, 100 * ratio, sigma, kind, methods[k].name.c_str(), x.pct(0.5),
                            x.pct(0.99), x.pct_total(0.5), x.precision(), x.recall(), x.f1(),
                            x.hyp_text().c_str());
                        if (fc != nullptr) {
                            std::fprintf(
                                fc,
                                "%d,%.2f,%.2f,%s,%s,%.3f,%.3f,%.3f,%.5f,%.5f,%.5f,%.0f,%.0f,%ld\n",
                                N, ratio, sigma, kind, methods[k].name.c_str(), x.pct(0.5),
                                x.pct(0.99), x.pct_total(0.5), x.precision(), x.recall(), x.f1(),
                                Stats::pct_of(x.hyps, 0.5), Stats::pct_of(x.hyps, 1.0),
                                x.exhausted);
                        }
                    }
                }
            }
        }
    }
    if (fc != nullptr) std::fclose(fc);
    return 0;
}
