// SPDX-License-Identifier: MIT
// sfd-hil: hardware-in-the-loop style timing of a running sfd-node (docs/hil.md). Publishes the
// sensor messages of a log (--log) or of a simulated flight (--sim, library sfd_sim_flight) over
// real LCM at the recorded pace scaled by --rate (0: closed loop, each frame as soon as the
// previous frame's verdict arrived or timed out), receives SFD_VERDICT and SFD_TIMING, matches
// them to the frames by utime, and reports end-to-end latency (CLOCK_MONOTONIC from just before
// the FEATURES publish to the verdict's arrival), the node's own time per frame (SFD_TIMING
// total_us), jitter, deadline misses and lost messages. One CSV row per frame (--csv); a latency
// histogram (--png) drawn by tools/plot_hil.py.
#include <lcm/lcm.h>
#include <spawn.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <condition_variable>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <string>
#include <thread>
#include <unordered_map>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "flight_log.hpp"
#include "sfd_app_config.hpp"
#include "sfd_cli.hpp"
#include "sfd_eval.hpp"
#include "sfd_feature_frame_t.h"
#include "sfd_feature_verdict_t.h"
#include "sfd_hil_paths.h"  // SFD_HIL_PYTHON, SFD_HIL_PLOT_SCRIPT (generated)
#include "sfd_log_reader.h"
#include "sfd_output.h"
#include "sfd_timing_t.h"
#include "sfd/sfd_prng.h"

