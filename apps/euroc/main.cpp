// SPDX-License-Identifier: MIT
// sfd-euroc: converts an EuRoC/ASL recording (Burri et al., IJRR 2016) into an sfd LCM log:
// IMU, CAMERA_INFO (intrinsics, distortion, T_BS as T_imu_cam), FEATURES from the OpenCV tracker
// (drivers/opencv) and, when ground truth is given, TRUTH poses at the frame times.
//
// EuRoC conventions used (dataset paper, Section 2, and the sensor.yaml files):
//  - timestamps in ns; written as microseconds (ns / 1000, truncated);
//  - imu0/data.csv: t, w_RS_S (rad/s, 3), a_RS_S (m/s^2, 3), IMU (body) frame = sfd's IMU frame;
//  - state_groundtruth_estimate0/data.csv: t, p_RS_R (m, 3), q_RS (w, x, y, z) = IMU (body)
//    orientation in the world (R), then velocity and biases (ignored). TRUTH carries p and q as
//    they are (truth_t: IMU position/orientation in the world frame; EuRoC's world is z up);
//  - cam0/sensor.yaml: T_BS = camera pose in the body (IMU) frame = CAMERA_INFO's T_imu_cam;
//    intrinsics fu fv cu cv; radial-tangential k1 k2 p1 p2 (or equidistant k1..k4).
// Real data carries no spurious labels: TRUTH's num_features is 0 (sfd-replay then says the
// verdicts are not scored instead of scoring them against invented labels).
#include <lcm/eventlog.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <dirent.h>
#include <string>
#include <type_traits>
#include <utility>
#include <sys/stat.h>
#include <vector>

#include "sfd/sfd.h"
#include "sfd_camera_info_t.h"
#include "sfd_feature_frame_t.h"
#include "sfd_feature_tracker.hpp"
#include "sfd_imu_t.h"
#include "sfd_truth_t.h"
#include "euroc_io.hpp"
#include "lcm_log.hpp"
#include "sfd_output.h"
#include "sfd_cli.hpp"
#include "sfd_opencv_quiet.hpp"

