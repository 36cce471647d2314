// SPDX-License-Identifier: MIT
// Simulated flight logs for sfd-replay / sfd-node (SPEC "sfd-sim").
//
// Trajectory (continuous time, so that IMU samples are consistent with it): the IMU flies at
// 5 m/s along x at 58 m (paper-uav) or 20 m (other scenarios) over flat ground (z = 0), with
// roll/pitch oscillating +-3 deg and a 0.1 rad/s yaw rate. The camera looks down: T_imu_cam has
// R = diag(1, -1, -1) and a 5 cm offset. IMU at 200 Hz: gyro = body rate + white noise + bias,
// accel = specific force. Camera: EuRoC cam0 intrinsics and radial-tangential distortion, 20 Hz.
// Landmarks lie on the ground; one leaving the image is replaced by a new one (new track id).
// Spurious features (TRUTH spurious = 1):
//  - paper-uav: each frame, a fraction outlier_ratio / (truth_window - 1) of the tracks get the
//    paper's fault k(-1, 1)^T (normalized coordinates) added from that frame on;
//  - mistracking: the same with a jump of jump_px in a random direction;
//  - moving-object: 10% of the landmarks move on the ground at 3 m/s (spurious in every frame),
//    plus mistracking at outlier_ratio;
//  - worst-case (the node at full capacity, for sfd-hil): the mistracking flight without
//    mistracks, in which every frame round(random_fraction * n) of the features, drawn at random,
//    are replaced by pixels uniform over the image (keeping their track ids; spurious). At
//    random_fraction = 1 every match is an outlier: RANSAC-type methods exhaust their hypothesis
//    budget and every parity group fails.
// A mistracked track follows a wrong point from the jump on; it is labelled spurious in the
// truth_window frames starting at the jump: for a detector window of L frames, the L - 1 frames
// whose window mixes observations of both points (default 2, for L = 3).
#include "flight_log.hpp"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <vector>

#include "lcm_log.hpp"
#include "sfd/sfd.h"
#include "sfd_camera_info_t.h"
#include "sfd_feature_frame_t.h"
#include "sfd_imu_t.h"
#include "sfd_sim_math.h"
#include "sfd_truth_t.h"

namespace sfdsim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kG = 9.81;

struct Pose {
    double R_BtoW[9];
    double p[3];
};

struct Trajectory {
    double altitude = 58.0;
    double speed = 5.0;
    Pose at(double t) const {
        Pose P;
        const double roll = 3.0 * kPi / 180.0 * std::sin(2.0 * kPi * 0.5 * t);
        const double pitch = 3.0 * kPi / 180.0 * std::sin(2.0 * kPi * 0.3 * t);
        const double yaw = 0.1 * t;
        const double ez[3] = {0, 0, yaw}, ey[3] = {0, pitch, 0}, ex[3] = {roll, 0, 0};
        double Ry[9], Rp[9], Rr[9], T[9];
        sfd_so3_exp(ez, Ry);
        sfd_so3_exp(ey, Rp);
        sfd_so3_exp(ex, Rr);
        sfd_sim_mat3_mul(Ry, Rp, T);
        sfd_sim_mat3_mul(T, Rr, P.R_BtoW);
        P.p[0] = speed * t;
        P.p[1] = 2.0 * std::sin(0.2 * t);
        P.p[2] = altitude + 0.5 * std::sin(0.3 * t);
        return P;
    }
    void accel_world(double t, double a[3]) const {
        a[0] = 0.0;
        a[1] = -2.0 * 0.04 * std::sin(0.2 * t);
        a[2] = -0.5 * 0.09 * std::sin(0.3 * t);
    }
    void body_rate(double t, double w[3]) const {
        const double h = 1e-5;
        const Pose a = at(t - h), b = at(t + h);
        double dR[9];
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) {
                double s = 0;
                for (int k = 0; k < 3; ++k) s += a.R_BtoW[3 * k + r] * b.R_BtoW[3 * k + c];
                dR[3 * r + c] = s;
            }
        double phi[3];
        sfd_so3_log(dR, phi);
        for (int k = 0; k < 3; ++k) w[k] = phi[k] / (2.0 * h);
    }
};

struct Landmark {
    double p[3];
    double vel[3];
    int64_t track_id;
    double offset_px[2];  // accumulated mistrack offset
    int64_t last_jump_frame;
    bool mover;
};

}  // namespace

