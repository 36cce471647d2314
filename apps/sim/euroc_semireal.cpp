// SPDX-License-Identifier: MIT
// sfd-sim euroc-semireal: semi-real evaluation log from a EuRoC sequence's IMU and ground truth
// (no images): real motion, real gyro and accelerometer errors, simulated landmarks.
//
// Inputs (EuRoC folder layout, Burri et al., IJRR 2016):
//  - mav0/imu0/data.csv: timestamp [ns], w_RS_S (rad/s), a_RS_S (m/s^2), IMU frame;
//  - mav0/state_groundtruth_estimate0/data.csv: timestamp [ns], p_RS_R (m), q_RS (w x y z),
//    v_RS_R (m/s), b_w (rad/s), b_a (m/s^2): the IMU (S) pose in the world (R, z up);
//  - mav0/cam0/sensor.yaml: T_BS (cam0 pose in the body = IMU frame), intrinsics fu fv cu cv,
//    radial-tangential distortion, resolution.
// Both CSVs' timestamps are on the same clock; the log covers their overlap only.
//
// The log (channels as sfd-sim's other scenarios, apps/sim/flight_log.cpp):
//  - IMU: every imu0 row inside the overlap, unchanged (utime = t_ns / 1000, floor);
//  - FEATURES at camera_hz from the overlap's start; TRUTH at the same times: the ground-truth IMU
//    pose interpolated there (sfd_gt_interpolate: slerp, linear position), the TRUTH frame
//    convention (IMU position and orientation in the world);
//  - CAMERA_INFO first and once per second: cam0's calibration and T_BS.
// Landmarks: the walls, floor and ceiling of a room around the flight (the ground truth's
// bounding box over the overlap grown by 2 m horizontally, floor z = 0 or below the lowest
// point, ceiling 4 m or above the highest): a new track casts a random pixel of the current view
// onto the room. A fixed number of tracks (features) stays in view: a track whose point leaves the
// image, or that the tracker loses (probability track_loss per frame), is replaced by a new one
// (new track id). Pixels: the landmark projected through the ground-truth camera pose (T_BS
// composed with the interpolated IMU pose) and cam0's distortion, plus N(0, pixel_sigma^2) per
// axis. Depth priors: the true depth plus N(0, depth_var).
// Spurious features (TRUTH spurious = 1), each kind a third of spurious_fraction:
//  - moving object: a group of tracks (a third of spurious_fraction of the slots) whose points
//    move together at mover_speed in one horizontal direction, drawn anew every 2 s; spurious in
//    every frame;
//  - mistracked: a jump of jump_px in a random direction onto the room's point there, or a
//    drift of drift_px per frame for drift_frames frames that then locks onto the room's point
//    under the slid pixel; either way the track then follows that static point for good, with
//    its own depth prior (until 2026-11-29 the track kept the pixel offset from its old point's
//    projection and that point's depth, so observations labelled clean after the label window
//    matched no static point: apps/sim/SEMIREAL.md);
//  - mismatched: the track's id jumps to another point of the room, 15-60 px away in the image.
// A step (jump, drift step, mismatch) labels the track spurious in the truth_window frames from
// the step: the windows of a detector with L = truth_window + 1 frames that mix observations from
// before and after it (as apps/sim/flight_log.cpp labels its mistracks).
#include "euroc_semireal.hpp"

#include <algorithm>
#include <cinttypes>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "euroc_io.hpp"
#include "lcm_log.hpp"
#include "sfd/sfd.h"
#include "sfd_feature_frame_t.h"
#include "sfd_gt_traj.h"
#include "sfd_imu_t.h"
#include "sfd_truth_t.h"