namespace {

const char *kProg = "sfd-euroc";

bool file_exists(const std::string &p) {
    struct stat st;
    return ::stat(p.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}
bool dir_exists(const std::string &p) {
    struct stat st;
    return ::stat(p.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

struct Frame {
    int64_t t_ns;
    std::string path;
};

// Frame list: from a EuRoC camera data.csv, or every <digits>.png/.jpg in the image folder.
bool list_frames(const std::string &images, const std::string &frames_csv,
                 std::vector<Frame> *frames, std::string *err) {
    if (!dir_exists(images)) {
        *err = images + ": no such folder";
        return false;
    }
    if (!frames_csv.empty()) {
        std::vector<sfdapp::EurocRow> rows;
        if (!sfdapp::read_euroc_csv(frames_csv, 2, sfdapp::kAnyCols, &rows, err)) return false;
        for (const sfdapp::EurocRow &r : rows) {
            if (r.fields[0].empty()) {
                err->assign(frames_csv)
                    .append(":")
                    .append(std::to_string(r.line))
                    .append(": field 2: no image file name");
                return false;
            }
            frames->push_back(Frame{r.t_ns, images + "/" + r.fields[0]});
        }
        return true;
    }
    DIR *d = ::opendir(images.c_str());
    if (d == nullptr) {
        *err = images + ": cannot list";
        return false;
    }
    for (const dirent *e = ::readdir(d); e != nullptr; e = ::readdir(d)) {
        const std::string name = e->d_name;
        const size_t dot = name.rfind('.');
        if (dot == std::string::npos || dot == 0) continue;
        const std::string stem = name.substr(0, dot), ext = name.substr(dot);
        if (ext != ".png" && ext != ".jpg" && ext != ".jpeg") continue;
        if (stem.empty() || stem.find_first_not_of("0123456789") != std::string::npos) continue;
        errno = 0;
        const long long t_ns = std::strtoll(stem.c_str(), nullptr, 10);
        if (errno != 0) continue;  // more than int64 ns: not a EuRoC timestamp
        std::string path = images;
        path += '/';
        path += name;
        frames->push_back(Frame{t_ns, path});
    }
    ::closedir(d);
    std::sort(frames->begin(), frames->end(),
              [](const Frame &a, const Frame &b) { return a.t_ns < b.t_ns; });
    for (size_t i = 1; i < frames->size(); ++i) {
        if ((*frames)[i].t_ns == (*frames)[i - 1].t_ns) {
            *err = images + ": two images with the timestamp " + std::to_string((*frames)[i].t_ns);
            return false;
        }
    }
    if (frames->empty()) {
        *err = images + ": no <timestamp_ns>.png/.jpg images";
        return false;
    }
    return true;
}

struct Pose {
    int64_t t_ns;
    double p[3];
    double q[4];  // w x y z
};

// Pose at t by linear interpolation of the position and slerp of the orientation between the
// bracketing rows (Shoemake 1985); false when t is outside the rows or the gap exceeds max_gap.
bool interpolate(const std::vector<Pose> &gt, int64_t t, int64_t max_gap_ns, Pose *out) {
    const auto it = std::lower_bound(gt.begin(), gt.end(), t,
                                     [](const Pose &p, int64_t v) { return p.t_ns < v; });
    if (it == gt.end()) return false;
    if (it->t_ns == t) {
        *out = *it;
        return true;
    }
    if (it == gt.begin()) return false;
    const Pose &a = *(it - 1), &b = *it;
    if (b.t_ns - a.t_ns > max_gap_ns) return false;
    const double s = double(t - a.t_ns) / double(b.t_ns - a.t_ns);
    out->t_ns = t;
    for (int k = 0; k < 3; ++k) out->p[k] = a.p[k] + s * (b.p[k] - a.p[k]);
    double qb[4], dot = 0;
    for (int k = 0; k < 4; ++k) dot += a.q[k] * b.q[k];
    for (int k = 0; k < 4; ++k) qb[k] = dot < 0 ? -b.q[k] : b.q[k];
    dot = std::fabs(dot);
    double wa = 1.0 - s, wb = s;
    if (dot < 0.9995) {
        const double th = std::acos(std::min(1.0, dot));
        wa = std::sin((1.0 - s) * th) / std::sin(th);
        wb = std::sin(s * th) / std::sin(th);
    }
    double n = 0;
    for (int k = 0; k < 4; ++k) {
        out->q[k] = wa * a.q[k] + wb * qb[k];
        n += out->q[k] * out->q[k];
    }
    n = std::sqrt(n);
    for (int k = 0; k < 4; ++k) out->q[k] /= n;
    return true;
}

// Events before writing: sorted by time, then by kind (IMU, CAMERA_INFO, FEATURES, TRUTH at one
// time, as sfd-sim writes them), then by order of creation.
struct LogEvent {
    int64_t utime;
    int rank;
    size_t seq;
    const char *channel;
    std::vector<uint8_t> data;
};

// OpenCV's exception text on one line (it holds line breaks).
std::string one_line(std::string m) {
    for (char &c : m) {
        if (c == '\n' || c == '\r') c = ' ';
    }
    while (!m.empty() && m.back() == ' ') m.pop_back();
    return m;
}

}  // namespace

int main(int argc, char **argv) {
    std::string euroc, images, frames_csv, imu_csv, calib_yaml, gt_csv, out_path, cam = "cam0";
    long max_frames = 0, camera_id = 0;
    double imu_before_s = 1.0;
    sfd::TrackerConfig tc;
    // OpenCV's own log lines (imread, cv::FileStorage) are silenced: sfd says what failed in
    // one line naming the file.
    sfdapp::quiet_opencv();
    sfdcli::Parser cli(
        kProg, kProg,
        "(--euroc DIR | --images DIR --imu CSV --calib YAML) -o OUT.lcmlog\n"
        "                 [--frames CSV] [--gt CSV] [--cam camN] [--max-frames N]\n"
        "                 [--imu-before-s S] [--camera-id ID] [tracker options]",
        "  Converts an EuRoC/ASL recording into an sfd log (IMU, CAMERA_INFO, FEATURES from\n"
        "  the OpenCV tracker, TRUTH at the frame times when ground truth is given). On a\n"
        "  terminal (and CI unset), a progress line on stderr.");
    const auto text_opt = [](std::string *dst) -> sfdcli::Setter {
        return [dst](const std::string &v, std::string *) {
            *dst = v;
            return true;
        };
    };
    cli.section("Input and output");
    cli.value("euroc", "DIR",
              "standard layout: DIR/mav0 (or DIR = mav0) with imu0/data.csv,\n"
              "camN/data.csv, camN/data/<ns>.png, camN/sensor.yaml and, if\n"
              "present, state_groundtruth_estimate0/data.csv; explicit flags\n"
              "override",
              text_opt(&euroc));
    cli.value("cam", "camN", "camera folder for --euroc (default cam0)", text_opt(&cam));
    cli.value("images", "DIR", "image folder (8-bit grayscale PNG/JPEG, read as grayscale)",
              text_opt(&images));
    cli.value("frames", "CSV",
              "EuRoC camera data.csv (timestamp [ns], file name); default:\n"
              "every <ns>.png/.jpg in --images, by time",
              text_opt(&frames_csv));
    cli.value("imu", "CSV", "EuRoC imu0/data.csv (t [ns], gyro xyz [rad/s], accel xyz [m/s^2])",
              text_opt(&imu_csv));
    cli.value("calib", "YAML",
              "EuRoC camera sensor.yaml (T_BS, resolution, intrinsics,\ndistortion)",
              text_opt(&calib_yaml));
    cli.value("gt", "CSV",
              "EuRoC ground truth (t [ns], p xyz [m], q w x y z, ...): TRUTH\n"
              "poses interpolated at the frame times (no spurious labels)",
              text_opt(&gt_csv));
    sfdcli::Option output;
    output.name = "output";
    output.short_name = 'o';
    output.metavar = "OUT.lcmlog";
    output.help = "the sfd log to write";
    output.set = text_opt(&out_path);
    cli.add(output);
    cli.value("max-frames", "N", "convert the first N frames only (default: all)",
              sfdcli::int_setter(&max_frames, 1, 100000000));
    cli.value("imu-before-s", "S",
              "IMU kept from S seconds before the first frame (default 1.0)\n"
              "to the last frame; the count of samples left out is printed",
              sfdcli::real_setter(&imu_before_s, 0.0, 1e6));
    cli.value("camera-id", "ID", "camera_id of CAMERA_INFO and FEATURES (default 0)",
              sfdcli::int_setter(&camera_id, 0, 2147483647));
    cli.section("Tracker (drivers/opencv/sfd_feature_tracker.hpp)");
    cli.value("max-features", "N",
              "tracks per frame, 1.." + std::to_string(sfd::kTrackerMaxFeatures) + " (default 150)",
              sfdcli::int_setter(&tc.max_features, 1, sfd::kTrackerMaxFeatures));
    cli.value("min-distance-px", "PX", "spacing between tracks (default 20)",
              sfdcli::real_setter(&tc.min_distance_px, 0.0, 1000.0));
    cli.flag("no-fb-check", "plain pyramidal LK, no forward-backward check",
             [&tc] { tc.fb_check = false; });
    cli.value("fb-threshold-px", "PX", "forward-backward round-trip limit (default 1.0)",
              sfdcli::real_setter(&tc.fb_threshold_px, 1e-6, 1000.0));
    cli.value("quality-level", "Q", "Shi-Tomasi quality level (default 0.01)",
              sfdcli::real_setter(&tc.quality_level, 1e-9, 0.999999));
    cli.value("lk-window-px", "W", "LK window side, odd (default 21)",
              sfdcli::int_setter(&tc.lk_window_px, 5, 101));
    cli.value("lk-levels", "L", "LK pyramid levels (default 3)",
              sfdcli::int_setter(&tc.lk_pyramid_levels, 0, 8));
    cli.value("border-px", "PX", "image border without features (default 8)",
              sfdcli::int_setter(&tc.border_px, 0, 1000));
    cli.epilog(
        "Exit: 0 ok, 2 bad usage or bad/missing input (the message names file and line),\n"
        "1 write failure.");
    std::vector<std::string> positional;
    if (const int rc = cli.parse(argc, argv, &positional); rc >= 0) return rc;
    if (!positional.empty()) return cli.fail("unexpected argument " + positional[0]);
    std::string err;
    if (!sfd::FeatureTracker::validate(tc, &err)) {
        std::fprintf(stderr, "%s: tracker: %s\n", kProg, err.c_str());
        return 2;
    }
    if (!euroc.empty()) {
        std::string mav = euroc + "/mav0";
        if (!dir_exists(mav)) mav = euroc;
        if (!dir_exists(mav + "/imu0")) {
            std::fprintf(stderr, "%s: --euroc %s: no mav0/imu0 folder (EuRoC layout)\n", kProg,
                         euroc.c_str());
            return 2;
        }
        if (images.empty()) images = mav + "/" + cam + "/data";
        if (frames_csv.empty() && file_exists(mav + "/" + cam + "/data.csv"))
            frames_csv = mav + "/" + cam + "/data.csv";
        if (imu_csv.empty()) imu_csv = mav + "/imu0/data.csv";
        if (calib_yaml.empty()) calib_yaml = mav + "/" + cam + "/sensor.yaml";
        const std::string gt = mav + "/state_groundtruth_estimate0/data.csv";
        if (gt_csv.empty() && file_exists(gt)) gt_csv = gt;
    }
    if (images.empty() || imu_csv.empty() || calib_yaml.empty() || out_path.empty()) {
        return cli.fail(
            "need --euroc DIR or --images, --imu and --calib; and -o (sfd-euroc --help)");
    }
    // No output may be an input (docs/deploy.md, "Reading logs and writing outputs"): not one of
    // the files read, and not inside the image folder.
    {
        const std::pair<const char *, std::string> ins[] = {{"--frames", frames_csv},
                                                            {"--imu", imu_csv},
                                                            {"--calib", calib_yaml},
                                                            {"--gt", gt_csv}};
        for (const auto &in : ins) {
            if (!in.second.empty() && sfd_same_file(out_path.c_str(), in.second.c_str())) {
                std::fprintf(stderr,
                             "%s: -o %s is the input %s %s (same file): an output may not "
                             "overwrite an input\n",
                             kProg, out_path.c_str(), in.first, in.second.c_str());
                return 2;
            }
        }
        const size_t slash = out_path.rfind('/');
        const std::string out_dir =
            slash == std::string::npos ? "." : out_path.substr(0, slash + 1);
        if (sfd_same_file(out_dir.c_str(), images.c_str())) {
            std::fprintf(stderr, "%s: -o %s is inside the input image folder %s\n", kProg,
                         out_path.c_str(), images.c_str());
            return 2;
        }
    }

    sfdapp::EurocCamera calib;
    std::vector<Frame> frames;
    std::vector<sfdapp::EurocRow> imu_rows, gt_rows;
    if (!sfdapp::read_euroc_sensor_yaml(calib_yaml, &calib, &err) ||
        !list_frames(images, frames_csv, &frames, &err) ||
        !sfdapp::read_euroc_csv(imu_csv, 7, sfdapp::kAnyCols, &imu_rows, &err) ||
        (!gt_csv.empty() && !sfdapp::read_euroc_csv(gt_csv, 8, sfdapp::kAnyCols, &gt_rows, &err))) {
        std::fprintf(stderr, "%s: %s\n", kProg, err.c_str());
        return 2;
    }
    if (max_frames > 0 && frames.size() > size_t(max_frames)) frames.resize(size_t(max_frames));
    std::vector<Pose> gt;
    for (const sfdapp::EurocRow &r : gt_rows) {
        double v[7];
        if (!sfdapp::euroc_row_numbers(gt_csv, r, 0, 7, v, &err)) {
            std::fprintf(stderr, "%s: %s\n", kProg, err.c_str());
            return 2;
        }
        Pose p{r.t_ns, {v[0], v[1], v[2]}, {v[3], v[4], v[5], v[6]}};
        const double qn = std::sqrt(v[3] * v[3] + v[4] * v[4] + v[5] * v[5] + v[6] * v[6]);
        if (!(std::fabs(qn - 1.0) < 1e-3)) {
            std::fprintf(stderr, "%s: %s:%ld: quaternion norm %.6f, expected 1 (w x y z)\n", kProg,
                         gt_csv.c_str(), r.line, qn);
            return 2;
        }
        for (double &q : p.q) q /= qn;
        gt.push_back(p);
    }

    std::vector<LogEvent> events;
    size_t seq = 0;
    std::vector<uint8_t> buf(size_t{64} * 1024);
    auto add = [&](int64_t utime, int rank, const char *ch, int n) {
        events.push_back(
            LogEvent{utime, rank, seq++, ch, std::vector<uint8_t>(buf.begin(), buf.begin() + n)});
    };
    const int64_t first_ns = frames.front().t_ns, last_ns = frames.back().t_ns;
    const int64_t imu_from_ns = first_ns - int64_t(imu_before_s * 1e9);
    long imu_written = 0, imu_skipped = 0;
    for (const sfdapp::EurocRow &r : imu_rows) {
        if (r.t_ns < imu_from_ns || r.t_ns > last_ns + 50000000) {
            ++imu_skipped;  // outside [first frame - imu_before_s, last frame + 50 ms]
            continue;
        }
        double v[6];
        if (!sfdapp::euroc_row_numbers(imu_csv, r, 0, 6, v, &err)) {
            std::fprintf(stderr, "%s: %s\n", kProg, err.c_str());
            return 2;
        }
        sfd_imu_t m;
        m.utime = r.t_ns / 1000;
        std::memcpy(m.gyro, v, sizeof m.gyro);
        std::memcpy(m.accel, v + 3, sizeof m.accel);
        add(m.utime, 0, "IMU", sfd_imu_t_encode(buf.data(), 0, int(buf.size()), &m));
        ++imu_written;
    }
    if (imu_written == 0) {
        std::fprintf(stderr,
                     "%s: %s: no IMU sample between %.3f s before the first frame and "
                     "the last frame (frames %lld..%lld ns)\n",
                     kProg, imu_csv.c_str(), imu_before_s, static_cast<long long>(first_ns),
                     static_cast<long long>(last_ns));
        return 2;
    }

    static sfd_camera_info_t ci;
    ci = sfdsim::camera_info_of(calib.camera, calib.T_BS);
    ci.utime = std::min(events.front().utime, first_ns / 1000);
    ci.camera_id = int32_t(camera_id);
    add(ci.utime, -1, "CAMERA_INFO", sfd_camera_info_t_encode(buf.data(), 0, int(buf.size()), &ci));

    sfd::FeatureTracker tracker(tc);
    static sfd_feature_frame_t ff;
    static sfd_truth_t tr;
    long features_total = 0, truth_written = 0, lost_fb = 0, lost_lk = 0;
    sfdcli::Progress progress(kProg, "frames");  // a terminal only (stderr, CI unset)
    long long frames_done = 0;
    for (const Frame &f : frames) {
        progress.update(frames_done, double(frames_done) / double(frames.size()));
        ++frames_done;
        // OpenCV reports some failures (corrupt files, internal checks) by exception: turned
        // into an error message naming the image, never a crash.
        cv::Mat img;
        try {
            img = cv::imread(f.path, cv::IMREAD_GRAYSCALE);
        } catch (const cv::Exception &e) {
            std::fprintf(stderr, "%s: %s: %s\n", kProg, f.path.c_str(), one_line(e.what()).c_str());
            return 2;
        }
        if (img.empty()) {
            std::fprintf(stderr, "%s: %s: cannot read the image\n", kProg, f.path.c_str());
            return 2;
        }
        if (img.cols != calib.camera.width_px || img.rows != calib.camera.height_px) {
            std::fprintf(stderr, "%s: %s: %dx%d image, calibration %s says %dx%d\n", kProg,
                         f.path.c_str(), img.cols, img.rows, calib_yaml.c_str(),
                         calib.camera.width_px, calib.camera.height_px);
            return 2;
        }
        bool tracked = false;
        try {
            tracked = tracker.track(img, &err);
        } catch (const cv::Exception &e) {
            err = "OpenCV: " + one_line(e.what());
        }
        if (!tracked) {
            std::fprintf(stderr, "%s: %s: tracker: %s\n", kProg, f.path.c_str(), err.c_str());
            return 2;
        }
        std::memset(&ff, 0, sizeof ff);
        ff.utime = f.t_ns / 1000;
        ff.camera_id = int32_t(camera_id);
        const auto &tracks = tracker.tracks();
        ff.num_features = int32_t(tracks.size());  // <= kTrackerMaxFeatures <= 512
        for (size_t k = 0; k < tracks.size(); ++k) {
            ff.track_id[k] = tracks[k].id;
            ff.u[k] = tracks[k].u_px;
            ff.v[k] = tracks[k].v_px;
            ff.depth[k] = 0.0;  // no depth prior (the node uses default_depth_m)
            ff.depth_var[k] = 0.0;
        }
        features_total += ff.num_features;
        lost_fb += tracker.stats().lost_fb;
        lost_lk += tracker.stats().lost_lk;
        add(ff.utime, 2, "FEATURES",
            sfd_feature_frame_t_encode(buf.data(), 0, int(buf.size()), &ff));
        Pose p;
        if (!gt.empty() && interpolate(gt, f.t_ns, 100000000, &p)) {
            std::memset(&tr, 0, sizeof tr);
            tr.utime = ff.utime;
            std::memcpy(tr.position, p.p, sizeof tr.position);
            std::memcpy(tr.orientation, p.q, sizeof tr.orientation);
            tr.num_features = 0;  // real data: no spurious labels
            add(tr.utime, 3, "TRUTH", sfd_truth_t_encode(buf.data(), 0, int(buf.size()), &tr));
            ++truth_written;
        }
    }
    progress.finish(frames_done);
    std::sort(events.begin(), events.end(), [](const LogEvent &a, const LogEvent &b) {
        if (a.utime != b.utime) return a.utime < b.utime;
        if (a.rank != b.rank) return a.rank < b.rank;
        return a.seq < b.seq;
    });
    // Written to a temporary file next to OUT and renamed into place when complete.
    struct Out {
        sfd_out_t o{};
        ~Out() { sfd_out_discard(&o); }
    } out;
    char oerr[8192];
    if (sfd_out_begin(&out.o, out_path.c_str(), oerr, sizeof oerr) != 0) {
        std::fprintf(stderr, "%s: -o %s\n", kProg, oerr);
        return 1;
    }
    lcm_eventlog_t *log = lcm_eventlog_create(out.o.write_path, "w");
    if (log == nullptr) {
        std::fprintf(stderr, "%s: -o %s: cannot open for writing (%s)\n", kProg, out_path.c_str(),
                     std::strerror(errno));
        return 1;
    }
    bool failed = false;
    for (LogEvent &e : events) {
        lcm_eventlog_event_t ev;
        std::memset(&ev, 0, sizeof ev);
        ev.timestamp = e.utime;
        ev.channellen = int32_t(std::strlen(e.channel));
        ev.channel = const_cast<char *>(e.channel);
        ev.datalen = int32_t(e.data.size());
        ev.data = e.data.data();
        if (lcm_eventlog_write_event(log, &ev) != 0) failed = true;
    }
    // liblcm's destroy does not report its flush: flush and check here first.
    if (std::fflush(log->f) != 0 || std::ferror(log->f) != 0) failed = true;
    lcm_eventlog_destroy(log);
    if (failed) {
        std::fprintf(stderr, "%s: -o %s: write failed (%s)\n", kProg, out_path.c_str(),
                     std::strerror(errno));
        return 1;
    }
    if (sfd_out_commit(&out.o, oerr, sizeof oerr) != 0) {
        std::fprintf(stderr, "%s: -o %s\n", kProg, oerr);
        return 1;
    }
    std::printf(
        "%s: wrote %s: %zu frames (%.1f features per frame; tracker lost %ld to LK, %ld "
        "to the forward-backward check%s), %ld IMU samples (%ld outside [first frame - "
        "%.2f s, last frame + 0.05 s] left out), 1 CAMERA_INFO, %ld TRUTH%s\n",
        kProg, out_path.c_str(), frames.size(), double(features_total) / double(frames.size()),
        lost_lk, lost_fb, tc.fb_check ? "" : ", off", imu_written, imu_skipped, imu_before_s,
        truth_written,
        gt.empty() ? " (no ground truth given)" : " (poses only, no spurious labels)");
    // EuRoC ground truth also holds the estimated biases (fields 11-13: b_w, rad/s): printed for
    // the node's gyro_bias_rad_s (filter.init_from_truth starts the filter with that bias).
    for (const sfdapp::EurocRow &r : gt_rows) {
        if (r.t_ns >= first_ns && r.fields.size() >= 13) {
            double bw[3];
            if (sfdapp::euroc_row_numbers(gt_csv, r, 10, 3, bw, &err)) {
                std::printf(
                    "%s: ground-truth gyro bias at the first frame: [%.6f, %.6f, %.6f] "
                    "rad/s\n",
                    kProg, bw[0], bw[1], bw[2]);
            }
            break;
        }
    }
    if (!gt.empty() && truth_written < long(frames.size())) {
        std::printf("%s: %ld frames have no TRUTH (outside the ground truth or a gap > 0.1 s)\n",
                    kProg, long(frames.size()) - truth_written);
    }
    return 0;
}