bool is_flight_scenario(const std::string &scenario) {
    return scenario == "paper-uav" || scenario == "mistracking" || scenario == "moving-object" ||
           scenario == "worst-case";
}

namespace {

// Per-frame message storage (~25 KB), heap-allocated once per flight.
struct FrameBuffers {
    sfd_feature_frame_t ff;
    sfd_truth_t tr;
    std::vector<uint8_t> buf = std::vector<uint8_t>(size_t{64} * 1024);
};

}  // namespace

int generate_flight(const FlightOptions &opt, FlightSink &sink, FlightStats *stats) {
    FlightStats local;
    FlightStats &st = stats != nullptr ? *stats : local;
    st = FlightStats{};
    if (!is_flight_scenario(opt.scenario)) return 2;
    const bool paper = opt.scenario == "paper-uav";
    const bool moving = opt.scenario == "moving-object";
    const bool worst = opt.scenario == "worst-case";
    Trajectory traj;
    traj.altitude = paper ? 58.0 : 20.0;
    sfd_prng_t rng;
    sfd_prng_seed(&rng, opt.seed);
    sfd_camera_t cam;
    const double dist[4] = {-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05};
    sfd_camera_init(&cam, SFD_DISTORTION_RADTAN, 752, 480, 458.654, 457.296, 367.215, 248.375,
                    dist);
    const double R_CtoB[9] = {1, 0, 0, 0, -1, 0, 0, 0, -1};
    const double p_CinB[3] = {0.05, 0.0, -0.02};

    std::unique_ptr<FrameBuffers> fb(new FrameBuffers);
    std::vector<uint8_t> &buf = fb->buf;
    bool encode_failed = false;
    // Encoded size n of the message in buf to the sink; false: stop (encode failure or the sink).
    auto emit = [&](const char *channel, int64_t utime, int n) {
        if (n < 0) {
            encode_failed = true;
            return false;
        }
        if (!sink.message(channel, utime, buf.data(), n)) {
            st.stopped = true;
            return false;
        }
        return true;
    };
    const int64_t t_start_us = 1000000;

    // CAMERA_INFO first (and once per second, as a live publisher would).
    double T_imu_cam[16] = {0};
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) T_imu_cam[4 * r + c] = R_CtoB[3 * r + c];
        T_imu_cam[4 * r + 3] = p_CinB[r];
    }
    T_imu_cam[15] = 1.0;
    sfd_camera_info_t ci = camera_info_of(cam, T_imu_cam);

    auto camera_pose = [&](double t, double R_CtoW[9], double p_CinW[3]) {
        const Pose P = traj.at(t);
        sfd_sim_mat3_mul(P.R_BtoW, R_CtoB, R_CtoW);
        for (int r = 0; r < 3; ++r) {
            p_CinW[r] = P.p[r];
            for (int k = 0; k < 3; ++k) p_CinW[r] += P.R_BtoW[3 * r + k] * p_CinB[k];
        }
    };
    auto project = [&](const Landmark &L, double t, double uv[2], double *depth) {
        double R[9], p[3], c[3];
        camera_pose(t, R, p);
        for (int r = 0; r < 3; ++r) {
            c[r] = 0;
            for (int k = 0; k < 3; ++k) c[r] += R[3 * k + r] * (L.p[k] - p[k]);
        }
        *depth = c[2];
        if (sfd_camera_project(&cam, c, uv, nullptr) != SFD_OK) return false;
        return uv[0] >= 0 && uv[0] < cam.width_px && uv[1] >= 0 && uv[1] < cam.height_px;
    };
    int64_t next_id = 1;
    auto spawn = [&](Landmark &L, double t) {
        // A random pixel of the current view, cast to the ground plane.
        double R[9], p[3];
        camera_pose(t, R, p);
        for (int tries = 0; tries < 32; ++tries) {
            const double uv[2] = {20.0 + 712.0 * sfd_prng_uniform(&rng),
                                  20.0 + 440.0 * sfd_prng_uniform(&rng)};
            double ray[3];
            if (sfd_camera_unproject(&cam, uv, ray) != SFD_OK) continue;
            double d[3];
            for (int r = 0; r < 3; ++r) {
                d[r] = 0;
                for (int k = 0; k < 3; ++k) d[r] += R[3 * r + k] * ray[k];
            }
            if (d[2] > -0.1) continue;
            const double s = -p[2] / d[2];
            for (int r = 0; r < 3; ++r) L.p[r] = p[r] + s * d[r];
            L.p[2] = 0.0;
            break;
        }
        L.track_id = next_id++;
        L.offset_px[0] = L.offset_px[1] = 0.0;
        L.last_jump_frame = -1000000;
        L.mover = moving && sfd_prng_uniform(&rng) < 0.1;
        const double heading = 2.0 * kPi * sfd_prng_uniform(&rng);
        L.vel[0] = L.mover ? 3.0 * std::cos(heading) : 0.0;
        L.vel[1] = L.mover ? 3.0 * std::sin(heading) : 0.0;
        L.vel[2] = 0.0;
    };
    const int features = opt.features > 0 ? opt.features : (worst ? SFD_MAX_FEATURES : 200);
    const int n_feat = std::min(features, SFD_FEATURE_FRAME_T_CAPACITY);
    std::vector<Landmark> lms(static_cast<size_t>(n_feat));
    for (auto &L : lms) spawn(L, 0.0);

    const double dt_imu = 0.005, dt_cam = 0.05;
    const double sigma_g = opt.gyro_noise / std::sqrt(dt_imu);
    const double p_jump = worst ? 0.0 : opt.outlier_ratio / std::max(1, opt.truth_window - 1);
    sfd_feature_frame_t &ff = fb->ff;
    sfd_truth_t &tr = fb->tr;
    std::vector<int> order(lms.size());  // worst-case: the features replaced this frame
    int64_t imu_index = 0;
    long n_spurious = 0, n_total = 0;
    for (int f = 0; f < opt.frames; ++f) {
        const double t_frame = f * dt_cam;
        // IMU samples up to (and including) this frame's time.
        for (; imu_index * dt_imu <= t_frame + 1e-9; ++imu_index) {
            const double t = imu_index * dt_imu;
            sfd_imu_t m;
            m.utime = t_start_us + imu_index * 5000;
            double w[3], a[3];
            traj.body_rate(t, w);
            traj.accel_world(t, a);
            const Pose P = traj.at(t);
            const double f_W[3] = {a[0], a[1], a[2] + kG};  // specific force = a - g, g = -9.81 z
            for (int r = 0; r < 3; ++r) {
                m.gyro[r] = w[r] + opt.gyro_bias[r] + sigma_g * sfd_prng_gaussian(&rng);
                m.accel[r] = 0.0;
                for (int k = 0; k < 3; ++k) m.accel[r] += P.R_BtoW[3 * k + r] * f_W[k];
            }
            const int n = sfd_imu_t_encode(buf.data(), 0, int(buf.size()), &m);
            if (!emit("IMU", m.utime, n)) break;
        }
        if (encode_failed || st.stopped) break;
        const int64_t utime = t_start_us + int64_t(f) * 50000;
        if (f % 20 == 0) {
            ci.utime = utime;
            const int n = sfd_camera_info_t_encode(buf.data(), 0, int(buf.size()), &ci);
            if (!emit("CAMERA_INFO", utime, n)) break;
        }
        std::memset(&ff, 0, sizeof ff);
        std::memset(&tr, 0, sizeof tr);
        ff.utime = utime;
        ff.camera_id = 0;
        tr.utime = utime;
        const Pose P = traj.at(t_frame);
        std::memcpy(tr.position, P.p, sizeof P.p);
        sfd_rotmat_to_quat(P.R_BtoW, tr.orientation);
        int k = 0;
        for (auto &L : lms) {
            for (int r = 0; r < 3; ++r) L.p[r] += (f > 0 ? dt_cam : 0.0) * L.vel[r];
            double uv[2], depth = 0;
            if (!project(L, t_frame, uv, &depth)) {
                spawn(L, t_frame);
                if (!project(L, t_frame, uv, &depth)) continue;
            }
            if (f > 0 && sfd_prng_uniform(&rng) < p_jump) {
                if (paper) {
                    L.offset_px[0] += -opt.fault_magnitude * cam.fx_px;
                    L.offset_px[1] += opt.fault_magnitude * cam.fy_px;
                } else {
                    const double ang = 2.0 * kPi * sfd_prng_uniform(&rng);
                    L.offset_px[0] += opt.jump_px * std::cos(ang);
                    L.offset_px[1] += opt.jump_px * std::sin(ang);
                }
                L.last_jump_frame = f;
            }
            ff.track_id[k] = L.track_id;
            ff.u[k] = uv[0] + L.offset_px[0] + opt.pixel_noise_px * sfd_prng_gaussian(&rng);
            ff.v[k] = uv[1] + L.offset_px[1] + opt.pixel_noise_px * sfd_prng_gaussian(&rng);
            double zhat = depth;
            if (opt.depth_var > 0.0) zhat += std::sqrt(opt.depth_var) * sfd_prng_gaussian(&rng);
            ff.depth[k] = zhat > 0.1 ? zhat : 0.1;
            ff.depth_var[k] = opt.depth_var;
            tr.track_id[k] = L.track_id;
            const bool spurious = L.mover || (f - L.last_jump_frame < opt.truth_window);
            tr.spurious[k] = spurious ? 1 : 0;
            tr.kind[k] = L.mover ? SFD_TRUTH_T_KIND_MOVING
                                 : (spurious ? SFD_TRUTH_T_KIND_JUMP : SFD_TRUTH_T_KIND_CLEAN);
            ++k;
        }
        if (worst) {
            // round(F * k) of this frame's features, drawn without replacement (partial
            // Fisher-Yates), move to uniformly random pixels: an outlier for every method.
            const int n_random = static_cast<int>(std::lround(opt.random_fraction * k));
            for (int i = 0; i < k; ++i) order[static_cast<size_t>(i)] = i;
            for (int i = 0; i < n_random; ++i) {
                const int j =
                    i + std::min(k - 1 - i, static_cast<int>(sfd_prng_uniform(&rng) * (k - i)));
                std::swap(order[static_cast<size_t>(i)], order[static_cast<size_t>(j)]);
                const int m = order[static_cast<size_t>(i)];
                ff.u[m] = cam.width_px * sfd_prng_uniform(&rng);
                ff.v[m] = cam.height_px * sfd_prng_uniform(&rng);
                tr.spurious[m] = 1;
                tr.kind[m] = SFD_TRUTH_T_KIND_MISMATCH;
            }
        }
        for (int i = 0; i < k; ++i) n_spurious += tr.spurious[i];
        n_total += k;
        ff.num_features = k;
        tr.num_features = k;
        int n = sfd_feature_frame_t_encode(buf.data(), 0, int(buf.size()), &ff);
        if (!emit("FEATURES", utime, n)) break;
        ++st.frames;
        n = sfd_truth_t_encode(buf.data(), 0, int(buf.size()), &tr);
        if (!emit("TRUTH", utime, n)) break;
    }
    st.imu = imu_index;
    st.features = n_total;
    st.spurious = n_spurious;
    return encode_failed ? 1 : 0;
}