namespace sfdsim {
namespace {

constexpr double kPi = 3.14159265358979323846;

struct ImuRow {
    int64_t t_ns;
    double w[3];  // rad/s
    double a[3];  // m/s^2
};

struct GtRow {
    sfd_gt_pose_t pose;
    double v[3];   // m/s
    double bw[3];  // rad/s
    double ba[3];  // m/s^2
    long line;     // line in the CSV (error messages)
};

// imu0/data.csv: timestamp, w_RS_S x y z (rad/s), a_RS_S x y z (m/s^2).
bool read_imu(const std::string &path, std::vector<ImuRow> *out, std::string *err) {
    std::vector<sfdapp::EurocRow> rows;
    if (!sfdapp::read_euroc_csv(path, 7, 7, &rows, err)) return false;
    out->resize(rows.size());
    for (size_t i = 0; i < rows.size(); ++i) {
        double v[6];
        if (!sfdapp::euroc_row_numbers(path, rows[i], 0, 6, v, err)) return false;
        (*out)[i].t_ns = rows[i].t_ns;
        for (size_t k = 0; k < 3; ++k) {
            (*out)[i].w[k] = v[k];
            (*out)[i].a[k] = v[3 + k];
        }
    }
    return true;
}

// state_groundtruth_estimate0/data.csv: timestamp, p (3), q_RS w x y z (4), v (3), b_w (3),
// b_a (3).
bool read_gt(const std::string &path, std::vector<GtRow> *out, std::string *err) {
    std::vector<sfdapp::EurocRow> rows;
    if (!sfdapp::read_euroc_csv(path, 17, 17, &rows, err)) return false;
    out->resize(rows.size());
    for (size_t i = 0; i < rows.size(); ++i) {
        GtRow &g = (*out)[i];
        double r[16];
        if (!sfdapp::euroc_row_numbers(path, rows[i], 0, 16, r, err)) return false;
        g.pose.t_ns = rows[i].t_ns;
        g.line = rows[i].line;
        for (size_t k = 0; k < 3; ++k) {
            g.pose.p_IinW_m[k] = r[k];
            g.v[k] = r[7 + k];
            g.bw[k] = r[10 + k];
            g.ba[k] = r[13 + k];
        }
        for (size_t k = 0; k < 4; ++k) g.pose.q_ItoW[k] = r[3 + k];
        const double n =
            std::sqrt(g.pose.q_ItoW[0] * g.pose.q_ItoW[0] + g.pose.q_ItoW[1] * g.pose.q_ItoW[1] +
                      g.pose.q_ItoW[2] * g.pose.q_ItoW[2] + g.pose.q_ItoW[3] * g.pose.q_ItoW[3]);
        // EuRoC prints the quaternion to 6 decimals: its norm is 1 within about 1e-5.
        if (!(std::fabs(n - 1.0) < 1e-3) || sfd_quat_normalize(g.pose.q_ItoW) != SFD_OK) {
            *err = path + ":" + std::to_string(rows[i].line) +
                   ": q_RS (fields 5-8) is not a unit quaternion (norm " + std::to_string(n) + ")";
            return false;
        }
    }
    return true;
}

struct Track {
    int64_t id = 0;
    double p_W[3] = {0, 0, 0};  // the point the track follows (m, world)
    double off_px[2] = {0, 0};  // accumulated mistrack offset
    double drift_px[2] = {0, 0};
    int drift_left = 0;
    int64_t last_step = INT32_MIN;  // frame of the last jump/drift step/mismatch
    int8_t last_kind = 0;           // TRUTH kind of that step (truth_t KIND_*)
    bool alive = false;
    bool mover = false;
};

}  // namespace

void semireal_help(FILE *out) {
    std::fprintf(
        out,
        "euroc-semireal (log scenario, needs --euroc DIR and -o): EuRoC IMU + ground truth\n"
        "  (no images): the real imu0 samples and the ground-truth motion over their overlap,\n"
        "  landmarks on the walls/floor/ceiling of a room around the flight projected through\n"
        "  cam0 (T_BS, intrinsics, distortion of mav0/cam0/sensor.yaml), spurious features\n"
        "  (moving group, mistracks, mismatches) labelled in TRUTH. See apps/sim/SEMIREAL.md.\n");
}

int write_semireal_log(const SemirealOptions &opt) {
    std::string mav = opt.euroc_dir;
    while (mav.size() > 1 && mav.back() == '/') mav.pop_back();
    {
        std::ifstream probe(mav + "/mav0/imu0/data.csv");
        if (probe) mav += "/mav0";
    }
    const std::string imu_path = mav + "/imu0/data.csv";
    const std::string gt_path = mav + "/state_groundtruth_estimate0/data.csv";
    const std::string cam_path = mav + "/cam0/sensor.yaml";
    // No output (-o, --config-out) may be an input or the other output (docs/deploy.md).
    {
        const std::pair<const char *, std::string> outs[2] = {{"-o", opt.out_path},
                                                              {"--config-out", opt.config_out}};
        const std::string ins[3] = {imu_path, gt_path, cam_path};
        for (const auto &o : outs) {
            for (const std::string &in : ins) {
                if (o.second.empty() || !sfd_same_file(o.second.c_str(), in.c_str())) continue;
                std::fprintf(stderr,
                             "sfd-sim: %s %s is the input %s (same file): an output may not "
                             "overwrite an input\n",
                             o.first, o.second.c_str(), in.c_str());
                return 2;
            }
        }
        if (!opt.config_out.empty() &&
            sfd_same_file(opt.out_path.c_str(), opt.config_out.c_str())) {
            std::fprintf(stderr, "sfd-sim: -o %s and --config-out %s are the same file\n",
                         opt.out_path.c_str(), opt.config_out.c_str());
            return 2;
        }
    }
    std::vector<ImuRow> imu;
    std::vector<GtRow> gt;
    sfdapp::EurocCamera calib;
    std::string err;
    if (!read_imu(imu_path, &imu, &err) || !read_gt(gt_path, &gt, &err) ||
        !sfdapp::read_euroc_sensor_yaml(cam_path, &calib, &err)) {
        std::fprintf(stderr, "sfd-sim: %s\n", err.c_str());
        return 2;
    }
    const sfd_camera_t &cam = calib.camera;
    const double *T_BS = calib.T_BS;
    const sfd_extrinsics_t &ext = calib.ext;
    // The overlap of IMU and ground truth (same clock): the log covers it only.
    const int64_t t_begin = std::max(imu.front().t_ns, gt.front().pose.t_ns);
    const int64_t t_end = std::min(imu.back().t_ns, gt.back().pose.t_ns);
    const int64_t period_ns = std::llround(1e9 / opt.camera_hz);
    if (t_end - t_begin < period_ns) {
        std::fprintf(stderr,
                     "sfd-sim: %s and %s overlap for less than one camera period "
                     "(IMU %" PRId64 "..%" PRId64 " ns, ground truth %" PRId64 "..%" PRId64
                     " ns)\n",
                     imu_path.c_str(), gt_path.c_str(), imu.front().t_ns, imu.back().t_ns,
                     gt.front().pose.t_ns, gt.back().pose.t_ns);
        return 2;
    }
    // Ground-truth gaps: interpolating over more than 0.2 s would invent motion.
    const int64_t max_gap_ns = 200000000;
    size_t g_first = 0;
    while (gt[g_first + 1].pose.t_ns <= t_begin && g_first + 2 < gt.size()) ++g_first;
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
    for (size_t i = g_first; i < gt.size() && gt[i].pose.t_ns <= t_end + max_gap_ns; ++i) {
        if (i + 1 < gt.size() && gt[i].pose.t_ns < t_end &&
            gt[i + 1].pose.t_ns - gt[i].pose.t_ns > max_gap_ns) {
            std::fprintf(stderr,
                         "sfd-sim: %s:%ld-%ld: ground-truth gap of %.3f s inside the IMU "
                         "overlap (more than 0.2 s cannot be interpolated)\n",
                         gt_path.c_str(), gt[i].line, gt[i + 1].line,
                         double(gt[i + 1].pose.t_ns - gt[i].pose.t_ns) * 1e-9);
            return 2;
        }
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::min(lo[k], gt[i].pose.p_IinW_m[k]);
            hi[k] = std::max(hi[k], gt[i].pose.p_IinW_m[k]);
        }
    }
    // The room: the flight's bounding box grown by 2 m horizontally; floor and ceiling.
    const double room_lo[3] = {lo[0] - 2.0, lo[1] - 2.0, std::min(0.0, lo[2] - 0.5)};
    const double room_hi[3] = {hi[0] + 2.0, hi[1] + 2.0, std::max(4.0, hi[2] + 1.0)};

