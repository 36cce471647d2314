// SPDX-License-Identifier: MIT
// sfd-replay: plays an LCM log through exactly the node's code path (drivers/lcm/sfd_node_core),
// as fast as possible, writes the input events plus the published ones to OUT (readable by
// lcm-logplayer), and a JSON summary scored against TRUTH. Same input and options give
// byte-identical OUT and summary: wall-clock timing goes only to a separate file
// (SUMMARY.timing.json) and never into OUT (the node publishes SFD_TIMING with durations 0 here).
#include <lcm/eventlog.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "sfd_app_cli.hpp"
#include "sfd_app_config.hpp"
#include "sfd_cli.hpp"
#include "sfd_eval.hpp"
#include "sfd_lcm_codec.h"
#include "sfd_log_reader.h"
#include "sfd_node_core.h"
#include "sfd_output.h"
#include "sfd_pose_oracle.hpp"

namespace {

using json = nlohmann::ordered_json;

struct VerdictRecord {
    std::vector<int64_t> ids;
    std::vector<int8_t> status;
};

struct TruthRecord {
    std::vector<int64_t> ids;
    std::vector<int8_t> kinds;  // KIND_* per feature (KIND_CLEAN when not spurious)
    sfdeval::Pose pose;
};

struct App {
    lcm_eventlog_t *out = nullptr;
    int64_t current_timestamp = 0;
    std::string verdict_channel = "SFD_VERDICT";
    std::string timing_channel = "SFD_TIMING";
    std::string state_channel = "SFD_STATE";
    std::map<int64_t, VerdictRecord> verdicts;  // SFD_VERDICT by frame time
    std::map<int64_t, sfdeval::Pose> states;    // SFD_STATE by frame time
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

// Records a published (or, with --score-only, logged) SFD_STATE or SFD_VERDICT for scoring.
void record_output(App *app, sfd_node_output_t kind, const void *data, int32_t size) {
    if (kind == SFD_NODE_OUT_STATE &&
        sfd_nav_state_t_decode(data, 0, size, &app->decoded_state) == size) {
        const sfd_nav_state_t &d = app->decoded_state;
        sfdeval::Pose &p = app->states[d.utime];
        p.t_us = d.utime;
        for (int k = 0; k < 3; ++k) {
            p.p[k] = d.position[k];
            p.var[k] = d.position_var[k];
        }
        for (int k = 0; k < 4; ++k) p.q[k] = d.orientation[k];
        p.has_var = true;
    }
    if (kind == SFD_NODE_OUT_VERDICT &&
        sfd_feature_verdict_t_decode(data, 0, size, &app->decoded) == size &&
        app->decoded.num_features >= 0) {
        VerdictRecord &r = app->verdicts[app->decoded.utime];
        r.ids.assign(app->decoded.track_id, app->decoded.track_id + app->decoded.num_features);
        r.status.assign(app->decoded.status, app->decoded.status + app->decoded.num_features);
    }
}

void on_publish(void *ctx, sfd_node_output_t kind, const void *data, int32_t size, int64_t) {
    App *app = static_cast<App *>(ctx);
    const std::string &ch = kind == SFD_NODE_OUT_VERDICT ? app->verdict_channel
                            : kind == SFD_NODE_OUT_STATE ? app->state_channel
                                                         : app->timing_channel;
    if (app->out != nullptr) write_event(app->out, ch, app->current_timestamp, data, size);
    record_output(app, kind, data, size);
}

// A score for the JSON summary: null where it is not defined (sfdeval::kUndefined).
json number(double x) {
    return std::isfinite(x) ? json(x) : json(nullptr);
}

json spread_json(const sfdeval::Spread &s) {
    return json{{"median", number(s.median)},
                {"p99", number(s.p99)},
                {"p999", number(s.p999)},
                {"max", number(s.max)},
                {"mean", number(s.mean)}};
}

json detection_json(const sfdeval::DetectionCounts &c, const sfdeval::FaultEvents &ev) {
    const sfdeval::DetectionScores s = sfdeval::score(c);
    json j{{"labelled", c.labelled()},
           {"spurious", c.spurious()},
           {"clean", c.clean()},
           {"tp", c.tp},
           {"fp", c.fp},
           {"tn", c.tn},
           {"fn", c.fn},
           {"untested_spurious", c.untested_spurious},
           {"untested_clean", c.untested_clean},
           {"precision", number(s.precision)},
           {"recall", number(s.recall)},
           {"f1", number(s.f1)},
           {"false_alarm_rate", number(s.false_alarm_rate)},
           {"coverage", number(s.coverage)},
           {"recall_tested", number(s.recall_tested)},
           {"false_alarm_rate_tested", number(s.false_alarm_rate_tested)}};
    json kinds = json::object();
    for (int k = sfdeval::kJump; k < sfdeval::kNumKinds; ++k) {
        json entry{{"spurious", c.kind_spurious[k]},
                   {"detected", c.kind_detected[k]},
                   {"untested", c.kind_untested[k]},
                   {"recall", number(s.kind_recall[k])},
                   {"events", ev.events[k]}};
        // fraction of the kind's events caught within W frames (sfd_eval.hpp FaultEvents)
        for (int w = 0; w < sfdeval::FaultEvents::kWindows; ++w) {
            entry["caught_" + std::to_string(sfdeval::FaultEvents::kCatchWindows[w])] =
                number(ev.fraction(k, w));
        }
        kinds[sfdeval::kind_name(k)] = entry;
    }
    j["by_kind"] = kinds;
    return j;
}

json segments_json(const sfdeval::SegmentErrors &s, bool with_percent) {
    json j{{"segments", s.segments}, {"mean_m", number(s.mean_m)}, {"rmse_m", number(s.rmse_m)}};
    if (with_percent) j["mean_percent"] = number(s.mean_percent);
    return j;
}

json trajectory_json(const sfdeval::TrajectoryErrors &e) {
    return json{{"frames", e.frames},
                {"distance_m", number(e.distance_m)},
                {"rmse_raw_m", number(e.rmse_raw_m)},
                {"ate_m", number(e.ate_m)},
                {"align_yaw_rad", number(e.alignment.yaw_rad)},
                {"final_error_m", number(e.final_error_m)},
                {"drift_percent", number(e.drift_percent)},
                {"rpe_1s", segments_json(e.rpe_1s, false)},
                {"rpe_10m", segments_json(e.rpe_10m, true)},
                {"nees_position", json{{"frames", e.nees_frames},
                                       {"mean", number(e.nees_mean)},
                                       {"in_band_95", number(e.nees_in_band_95)}}}};
}

// The output files of a run (-o, --summary, SUMMARY.timing.json): each is written to a temporary
// file next to it and renamed into place only when the whole run succeeded (sfd_output.h).
struct Outputs {
    sfd_out_t log, summary, timing;
    ~Outputs() {
        sfd_out_discard(&log);
        sfd_out_discard(&summary);
        sfd_out_discard(&timing);
    }
};

// Writes `text` to the output `o` (exit code 0, or 1 with a message naming the path on any
// failure: the open, a short write, the flush or the close).
int write_text(const sfd_out_t &o, const std::string &text, const char *what) {
    std::FILE *f = std::fopen(o.write_path, "w");
    if (f == nullptr) {
        std::fprintf(stderr, "sfd-replay: %s %s: cannot open for writing (%s)\n", what, o.path,
                     std::strerror(errno));
        return 1;
    }
    const bool ok = std::fwrite(text.data(), 1, text.size(), f) == text.size();
    if (sfd_close_checked(f) != 0 || !ok) {
        std::fprintf(stderr, "sfd-replay: %s %s: write failed (%s)\n", what, o.path,
                     std::strerror(errno));
        return 1;
    }
    return 0;
}

// Exit 2 when an output is an input or another output (same path or same file).
bool outputs_distinct(const std::vector<std::pair<const char *, std::string>> &inputs,
                      const std::vector<std::pair<const char *, std::string>> &outputs) {
    for (size_t i = 0; i < outputs.size(); ++i) {
        for (const auto &in : inputs) {
            if (sfd_same_file(outputs[i].second.c_str(), in.second.c_str())) {
                std::fprintf(stderr,
                             "sfd-replay: %s %s is the input %s %s (same file): an output may "
                             "not overwrite an input\n",
                             outputs[i].first, outputs[i].second.c_str(), in.first,
                             in.second.c_str());
                return false;
            }
        }
        struct stat st;  // two outputs to /dev/null (a character device) are fine
        const bool device = stat(outputs[i].second.c_str(), &st) == 0 && S_ISCHR(st.st_mode);
        for (size_t j = 0; j < i && !device; ++j) {
            if (sfd_same_file(outputs[i].second.c_str(), outputs[j].second.c_str())) {
                std::fprintf(stderr, "sfd-replay: %s %s and %s %s are the same file\n",
                             outputs[j].first, outputs[j].second.c_str(), outputs[i].first,
                             outputs[i].second.c_str());
                return false;
            }
        }
    }
    return true;
}

// --oracle-poses (sfd_pose_oracle.hpp): the camera the node would follow (the configured
// camera_id, else the first one calibrated; a changed calibration of it starts the oracle
// again, dropping the frames of the old one that still wait, a republished one keeps it),
// its frames queued until TRUTH gives their pose, judged in time order; a frame whose TRUTH
// never comes (TRUTH of a later frame arrived, or the log ended) stays unjudged.
struct Oracle {
    static_assert(SFD_VERDICT_UNTESTED == SFD_FEATURE_VERDICT_T_UNTESTED &&
                      SFD_VERDICT_CONSISTENT == SFD_FEATURE_VERDICT_T_CONSISTENT &&
                      SFD_VERDICT_SPURIOUS == SFD_FEATURE_VERDICT_T_SPURIOUS,
                  "core and wire verdict codes");
    sfdoracle::PoseOracle po;
    int32_t camera_id = -1;
    bool have_camera = false;
    long judged = 0, unjudged = 0, refused = 0, failed = 0, judged_untested = 0;
    static constexpr size_t kMaxPending = 256;          // frames waiting for their TRUTH
    std::vector<std::unique_ptr<sfd_frame_t>> pending;  // oldest first
    sfd_camera_info_t ci_msg;
    sfd_feature_frame_t ff_msg;
    sfd_verdict_t verdict;
    sfd_camera_t camera;
    sfd_extrinsics_t extrinsics;