namespace {

// The log file sink of sfd-sim -o.
class LogSink : public FlightSink {
  public:
    explicit LogSink(const std::string &path) : log_(path) {}
    bool ok() const { return log_.ok(); }
    bool message(const char *channel, int64_t utime, const uint8_t *data, int size) override {
        log_.write(channel, utime, data, size);
        return true;
    }

  private:
    LogWriter log_;
};

}  // namespace

int write_flight_log(const FlightOptions &opt) {
    if (!is_flight_scenario(opt.scenario)) {
        std::fprintf(stderr, "sfd-sim: -o: scenario %s writes no log\n", opt.scenario.c_str());
        return 2;
    }
    LogSink log(opt.out_path);
    if (!log.ok()) {
        std::fprintf(stderr, "sfd-sim: -o: cannot write %s\n", opt.out_path.c_str());
        return 2;
    }
    FlightStats st;
    const int rc = generate_flight(opt, log, &st);
    if (rc != 0 || !log.ok()) {
        std::fprintf(stderr, "sfd-sim: writing %s failed\n", opt.out_path.c_str());
        return 1;
    }
    std::printf(
        "sfd-sim %s: wrote %s: %d frames, %lld IMU samples, %.1f features per frame, "
        "%.1f%% spurious (seed %llu)\n",
        opt.scenario.c_str(), opt.out_path.c_str(), opt.frames, st.imu,
        double(st.features) / opt.frames,
        100.0 * double(st.spurious) / double(st.features ? st.features : 1),
        static_cast<unsigned long long>(opt.seed));
    return 0;
}

}  // namespace sfdsim