    LogWriter log(opt.out_path);
    if (!log.ok()) {
        std::fprintf(stderr, "sfd-sim: -o %s\n", log.error().c_str());
        return 1;
    }
    sfd_prng_t rng;
    sfd_prng_seed(&rng, opt.seed);
    std::vector<uint8_t> buf(size_t{64} * 1024);
    sfd_camera_info_t ci = camera_info_of(cam, T_BS);
    const int n_feat = std::min(opt.features, SFD_FEATURE_FRAME_T_CAPACITY);
    const int n_move =
        std::min(n_feat, int(std::lround(opt.spurious_fraction / 3.0 * double(n_feat))));
    // Events per frame per non-moving track, two thirds of the spurious fraction together: a jump
    // or a mismatch labels truth_window frames, a drift drift_frames + truth_window - 1; the
    // three kinds are equally likely.
    const double frames_per_event = (3.0 * opt.truth_window + opt.drift_frames - 1.0) / 3.0;
    const double p_event = (2.0 / 3.0) * opt.spurious_fraction /
                           (frames_per_event * std::max(0.05, 1.0 - opt.spurious_fraction / 3.0));
    std::vector<Track> tracks(static_cast<size_t>(n_feat));
    for (int i = 0; i < n_move; ++i) tracks[size_t(i)].mover = true;
    int64_t next_id = 1;
    const double margin_px = 10.0;