namespace {

volatile std::sig_atomic_t g_stop = 0;  // 1: first SIGINT/SIGTERM, 2: second
void on_signal(int) {
    g_stop = g_stop + 1 < 2 ? g_stop + 1 : 2;
}

int64_t mono_ns() {
    timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return int64_t(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}
int64_t realtime_us() {
    timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return int64_t(ts.tv_sec) * 1000000LL + ts.tv_nsec / 1000;
}

int64_t get_be64(const uint8_t *p) {
    uint64_t v = 0;
    for (int k = 0; k < 8; ++k) v = (v << 8) | p[k];
    return static_cast<int64_t>(v);
}
void put_be64(uint8_t *p, int64_t x) {
    uint64_t v = static_cast<uint64_t>(x);
    for (int k = 7; k >= 0; --k) {
        p[k] = static_cast<uint8_t>(v & 0xFF);
        v >>= 8;
    }
}

// What --budget-of applies the deadline to, as the report names it (Options::BudgetOf order).
constexpr const char *kBudgetOfNames[] = {"node total_us", "end-to-end", "node processing"};

struct Options {
    std::string log_path;
    std::string sim;
    int frames = 400;
    int features = -1;  // scenario default
    uint64_t seed = 1;
    double random_fraction = 1.0;
    double rate = 1.0;
    long budget_us = 0;                                            // 0: no deadline
    enum BudgetOf { kNode, kE2e, kProcessing } budget_of = kNode;  // kBudgetOfNames
    std::string csv, png, json;
    long timeout_ms = 1000;
    long warmup = 10;
    bool restamp = true;
    // Fault injection on the publisher's side (docs/hil.md "Fault injection"). Frame indexes
    // count the source's FEATURES messages from 0.
    struct Faults {
        double drop = 0.0, dup = 0.0, reorder = 0.0;  // per frame of [from, to]
        long from = 0, to = -1;                       // to < 0: to the end
        long future_frame = -1;                       // this frame stamped kFutureUs ahead
        long restart_frame = -1;  // from this frame on, every message kRestartUs earlier
        long stall_frame = -1;    // the publisher stops stall_ms before this frame
        long stall_ms = 0;
        uint64_t seed = 1;
        bool any() const {
            return drop > 0.0 || dup > 0.0 || reorder > 0.0 || future_frame >= 0 ||
                   restart_frame >= 0 || stall_frame >= 0;
        }
    } faults;
};

constexpr int64_t kFutureUs = 1000LL * 1000000LL;  // a future-stamped frame: +1000 s
constexpr int64_t kRestartUs = 100LL * 1000000LL;  // a restarted publisher: 100 s back

// One FEATURES frame: what was published and what came back.
struct Frame {
    int64_t utime = 0;     // as published (restamped)
    int64_t sched_ns = 0;  // when the pacing meant to publish it (rate > 0)
    int64_t pub_ns = 0;    // CLOCK_MONOTONIC just before lcm_publish
    int64_t verdict_ns = -1;
    int32_t features = 0;
    int32_t verdict_features = -1;
    bool timing = false;
    int32_t ingest_us = 0, parity_us = 0, association_us = 0, update_us = 0, total_us = 0;
    int32_t publish_us = 0;  // of total_us: the node's sends of SFD_VERDICT and SFD_STATE
    int32_t hypotheses = 0;
    int8_t budget_exhausted = 0;
    bool refused = false;  // a fault the node must refuse (reordered, future-stamped, a restarted
                           // stream's first frames): no verdict expected
};

struct Shared {
    std::mutex mu;
    std::condition_variable cv;
    std::vector<Frame> frames;
    std::unordered_map<int64_t, size_t> by_utime;
    long verdicts = 0, timings = 0, unknown_verdicts = 0, unknown_timings = 0, duplicates = 0;
    bool have_first_timing = false;
    int64_t status_reports = 0;       // SFD_TIMING with frame_processed 0
    int64_t last_frames_in = 0;       // the node's FEATURES count in the newest SFD_TIMING
    int64_t last_frames_refused = 0;  // of those, refused
    int64_t first_rejected[SFD_TIMING_T_NUM_REASONS] = {0};
    int64_t last_rejected[SFD_TIMING_T_NUM_REASONS] = {0};
    int32_t first_timing_features = 0;
};

Shared g;

// The published frame a received message names by its utime; nullptr (counted in *unknown) for a
// message that did not decode or names no published frame. Called with g.mu held.
Frame *published_frame(bool decoded, int64_t utime, long *unknown) {
    const auto it = decoded ? g.by_utime.find(utime) : g.by_utime.end();
    if (it == g.by_utime.end()) {
        ++*unknown;
        return nullptr;
    }
    return &g.frames[it->second];
}

void on_verdict(const lcm_recv_buf_t *rbuf, const char *, void *) {
    const int64_t now = mono_ns();
    static sfd_feature_verdict_t v;  // the receive thread's only
    const bool decoded =
        sfd_feature_verdict_t_decode(rbuf->data, 0, static_cast<int>(rbuf->data_size), &v) >= 0;
    std::lock_guard<std::mutex> lk(g.mu);
    Frame *fp = published_frame(decoded, v.utime, &g.unknown_verdicts);
    if (fp == nullptr) return;
    Frame &f = *fp;
    if (f.verdict_ns >= 0) {
        ++g.duplicates;
        return;
    }
    ++g.verdicts;
    f.verdict_ns = now;
    f.verdict_features = v.num_features;
    g.cv.notify_all();
}

void on_timing(const lcm_recv_buf_t *rbuf, const char *, void *) {
    sfd_timing_t t{};
    const bool decoded =
        sfd_timing_t_decode(rbuf->data, 0, static_cast<int>(rbuf->data_size), &t) >= 0;
    std::lock_guard<std::mutex> lk(g.mu);
    if (decoded && t.frame_processed == 0) {
        // a status report while the node judges no frame: counters only, no frame's timing
        ++g.status_reports;
        g.last_frames_in = std::max(g.last_frames_in, t.frames_in);
        g.last_frames_refused = std::max(g.last_frames_refused, t.frames_refused);
        if (!g.have_first_timing) {
            g.have_first_timing = true;
            std::memcpy(g.first_rejected, t.rejected, sizeof g.first_rejected);
        }
        std::memcpy(g.last_rejected, t.rejected, sizeof g.last_rejected);
        return;
    }
    Frame *fp = published_frame(decoded, t.utime, &g.unknown_timings);
    if (fp == nullptr) return;
    Frame &f = *fp;
    if (f.timing) return;
    ++g.timings;
    f.timing = true;
    f.ingest_us = t.ingest_us;
    f.parity_us = t.parity_us;
    f.association_us = t.association_us;
    f.update_us = t.update_us;
    f.total_us = t.total_us;
    f.publish_us = t.publish_us;
    f.hypotheses = t.hypotheses_used;
    f.budget_exhausted = t.budget_exhausted;
    if (!g.have_first_timing) {
        g.have_first_timing = true;
        std::memcpy(g.first_rejected, t.rejected, sizeof g.first_rejected);
    }
    std::memcpy(g.last_rejected, t.rejected, sizeof g.last_rejected);
    g.last_frames_in = std::max(g.last_frames_in, t.frames_in);
    g.last_frames_refused = std::max(g.last_frames_refused, t.frames_refused);
    g.cv.notify_all();
}

// Publishes the sensor messages over LCM: pacing, restamping, closed loop.
class Publisher : public sfdsim::FlightSink {
  public:
    /// `total`: the source's events (--log) or frames (--sim), for the progress line.
    Publisher(lcm_t *lcm, const sfdapp::Channels &ch, const Options &opt, double total)
        : lcm_(lcm), ch_(ch), opt_(opt), total_(total) {}

    bool message(const char *channel, int64_t utime, const uint8_t *data, int size) override {
        if (g_stop) return false;
        ++events_;
        if (progress_.enabled()) {
            const double done = opt_.sim.empty() ? double(events_) : double(frame_index_);
            progress_.update(frame_index_, total_ > 0 ? done / total_ : -1.0);
        }
        const std::string *out = channel_of(channel);
        if (out == nullptr || size < 0) return true;  // not a sensor channel: not published
        buf_.assign(data, data + size);
        const bool features = out == &ch_.features;
        int32_t n_feat = 0;
        int64_t frame_utime = 0;
        if (features) {
            if (sfd_feature_frame_t_decode(buf_.data(), 0, size, &ff_) != size) {
                ++malformed_;
                return true;
            }
            n_feat = ff_.num_features;
            frame_utime = ff_.utime;
        }
        if (!started_) {
            started_ = true;
            t0_event_us_ = utime;
            t0_ns_ = mono_ns();
            offset_us_ = opt_.restamp && size >= 16 ? realtime_us() - get_be64(buf_.data() + 8) : 0;
        }
        const Options::Faults &fa = opt_.faults;
        const long k = features ? frame_index_++ : -1;
        if (features && k == fa.restart_frame) {
            shift_us_ -= kRestartUs;  // this frame and every message after it
            restart_left_ = resync_messages_ - 1;
            ++restarts_;
        }
        if (size >= 16 && (opt_.restamp || shift_us_ != 0)) {
            const int64_t add = (opt_.restamp ? offset_us_ : 0) + shift_us_;
            put_be64(buf_.data() + 8, get_be64(buf_.data() + 8) + add);
            frame_utime += add;
        }
        bool refused = false;
        if (features && k == fa.future_frame) {
            put_be64(buf_.data() + 8, get_be64(buf_.data() + 8) + kFutureUs);
            frame_utime += kFutureUs;
            refused = true;
            ++future_;
        }
        if (features && restart_left_ > 0) {  // a restarted stream's first N - 1 frames
            refused = true;
            --restart_left_;
        }
        int64_t sched = 0;
        if (opt_.rate > 0.0) {
            sched =
                t0_ns_ + static_cast<int64_t>(double(utime - t0_event_us_) * 1000.0 / opt_.rate);
            timespec ts;
            ts.tv_sec = static_cast<time_t>(sched / 1000000000LL);
            ts.tv_nsec = static_cast<long>(sched % 1000000000LL);
            while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
                if (g_stop) return false;
            }
        }
        if (features && k == fa.stall_frame && fa.stall_ms > 0) {
            // the publisher goes silent, then carries on at its pace from where it stopped (no
            // burst of the backlog): the node sees every message, stall_ms late
            std::this_thread::sleep_for(std::chrono::milliseconds(fa.stall_ms));
            t0_ns_ += fa.stall_ms * 1000000LL;
            ++stalls_;
        }
        // drop / duplicate / reorder: one draw per frame inside the window, none while a
        // reordered frame is held (it goes out after the next frame published)
        enum { kPass, kDrop, kDup, kHold } act = kPass;
        const bool in_window = features && k >= fa.from && (fa.to < 0 || k <= fa.to);
        if (in_window && (fa.drop > 0.0 || fa.dup > 0.0 || fa.reorder > 0.0)) {
            const double u = sfd_prng_uniform(&rng_);
            if (held_.empty()) {
                act = u < fa.drop                         ? kDrop
                      : u < fa.drop + fa.dup              ? kDup
                      : u < fa.drop + fa.dup + fa.reorder ? kHold
                                                          : kPass;
            } else if (u < fa.drop) {
                act = kDrop;
            }
        }
        if (act == kDrop) {
            ++dropped_;
            return !g_stop;
        }
        if (act == kHold) {
            held_ = buf_;
            held_utime_ = frame_utime;
            held_features_ = n_feat;
            held_sched_ = sched;
            ++reordered_;
            return !g_stop;
        }
        const size_t index = features ? record(frame_utime, sched, n_feat, refused) : 0;
        publish(*out, buf_);
        if (act == kDup) {
            publish(*out, buf_);  // the second copy: refused as out of order, no record
            ++duplicated_;
        }
        if (features && !held_.empty()) {  // the reordered frame, after the one that followed it
            record(held_utime_, held_sched_, held_features_, true);
            publish(*out, held_);
            held_.clear();
        }
        if (features && opt_.rate <= 0.0) {
            // Closed loop: the next frame waits for this frame's verdict (or the timeout).
            std::unique_lock<std::mutex> lk(g.mu);
            const int64_t deadline = g.frames[index].pub_ns + opt_.timeout_ms * 1000000LL;
            while (g.frames[index].verdict_ns < 0 && !g_stop) {
                const int64_t left = deadline - mono_ns();
                if (left <= 0) break;
                g.cv.wait_for(lk, std::chrono::nanoseconds(std::min<int64_t>(left, 50000000)));
            }
        }
        return !g_stop;
    }

    /// The node's resync count (time_resync_messages of its config): a restarted stream's first
    /// N - 1 frames are refused.
    void set_resync_messages(int n) { resync_messages_ = n; }
    long dropped() const { return dropped_; }
    long duplicated() const { return duplicated_; }
    long reordered() const { return reordered_; }
    long future() const { return future_; }
    long restarts() const { return restarts_; }
    long stalls() const { return stalls_; }
    long frame_copies() const { return frame_copies_; }

    long published() const { return published_; }
    /// Ends the progress line (terminal only).
    void finish_progress() { progress_.finish(frame_index_); }
    long malformed() const { return malformed_; }
    long publish_failures() const { return publish_failures_; }

  private:
    size_t record(int64_t frame_utime, int64_t sched, int32_t n_feat, bool refused) {
        std::lock_guard<std::mutex> lk(g.mu);
        const size_t index = g.frames.size();
        Frame f;
        f.utime = frame_utime;
        f.sched_ns = sched;
        f.features = n_feat;
        f.refused = refused;
        g.frames.push_back(f);
        g.by_utime.emplace(frame_utime, index);  // a repeated utime keeps the first frame
        g.frames[index].pub_ns = mono_ns();
        return index;
    }

    void publish(const std::string &channel, const std::vector<uint8_t> &msg) {
        if (lcm_publish(lcm_, channel.c_str(), msg.data(), static_cast<unsigned int>(msg.size())) !=
            0) {
            ++publish_failures_;
        }
        ++published_;
        if (&channel == &ch_.features) ++frame_copies_;
    }

    // The configured channel of a sensor message given by its default or configured name.
    const std::string *channel_of(const char *c) const {
        if (!std::strcmp(c, "IMU") || ch_.imu == c) return &ch_.imu;
        if (!std::strcmp(c, "CAMERA_INFO") || ch_.camera_info == c) return &ch_.camera_info;
        if (!std::strcmp(c, "FEATURES") || ch_.features == c) return &ch_.features;
        if (!std::strcmp(c, "TRUTH") || ch_.truth == c) return &ch_.truth;
        return nullptr;
    }

    lcm_t *lcm_;
    const sfdapp::Channels &ch_;
    const Options &opt_;
    double total_;
    long events_ = 0;
    sfdcli::Progress progress_{"sfd-hil", "frames"};
    std::vector<uint8_t> buf_;
    sfd_feature_frame_t ff_{};
    bool started_ = false;
    int64_t t0_event_us_ = 0, t0_ns_ = 0, offset_us_ = 0;
    long published_ = 0, malformed_ = 0, publish_failures_ = 0;
    // fault injection
    sfd_prng_t rng_ = make_rng(opt_.faults.seed);
    long frame_index_ = 0;
    int64_t shift_us_ = 0;
    int resync_messages_ = 5;
    int restart_left_ = 0;
    std::vector<uint8_t> held_;
    int64_t held_utime_ = 0, held_sched_ = 0;
    int32_t held_features_ = 0;
    long dropped_ = 0, duplicated_ = 0, reordered_ = 0, future_ = 0, restarts_ = 0, stalls_ = 0;
    long frame_copies_ = 0;

    static sfd_prng_t make_rng(uint64_t seed) {
        sfd_prng_t r;
        sfd_prng_seed(&r, seed);
        return r;
    }
};

// Plays an LCM log through the one bounded reader of the tools (sfd_log_reader.h: lengths checked
// against the file size, so that no input file can crash the tool); events go to the sink in file
// order. Returns 0, or 2 with the reader's one-line reason (the file and the bad event's offset).
// With `sink` null it only checks the whole log (before anything is published).
int play_log(const std::string &path, sfdsim::FlightSink *sink, long *events, std::string *err) {
    static sfd_log_reader_t r;  // ~3 KiB of buffers: static
    sfd_log_event_t ev;
    sfd_log_status_t st = sfd_log_open(&r, path.c_str(), 0);
    *events = 0;
    while (st == SFD_LOG_OK && (st = sfd_log_next(&r, &ev)) == SFD_LOG_OK) {
        ++*events;
        if (sink != nullptr && !sink->message(ev.channel, ev.timestamp, ev.data, ev.datalen)) {
            st = SFD_LOG_END;
        }
    }
    const int rc = st == SFD_LOG_END ? 0 : 2;
    if (rc != 0) *err = r.message;
    sfd_log_close(&r);
    return rc;
}

// Latency statistics by the one rule of every sfd tool (sfd_eval.hpp: nearest-rank percentiles,
// sample standard deviation).
using Stats = sfdeval::Spread;
Stats stats_of(std::vector<double> v) {
    return sfdeval::spread_of(std::move(v));
}

// tools/plot_hil.py: $SFD_PLOT_HIL, else next to an installed sfd-hil (PREFIX/share/sfd), else
// the source tree's. The interpreter: $SFD_PYTHON, else the project's venv, else python3.
int run_plot(const std::string &csv, const std::string &png) {
    const char *py = std::getenv("SFD_PYTHON");
    const char *script = std::getenv("SFD_PLOT_HIL");
    std::string p = py && *py ? py : SFD_HIL_PYTHON;
    if (!(py && *py) && access(p.c_str(), X_OK) != 0) p = "python3";
    std::string s = SFD_HIL_PLOT_SCRIPT;
    char exe[4096];
    const ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (n > 0) {
        exe[n] = '\0';
        std::string dir(exe);
        dir.resize(dir.rfind('/'));
        const std::string installed = dir + "/../share/sfd/plot_hil.py";
        if (access(installed.c_str(), R_OK) == 0) s = installed;
    }
    if (script && *script) s = script;
    std::vector<std::string> args = {p, s, csv, png};
    std::vector<char *> argv;
    argv.reserve(args.size() + 1);
    for (std::string &a : args) argv.push_back(&a[0]);
    argv.push_back(nullptr);
    pid_t pid = 0;
    if (posix_spawnp(&pid, p.c_str(), nullptr, nullptr, argv.data(), environ) != 0) {
        std::fprintf(stderr, "sfd-hil: --png: cannot run %s\n", p.c_str());
        return 1;
    }
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        std::fprintf(stderr, "sfd-hil: --png: %s %s failed\n", p.c_str(), s.c_str());
        return 1;
    }
    return 0;
}

