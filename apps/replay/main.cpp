// SPDX-License-Identifier: MIT
// sfd-replay: plays an LCM log through exactly the node's code path (drivers/lcm/sfd_node_core),
// as fast as possible, writes the input events plus the published ones to OUT (readable by
// lcm-logplayer), and a JSON summary scored against TRUTH. Same input and options give
// byte-identical OUT and summary: wall-clock timing goes only to a separate file
// (SUMMARY.timing.json) and never into OUT (the node publishes SFD_TIMING with durations 0 here).
#include <lcm/eventlog.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "sfd_app_config.hpp"
#include "sfd_node_core.h"
#include "sfd_truth_t.h"

namespace {

struct FrameRecord {
    std::vector<int64_t> ids;
    std::vector<int8_t> status;
    double position[3] = {0, 0, 0};  // TRUTH: true IMU position; states: the EKF's
};

struct App {
    lcm_eventlog_t *out = nullptr;
    int64_t current_timestamp = 0;
    std::string verdict_channel = "SFD_VERDICT";
    std::string timing_channel = "SFD_TIMING";
    std::string state_channel = "SFD_STATE";
    std::map<int64_t, FrameRecord> verdicts;
    std::map<int64_t, FrameRecord> states;  // SFD_STATE by frame time
    sfd_nav_state_t decoded_state;
    bool write_failed = false;
    sfd_feature_verdict_t decoded;
};

App g_app;
sfd_node_t g_node;  // ~0.3 MiB: static

void write_event(lcm_eventlog_t *log, const std::string &channel, int64_t ts, const void *data,
                 int32_t size) {
    lcm_eventlog_event_t ev;
    std::memset(&ev, 0, sizeof ev);
    ev.timestamp = ts;
    ev.channellen = static_cast<int32_t>(channel.size());
    ev.channel = const_cast<char *>(channel.c_str());
    ev.datalen = size;
    ev.data = const_cast<void *>(data);
    if (lcm_eventlog_write_event(log, &ev) != 0) g_app.write_failed = true;
}

void on_publish(void *ctx, sfd_node_output_t kind, const void *data, int32_t size, int64_t) {
    App *app = static_cast<App *>(ctx);
    const std::string &ch = kind == SFD_NODE_OUT_VERDICT ? app->verdict_channel
                            : kind == SFD_NODE_OUT_STATE ? app->state_channel
                                                         : app->timing_channel;
    if (app->out != nullptr) write_event(app->out, ch, app->current_timestamp, data, size);
    if (kind == SFD_NODE_OUT_STATE &&
        sfd_nav_state_t_decode(data, 0, size, &app->decoded_state) == size) {
        FrameRecord &r = app->states[app->decoded_state.utime];
        for (int k = 0; k < 3; ++k) r.position[k] = app->decoded_state.position[k];
    }
    if (kind == SFD_NODE_OUT_VERDICT &&
        sfd_feature_verdict_t_decode(data, 0, size, &app->decoded) == size) {
        FrameRecord &r = app->verdicts[app->decoded.utime];
        r.ids.assign(app->decoded.track_id, app->decoded.track_id + app->decoded.num_features);
        r.status.assign(app->decoded.status, app->decoded.status + app->decoded.num_features);
    }
}

void usage(FILE *f) {
    std::fprintf(
        f,
        "usage: sfd-replay IN.lcmlog [--config F] [-o OUT.lcmlog] [--summary S.json] [--method M]\n"
        "                  [--alpha A] [--window L] [--group n] [--pixel-sigma PX]\n"
        "                  [--depth-default M] [--no-isolation]\n"
        "  Plays IN through the node's code path as fast as possible.\n"
        "  -o          write the input events and the published SFD_VERDICT/SFD_STATE/\n"
        "              SFD_TIMING\n"
        "  --summary   JSON summary (scored against TRUTH when the log has it); wall-\n"
        "              clock timing goes to S.timing.json\n"
        "  --method    none | parity | oprf | ransac1 | ransacf | both (default: the\n"
        "              config's, parity); oprf, ransac1, ransacf, both need filter.enabled\n"
        "  TRUTH in IN scores the verdicts and the SFD_STATE positions (RMSE); with\n"
        "  filter.init_from_truth: 1 the filter starts from TRUTH instead of at rest.\n"
        "Exit: 0 ok, 2 bad usage or unreadable input, 1 internal failure.\n");
}

double parse_double(const char *flag, const char *s, double lo, double hi, bool *ok) {
    char *end = nullptr;
    const double v = std::strtod(s, &end);
    if (*end != '\0' || !(v >= lo && v <= hi)) {
        std::fprintf(stderr, "sfd-replay: %s: expected %g..%g, got %s\n", flag, lo, hi, s);
        *ok = false;
    }
    return v;
}

}  // namespace