    // A point of the room seen at pixel uv by the camera (R_CtoW, p_C); false if none.
    auto cast = [&](const double uv[2], const double R[9], const double p[3], double out[3]) {
        double ray[3], d[3];
        if (sfd_camera_unproject(&cam, uv, ray) != SFD_OK) return false;
        for (int r = 0; r < 3; ++r) {
            d[r] = 0;
            for (int k = 0; k < 3; ++k) d[r] += R[3 * r + k] * ray[k];
        }
        return sfd_gt_room_hit(room_lo, room_hi, p, d, out) == 0;
    };
    // The room's point under the pixel r px from `from` in direction ang, or on the other side
    // when that pixel is within margin_px of the border or casts onto nothing; false (out left
    // as it was) when neither side serves.
    auto step_onto = [&](const double from[2], double r, double ang, const double R[9],
                         const double p[3], double out[3]) {
        for (int side = 0; side < 2; ++side) {
            const double s = side ? -1.0 : 1.0;
            const double uv2[2] = {from[0] + s * r * std::cos(ang),
                                   from[1] + s * r * std::sin(ang)};
            double p2[3];
            if (uv2[0] < margin_px || uv2[0] > cam.width_px - margin_px || uv2[1] < margin_px ||
                uv2[1] > cam.height_px - margin_px || !cast(uv2, R, p, p2)) {
                continue;
            }
            std::memcpy(out, p2, sizeof p2);
            return true;
        }
        return false;
    };
    auto spawn = [&](Track &T, const double R[9], const double p[3]) {
        T.alive = false;
        for (int tries = 0; tries < 32 && !T.alive; ++tries) {
            const double uv[2] = {
                margin_px + (cam.width_px - 2 * margin_px) * sfd_prng_uniform(&rng),
                margin_px + (cam.height_px - 2 * margin_px) * sfd_prng_uniform(&rng)};
            T.alive = cast(uv, R, p, T.p_W);
        }
        T.id = next_id++;
        T.off_px[0] = T.off_px[1] = 0.0;
        T.drift_px[0] = T.drift_px[1] = 0.0;
        T.drift_left = 0;
        T.last_step = INT32_MIN;
        T.last_kind = SFD_TRUTH_T_KIND_CLEAN;
    };