int run(int argc, char **argv) {
    Options opt;
    sfdapp::AppConfig cfg;
    std::string err, config_path, lcm_url;
    sfdcli::Parser cli(
        "sfd-hil", "sfd-hil",
        "(--log IN.lcmlog | --sim SCENARIO [--frames N] [--features N] [--seed N]\n"
        "               [--random-fraction F]) [--config F] [--rate R] [--budget-us N]\n"
        "               [--budget-of node|processing|e2e] [--lcm-url URL] [--csv OUT.csv]\n"
        "               [--png OUT.png] [--json OUT.json] [--timeout-ms N] [--warmup N]\n"
        "               [--no-restamp] [fault options]",
        "  Publishes IMU, CAMERA_INFO, FEATURES and TRUTH to a running sfd-node over LCM,\n"
        "  receives SFD_VERDICT and SFD_TIMING, and reports latency, jitter, deadline misses\n"
        "  and lost messages (docs/hil.md). On a terminal (and CI unset), a progress line on\n"
        "  stderr.");
    const auto text_opt = [](std::string *dst) -> sfdcli::Setter {
        return [dst](const std::string &v, std::string *) {
            *dst = v;
            return true;
        };
    };
    long frames = opt.frames, features = opt.features, seed = 1, fault_seed = 1;
    cli.section("Source");
    cli.value("log", "F", "sensor messages from an LCM log (other channels are skipped)",
              text_opt(&opt.log_path));
    cli.value("sim", "S",
              "a simulated flight generated on the fly: paper-uav, mistracking,\n"
              "moving-object, worst-case (sfd-sim --help)",
              text_opt(&opt.sim));
    cli.value("frames", "N", "--sim: camera frames at 20 Hz (400)",
              sfdcli::int_setter(&frames, 1, 1000000));
    cli.value(
        "features", "N",
        "--sim: features per frame (200; worst-case " + std::to_string(SFD_MAX_FEATURES) + ")",
        sfdcli::int_setter(&features, 1, SFD_MAX_FEATURES));
    cli.value("seed", "N", "--sim: seed (1)", sfdcli::int_setter(&seed, 0, 2147483647LL));
    cli.value("random-fraction", "F", "--sim worst-case: features replaced by random pixels (1.0)",
              sfdcli::real_setter(&opt.random_fraction, 0.0, 1.0));
    cli.section("Node and pacing");
    cli.value("config", "F", "YAML configuration of the node (channels.*, lcm_url)",
              text_opt(&config_path));
    cli.value("lcm-url", "URL",
              "LCM provider (default: the config's, udpm://239.255.76.67:7667?ttl=0)",
              text_opt(&lcm_url));
    cli.value("rate", "R",
              "pace: R x the recorded pace (1.0); 0 = closed loop, each frame\n"
              "published as soon as the previous verdict arrived or timed out",
              sfdcli::real_setter(&opt.rate, 0.0, 1000.0));
    cli.value("budget-us", "N", "deadline per frame in us (none by default)",
              sfdcli::int_setter(&opt.budget_us, 1, 100000000));
    cli.value("budget-of", "W",
              "node: SFD_TIMING total_us (default); processing: total_us -\n"
              "publish_us (the node without its sends); e2e: end-to-end",
              [&opt](const std::string &w, std::string *why) {
                  if (w != "e2e" && w != "node" && w != "processing") {
                      *why = "is not one of node, processing, e2e";
                      return false;
                  }
                  opt.budget_of = w == "e2e"    ? Options::kE2e
                                  : w == "node" ? Options::kNode
                                                : Options::kProcessing;
                  return true;
              });
    cli.value("timeout-ms", "N",
              "a frame without verdict this long after its publish is lost (1000)",
              sfdcli::int_setter(&opt.timeout_ms, 1, 600000));
    cli.value("warmup", "N", "first N frames left out of the latency figures (10)",
              sfdcli::int_setter(&opt.warmup, 0, 10000000));
    cli.flag("no-restamp",
             "publish the recorded utimes (default: shifted so that the first\n"
             "message is at the wall-clock time now, so a running node accepts\n"
             "repeated runs)",
             [&opt] { opt.restamp = false; });
    cli.section("Outputs");
    cli.value("csv", "F", "one row per frame", text_opt(&opt.csv));
    cli.value("png", "F",
              "latency histogram (runs tools/plot_hil.py; $SFD_PYTHON and\n"
              "$SFD_PLOT_HIL override the interpreter and the script); needs --csv",
              text_opt(&opt.png));
    cli.value("json", "F",
              "the report as JSON (the figures of the printed tables: counts,\n"
              "losses, latency percentiles and max, misses, node counters)",
              text_opt(&opt.json));
    cli.section("Fault injection (docs/hil.md; frame indexes count the source's frames from 0)");
    cli.value("fault-drop", "P", "drop a frame with probability P (in --fault-frames)",
              sfdcli::real_setter(&opt.faults.drop, 0.0, 1.0));
    cli.value("fault-dup", "P", "publish a frame twice with probability P",
              sfdcli::real_setter(&opt.faults.dup, 0.0, 1.0));
    cli.value("fault-reorder", "P", "publish a frame after the next one with probability P",
              sfdcli::real_setter(&opt.faults.reorder, 0.0, 1.0));
    cli.value("fault-frames", "A:B", "the frames the three above apply to (all)",
              [&opt](const std::string &r, std::string *why) {
                  const size_t c = r.find(':');
                  long long lo = 0, hi = 0;
                  if (c == std::string::npos ||
                      !sfdcli::parse_int(r.substr(0, c), 0, 100000000, &lo, why) ||
                      !sfdcli::parse_int(r.substr(c + 1), lo, 100000000, &hi, why)) {
                      *why = "is not A:B with 0 <= A <= B <= 100000000";
                      return false;
                  }
                  opt.faults.from = static_cast<long>(lo);
                  opt.faults.to = static_cast<long>(hi);
                  return true;
              });
    cli.value("fault-future-frame", "N", "stamp frame N 1000 s in the future",
              sfdcli::int_setter(&opt.faults.future_frame, 0, 100000000));
    cli.value("fault-restart-frame", "N",
              "from frame N on, stamp every message 100 s earlier (a\n"
              "restarted publisher; the node's first N - 1 are refused)",
              sfdcli::int_setter(&opt.faults.restart_frame, 0, 100000000));
    cli.value("fault-stall-frame", "N",
              "stop publishing --fault-stall-ms before frame N, then go\n"
              "on at the pace from there (every message late, none lost)",
              sfdcli::int_setter(&opt.faults.stall_frame, 0, 100000000));
    cli.value("fault-stall-ms", "MS", "(1000)",
              sfdcli::int_setter(&opt.faults.stall_ms, 1, 600000));
    cli.value("fault-seed", "N", "seed of the fault draws (1)",
              sfdcli::int_setter(&fault_seed, 0, 2147483647LL));
    cli.epilog(
        "SIGINT/SIGTERM: stop publishing, wait up to --timeout-ms for outstanding verdicts (a\n"
        "second signal: at once), report what was measured.\n"
        "Exit: 0 ok; 2 bad usage or input; 3 a frame missed the budget or messages were lost;\n"
        "1 internal failure.");
    std::vector<std::string> positional;
    if (const int rc = cli.parse(argc, argv, &positional); rc >= 0) return rc;
    if (!positional.empty()) return cli.fail("unexpected argument " + positional[0]);
    opt.frames = static_cast<int>(frames);
    opt.features = static_cast<int>(features);
    opt.seed = static_cast<uint64_t>(seed);
    opt.faults.seed = static_cast<uint64_t>(fault_seed);
    if (opt.faults.stall_frame >= 0 && opt.faults.stall_ms == 0) opt.faults.stall_ms = 1000;
    if (opt.faults.drop + opt.faults.dup + opt.faults.reorder > 1.0) {
        std::fprintf(stderr, "sfd-hil: --fault-drop + --fault-dup + --fault-reorder exceed 1\n");
        return 2;
    }
    if (opt.log_path.empty() == opt.sim.empty()) {
        std::fprintf(stderr, "sfd-hil: give exactly one of --log IN.lcmlog and --sim SCENARIO\n");
        return 2;
    }
    if (!opt.sim.empty() && !sfdsim::is_flight_scenario(opt.sim)) {
        std::fprintf(stderr,
                     "sfd-hil: --sim: unknown scenario %s (paper-uav, mistracking, "
                     "moving-object, worst-case)\n",
                     opt.sim.c_str());
        return 2;
    }
    if (!config_path.empty() && !sfdapp::load_config(config_path, &cfg, &err)) {
        std::fprintf(stderr, "sfd-hil: %s\n", err.c_str());
        return 2;
    }
    if (!lcm_url.empty()) cfg.lcm_url = lcm_url;
    // No output (--csv, --png, --json) may be an input (--log, --config) or another output.
    const std::pair<const char *, std::string> ins[2] = {{"--log", opt.log_path},
                                                         {"--config", config_path}};
    const std::pair<const char *, std::string> outs[3] = {
        {"--csv", opt.csv}, {"--png", opt.png}, {"--json", opt.json}};
    for (const auto &o : outs) {
        for (const auto &in : ins) {
            if (o.second.empty() || in.second.empty()) continue;
            if (sfd_same_file(o.second.c_str(), in.second.c_str())) {
                std::fprintf(stderr,
                             "sfd-hil: %s %s is the input %s %s (same file): an output may not "
                             "overwrite an input\n",
                             o.first, o.second.c_str(), in.first, in.second.c_str());
                return 2;
            }
        }
    }
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < i; ++j) {
            if (!outs[i].second.empty() && !outs[j].second.empty() &&
                sfd_same_file(outs[i].second.c_str(), outs[j].second.c_str())) {
                std::fprintf(stderr, "sfd-hil: %s %s and %s %s are the same file\n", outs[j].first,
                             outs[j].second.c_str(), outs[i].first, outs[i].second.c_str());
                return 2;
            }
        }
    }
    if (!opt.png.empty() && opt.csv.empty()) {
        std::fprintf(stderr, "sfd-hil: --png needs --csv (the plot reads the CSV)\n");
        return 2;
    }
    long log_events = 0;          // the log's events (progress: fraction published)
    if (!opt.log_path.empty()) {  // the whole log is checked before anything is published
        if (play_log(opt.log_path, nullptr, &log_events, &err) != 0) {
            std::fprintf(stderr, "sfd-hil: --log: %s\n", err.c_str());
            return 2;
        }
    }
    // --csv: written to a temporary file next to it, renamed into place when complete.
    struct CsvOut {
        sfd_out_t out{};
        ~CsvOut() { sfd_out_discard(&out); }
    } csv_out;
    FILE *csv = nullptr;
    if (!opt.csv.empty()) {
        char oerr[8192];
        if (sfd_out_begin(&csv_out.out, opt.csv.c_str(), oerr, sizeof oerr) != 0) {
            std::fprintf(stderr, "sfd-hil: --csv %s\n", oerr);
            return 1;
        }
        csv = std::fopen(csv_out.out.write_path, "w");
        if (csv == nullptr) {
            std::fprintf(stderr, "sfd-hil: --csv %s: cannot open for writing (%s)\n",
                         opt.csv.c_str(), std::strerror(errno));
            return 1;
        }
    }
    // --json: the report, renamed into place when complete (as --csv).
    struct JsonOut {
        sfd_out_t out{};
        ~JsonOut() { sfd_out_discard(&out); }
    } json_out;
    if (!opt.json.empty()) {
        char oerr[8192];
        if (sfd_out_begin(&json_out.out, opt.json.c_str(), oerr, sizeof oerr) != 0) {
            std::fprintf(stderr, "sfd-hil: --json %s\n", oerr);
            if (csv != nullptr) std::fclose(csv);
            return 1;
        }
    }
    lcm_t *tx = lcm_create(cfg.lcm_url.c_str());
    lcm_t *rx = tx != nullptr ? lcm_create(cfg.lcm_url.c_str()) : nullptr;
    if (tx == nullptr || rx == nullptr) {
        std::fprintf(stderr, "sfd-hil: --lcm-url %s: cannot create the LCM instance\n",
                     cfg.lcm_url.c_str());
        if (tx != nullptr) lcm_destroy(tx);
        if (csv != nullptr) std::fclose(csv);
        return 2;
    }
    lcm_subscribe(rx, cfg.channels.verdict.c_str(), on_verdict, nullptr);
    lcm_subscribe(rx, cfg.channels.timing.c_str(), on_timing, nullptr);
    if (opt.frames > 0 && !opt.sim.empty()) g.frames.reserve(static_cast<size_t>(opt.frames));
    std::atomic<bool> rx_done(false);
    std::thread receiver([&] {
        while (!rx_done.load()) {
            if (lcm_handle_timeout(rx, 20) < 0) break;
        }
    });
    struct sigaction sa;
    std::memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, nullptr);
    sigaction(SIGTERM, &sa, nullptr);
    // Let the receive socket join the group before the first frame.
    std::this_thread::sleep_for(std::chrono::milliseconds(100));

    std::string source;
    char line[256];
    if (!opt.sim.empty()) {
        std::snprintf(line, sizeof line, "sim %s, %d frames, seed %llu", opt.sim.c_str(),
                      opt.frames, static_cast<unsigned long long>(opt.seed));
        source = line;
    } else {
        source = "log " + opt.log_path;
    }
    char rate[64];
    if (opt.rate > 0) {
        std::snprintf(rate, sizeof rate, "%g", opt.rate);
    } else {
        std::snprintf(rate, sizeof rate, "0 (closed loop)");
    }
    std::printf("sfd-hil: %s -> %s, rate %s, lcm %s\n", source.c_str(),
                cfg.channels.features.c_str(), rate, cfg.lcm_url.c_str());
    std::fflush(stdout);

    Publisher pub(tx, cfg.channels, opt,
                  opt.sim.empty() ? static_cast<double>(log_events) : double(opt.frames));
    pub.set_resync_messages(cfg.node.time.resync_messages);
    int input_rc = 0;
    long events = 0;
    sfdsim::FlightStats fst;
    if (!opt.sim.empty()) {
        sfdsim::FlightOptions fo;
        fo.scenario = opt.sim;
        fo.seed = opt.seed;
        fo.frames = opt.frames;
        fo.features = opt.features;  // <= 0: the scenario's default
        fo.random_fraction = opt.random_fraction;
        if (sfdsim::generate_flight(fo, pub, &fst) != 0) input_rc = 1;
    } else {
        input_rc = play_log(opt.log_path, &pub, &events, &err);
        if (input_rc != 0) std::fprintf(stderr, "sfd-hil: --log: %s\n", err.c_str());
    }
    pub.finish_progress();
    // Outstanding verdicts and timings: until every frame has both, or the last publish is
    // --timeout-ms old; a second signal ends the wait.
    {
        std::unique_lock<std::mutex> lk(g.mu);
        const int64_t last_pub = g.frames.empty() ? mono_ns() : g.frames.back().pub_ns;
        const int64_t deadline = last_pub + opt.timeout_ms * 1000000LL;
        while (g_stop < 2) {
            bool all = true;
            for (const Frame &f : g.frames) all = all && f.verdict_ns >= 0 && f.timing;
            const int64_t left = deadline - mono_ns();
            if (all || left <= 0) break;
            g.cv.wait_for(lk, std::chrono::nanoseconds(std::min<int64_t>(left, 50000000)));
        }
    }
    rx_done.store(true);
    receiver.join();
    lcm_destroy(rx);
    lcm_destroy(tx);

    std::lock_guard<std::mutex> lk(g.mu);
    const std::vector<Frame> &fr = g.frames;
    const int64_t timeout_ns = opt.timeout_ms * 1000000LL;
    long no_verdict = 0, late = 0, measured = 0, misses = 0, exhausted = 0, timed = 0;
    long refused_judged = 0;
    long hyp_max = 0;
    double hyp_sum = 0;
    std::vector<double> e2e, node, processing, publishing, lateness, period_err;
    for (size_t i = 0; i < fr.size(); ++i) {
        const Frame &f = fr[i];
        const bool got = f.verdict_ns >= 0;
        const bool in_time = got && f.verdict_ns - f.pub_ns <= timeout_ns;
        if (f.refused) {  // a fault the node must refuse: a verdict for it is the anomaly
            if (got) ++refused_judged;
            continue;
        }
        if (!got) ++no_verdict;
        if (got && !in_time) ++late;
        if (opt.rate > 0) {
            lateness.push_back(double(f.pub_ns - f.sched_ns) / 1000.0);
            if (i > 0) {
                period_err.push_back(
                    double((f.pub_ns - fr[i - 1].pub_ns) - (f.sched_ns - fr[i - 1].sched_ns)) /
                    1000.0);
            }
        }
        if (long(i) < opt.warmup || !in_time) continue;
        ++measured;
        const double e = double(f.verdict_ns - f.pub_ns) / 1000.0;
        e2e.push_back(e);
        if (f.timing) {
            ++timed;
            node.push_back(double(f.total_us));
            processing.push_back(double(f.total_us - f.publish_us));
            publishing.push_back(double(f.publish_us));
            exhausted += f.budget_exhausted ? 1 : 0;
            hyp_sum += f.hypotheses;
            hyp_max = std::max<long>(hyp_max, f.hypotheses);
        }
        if (opt.budget_us > 0) {
            const double x = opt.budget_of == Options::kE2e    ? e
                             : !f.timing                       ? 0.0
                             : opt.budget_of == Options::kNode ? double(f.total_us)
                                                               : double(f.total_us - f.publish_us);
            if (x > double(opt.budget_us)) ++misses;
        }
    }
    // Node-side drops during the run (SFD_TIMING rejected[], last minus first received): inputs
    // the node discarded, IMU_OVERFLOW included (IMU samples overwritten in the node's ring
    // before a frame could use them; the ring wrapping over consumed samples is not counted).
    // DEPTH (a missing depth prior replaced), IMU_GAP / IMU_LATE (frames judged UNTESTED),
    // CORE, RESTART, the FEATURE_* counts (features kept) and FRAME_GAP (frames the node never
    // received: counted above as frames without verdict) are shown but are not message losses.
    long node_drops = 0;
    std::string rej_line;
    for (int k = 0; k < SFD_TIMING_T_NUM_REASONS; ++k) {
        const int64_t d = g.last_rejected[k] - g.first_rejected[k];
        const bool loss =
            k == SFD_TIMING_T_REJECT_DECODE || k == SFD_TIMING_T_REJECT_COUNT ||
            k == SFD_TIMING_T_REJECT_NONFINITE || k == SFD_TIMING_T_REJECT_ORDER ||
            k == SFD_TIMING_T_REJECT_CAMERA_ID || k == SFD_TIMING_T_REJECT_NO_CAMERA_INFO ||
            k == SFD_TIMING_T_REJECT_IMU_OVERFLOW || k == SFD_TIMING_T_REJECT_CAPACITY ||
            k == SFD_TIMING_T_REJECT_TIME_JUMP || k == SFD_TIMING_T_REJECT_CALIB_INTRINSICS ||
            k == SFD_TIMING_T_REJECT_CALIB_DISTORTION || k == SFD_TIMING_T_REJECT_CALIB_EXTRINSICS;
        if (loss) node_drops += d;
        if (d != 0 || g.last_rejected[k] != 0) {
            rej_line += std::string(" ") + sfd_reject_reason_str(k) + "=" + std::to_string(d) +
                        "(" + std::to_string(g.last_rejected[k]) + ")";
        }
    }
    // Injected faults the node must refuse, and whether every frame is accounted for (counters
    // since the node started: a fresh node per run).
    const long restart_refusals = pub.restarts() * (cfg.node.time.resync_messages - 1);
    const long expected_drops =
        pub.duplicated() + pub.reordered() + pub.future() + 2 * restart_refusals;
    const long unexplained_drops = node_drops - expected_drops;
    const long frame_refusals = static_cast<long>(g.last_frames_refused);
    const long judged = g.verdicts + g.unknown_verdicts;
    const long received = static_cast<long>(g.last_frames_in);
    const bool accounted = received == judged + frame_refusals;
    const long lost = no_verdict + late + g.unknown_verdicts + std::labs(unexplained_drops) +
                      refused_judged + (opt.faults.any() && !accounted ? 1 : 0);
    const Stats se = stats_of(e2e), sn = stats_of(node), sl = stats_of(lateness),
                sp = stats_of(period_err), sc = stats_of(processing), sb = stats_of(publishing);

    std::printf("\n| sfd-hil | %s, rate %s, timeout %ld ms, warm-up %ld |\n", source.c_str(), rate,
                opt.timeout_ms, opt.warmup);
    std::printf("| --- | --- |\n");
    std::printf("| frames published | %zu (%ld messages) |\n", fr.size(), pub.published());
    std::printf("| verdicts received | %ld |\n", g.verdicts);
    std::printf("| timing received | %ld (and %ld status reports: no frame judged) |\n", g.timings,
                static_cast<long>(g.status_reports));
    std::printf("| lost: frames without verdict within %ld ms | %ld (%ld late) |\n", opt.timeout_ms,
                no_verdict + late, late);
    std::printf("| lost: verdicts for unknown frames | %ld |\n", g.unknown_verdicts);
    if (opt.faults.any()) {
        std::printf(
            "| faults injected | dropped %ld, duplicated %ld, reordered %ld, future-stamped %ld, "
            "restarts %ld (100 s back), stalls %ld (%ld ms) |\n",
            pub.dropped(), pub.duplicated(), pub.reordered(), pub.future(), pub.restarts(),
            pub.stalls(), opt.faults.stall_ms);
        std::printf(
            "| frames: copies published / received by the node / judged / refused by the node / "
            "lost on the transport | %ld / %ld / %ld / %ld / %ld |\n",
            pub.frame_copies(), received, judged, frame_refusals, pub.frame_copies() - received);
        std::printf("| every frame received accounted for (judged + refused) | %s |\n",
                    accounted ? "yes" : "NO");
        std::printf("| refused frames the node judged anyway | %ld |\n", refused_judged);
        std::printf("| node-side drops expected from the faults | %ld |\n", expected_drops);
    }
    std::printf("| lost: node-side drops (SFD_TIMING rejected[]) | %ld |\n",
                opt.faults.any() ? unexplained_drops : node_drops);
    std::printf("| node rejected[] during run (since node start) |%s |\n",
                rej_line.empty() ? " none" : rej_line.c_str());
    if (pub.malformed() > 0 || pub.publish_failures() > 0) {
        std::printf("| input FEATURES skipped (malformed) / publish failures | %ld / %ld |\n",
                    pub.malformed(), pub.publish_failures());
    }
    std::printf("| frames measured (after warm-up, verdict in time) | %ld (%ld with timing) |\n",
                measured, timed);
    std::printf("\n| latency (us) | min | median | p99 | p99.9 | max | mean | std |\n");
    std::printf("| --- | --- | --- | --- | --- | --- | --- | --- |\n");
    auto row = [](const char *name, const Stats &s) {
        if (s.n == 0) {
            std::printf("| %s | - | - | - | - | - | - | - |\n", name);
        } else {
            std::printf("| %s | %.0f | %.0f | %.0f | %.0f | %.0f | %.1f | %.1f |\n", name, s.min,
                        s.median, s.p99, s.p999, s.max, s.mean, s.sd);
        }
    };
    row("end-to-end", se);
    row("node total_us", sn);
    row("node processing (total_us - publish_us)", sc);
    row("node publish_us (sends of SFD_VERDICT, SFD_STATE)", sb);
    std::printf("\n| jitter | value |\n| --- | --- |\n");
    std::printf("| end-to-end: std / p99 - median | %.1f / %.0f us |\n", se.sd, se.p99 - se.median);
    if (opt.rate > 0) {
        std::printf("| pacing: publish lateness median / p99 / max | %.0f / %.0f / %.0f us |\n",
                    sl.median, sl.p99, sl.max);
        std::printf("| pacing: frame period error std / max abs | %.1f / %.0f us |\n", sp.sd,
                    std::max(std::fabs(sp.min), std::fabs(sp.max)));
    } else {
        std::printf("| pacing | closed loop (no schedule) |\n");
    }
    std::printf("\n| workload | value |\n| --- | --- |\n");
    std::printf("| hypotheses per frame mean / max | %.1f / %ld |\n",
                timed ? hyp_sum / double(timed) : 0.0, hyp_max);
    std::printf("| frames with budget_exhausted | %ld of %ld |\n", exhausted, timed);
    if (opt.budget_us > 0) {
        std::printf("| deadline misses (%s > %ld us) | %ld of %ld |\n",
                    kBudgetOfNames[opt.budget_of], opt.budget_us, misses, measured);
    } else {
        std::printf("| deadline misses | no --budget-us |\n");
    }
    const bool fail = lost > 0 || misses > 0 || fr.empty();
    const bool input_error = input_rc == 2 || (!opt.log_path.empty() && fr.empty());
    std::printf("| result | %s%s |\n",
                input_error     ? "input error (exit 2)"
                : input_rc == 1 ? "internal failure (exit 1)"
                : fail          ? "FAIL (exit 3)"
                                : "ok",
                g_stop ? ", interrupted" : "");
    std::fflush(stdout);

    int rc = fail ? 3 : 0;
    if (!opt.json.empty()) {
        // The figures of the tables above, by the same names; null where nothing was measured.
        using json = nlohmann::ordered_json;
        const auto stats_json = [](const Stats &st) {
            if (st.n == 0) return json(nullptr);
            return json{{"n", st.n},       {"min", st.min}, {"median", st.median}, {"p99", st.p99},
                        {"p999", st.p999}, {"max", st.max}, {"mean", st.mean},     {"std", st.sd}};
        };
        json rejected = json::object();
        for (int k = 0; k < SFD_TIMING_T_NUM_REASONS; ++k) {
            rejected[sfd_reject_reason_str(k)] = json{
                {"during_run", static_cast<long long>(g.last_rejected[k] - g.first_rejected[k])},
                {"since_node_start", static_cast<long long>(g.last_rejected[k])}};
        }
        json j;
        j["source"] = source;
        j["rate"] = opt.rate;
        j["timeout_ms"] = opt.timeout_ms;
        j["warmup"] = opt.warmup;
        j["frames_published"] = static_cast<long long>(fr.size());
        j["messages_published"] = pub.published();
        j["verdicts_received"] = g.verdicts;
        j["timing_received"] = g.timings;
        j["status_reports"] = static_cast<long long>(g.status_reports);
        j["lost"] = json{{"total", lost},
                         {"frames_without_verdict", no_verdict + late},
                         {"late", late},
                         {"verdicts_for_unknown_frames", g.unknown_verdicts},
                         {"node_side_drops", opt.faults.any() ? unexplained_drops : node_drops}};
        if (opt.faults.any()) {
            j["faults"] = json{{"dropped", pub.dropped()},
                               {"duplicated", pub.duplicated()},
                               {"reordered", pub.reordered()},
                               {"future_stamped", pub.future()},
                               {"restarts", pub.restarts()},
                               {"stalls", pub.stalls()},
                               {"frame_copies_published", pub.frame_copies()},
                               {"frames_received_by_node", received},
                               {"frames_judged", judged},
                               {"frames_refused_by_node", frame_refusals},
                               {"every_frame_accounted_for", accounted},
                               {"refused_frames_judged", refused_judged},
                               {"expected_node_side_drops", expected_drops}};
        }
        j["node_rejected"] = rejected;
        j["input_features_malformed"] = pub.malformed();
        j["publish_failures"] = pub.publish_failures();
        j["frames_measured"] = measured;
        j["frames_measured_with_timing"] = timed;
        j["latency_us"] = json{{"end_to_end", stats_json(se)},
                               {"node_total", stats_json(sn)},
                               {"node_processing", stats_json(sc)},
                               {"node_publish", stats_json(sb)}};
        if (opt.rate > 0) {
            j["pacing_us"] = json{{"lateness", stats_json(sl)}, {"period_error", stats_json(sp)}};
        } else {
            j["pacing_us"] = nullptr;  // closed loop: no schedule
        }
        j["hypotheses_per_frame"] =
            json{{"mean", timed ? hyp_sum / double(timed) : 0.0}, {"max", hyp_max}};
        j["frames_budget_exhausted"] = exhausted;
        if (opt.budget_us > 0) {
            j["deadline"] = json{{"budget_us", opt.budget_us},
                                 {"of", kBudgetOfNames[opt.budget_of]},
                                 {"misses", misses},
                                 {"frames", measured}};
        } else {
            j["deadline"] = nullptr;
        }
        j["result"] = input_error     ? "input error"
                      : input_rc == 1 ? "internal failure"
                      : fail          ? "FAIL"
                                      : "ok";
        j["interrupted"] = g_stop != 0;
        const std::string text = j.dump(2, ' ', false, json::error_handler_t::replace) + "\n";
        std::FILE *jf = std::fopen(json_out.out.write_path, "w");
        char oerr[8192];
        bool ok = jf != nullptr;
        if (ok) {
            ok = std::fwrite(text.data(), 1, text.size(), jf) == text.size();
            ok = sfd_close_checked(jf) == 0 && ok;
        }
        if (!ok || sfd_out_commit(&json_out.out, oerr, sizeof oerr) != 0) {
            std::fprintf(stderr, "sfd-hil: --json %s: write failed (%s)\n", opt.json.c_str(),
                         std::strerror(errno));
            if (csv != nullptr) std::fclose(csv);
            return 1;
        }
    }
    if (csv != nullptr) {
        std::fprintf(csv,
                     "frame,utime,features,sched_lateness_us,e2e_us,node_total_us,ingest_us,"
                     "parity_us,association_us,update_us,hypotheses,budget_exhausted,verdict,"
                     "timing,warmup,lost,publish_us\n");
        for (size_t i = 0; i < fr.size(); ++i) {
            const Frame &f = fr[i];
            const bool got = f.verdict_ns >= 0;
            const bool in_time = got && f.verdict_ns - f.pub_ns <= timeout_ns;
            std::fprintf(csv, "%zu,%lld,%d,", i, static_cast<long long>(f.utime), f.features);
            if (opt.rate > 0) {
                std::fprintf(csv, "%.1f,", double(f.pub_ns - f.sched_ns) / 1000.0);
            } else {
                std::fprintf(csv, ",");
            }
            if (got) {
                std::fprintf(csv, "%.1f,", double(f.verdict_ns - f.pub_ns) / 1000.0);
            } else {
                std::fprintf(csv, ",");
            }
            if (f.timing) {
                std::fprintf(csv, "%d,%d,%d,%d,%d,%d,%d,", f.total_us, f.ingest_us, f.parity_us,
                             f.association_us, f.update_us, f.hypotheses, f.budget_exhausted);
            } else {
                std::fprintf(csv, ",,,,,,,");
            }
            std::fprintf(csv, "%d,%d,%d,%d,", got ? 1 : 0, f.timing ? 1 : 0,
                         long(i) < opt.warmup ? 1 : 0, in_time ? 0 : 1);
            if (f.timing) {
                std::fprintf(csv, "%d\n", f.publish_us);
            } else {
                std::fprintf(csv, "\n");
            }
        }
        char oerr[8192];
        if (sfd_close_checked(csv) != 0) {
            std::fprintf(stderr, "sfd-hil: --csv %s: write failed (%s)\n", opt.csv.c_str(),
                         std::strerror(errno));
            return 1;
        }
        if (sfd_out_commit(&csv_out.out, oerr, sizeof oerr) != 0) {
            std::fprintf(stderr, "sfd-hil: --csv %s\n", oerr);
            return 1;
        }
        if (!opt.png.empty() && run_plot(opt.csv, opt.png) != 0 && rc == 0) rc = 1;
    }
    if (input_error) {
        if (input_rc == 0) {
            std::fprintf(stderr, "sfd-hil: --log: %s has no FEATURES frame\n",
                         opt.log_path.c_str());
        }
        return 2;
    }
    if (input_rc == 1) {
        std::fprintf(stderr, "sfd-hil: --sim: a message could not be encoded\n");
        return 1;
    }
    (void)events;
    (void)fst;
    return rc;
}

}  // namespace

int main(int argc, char **argv) {
    try {
        return run(argc, argv);
    } catch (const std::exception &e) {  // std::bad_alloc, a JSON encoding failure
        std::fprintf(stderr, "sfd-hil: %s\n", e.what());
    } catch (...) {
        std::fprintf(stderr, "sfd-hil: unexpected failure\n");
    }
    return 1;
}