int main(int argc, char **argv) {
    const char *in_path = nullptr, *out_path = nullptr, *summary_path = nullptr;
    sfdapp::AppConfig app_cfg;
    std::string err;
    for (int i = 1; i + 1 < argc; ++i) {  // the config file first, flags override it
        if (!std::strcmp(argv[i], "--config") &&
            !sfdapp::load_config(argv[i + 1], &app_cfg, &err)) {
            std::fprintf(stderr, "sfd-replay: %s\n", err.c_str());
            return 2;
        }
    }
    sfd_node_config_t &cfg = app_cfg.node;
    bool ok = true;
    for (int i = 1; i < argc && ok; ++i) {
        const char *a = argv[i];
        const bool has = i + 1 < argc;
        if (!std::strcmp(a, "--help") || !std::strcmp(a, "-h")) {
            usage(stdout);
            return 0;
        } else if (!std::strcmp(a, "--config") && has) {
            ++i;
        } else if (!std::strcmp(a, "-o") && has) {
            out_path = argv[++i];
        } else if (!std::strcmp(a, "--summary") && has) {
            summary_path = argv[++i];
        } else if (!std::strcmp(a, "--method") && has) {
            if (!sfdapp::set_method(argv[++i], &app_cfg, &err)) {
                std::fprintf(stderr, "sfd-replay: --method: %s\n", err.c_str());
                return 2;
            }
        } else if (!std::strcmp(a, "--alpha") && has) {
            cfg.params.false_alarm_rate = parse_double(a, argv[++i], 1e-12, 0.5, &ok);
        } else if (!std::strcmp(a, "--window") && has) {
            cfg.params.window_frames = int(parse_double(a, argv[++i], 2, SFD_MAX_WINDOW, &ok));
        } else if (!std::strcmp(a, "--group") && has) {
            cfg.params.group_size = int(parse_double(a, argv[++i], 1, SFD_MAX_GROUP, &ok));
        } else if (!std::strcmp(a, "--pixel-sigma") && has) {
            cfg.params.pixel_sigma_px = parse_double(a, argv[++i], 1e-6, 1e3, &ok);
        } else if (!std::strcmp(a, "--depth-default") && has) {
            cfg.params.default_depth_m = parse_double(a, argv[++i], 1e-3, 1e6, &ok);
        } else if (!std::strcmp(a, "--no-isolation")) {
            cfg.params.parity_isolation = 0;
        } else if (a[0] != '-' && in_path == nullptr) {
            in_path = a;
        } else {
            std::fprintf(stderr, "sfd-replay: unknown or incomplete option: %s\n", a);
            usage(stderr);
            return 2;
        }
    }
    if (!ok) return 2;
    if (!sfdapp::validate(app_cfg, &err)) {
        std::fprintf(stderr, "sfd-replay: %s\n", err.c_str());
        return 2;
    }
    const std::string method_name = app_cfg.method;
    g_app.verdict_channel = app_cfg.channels.verdict;
    g_app.timing_channel = app_cfg.channels.timing;
    g_app.state_channel = app_cfg.channels.state;
    if (in_path == nullptr) {
        std::fprintf(stderr, "sfd-replay: missing IN.lcmlog\n");
        usage(stderr);
        return 2;
    }
    lcm_eventlog_t *in = lcm_eventlog_create(in_path, "r");
    if (in == nullptr) {
        std::fprintf(stderr, "sfd-replay: %s: cannot open for reading\n", in_path);
        return 2;
    }
    if (out_path != nullptr) {
        g_app.out = lcm_eventlog_create(out_path, "w");
        if (g_app.out == nullptr) {
            std::fprintf(stderr, "sfd-replay: -o %s: cannot open for writing\n", out_path);
            lcm_eventlog_destroy(in);
            return 2;
        }
    }
    if (sfd_node_init(&g_node, &cfg, on_publish, nullptr, &g_app) != SFD_OK) {
        std::fprintf(stderr, "sfd-replay: invalid detector parameters\n");
        return 2;
    }
    std::fseek(in->f, 0, SEEK_END);
    const long file_size = std::ftell(in->f);
    std::fseek(in->f, 0, SEEK_SET);
    const bool progress = isatty(STDERR_FILENO) != 0;
    std::map<int64_t, FrameRecord> truth;
    static sfd_truth_t tr;
    std::vector<double> frame_us;
    int64_t first_ts = 0, last_ts = 0, events = 0, foreign = 0;
    int last_pct = -1;
    const auto wall0 = std::chrono::steady_clock::now();
    for (lcm_eventlog_event_t *ev = lcm_eventlog_read_next_event(in); ev != nullptr;
         ev = lcm_eventlog_read_next_event(in)) {
        if (events == 0) first_ts = ev->timestamp;
        last_ts = ev->timestamp;
        ++events;
        g_app.current_timestamp = ev->timestamp;
        const std::string ch(ev->channel, size_t(ev->channellen));
        if (g_app.out != nullptr) write_event(g_app.out, ch, ev->timestamp, ev->data, ev->datalen);
        if (ch == app_cfg.channels.imu) {
            sfd_node_handle(&g_node, SFD_NODE_IMU, ev->data, ev->datalen);
        } else if (ch == app_cfg.channels.camera_info) {
            sfd_node_handle(&g_node, SFD_NODE_CAMERA_INFO, ev->data, ev->datalen);
        } else if (ch == app_cfg.channels.features) {
            const auto t0 = std::chrono::steady_clock::now();
            sfd_node_handle(&g_node, SFD_NODE_FEATURES, ev->data, ev->datalen);
            const auto t1 = std::chrono::steady_clock::now();
            frame_us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
        } else if (ch == "TRUTH") {
            sfd_node_handle(&g_node, SFD_NODE_TRUTH, ev->data, ev->datalen);
            if (sfd_truth_t_decode(ev->data, 0, ev->datalen, &tr) == ev->datalen &&
                tr.num_features >= 0 && tr.num_features <= SFD_TRUTH_T_CAPACITY) {
                FrameRecord &r = truth[tr.utime];
                r.ids.assign(tr.track_id, tr.track_id + tr.num_features);
                r.status.assign(tr.spurious, tr.spurious + tr.num_features);
                for (int k = 0; k < 3; ++k) r.position[k] = tr.position[k];
            }
        } else {
            ++foreign;  // other channels (e.g. a previous run's outputs) are copied, not read
        }
        lcm_eventlog_free_event(ev);
        if (progress && file_size > 0) {
            const int pct = int(100.0 * double(std::ftell(in->f)) / double(file_size));
            if (pct != last_pct) {
                std::fprintf(stderr, "\rsfd-replay: %3d%%", pct);
                last_pct = pct;
            }
        }
    }
    sfd_node_flush(&g_node);
    const double wall_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    if (progress) std::fprintf(stderr, "\rsfd-replay: 100%%\n");
    lcm_eventlog_destroy(in);
    if (g_app.out != nullptr) lcm_eventlog_destroy(g_app.out);
    if (g_app.write_failed) {
        std::fprintf(stderr, "sfd-replay: -o %s: write failed\n", out_path);
        return 1;
    }

    // Verdict counts without TRUTH (tested = CONSISTENT or SPURIOUS), for logs without labels.
    long judged_tested = 0, judged_spurious = 0;
    for (const auto &kv : g_app.verdicts) {
        for (const int8_t st : kv.second.status) {
            judged_tested += st != SFD_FEATURE_VERDICT_T_UNTESTED;
            judged_spurious += st == SFD_FEATURE_VERDICT_T_SPURIOUS;
        }
    }
    // Score verdicts against TRUTH (tested features only; untested counted apart). Only features
    // TRUTH labels count; a frame is scored when TRUTH labels at least one of its features. TRUTH
    // of real data (sfd-euroc) carries poses and no labels: nothing is scored, and the summary
    // says so instead of printing zero scores.
    long tp = 0, fp = 0, tn = 0, fn = 0, untested_spurious = 0, untested_consistent = 0, scored = 0;
    long labelled = 0;
    for (const auto &kv : g_app.verdicts) {
        const auto it = truth.find(kv.first);
        if (it == truth.end()) continue;
        const long labelled_before = labelled;
        std::map<int64_t, int8_t> lab;
        for (size_t i = 0; i < it->second.ids.size(); ++i)
            lab[it->second.ids[i]] = it->second.status[i];
        for (size_t i = 0; i < kv.second.ids.size(); ++i) {
            const auto l = lab.find(kv.second.ids[i]);
            if (l == lab.end()) continue;
            ++labelled;
            const bool sp = l->second != 0;
            const int8_t st = kv.second.status[i];
            if (st == SFD_FEATURE_VERDICT_T_UNTESTED) {
                (sp ? untested_spurious : untested_consistent)++;
            } else if (st == SFD_FEATURE_VERDICT_T_SPURIOUS) {
                (sp ? tp : fp)++;
            } else {
                (sp ? fn : tn)++;
            }
        }
        scored += labelled > labelled_before;
    }
    // Position RMSE of SFD_STATE against TRUTH at the same frame times (no alignment: the filter
    // starts from TRUTH (filter.init_from_truth) or at rest at the origin of its own frame, in
    // which case the RMSE measures the drift from that start).
    double se = 0.0;
    long state_frames = 0;
    for (const auto &kv : g_app.states) {
        const auto it = truth.find(kv.first);
        if (it == truth.end()) continue;
        for (int k = 0; k < 3; ++k) {
            const double d = kv.second.position[k] - it->second.position[k];
            se += d * d;
        }
        ++state_frames;
    }
    const double rmse = state_frames > 0 ? std::sqrt(se / double(state_frames)) : 0.0;
    const double precision = tp + fp ? double(tp) / double(tp + fp) : 0.0;
    const double recall = tp + fn ? double(tp) / double(tp + fn) : 0.0;
    const double f1 = precision + recall > 0 ? 2 * precision * recall / (precision + recall) : 0.0;
    const double far = fp + tn ? double(fp) / double(fp + tn) : 0.0;
    const sfd_node_counters_t &c = g_node.counters;
    std::printf(
        "sfd-replay %s: method %s, %lld events, %lld frames processed (%lld untested), "
        "%ld scored against TRUTH\n",
        in_path, method_name.c_str(), static_cast<long long>(events),
        static_cast<long long>(c.frames_processed), static_cast<long long>(c.frames_untested),
        scored);
    std::printf("  judged: %ld features tested, %ld spurious (%.2f%%)\n", judged_tested,
                judged_spurious,
                judged_tested ? 100.0 * double(judged_spurious) / double(judged_tested) : 0.0);
    if (scored == 0 && !truth.empty()) {
        std::printf(
            "  TRUTH has no spurious labels for the judged features: verdicts not scored\n");
    }
    if (scored > 0) {
        std::printf(
            "  precision %.4f  recall %.4f  F1 %.4f  false-alarm rate %.5f  "
            "(TP %ld FP %ld TN %ld FN %ld; untested: %ld spurious, %ld consistent)\n",
            precision, recall, f1, far, tp, fp, tn, fn, untested_spurious, untested_consistent);
    }
    if (state_frames > 0) {
        std::printf("  position RMSE %.4f m over %ld frames with SFD_STATE and TRUTH\n", rmse,
                    state_frames);
    }
    std::sort(frame_us.begin(), frame_us.end());
    const double med = frame_us.empty() ? 0 : frame_us[frame_us.size() / 2];
    const double p99 =
        frame_us.empty()
            ? 0
            : frame_us[std::min(frame_us.size() - 1, size_t(0.99 * double(frame_us.size())))];
    const double mx = frame_us.empty() ? 0 : frame_us.back();
    const double log_s = double(last_ts - first_ts) * 1e-6;
    std::printf("  time per frame: median %.1f us, p99 %.1f us, max %.1f us; %.1fx real time\n",
                med, p99, mx, wall_s > 0 ? log_s / wall_s : 0.0);
    if (summary_path != nullptr) {
        FILE *f = std::fopen(summary_path, "w");
        if (f == nullptr) {
            std::fprintf(stderr, "sfd-replay: --summary %s: cannot write\n", summary_path);
            return 2;
        }
        std::fprintf(f, "{\n  \"input\": \"%s\",\n  \"events\": %lld,\n", in_path,
                     static_cast<long long>(events));
        std::fprintf(f, "  \"frames\": {\"in\": %lld, \"processed\": %lld, \"untested\": %lld},\n",
                     static_cast<long long>(c.frames_in),
                     static_cast<long long>(c.frames_processed),
                     static_cast<long long>(c.frames_untested));
        std::fprintf(f, "  \"rejected\": {");
        for (int k = 0; k < SFD_REJECT_NUM_REASONS; ++k) {
            std::fprintf(f, "%s\"%s\": %lld", k ? ", " : "", sfd_reject_reason_str(k),
                         static_cast<long long>(c.rejected[k]));
        }
        std::fprintf(f,
                     "},\n  \"methods\": {\n    \"%s\": {\"judged_tested\": %ld, "
                     "\"judged_spurious\": %ld, \"labelled_features\": %ld, "
                     "\"frames_scored\": %ld, \"tp\": %ld, "
                     "\"fp\": %ld, \"tn\": %ld, \"fn\": %ld, \"untested_spurious\": %ld, "
                     "\"untested_consistent\": %ld",
                     method_name.c_str(), judged_tested, judged_spurious, labelled, scored, tp, fp,
                     tn, fn, untested_spurious, untested_consistent);
        if (labelled > 0) {
            std::fprintf(f,
                         ", \"precision\": %.6f, \"recall\": %.6f, \"f1\": %.6f, "
                         "\"false_alarm_rate\": %.6f",
                         precision, recall, f1, far);
        } else {  // no labels: no scores (null, not 0)
            std::fprintf(f,
                         ", \"precision\": null, \"recall\": null, \"f1\": null, "
                         "\"false_alarm_rate\": null");
        }
        if (state_frames > 0) {
            std::fprintf(f, ", \"state_frames\": %ld, \"position_rmse_m\": %.6f", state_frames,
                         rmse);
        }
        std::fprintf(f, "}\n  }\n}\n");
        std::fclose(f);
        const std::string tpath = std::string(summary_path) + ".timing.json";
        FILE *t = std::fopen(tpath.c_str(), "w");
        if (t != nullptr) {
            std::fprintf(t,
                         "{\"frames\": %zu, \"frame_us\": {\"median\": %.3f, \"p99\": %.3f, "
                         "\"max\": %.3f}, \"wall_s\": %.6f, \"log_s\": %.6f, "
                         "\"speed_vs_real_time\": %.2f}\n",
                         frame_us.size(), med, p99, mx, wall_s, log_s,
                         wall_s > 0 ? log_s / wall_s : 0.0);
            std::fclose(t);
        }
    }
    return 0;
}