    static sfd_feature_frame_t ff;
    static sfd_truth_t tr;
    size_t imu_i = 0;
    while (imu_i < imu.size() && imu[imu_i].t_ns < t_begin) ++imu_i;
    int64_t imu_written = 0;
    auto write_imu_until = [&](int64_t t_ns) {
        for (; imu_i < imu.size() && imu[imu_i].t_ns <= t_ns; ++imu_i) {
            sfd_imu_t m;
            m.utime = imu[imu_i].t_ns / 1000;
            for (int k = 0; k < 3; ++k) {
                m.gyro[k] = imu[imu_i].w[k];
                m.accel[k] = imu[imu_i].a[k];
            }
            log.write("IMU", m.utime, buf, sfd_imu_t_encode(buf.data(), 0, int(buf.size()), &m));
            ++imu_written;
        }
    };
    size_t g = g_first;
    const int frames = int((t_end - t_begin) / period_ns) + 1;
    const int info_every = std::max(1, int(std::lround(opt.camera_hz)));
    long n_total = 0, n_mover = 0, n_mistrack = 0, n_mismatch_events = 0, n_spurious = 0,
         n_dropped = 0;
    double mover_v[3] = {0, 0, 0};
    int mover_epoch = -1;
    sfd_gt_pose_t first_pose{};
    for (int f = 0; f < frames; ++f) {
        const int64_t t_ns = t_begin + int64_t(f) * period_ns;
        const int64_t utime = t_ns / 1000;
        write_imu_until(t_ns);
        while (g + 2 < gt.size() && gt[g + 1].pose.t_ns < t_ns) ++g;
        sfd_gt_pose_t P;
        double R[9], pc[3];
        if (sfd_gt_interpolate(&gt[g].pose, &gt[g + 1].pose, t_ns, &P) != 0 ||
            sfd_gt_camera_pose(&P, &ext, R, pc) != 0) {
            std::fprintf(stderr, "sfd-sim: %s: cannot interpolate the pose at %" PRId64 " ns\n",
                         gt_path.c_str(), t_ns);
            return 2;
        }
        if (f == 0) first_pose = P;
        if (f % info_every == 0) {
            ci.utime = utime;
            log.write("CAMERA_INFO", utime, buf,
                      sfd_camera_info_t_encode(buf.data(), 0, int(buf.size()), &ci));
        }
        // The moving group's velocity: a new horizontal direction every 2 s.
        const int epoch = int(double(t_ns - t_begin) * 1e-9 / 2.0);
        if (epoch != mover_epoch) {
            mover_epoch = epoch;
            const double heading = 2.0 * kPi * sfd_prng_uniform(&rng);
            mover_v[0] = opt.mover_speed_m_s * std::cos(heading);
            mover_v[1] = opt.mover_speed_m_s * std::sin(heading);
        }
        const double dt = double(period_ns) * 1e-9;
        std::memset(&ff, 0, sizeof ff);
        std::memset(&tr, 0, sizeof tr);
        ff.utime = utime;
        ff.camera_id = 0;
        tr.utime = utime;
        std::memcpy(tr.position, P.p_IinW_m, sizeof tr.position);
        std::memcpy(tr.orientation, P.q_ItoW, sizeof tr.orientation);
        int k = 0;
        for (Track &T : tracks) {
            // Draws in a fixed order per track and frame (determinism).
            const double u_loss = sfd_prng_uniform(&rng);
            const double u_event = sfd_prng_uniform(&rng);
            const double u_kind = sfd_prng_uniform(&rng);
            const double u_dir = sfd_prng_uniform(&rng);
            const double u_r = sfd_prng_uniform(&rng);
            const double n_u = sfd_prng_gaussian(&rng), n_v = sfd_prng_gaussian(&rng);
            const double n_d = sfd_prng_gaussian(&rng);
            bool fresh = false;
            if (!T.alive || (f > 0 && u_loss < opt.track_loss)) {
                spawn(T, R, pc);
                fresh = true;
            }
            if (!T.alive) {
                ++n_dropped;
                continue;
            }
            if (T.mover && f > 0) {
                for (int a = 0; a < 3; ++a) T.p_W[a] += mover_v[a] * dt;
            }
            double uv[2], depth = 0.0;
            bool vis = sfd_gt_project(&cam, R, pc, T.p_W, uv, &depth) != 0;
            const double ang = 2.0 * kPi * u_dir;
            if (vis && !fresh && !T.mover && u_event < p_event) {
                if (u_kind < 1.0 / 3.0) {
                    // Jump: onto the room's point jump_px away from where the tracker is (either
                    // side), followed for good with its own depth; a slide in progress ends.
                    const double at[2] = {uv[0] + T.off_px[0], uv[1] + T.off_px[1]};
                    if (step_onto(at, opt.jump_px, ang, R, pc, T.p_W)) {
                        T.off_px[0] = T.off_px[1] = 0.0;
                        T.drift_left = 0;
                        T.last_step = f;
                        T.last_kind = SFD_TRUTH_T_KIND_JUMP;
                        ++n_mistrack;
                    }
                    vis = sfd_gt_project(&cam, R, pc, T.p_W, uv, &depth) != 0;
                } else if (u_kind < 2.0 / 3.0) {  // drift, from this frame on
                    T.drift_px[0] = opt.drift_px * std::cos(ang);
                    T.drift_px[1] = opt.drift_px * std::sin(ang);
                    T.drift_left = opt.drift_frames;
                    ++n_mistrack;
                } else {  // mismatch: another point 15-60 px away
                    if (step_onto(uv, 15.0 + 45.0 * u_r, ang, R, pc, T.p_W)) {
                        T.last_step = f;
                        T.last_kind = SFD_TRUTH_T_KIND_MISMATCH;
                        ++n_mismatch_events;
                    }
                    vis = sfd_gt_project(&cam, R, pc, T.p_W, uv, &depth) != 0;
                }
            }
            if (T.drift_left > 0) {
                T.off_px[0] += T.drift_px[0];
                T.off_px[1] += T.drift_px[1];
                T.drift_left--;
                T.last_step = f;
                T.last_kind = SFD_TRUTH_T_KIND_DRIFT;
                if (T.drift_left == 0 && vis) {
                    // The slide ends: the track locks onto the room's point under the slid pixel,
                    // followed for good with its own depth (left out of view: replaced below).
                    const double at[2] = {uv[0] + T.off_px[0], uv[1] + T.off_px[1]};
                    double p2[3];
                    if (at[0] >= 0 && at[0] < cam.width_px && at[1] >= 0 && at[1] < cam.height_px &&
                        cast(at, R, pc, p2)) {
                        std::memcpy(T.p_W, p2, sizeof p2);
                        T.off_px[0] = T.off_px[1] = 0.0;
                        vis = sfd_gt_project(&cam, R, pc, T.p_W, uv, &depth) != 0;
                    }
                }
            }
            double u = uv[0] + T.off_px[0], v = uv[1] + T.off_px[1];
            if (!vis || u < 0 || u >= cam.width_px || v < 0 || v >= cam.height_px) {
                // Out of view: a new track takes the slot (no event on it this frame).
                spawn(T, R, pc);
                if (!T.alive || !sfd_gt_project(&cam, R, pc, T.p_W, uv, &depth)) {
                    ++n_dropped;
                    continue;
                }
                u = uv[0];
                v = uv[1];
            }
            ff.track_id[k] = T.id;
            ff.u[k] = u + opt.pixel_sigma_px * n_u;
            ff.v[k] = v + opt.pixel_sigma_px * n_v;
            const double zhat = depth + std::sqrt(opt.depth_var_m2) * n_d;
            ff.depth[k] = zhat > 0.1 ? zhat : 0.1;
            ff.depth_var[k] = opt.depth_var_m2;
            const bool spurious = T.mover || (f - T.last_step < opt.truth_window);
            tr.track_id[k] = T.id;
            tr.spurious[k] = spurious ? 1 : 0;
            tr.kind[k] = T.mover ? SFD_TRUTH_T_KIND_MOVING
                                 : (spurious ? T.last_kind : SFD_TRUTH_T_KIND_CLEAN);
            n_spurious += spurious;
            n_mover += T.mover;
            ++n_total;
            ++k;
        }
        ff.num_features = k;
        tr.num_features = k;
        log.write("FEATURES", utime, buf,
                  sfd_feature_frame_t_encode(buf.data(), 0, int(buf.size()), &ff));
        log.write("TRUTH", utime, buf, sfd_truth_t_encode(buf.data(), 0, int(buf.size()), &tr));
    }
    write_imu_until(t_end);
    if (!log.finish()) {
        std::fprintf(stderr, "sfd-sim: -o %s\n", log.error().c_str());
        return 1;
    }
    const GtRow &g0 = gt[g_first];
    if (!opt.config_out.empty()) {
        FILE *c = std::fopen(opt.config_out.c_str(), "w");
        if (c == nullptr) {
            std::fprintf(stderr, "sfd-sim: --config-out: cannot write %s\n",
                         opt.config_out.c_str());
            return 2;
        }
        std::fprintf(c,
                     "%%YAML:1.0\n---\n"
                     "# sfd-replay configuration for %s (written by sfd-sim euroc-semireal).\n"
                     "# The simulated pixel noise.\n"
                     "pixel_sigma_px: %.17g\n"
                     "# The ground truth's gyro bias estimate (b_w) at the log's start: the\n"
                     "# filter's initial gyro bias when it starts from TRUTH.\n"
                     "gyro_bias_rad_s: [ %.17g, %.17g, %.17g ]\n"
                     "filter:\n"
                     "   # The filter starts from the first two TRUTH poses (evaluation only).\n"
                     "   init_from_truth: 1\n"
                     "   # The ground truth's accelerometer bias estimate (b_a) at the start.\n"
                     "   init_accel_bias_m_s2: [ %.17g, %.17g, %.17g ]\n",
                     opt.out_path.c_str(), opt.pixel_sigma_px, g0.bw[0], g0.bw[1], g0.bw[2],
                     g0.ba[0], g0.ba[1], g0.ba[2]);
        if (std::fclose(c) != 0) {
            std::fprintf(stderr, "sfd-sim: --config-out: writing %s failed\n",
                         opt.config_out.c_str());
            return 1;
        }
    }
    std::printf(
        "sfd-sim euroc-semireal: wrote %s: %d frames at %g Hz over %.3f s (IMU/ground-truth "
        "overlap %" PRId64 "..%" PRId64
        " ns), %lld IMU samples, %.1f features per frame, "
        "%.2f%% spurious (moving group %.2f%%, %ld mistracks, %ld mismatches), %ld slots left "
        "empty (seed %llu)\n",
        opt.out_path.c_str(), frames, opt.camera_hz, double(t_end - t_begin) * 1e-9, t_begin, t_end,
        static_cast<long long>(imu_written), double(n_total) / frames,
        100.0 * double(n_spurious) / double(n_total ? n_total : 1),
        100.0 * double(n_mover) / double(n_total ? n_total : 1), n_mistrack, n_mismatch_events,
        n_dropped, static_cast<unsigned long long>(opt.seed));
    std::printf(
        "  room x %.2f..%.2f y %.2f..%.2f z %.2f..%.2f m; start p %.3f %.3f %.3f m; "
        "ground-truth b_w %.6f %.6f %.6f rad/s, b_a %.6f %.6f %.6f m/s^2\n",
        room_lo[0], room_hi[0], room_lo[1], room_hi[1], room_lo[2], room_hi[2],
        first_pose.p_IinW_m[0], first_pose.p_IinW_m[1], first_pose.p_IinW_m[2], g0.bw[0], g0.bw[1],
        g0.bw[2], g0.ba[0], g0.ba[1], g0.ba[2]);
    return 0;
}

}  // namespace sfdsim