    // bit for bit, field by field (the structs' padding is not part of the value)
    static bool same_bits(const double *a, const double *b, int n) {
        for (int k = 0; k < n; ++k) {
            uint64_t x = 0, y = 0;
            std::memcpy(&x, &a[k], sizeof x);
            std::memcpy(&y, &b[k], sizeof y);
            if (x != y) return false;
        }
        return true;
    }
    bool same_calibration(const sfd_camera_t &c, const sfd_extrinsics_t &e) const {
        const double a[8] = {c.fx_px,   c.fy_px,   c.cx_px,   c.cy_px,
                             c.dist[0], c.dist[1], c.dist[2], c.dist[3]};
        const double b[8] = {camera.fx_px,   camera.fy_px,   camera.cx_px,   camera.cy_px,
                             camera.dist[0], camera.dist[1], camera.dist[2], camera.dist[3]};
        return c.model == camera.model && c.width_px == camera.width_px &&
               c.height_px == camera.height_px && same_bits(a, b, 8) &&
               same_bits(e.R_CtoI, extrinsics.R_CtoI, 9) &&
               same_bits(e.p_CinI, extrinsics.p_CinI, 3);
    }
    void camera_info(const sfd_params_t &params, const void *data, int32_t size) {
        sfd_camera_t cam;
        sfd_extrinsics_t ext;
        int32_t id = 0;
        if (sfd_lcm_decode_camera_info(data, size, &ci_msg, &cam, &ext, &id) != SFD_REJECT_NONE ||
            ((have_camera || camera_id >= 0) && id != camera_id)) {
            return;
        }
        camera_id = id;
        // the same calibration again (published periodically) keeps the window, as in the node
        if (have_camera && same_calibration(cam, ext)) return;
        camera = cam;
        extrinsics = ext;
        // frames of the old calibration still waiting for TRUTH are not judged with the new one
        refused += static_cast<long>(pending.size());
        pending.clear();
        have_camera = po.start(params, cam, ext) == SFD_OK;
    }
    void features(const void *data, int32_t size) {
        auto f = std::make_unique<sfd_frame_t>();
        int32_t id = 0;
        int fixed = 0;
        if (!have_camera ||
            sfd_lcm_decode_features(data, size, &ff_msg, f.get(), &id, &fixed) != SFD_REJECT_NONE ||
            id != camera_id || (!pending.empty() && f->utime <= pending.back()->utime)) {
            ++refused;
            return;
        }
        pending.push_back(std::move(f));
    }
    void drain(const std::map<int64_t, TruthRecord> &truth, std::vector<double> *frame_us,
               bool at_end) {
        size_t k = 0;
        for (; k < pending.size(); ++k) {
            const sfd_frame_t &f = *pending[k];
            const auto it = truth.find(f.utime);
            if (it == truth.end()) {
                const bool never = at_end || (!truth.empty() && truth.rbegin()->first > f.utime);
                if (!never) break;
                ++unjudged;
                continue;
            }
            const auto t0 = std::chrono::steady_clock::now();
            if (po.judge(f, it->second.pose.p, it->second.pose.q, &verdict) != SFD_OK) {
                ++failed;  // refused by the detector (a bad pose or frame): not judged
                continue;
            }
            frame_us->push_back(
                std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0)
                    .count());
            ++judged;
            judged_untested += verdict.num_consistent + verdict.num_spurious == 0;
            VerdictRecord &r = g_app.verdicts[f.utime];
            r.ids.resize(size_t(verdict.num_features));
            r.status.resize(size_t(verdict.num_features));
            for (int i = 0; i < verdict.num_features; ++i) {
                r.ids[size_t(i)] = verdict.features[i].track_id;
                r.status[size_t(i)] = verdict.features[i].status;
            }
        }
        pending.erase(pending.begin(), pending.begin() + static_cast<std::ptrdiff_t>(k));
        // a log without TRUTH for its frames: the oldest give up waiting (bounded memory)
        while (pending.size() > kMaxPending) {
            pending.erase(pending.begin());
            ++unjudged;
        }
    }
};

int run(int argc, char **argv) {
    const char *in_path = nullptr, *out_path = nullptr, *summary_path = nullptr;
    std::string in_arg, out_arg, summary_arg;
    bool score_only = false, salvage = false, oracle_poses = false;
    sfdapp::AppConfig app_cfg;
    // The same parser and configuration flags as sfd-node (apps/common/sfd_app_cli.hpp).
    sfdcli::Parser cli(
        "sfd-replay", "sfd-replay",
        "IN.lcmlog [-o OUT.lcmlog] [--summary S.json] [--config F] [--KEY VALUE ...]\n"
        "       sfd-replay IN.lcmlog --score-only [--summary S.json] [--config F] [--salvage]\n"
        "       sfd-replay IN.lcmlog --oracle-poses [--summary S.json] [--config F] [--KEY VALUE]",
        "  Plays IN through the node's code path as fast as possible. IN must be an LCM log:\n"
        "  the first bad event (no sync word where an event starts, a channel length outside\n"
        "  1..999 or a negative data length, an event running past the end of the file) is\n"
        "  exit 2 naming IN and its byte offset; an empty file, a directory or anything else\n"
        "  that is not a regular file is exit 2 too. TRUTH in IN scores the verdicts (every\n"
        "  labelled feature counts: an UNTESTED spurious one is a miss) and the SFD_STATE\n"
        "  poses (ATE after position+yaw alignment, raw RMSE, drift, RPE, NEES;\n"
        "  docs/evaluation.md). With filter.init_from_truth: 1 the filter starts from TRUTH\n"
        "  instead of at rest. On a terminal (and CI unset), a progress line on stderr.");
    cli.section("Input and outputs");
    sfdcli::Option out;
    out.name = "output";
    out.short_name = 'o';
    out.metavar = "OUT.lcmlog";
    out.help =
        "write the input events and the published SFD_VERDICT,\n"
        "SFD_STATE and SFD_TIMING";
    out.set = [&out_arg, &out_path](const std::string &v, std::string *) {
        out_arg = v;
        out_path = out_arg.c_str();
        return true;
    };
    cli.add(out);
    cli.value("summary", "S.json",
              "JSON summary (scored against TRUTH when the log has\n"
              "it); wall-clock timing goes to S.json.timing.json",
              [&summary_arg, &summary_path](const std::string &v, std::string *) {
                  summary_arg = v;
                  summary_path = summary_arg.c_str();
                  return true;
              });
    cli.flag("score-only",
             "run no node: score the SFD_VERDICT and SFD_STATE\n"
             "already in IN (a recorded sfd-node run, or a previous\n"
             "-o) against its TRUTH",
             [&score_only] { score_only = true; });
    cli.flag("oracle-poses",
             "evaluation only: run no node; parity's test with the\n"
             "filter's translation judges each frame with the TRUE\n"
             "poses of TRUTH in place of the window filter (method\n"
             "parity; docs/evaluation.md \"What the test can see\n"
             "with true poses\"); frames without TRUTH go unjudged",
             [&oracle_poses] { oracle_poses = true; });
    cli.flag("salvage",
             "skip bad events instead (resynchronizing on the next\n"
             "sync word that starts a good event); the summary\n"
             "counts them (\"log\": bad_events, bytes_skipped); a\n"
             "file with no good event is still exit 2",
             [&salvage] { salvage = true; });
    sfdapp::ConfigCommandLine config;
    config.add_to(&cli);
    cli.epilog(
        "Outputs: an output (-o, --summary, S.timing.json) that is an input (IN, --config) or\n"
        "  another output (a character device such as /dev/null aside), by path or by file\n"
        "  (hard or symbolic link), is exit 2 before anything is written. Outputs are written\n"
        "  to a temporary file in their directory and renamed into place when the run succeeds\n"
        "  (special files such as /dev/null are written directly); a failed write is exit 1\n"
        "  naming the path, and a failed run leaves no output behind.\n"
        "Configuration: --config files (several: later keys win), then the flags over them,\n"
        "  validated as a whole as by sfd-node: the first bad key is exit 2 naming its file or\n"
        "  flag, the key and the value.\n"
        "Exit: 0 ok, 2 bad usage or bad input (a one-line reason naming the file), 1 internal\n"
        "  failure or a failed write.");
    std::vector<std::string> positional;
    if (const int rc = cli.parse(argc, argv, &positional); rc >= 0) return rc;
    if (positional.size() > 1) return cli.fail("unexpected argument " + positional[1]);
    if (!positional.empty()) {
        in_arg = positional[0];
        in_path = in_arg.c_str();
    }
    if (const int rc = config.load("sfd-replay", &app_cfg); rc != 0) return rc;
    std::vector<std::pair<const char *, std::string>> inputs;
    for (const std::string &f : config.files()) inputs.emplace_back("--config", f);
    sfd_node_config_t &cfg = app_cfg.node;
    const std::string method_name = app_cfg.method;
    g_app.verdict_channel = app_cfg.channels.verdict;
    g_app.timing_channel = app_cfg.channels.timing;
    g_app.state_channel = app_cfg.channels.state;
    if (in_path == nullptr) return cli.fail("missing IN.lcmlog (sfd-replay --help)");
    if (score_only && out_path != nullptr) {
        std::fprintf(stderr, "sfd-replay: --score-only writes no OUT (-o)\n");
        return 2;
    }
    if (oracle_poses && (out_path != nullptr || score_only)) {
        std::fprintf(stderr,
                     "sfd-replay: --oracle-poses takes no %s (it runs no node and writes no OUT)\n",
                     score_only ? "--score-only" : "-o");
        return 2;
    }
    if (oracle_poses &&
        (cfg.params.method != SFD_METHOD_PARITY || cfg.params.translation_known != 1)) {
        std::fprintf(stderr,
                     "sfd-replay: --oracle-poses judges with parity's test with the filter's "
                     "translation: needs method parity and translation_known 1\n");
        return 2;
    }
    // No output may be an input or another output: checked before anything is opened.
    inputs.emplace(inputs.begin(), "log", in_path);
    std::vector<std::pair<const char *, std::string>> outputs;
    if (out_path != nullptr) outputs.emplace_back("-o", out_path);
    if (summary_path != nullptr) {
        outputs.emplace_back("--summary", summary_path);
        outputs.emplace_back("--summary timing", std::string(summary_path) + ".timing.json");
    }
    if (!outputs_distinct(inputs, outputs)) return 2;
    static sfd_log_reader_t in;  // ~3 KiB of buffers: static
    struct ReaderCloser {
        ~ReaderCloser() { sfd_log_close(&in); }
    } close_in;
    if (sfd_log_open(&in, in_path, salvage ? 1 : 0) != SFD_LOG_OK) {
        std::fprintf(stderr, "sfd-replay: %s\n", in.message);
        return 2;
    }
    Outputs outs;
    char oerr[8192];
    const auto begin = [&oerr](sfd_out_t *o, const char *flag, const std::string &path) {
        if (sfd_out_begin(o, path.c_str(), oerr, sizeof oerr) == 0) return true;
        std::fprintf(stderr, "sfd-replay: %s %s\n", flag, oerr);
        return false;
    };
    if ((out_path != nullptr && !begin(&outs.log, "-o", out_path)) ||
        (summary_path != nullptr &&
         (!begin(&outs.summary, "--summary", summary_path) ||
          !begin(&outs.timing, "--summary", std::string(summary_path) + ".timing.json")))) {
        return 1;
    }
    if (out_path != nullptr) {
        g_app.out = lcm_eventlog_create(outs.log.write_path, "w");
        if (g_app.out == nullptr) {
            std::fprintf(stderr, "sfd-replay: -o %s: cannot open for writing (%s)\n", out_path,
                         std::strerror(errno));
            return 1;
        }
    }
    if (sfd_node_init(&g_node, &cfg, on_publish, nullptr, &g_app) != SFD_OK) {
        std::fprintf(stderr,
                     "sfd-replay: internal: node initialization failed on a validated "
                     "configuration\n");
        if (g_app.out != nullptr) lcm_eventlog_destroy(g_app.out);
        return 1;
    }
    // Frames done, rate and time left on a terminal (stderr, CI unset); nothing otherwise.
    sfdcli::Progress progress("sfd-replay", score_only ? "events" : "frames");
    std::map<int64_t, TruthRecord> truth;  // TRUTH by frame time
    static sfd_truth_t tr;
    static sfd_truth_v1_t tr_v1;  // scratch for logs written before TRUTH had kind[]
    long truth_bad = 0;
    std::vector<double> frame_us;
    int64_t first_ts = 0, last_ts = 0, events = 0, foreign = 0;
    // --oracle-poses: frames wait for their TRUTH (in time order), then the oracle judges them.
    static Oracle oracle;  // ~60 KiB of message scratch: static
    oracle.camera_id = cfg.camera_id;
    const auto wall0 = std::chrono::steady_clock::now();
    sfd_log_event_t event;
    sfd_log_status_t read_status;
    while ((read_status = sfd_log_next(&in, &event)) == SFD_LOG_OK) {
        const sfd_log_event_t *ev = &event;
        if (events == 0) first_ts = ev->timestamp;
        last_ts = ev->timestamp;
        ++events;
        g_app.current_timestamp = ev->timestamp;
        const std::string ch(ev->channel, size_t(ev->channellen));
        if (g_app.out != nullptr) write_event(g_app.out, ch, ev->timestamp, ev->data, ev->datalen);
        if (ch == "TRUTH") {
            if (!score_only && !oracle_poses) {
                sfd_node_handle(&g_node, SFD_NODE_TRUTH, ev->data, ev->datalen);
            }
            if (sfd_lcm_decode_truth(ev->data, ev->datalen, &tr, &tr_v1) == SFD_REJECT_NONE) {
                TruthRecord &r = truth[tr.utime];
                r.ids.assign(tr.track_id, tr.track_id + tr.num_features);
                r.kinds.assign(tr.kind, tr.kind + tr.num_features);
                r.pose.t_us = tr.utime;
                for (int k = 0; k < 3; ++k) r.pose.p[k] = tr.position[k];
                for (int k = 0; k < 4; ++k) r.pose.q[k] = tr.orientation[k];
            } else {
                ++truth_bad;  // not scored (counted in the summary)
            }
            if (oracle_poses) oracle.drain(truth, &frame_us, false);
        } else if (oracle_poses) {
            if (ch == app_cfg.channels.camera_info) {
                oracle.camera_info(cfg.params, ev->data, ev->datalen);
            } else if (ch == app_cfg.channels.features) {
                oracle.features(ev->data, ev->datalen);
                oracle.drain(truth, &frame_us, false);
            }
            foreign += !(ch == app_cfg.channels.camera_info || ch == app_cfg.channels.features ||
                         ch == app_cfg.channels.imu);
        } else if (score_only) {  // the recorded outputs; nothing goes to a node
            const bool verdict = ch == g_app.verdict_channel, state = ch == g_app.state_channel;
            if (verdict || state) {
                record_output(&g_app, verdict ? SFD_NODE_OUT_VERDICT : SFD_NODE_OUT_STATE, ev->data,
                              ev->datalen);
            }
            foreign += !(verdict || state);
        } else if (ch == app_cfg.channels.imu) {
            sfd_node_handle(&g_node, SFD_NODE_IMU, ev->data, ev->datalen);
        } else if (ch == app_cfg.channels.camera_info) {
            sfd_node_handle(&g_node, SFD_NODE_CAMERA_INFO, ev->data, ev->datalen);
        } else if (ch == app_cfg.channels.features) {
            const auto t0 = std::chrono::steady_clock::now();
            sfd_node_handle(&g_node, SFD_NODE_FEATURES, ev->data, ev->datalen);
            const auto t1 = std::chrono::steady_clock::now();
            frame_us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
        } else {
            ++foreign;  // other channels (e.g. a previous run's outputs) are copied, not read
        }
        if (progress.enabled()) {
            progress.update(score_only ? events : static_cast<long long>(frame_us.size()),
                            in.size > 0 ? double(in.offset) / double(in.size) : -1.0);
        }
    }
    progress.finish(score_only ? events : static_cast<long long>(frame_us.size()));
    if (read_status != SFD_LOG_END) {  // a bad event (strict), or no good event at all: no output
        std::fprintf(stderr, "sfd-replay: %s\n", in.message);
        if (g_app.out != nullptr) lcm_eventlog_destroy(g_app.out);
        return read_status == SFD_LOG_IO_ERROR || read_status == SFD_LOG_NO_MEMORY ? 1 : 2;
    }
    if (in.bad_events > 0) {
        std::fprintf(stderr, "sfd-replay: %s: --salvage: skipped %lld bad events (%lld bytes)\n",
                     in_path, static_cast<long long>(in.bad_events),
                     static_cast<long long>(in.bytes_skipped));
    }
    if (oracle_poses) {
        oracle.drain(truth, &frame_us, true);
    } else if (!score_only) {
        sfd_node_flush(&g_node);
    }
    const double wall_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    if (g_app.out != nullptr) {
        // liblcm's destroy does not report its flush: flush and check here first.
        if (std::fflush(g_app.out->f) != 0 || std::ferror(g_app.out->f) != 0) {
            g_app.write_failed = true;
        }
        lcm_eventlog_destroy(g_app.out);
        g_app.out = nullptr;
    }
    if (g_app.write_failed) {
        std::fprintf(stderr, "sfd-replay: -o %s: write failed (%s)\n", out_path,
                     std::strerror(errno));
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
    // Detection (sfd_eval.hpp): every feature TRUTH labels counts, whether or not its frame got a
    // verdict; a spurious one left UNTESTED or without a verdict is a miss. TRUTH of real data
    // (sfd-euroc) carries poses and no features: then nothing is scored (null, not zeros).
    sfdeval::DetectionCounts counts;
    sfdeval::FaultEvents fault_events;  // how soon each fault event is caught
    static const std::vector<int64_t> no_ids;
    static const std::vector<int8_t> no_status;
    for (const auto &kv : truth) {  // frames in time order
        const auto v = g_app.verdicts.find(kv.first);
        const bool judged = v != g_app.verdicts.end();
        counts.add_frame(kv.second.ids, kv.second.kinds, judged ? v->second.ids : no_ids,
                         judged ? v->second.status : no_status);
        fault_events.add_frame(kv.second.ids, kv.second.kinds, judged ? v->second.ids : no_ids,
                               judged ? v->second.status : no_status);
    }
    const sfdeval::DetectionScores sc = sfdeval::score(counts);
    // Trajectory: SFD_STATE against TRUTH at the same frame times.
    std::vector<sfdeval::Pose> est, gt;
    for (const auto &kv : g_app.states) {
        const auto it = truth.find(kv.first);
        if (it == truth.end()) continue;
        est.push_back(kv.second);
        gt.push_back(it->second.pose);
    }
    const sfdeval::TrajectoryErrors te = sfdeval::evaluate_trajectory(est, gt);
    const sfdeval::Spread fs = sfdeval::spread_of(frame_us);
    const double log_s = double(last_ts - first_ts) * 1e-6;
    const double speed = wall_s > 0 ? log_s / wall_s : 0.0;
    const char *filter_start = oracle_poses              ? "oracle"
                               : score_only              ? "unknown"
                               : !cfg.nav.enabled        ? "none"
                               : cfg.nav.init_from_truth ? "truth"
                                                         : "rest";
    const sfd_node_counters_t &c = g_node.pipe.counters;

    if (oracle_poses) {
        std::printf(
            "sfd-replay %s: oracle with TRUTH's poses (parity's test, no filter), %lld events, "
            "%ld frames judged, %ld without TRUTH, %ld refused, %ld failed, %ld by the "
            "fallback\n",
            in_path, static_cast<long long>(events), oracle.judged, oracle.unjudged, oracle.refused,
            oracle.failed, oracle.po.fallbacks());
    } else if (score_only) {
        std::printf("sfd-replay %s: scoring the recorded %s and %s, %lld events\n", in_path,
                    g_app.verdict_channel.c_str(), g_app.state_channel.c_str(),
                    static_cast<long long>(events));
    } else {
        std::printf(
            "sfd-replay %s: method %s, filter start %s, %lld events, %lld frames processed "
            "(%lld untested)\n",
            in_path, method_name.c_str(), filter_start, static_cast<long long>(events),
            static_cast<long long>(c.frames_processed), static_cast<long long>(c.frames_untested));
    }
    std::printf("  judged: %ld features tested, %ld spurious (%.2f%%)\n", judged_tested,
                judged_spurious,
                judged_tested ? 100.0 * double(judged_spurious) / double(judged_tested) : 0.0);
    if (truth_bad > 0) std::printf("  %ld TRUTH messages not decodable: not scored\n", truth_bad);
    if (counts.labelled() == 0 && !truth.empty()) {
        std::printf("  TRUTH labels no feature: verdicts not scored\n");
    }
    if (counts.labelled() > 0) {
        std::printf(
            "  detection (strict: untested spurious = miss): precision %.4f  recall %.4f  "
            "F1 %.4f  false-alarm rate %.5f  coverage %.4f\n"
            "    %ld labelled: TP %ld FP %ld TN %ld FN %ld; untested %ld spurious, %ld clean; "
            "tested only: recall %.4f, false-alarm rate %.5f\n",
            sc.precision, sc.recall, sc.f1, sc.false_alarm_rate, sc.coverage, counts.labelled(),
            counts.tp, counts.fp, counts.tn, counts.fn, counts.untested_spurious,
            counts.untested_clean, sc.recall_tested, sc.false_alarm_rate_tested);
        std::printf("    recall by kind:");
        for (int k = sfdeval::kJump; k < sfdeval::kNumKinds; ++k) {
            if (counts.kind_spurious[k] == 0) continue;
            std::printf(" %s %.3f (%ld/%ld, %ld untested)", sfdeval::kind_name(k),
                        sc.kind_recall[k], counts.kind_detected[k], counts.kind_spurious[k],
                        counts.kind_untested[k]);
        }
        static_assert(sfdeval::FaultEvents::kCatchWindows[3] == 10, "window 3 is 10 frames");
        std::printf("\n    events caught within 10 frames:");
        for (int k = sfdeval::kJump; k < sfdeval::kNumKinds; ++k) {
            if (fault_events.events[k] == 0) continue;
            std::printf(" %s %.3f (%ld/%ld)", sfdeval::kind_name(k), fault_events.fraction(k, 3),
                        fault_events.caught[k][3], fault_events.events[k]);
        }
        std::printf("\n");
    }
    if (te.frames > 0) {
        std::printf(
            "  trajectory over %ld frames, %.1f m: ATE %.4f m (position+yaw aligned), raw RMSE "
            "%.4f m, final drift %.4f m (%.2f%%), RPE 1 s %.4f m, 10 m %.4f m (%ld segments)\n",
            te.frames, te.distance_m, te.ate_m, te.rmse_raw_m, te.final_error_m, te.drift_percent,
            te.rpe_1s.rmse_m, te.rpe_10m.rmse_m, te.rpe_10m.segments);
        if (te.nees_frames > 0) {
            std::printf(
                "  position NEES (diagonal variances): mean %.2f (3 if consistent), %.1f%% of "
                "frames inside the 95%% band\n",
                te.nees_mean, 100.0 * te.nees_in_band_95);
        }
    }
    if (!score_only && !oracle_poses) {
        std::printf(
            "  time per frame: median %.1f us, p99 %.1f us, p99.9 %.1f us, max %.1f us; %.1fx real "
            "time\n",
            fs.median, fs.p99, fs.p999, fs.max, speed);
    }
    if (summary_path != nullptr) {
        json rejected = json::object();
        for (int k = 0; k < SFD_REJECT_NUM_REASONS; ++k) {
            rejected[sfd_reject_reason_str(k)] = static_cast<long long>(c.rejected[k]);
        }
        json j;
        j["input"] = in_path;
        j["method"] = oracle_poses ? std::string("parity-oracle")
                      : score_only ? std::string("recorded")
                                   : method_name;
        j["events"] = static_cast<long long>(events);
        j["log"] = json{{"salvage", salvage},
                        {"bad_events", static_cast<long long>(in.bad_events)},
                        {"bytes_skipped", static_cast<long long>(in.bytes_skipped)}};
        j["filter_start"] = filter_start;
        if (oracle_poses) {
            j["oracle"] = json{{"judged", oracle.judged},
                               {"without_truth", oracle.unjudged},
                               {"refused", oracle.refused},
                               {"failed", oracle.failed},
                               {"fallbacks", oracle.po.fallbacks()}};
        }
        if (oracle_poses) {
            j["frames"] =
                json{{"in", oracle.judged + oracle.unjudged + oracle.refused + oracle.failed},
                     {"refused", oracle.refused + oracle.unjudged + oracle.failed},
                     {"processed", oracle.judged},
                     {"untested", oracle.judged_untested}};
        } else {
            j["frames"] = json{{"in", static_cast<long long>(c.frames_in)},
                               {"refused", static_cast<long long>(c.frames_refused)},
                               {"processed", static_cast<long long>(c.frames_processed)},
                               {"untested", static_cast<long long>(c.frames_untested)}};
        }
        j["rejected"] = rejected;
        j["judged"] = json{{"tested", judged_tested}, {"spurious", judged_spurious}};
        j["truth"] =
            json{{"frames", static_cast<long long>(truth.size())}, {"undecodable", truth_bad}};
        j["detection"] =
            counts.labelled() > 0 ? detection_json(counts, fault_events) : json(nullptr);
        j["trajectory"] = te.frames > 0 ? trajectory_json(te) : json(nullptr);
        if (const int rc = write_text(outs.summary,
                                      j.dump(2, ' ', false, json::error_handler_t::replace) + "\n",
                                      "--summary"))
            return rc;
        json t{{"frames", static_cast<long long>(frame_us.size())},
               {"frame_us", spread_json(fs)},
               {"wall_s", wall_s},
               {"log_s", log_s},
               {"speed_vs_real_time", speed}};
        if (const int rc = write_text(outs.timing, t.dump(2) + "\n", "--summary")) return rc;
    }
    // Every output complete: renamed into place together.
    for (sfd_out_t *o : {&outs.log, &outs.summary, &outs.timing}) {
        if (o->active && sfd_out_commit(o, oerr, sizeof oerr) != 0) {
            std::fprintf(stderr, "sfd-replay: %s\n", oerr);
            return 1;
        }
    }
    return 0;
}

}  // namespace

int main(int argc, char **argv) {
    try {
        return run(argc, argv);
    } catch (const std::exception &e) {  // std::bad_alloc from the records of a huge log
        std::fprintf(stderr, "sfd-replay: %s\n", e.what());
    } catch (...) {
        std::fprintf(stderr, "sfd-replay: unexpected failure\n");
    }
    return 1;
}
