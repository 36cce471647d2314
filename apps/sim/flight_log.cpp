// SPDX-License-Identifier: MIT
// Simulated flight logs for sfd-replay / sfd-node (SPEC "sfd-sim"; the model in detail, with
// measured fault fractions: apps/sim/SIMULATION.md).
//
// Trajectory (continuous time, so that IMU samples are consistent with it): rest_s seconds at
// rest (zero velocity and rate, gravity only), then a C2 ramp (quintic smooth step of the time
// warp's rate, ramp_s seconds) into the cruise: 5 m/s along x at 58 m (paper-uav) or 20 m (other
// scenarios), roll/pitch oscillating +-3 deg, a 0.1 rad/s yaw rate. Camera frames and TRUTH
// cover the rest too. The camera looks down: T_imu_cam has R = diag(1, -1, -1) and a 5 cm
// offset; EuRoC cam0 intrinsics and radial-tangential distortion, 20 Hz.
// IMU at 200 Hz: gyro = body rate + b_g + white noise, accel = specific force + b_a + white
// noise; white noise sigma = density / sqrt(dt) per sample, biases random walks b += rw sqrt(dt)
// N(0, 1) after each sample, initial biases given or drawn. A separate PRNG stream from the
// scene's (both from the seed).
// Scene: static points on the ground (paper-uav: flat ground; the others: half on the ground,
// half on structures up to 0.3 x altitude); a track whose point leaves the image is replaced by
// a new one (new track id). Frames list their tracks in id order (a tracker's creation order).
// Spurious features (TRUTH spurious = 1, kind[] says which fault):
//  - paper-uav: each frame, a fraction outlier_ratio / (truth_window - 1) of the tracks take the
//    paper's fault k(-1, 1)^T (normalized coordinates; -k fx, +k fy px) as a step onto the ground
//    point under the shifted pixel, followed for good (KIND_JUMP; until 2026-11 the offset was
//    added to the old point's projection and accumulated, so that observations labelled clean
//    after the label window matched no static point: apps/sim/SIMULATION.md);
//  - mistracking: static tracker faults, each kind a third of the labelled observations (events
//    drawn in inverse proportion to the frames they label): a jump onto another static point
//    5-30 px away (its own depth, followed for good), a drift of 0.3-2 px per frame for 3-10
//    frames that then locks onto the scene point under it, a one-frame mismatch with another
//    point 15-60 px away;
//  - moving-object: 2-4 rigid groups (walkers 1-2 m/s, vehicles 5-15 m/s) crossing the view,
//    half of outlier_ratio, spurious in every frame they are seen (KIND_MOVING), plus the static
//    tracker faults at the other half;
//  - worst-case (the node at full capacity, for sfd-hil): the mistracking flight without
//    faults, in which every frame round(random_fraction * n) of the features, drawn at random,
//    are replaced by pixels uniform over the image (keeping their track ids; KIND_MISMATCH). At
//    random_fraction = 1 every match is an outlier: RANSAC-type methods exhaust their hypothesis
//    budget and every parity group fails. A random pixel is a one-frame mismatch and labelled as
//    one: spurious in its frame and the W frames after it (the windows that contain it).
// Label windows: a step (jump, each drift step, each of a mismatch's two steps: away and back
// the next frame) labels the track spurious in the truth_window = W frames starting at the step,
// with the kind of its last step: for a detector window of L = W + 1 frames, exactly the frames
// whose window mixes observations from both sides of a step (default W = 2, for L = 3); a
// one-frame mismatch thus labels W + 1 frames, the L windows that contain it. A track locked
// onto a wrong static point is a consistent track of that point afterwards, and clean (as
// euroc-semireal labels it). Moving points are spurious in every frame they are seen.
#include "flight_log.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <unordered_map>
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

// Fault model constants (apps/sim/SIMULATION.md).
constexpr double kJumpMinPx = 5.0, kJumpMaxPx = 30.0;     // jump: the new point's distance
constexpr double kDriftMinPx = 0.3, kDriftMaxPx = 2.0;    // drift: px per frame
constexpr int kDriftMinFrames = 3, kDriftMaxFrames = 10;  // drift: frames of sliding
constexpr double kMismatchMinPx = 15.0, kMismatchMaxPx = 60.0;
constexpr double kMarginPx = 10.0;  // targets of jumps/mismatches stay this far inside the image
// Scene relief (all scenarios but paper-uav): half the static points lie on the ground, half on
// structures up to this fraction of the altitude (roofs, trees).
constexpr double kReliefFraction = 0.3;
// Initial IMU biases when not given: per-axis standard deviations.
constexpr double kGyroBias0Sigma = 0.002;  // rad/s
constexpr double kAccelBias0Sigma = 0.02;  // m/s^2

struct Pose {
    double R_BtoW[9];
    double p[3];
};

// The flight: a rest of rest_s seconds, then the cruise trajectory shape(tau) entered through a
// time warp tau(t) whose rate tau'(t) rises from 0 to 1 over ramp_s seconds along the quintic
// smooth step s(x) = 10x^3 - 15x^4 + 6x^5 (s, s' and s'' continuous, s'(0) = s'(1) = 0 =
// s''(0) = s''(1)). tau = ramp_s S(x), S(x) = x^4 (2.5 - 3x + x^2) (S' = s), tau = t - rest_s -
// ramp_s / 2 after the ramp. Position p(tau(t)), velocity p' tau', acceleration p'' tau'^2 +
// p' tau'': all continuous, zero velocity, rate and acceleration during the rest.
struct Trajectory {
    double altitude = 58.0;
    double speed = 5.0;
    double rest_s = 2.0;
    double ramp_s = 3.0;
    // tau, tau', tau'' at time t.
    void warp(double t, double w[3]) const {
        if (rest_s <= 0.0) {
            w[0] = t;
            w[1] = 1.0;
            w[2] = 0.0;
            return;
        }
        const double x = (t - rest_s) / ramp_s;
        if (x <= 0.0) {
            w[0] = w[1] = w[2] = 0.0;
        } else if (x >= 1.0) {
            w[0] = ramp_s * (x - 0.5);
            w[1] = 1.0;
            w[2] = 0.0;
        } else {
            w[0] = ramp_s * x * x * x * x * (2.5 - 3.0 * x + x * x);
            w[1] = x * x * x * (10.0 - 15.0 * x + 6.0 * x * x);
            w[2] = 30.0 * x * x * (1.0 - x) * (1.0 - x) / ramp_s;
        }
    }
    // The cruise: speed m/s along x, lateral and vertical sways, roll/pitch +-3 deg, yaw 0.1 rad/s.
    Pose shape(double tau) const {
        Pose P;
        const double roll = 3.0 * kPi / 180.0 * std::sin(2.0 * kPi * 0.5 * tau);
        const double pitch = 3.0 * kPi / 180.0 * std::sin(2.0 * kPi * 0.3 * tau);
        const double yaw = 0.1 * tau;
        const double ez[3] = {0, 0, yaw}, ey[3] = {0, pitch, 0}, ex[3] = {roll, 0, 0};
        double Ry[9], Rp[9], Rr[9], T[9];
        sfd_so3_exp(ez, Ry);
        sfd_so3_exp(ey, Rp);
        sfd_so3_exp(ex, Rr);
        sfd_sim_mat3_mul(Ry, Rp, T);
        sfd_sim_mat3_mul(T, Rr, P.R_BtoW);
        P.p[0] = speed * tau;
        P.p[1] = 2.0 * std::sin(0.2 * tau);
        P.p[2] = altitude + 0.5 * std::sin(0.3 * tau);
        return P;
    }
    Pose at(double t) const {
        double w[3];
        warp(t, w);
        return shape(w[0]);
    }
    void accel_world(double t, double a[3]) const {
        double w[3];
        warp(t, w);
        const double tau = w[0];
        const double v[3] = {speed, 0.4 * std::cos(0.2 * tau), 0.15 * std::cos(0.3 * tau)};
        const double acc[3] = {0.0, -0.08 * std::sin(0.2 * tau), -0.045 * std::sin(0.3 * tau)};
        for (int k = 0; k < 3; ++k) a[k] = acc[k] * w[1] * w[1] + v[k] * w[2];
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

// A track of a static scene point (paper-uav, mistracking, moving-object, worst-case).
struct Track {
    double p[3];         // the static point the track follows (m, world)
    int64_t id;          // track id
    double off_px[2];    // pixel offset from p's projection (a drift's slide)
    double drift_px[2];  // drift step (px per frame)
    int drift_left;      // drift steps still to come
    bool mismatch_back;  // a mismatch last frame: the track returns to p in this frame
    int64_t last_step;   // frame of the last step (jump, drift step, mismatch)
    int8_t last_kind;    // its TRUTH kind
    bool lost;           // pushed out of the image: replaced by a new track next frame
};

// A point of a moving group (rigid, translating with the group).
struct MovingPoint {
    double off[3];  // from the group's centre (m, world)
    int64_t id;     // track id while in view; a new one each time it enters the image
    bool in_view;
};

struct Group {
    double c[3];  // centre (m, world)
    double v[3];  // velocity (m/s, horizontal)
    std::vector<MovingPoint> pts;
    bool seen;   // some point was in view since the spawn
    int unseen;  // frames since the spawn, or since a point was last in view
};

// One observation of a frame before it is written (the frame is sorted by track id, a tracker's
// creation order, so that moving points and steps do not gather at the end of the frame).
struct Obs {
    int64_t id;
    double u, v, depth;
    int8_t kind;
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
    traj.rest_s = std::max(0.0, opt.rest_s);
    traj.ramp_s = std::max(0.1, opt.ramp_s);
    // Two streams: the scene and its faults, and the IMU's noise (changing the IMU options
    // leaves the features unchanged, and the other way round).
    sfd_prng_t rng, rng_imu;
    sfd_prng_seed(&rng, opt.seed);
    sfd_prng_seed(&rng_imu, opt.seed ^ 0x494d55494d55494dULL);
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

    // Camera pose of the frame being made (world <- camera).
    double R_cw[9], p_cw[3];
    auto set_camera_pose = [&](double t) {
        const Pose P = traj.at(t);
        sfd_sim_mat3_mul(P.R_BtoW, R_CtoB, R_cw);
        for (int r = 0; r < 3; ++r) {
            p_cw[r] = P.p[r];
            for (int k = 0; k < 3; ++k) p_cw[r] += P.R_BtoW[3 * r + k] * p_CinB[k];
        }
    };
    // Pixel and depth (camera z) of a world point; false when outside the image or behind.
    auto project = [&](const double pw[3], double uv[2], double *depth) {
        double c[3];
        for (int r = 0; r < 3; ++r) {
            c[r] = 0;
            for (int k = 0; k < 3; ++k) c[r] += R_cw[3 * k + r] * (pw[k] - p_cw[k]);
        }
        *depth = c[2];
        if (c[2] <= 0.1 || sfd_camera_project(&cam, c, uv, nullptr) != SFD_OK) return false;
        return uv[0] >= 0 && uv[0] < cam.width_px && uv[1] >= 0 && uv[1] < cam.height_px;
    };
    auto inside = [&](const double uv[2], double margin) {
        return uv[0] >= margin && uv[0] < cam.width_px - margin && uv[1] >= margin &&
               uv[1] < cam.height_px - margin;
    };
    // The point at height z seen at pixel uv; false if the ray does not reach it.
    auto cast = [&](const double uv[2], double z, double out[3]) {
        double ray[3], d[3];
        if (sfd_camera_unproject(&cam, uv, ray) != SFD_OK) return false;
        for (int r = 0; r < 3; ++r) {
            d[r] = 0;
            for (int k = 0; k < 3; ++k) d[r] += R_cw[3 * r + k] * ray[k];
        }
        if (d[2] > -0.1) return false;
        const double s = (z - p_cw[2]) / d[2];
        if (!(s > 0.5)) return false;
        for (int r = 0; r < 3; ++r) out[r] = p_cw[r] + s * d[r];
        out[2] = z;
        return true;
    };
    // Height of a new static scene point: flat ground for paper-uav, else relief.
    const double relief_m = paper ? 0.0 : kReliefFraction * traj.altitude;
    auto scene_height = [&]() {
        if (relief_m <= 0.0) return 0.0;
        const double u = sfd_prng_uniform(&rng);
        return u < 0.5 ? 0.0 : relief_m * 2.0 * (u - 0.5);
    };
    // The static scene point at pixel uv (a new height drawn).
    auto scene_point = [&](const double uv[2], double out[3]) {
        return cast(uv, scene_height(), out);
    };
    int64_t next_id = 1;
    auto spawn = [&](Track &T) {
        // A random pixel of the current view, cast onto the scene.
        for (int tries = 0; tries < 32; ++tries) {
            const double uv[2] = {20.0 + (cam.width_px - 40.0) * sfd_prng_uniform(&rng),
                                  20.0 + (cam.height_px - 40.0) * sfd_prng_uniform(&rng)};
            if (scene_point(uv, T.p)) break;
        }
        T.id = next_id++;
        T.off_px[0] = T.off_px[1] = 0.0;
        T.drift_px[0] = T.drift_px[1] = 0.0;
        T.drift_left = 0;
        T.mismatch_back = false;
        T.last_step = -1000000;
        T.last_kind = SFD_TRUTH_T_KIND_CLEAN;
        T.lost = false;
    };
    // A moving group entering the view: a walker group (3-5 points in 2 x 2 x 1.8 m, 1-2 m/s) or
    // a vehicle (5-10 points in 4.5 x 1.8 x 1.5 m, 5-15 m/s), starting 1 m outside the image edge
    // on the ground and heading toward the image centre +-45 deg.
    auto spawn_group = [&](Group &G) {
        const bool vehicle = sfd_prng_uniform(&rng) < 0.5;
        const int n = vehicle ? 5 + int(sfd_prng_uniform_index(&rng, 6))
                              : 3 + int(sfd_prng_uniform_index(&rng, 3));
        const double speed =
            vehicle ? 5.0 + 10.0 * sfd_prng_uniform(&rng) : 1.0 + sfd_prng_uniform(&rng);
        const double len = vehicle ? 4.5 : 2.0, wid = vehicle ? 1.8 : 2.0,
                     hgt = vehicle ? 1.5 : 1.8;
        const double W = cam.width_px, H = cam.height_px;
        const double s = 2.0 * (W + H) * sfd_prng_uniform(&rng);
        double uv[2];
        if (s < W) {
            uv[0] = s, uv[1] = 1.0;
        } else if (s < W + H) {
            uv[0] = W - 1.0, uv[1] = s - W;
        } else if (s < 2.0 * W + H) {
            uv[0] = s - W - H, uv[1] = H - 1.0;
        } else {
            uv[0] = 1.0, uv[1] = s - 2.0 * W - H;
        }
        const double centre_uv[2] = {0.5 * W, 0.5 * H};
        double cc[3] = {0, 0, 0};
        G.c[0] = G.c[1] = G.c[2] = 0.0;
        cast(uv, 0.0, G.c);
        cast(centre_uv, 0.0, cc);
        const double heading =
            std::atan2(cc[1] - G.c[1], cc[0] - G.c[0]) + 0.5 * kPi * (sfd_prng_uniform(&rng) - 0.5);
        const double dir[3] = {std::cos(heading), std::sin(heading), 0.0};
        const double perp[3] = {-dir[1], dir[0], 0.0};
        for (int k = 0; k < 3; ++k) {
            G.c[k] -= 1.0 * dir[k];
            G.v[k] = speed * dir[k];
        }
        G.pts.assign(static_cast<size_t>(n), MovingPoint{});
        for (MovingPoint &m : G.pts) {
            const double a = len * (sfd_prng_uniform(&rng) - 0.5);
            const double b = wid * (sfd_prng_uniform(&rng) - 0.5);
            const double z = hgt * sfd_prng_uniform(&rng);
            for (int k = 0; k < 3; ++k) m.off[k] = a * dir[k] + b * perp[k];
            m.off[2] = z;
            m.id = 0;
            m.in_view = false;
        }
        G.seen = false;
        G.unseen = 0;
        ++st.events[SFD_TRUTH_T_KIND_MOVING];
    };

    const int features = opt.features > 0 ? opt.features : (worst ? SFD_MAX_FEATURES : 200);
    const int n_feat = std::min(features, SFD_FEATURE_FRAME_T_CAPACITY);
    // Spurious budget: moving-object gives half of outlier_ratio to its moving groups (their
    // points replace as many static tracks) and half to the static tracks' faults.
    const double ratio = worst ? 0.0 : std::min(0.9, std::max(0.0, opt.outlier_ratio));
    const double moving_share = moving ? 0.5 * ratio : 0.0;
    const int n_moving_slots = int(std::lround(moving_share * n_feat));
    const int n_groups =
        moving_share > 0.0 ? std::min(4, std::max(2, int(std::lround(n_moving_slots / 4.0)))) : 0;
    const int n_static = std::max(1, n_feat - n_moving_slots);
    // Static faults: a fraction rho of the static observations labelled, a third per kind. An
    // event labels F_k frames: a jump W, a drift of D steps D + W - 1 (mean D = 6.5), a mismatch
    // (there and back) W + 1; kind k is drawn with probability P_k proportional to 1 / F_k (equal
    // labelled shares), so an event labels F = sum P_k F_k = 3 / sum(1 / F_k) frames on average,
    // and an event per clean observation with probability p labels rho = (1 - rho) p F.
    const int W = std::max(1, opt.truth_window);
    const double rho = moving ? (ratio - moving_share) / std::max(0.1, 1.0 - moving_share) : ratio;
    const double mean_drift = 0.5 * (kDriftMinFrames + kDriftMaxFrames);
    const double inv_f[3] = {1.0 / W, 1.0 / (mean_drift + W - 1.0), 1.0 / (W + 1.0)};
    const double inv_sum = inv_f[0] + inv_f[1] + inv_f[2];
    const double p_jump = inv_f[0] / inv_sum, p_drift = inv_f[1] / inv_sum;
    const double frames_per_event = 3.0 / inv_sum;
    const double p_event =
        paper ? ratio / std::max(1, W - 1) : rho / (std::max(0.1, 1.0 - rho) * frames_per_event);

    std::vector<Track> tracks(static_cast<size_t>(n_static));
    std::vector<Group> groups(static_cast<size_t>(n_groups));
    set_camera_pose(0.0);
    for (Track &T : tracks) spawn(T);
    for (Group &G : groups) spawn_group(G);

    // IMU: initial biases, white noise and random-walk biases (discrete, per sample of dt).
    const double dt_imu = 0.005, dt_cam = 0.05;
    double bg[3], ba[3];
    for (int k = 0; k < 3; ++k) {
        bg[k] =
            opt.gyro_bias_given ? opt.gyro_bias[k] : kGyroBias0Sigma * sfd_prng_gaussian(&rng_imu);
        ba[k] = opt.accel_bias_given ? opt.accel_bias[k]
                                     : kAccelBias0Sigma * sfd_prng_gaussian(&rng_imu);
        st.gyro_bias0[k] = bg[k];
        st.accel_bias0[k] = ba[k];
    }
    const double sigma_g = opt.gyro_noise / std::sqrt(dt_imu);
    const double sigma_a = opt.accel_noise / std::sqrt(dt_imu);
    const double step_bg = opt.gyro_bias_rw * std::sqrt(dt_imu);
    const double step_ba = opt.accel_bias_rw * std::sqrt(dt_imu);

    sfd_feature_frame_t &ff = fb->ff;
    sfd_truth_t &tr = fb->tr;
    std::vector<Obs> obs;
    obs.reserve(SFD_FEATURE_FRAME_T_CAPACITY);
    std::vector<int> order;  // worst-case: the features replaced this frame
    // worst-case: track id -> the last frame it was a random pixel (its label window)
    std::unordered_map<int64_t, int> last_random;
    int64_t imu_index = 0;
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
                m.gyro[r] = w[r] + bg[r] + sigma_g * sfd_prng_gaussian(&rng_imu);
                m.accel[r] = ba[r] + sigma_a * sfd_prng_gaussian(&rng_imu);
                for (int k = 0; k < 3; ++k) m.accel[r] += P.R_BtoW[3 * k + r] * f_W[k];
            }
            for (int r = 0; r < 3; ++r) {
                bg[r] += step_bg * sfd_prng_gaussian(&rng_imu);
                ba[r] += step_ba * sfd_prng_gaussian(&rng_imu);
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
        set_camera_pose(t_frame);
        obs.clear();
        auto spurious_now = [&](const Track &T) { return f - T.last_step < W; };

        // Static tracks.
        for (Track &T : tracks) {
            double uv[2], depth = 0.0;
            bool fresh = false;
            if (T.lost || !project(T.p, uv, &depth)) {
                spawn(T);
                fresh = true;
                if (!project(T.p, uv, &depth)) continue;
            }
            double ou = uv[0], ov = uv[1], odepth = depth;  // this frame's observation
            if (paper) {
                // The paper's fault k(-1, 1)^T as a step onto the ground point under the shifted
                // pixel, followed from then on (the tracker slipped onto other texture): in the
                // step frame the observation is the old projection plus the fault exactly, later
                // a consistent track of that point (clean after the label window, as a
                // mistracking jump). A shifted pixel outside the image loses the track.
                if (!fresh && f > 0 && sfd_prng_uniform(&rng) < p_event) {
                    const double target[2] = {uv[0] - opt.fault_magnitude * cam.fx_px,
                                              uv[1] + opt.fault_magnitude * cam.fy_px};
                    double q[3], quv[2], qdepth = 0.0;
                    if (!inside(target, 0.0) || !scene_point(target, q) ||
                        !project(q, quv, &qdepth)) {
                        T.lost = true;
                        continue;
                    }
                    std::memcpy(T.p, q, sizeof q);
                    ou = quv[0];
                    ov = quv[1];
                    odepth = qdepth;
                    T.last_step = f;
                    T.last_kind = SFD_TRUTH_T_KIND_JUMP;
                    ++st.events[SFD_TRUTH_T_KIND_JUMP];
                }
            } else if (T.mismatch_back) {
                // Back on its own point after a one-frame mismatch: a step too.
                T.mismatch_back = false;
                T.last_step = f;
                T.last_kind = SFD_TRUTH_T_KIND_MISMATCH;
            } else if (!fresh && f > 0 && T.drift_left == 0 && p_event > 0.0 &&
                       sfd_prng_uniform(&rng) < p_event) {
                const double u_kind = sfd_prng_uniform(&rng);
                const double ang = 2.0 * kPi * sfd_prng_uniform(&rng);
                const double dir[2] = {std::cos(ang), std::sin(ang)};
                if (u_kind < p_jump || u_kind >= p_jump + p_drift) {
                    // Jump (locks onto another static point 5-30 px away, for good) or
                    // mismatch (another point 15-60 px away, this frame only).
                    const bool jump = u_kind < p_jump;
                    const double r =
                        jump ? kJumpMinPx + (kJumpMaxPx - kJumpMinPx) * sfd_prng_uniform(&rng)
                             : kMismatchMinPx +
                                   (kMismatchMaxPx - kMismatchMinPx) * sfd_prng_uniform(&rng);
                    for (int side = 0; side < 2; ++side) {
                        const double sgn = side ? -1.0 : 1.0;
                        const double target[2] = {uv[0] + sgn * r * dir[0],
                                                  uv[1] + sgn * r * dir[1]};
                        double q[3], quv[2], qdepth = 0.0;
                        if (!inside(target, kMarginPx) || !scene_point(target, q) ||
                            !project(q, quv, &qdepth))
                            continue;
                        ou = quv[0];
                        ov = quv[1];
                        odepth = qdepth;
                        T.last_step = f;
                        if (jump) {
                            std::memcpy(T.p, q, sizeof q);
                            T.last_kind = SFD_TRUTH_T_KIND_JUMP;
                            ++st.events[SFD_TRUTH_T_KIND_JUMP];
                        } else {
                            T.mismatch_back = true;
                            T.last_kind = SFD_TRUTH_T_KIND_MISMATCH;
                            ++st.events[SFD_TRUTH_T_KIND_MISMATCH];
                        }
                        break;
                    }
                } else {
                    // Drift: slides step px per frame for D frames from this one.
                    const double step =
                        kDriftMinPx + (kDriftMaxPx - kDriftMinPx) * sfd_prng_uniform(&rng);
                    T.drift_px[0] = step * dir[0];
                    T.drift_px[1] = step * dir[1];
                    T.drift_left = kDriftMinFrames +
                                   int(sfd_prng_uniform_index(
                                       &rng, uint32_t(kDriftMaxFrames - kDriftMinFrames + 1)));
                    ++st.events[SFD_TRUTH_T_KIND_DRIFT];
                }
            }
            if (!paper && T.drift_left > 0) {
                T.off_px[0] += T.drift_px[0];
                T.off_px[1] += T.drift_px[1];
                --T.drift_left;
                T.last_step = f;
                T.last_kind = SFD_TRUTH_T_KIND_DRIFT;
                const double at[2] = {uv[0] + T.off_px[0], uv[1] + T.off_px[1]};
                ou = at[0];
                ov = at[1];
                if (T.drift_left == 0) {
                    // The slide ends: the track locks onto the scene point under it.
                    double q[3], quv[2], qdepth = 0.0;
                    if (inside(at, 0.0) && scene_point(at, q) && project(q, quv, &qdepth)) {
                        std::memcpy(T.p, q, sizeof q);
                        ou = quv[0];
                        ov = quv[1];
                        odepth = qdepth;
                    }
                    T.off_px[0] = T.off_px[1] = 0.0;
                }
            }
            if (!(ou >= 0 && ou < cam.width_px && ov >= 0 && ov < cam.height_px)) {
                // Slid or pushed out of the image: the tracker loses it; a new track next frame.
                T.lost = true;
                continue;
            }
            Obs o;
            o.id = T.id;
            o.u = ou;
            o.v = ov;
            o.depth = odepth;
            o.kind = spurious_now(T) ? T.last_kind : int8_t(SFD_TRUTH_T_KIND_CLEAN);
            obs.push_back(o);
        }
        // Moving groups: every observation spurious; a point entering the image gets a new id.
        for (Group &G : groups) {
            if (f > 0)
                for (int k = 0; k < 3; ++k) G.c[k] += dt_cam * G.v[k];
            bool any = false;
            for (MovingPoint &m : G.pts) {
                double pw[3], uv[2], depth = 0.0;
                for (int k = 0; k < 3; ++k) pw[k] = G.c[k] + m.off[k];
                if (!project(pw, uv, &depth)) {
                    m.in_view = false;
                    continue;
                }
                if (!m.in_view) m.id = next_id++;
                m.in_view = true;
                any = true;
                if (obs.size() >= size_t(SFD_FEATURE_FRAME_T_CAPACITY)) continue;
                obs.push_back(Obs{m.id, uv[0], uv[1], depth, int8_t(SFD_TRUTH_T_KIND_MOVING)});
            }
            G.unseen = any ? 0 : G.unseen + 1;
            G.seen = G.seen || any;
            // Left the view (or never entered within 3 s): a new group enters.
            if ((G.seen && !any) || G.unseen > 60) spawn_group(G);
        }
        std::stable_sort(obs.begin(), obs.end(),
                         [](const Obs &a, const Obs &b) { return a.id < b.id; });
        const int k = std::min(int(obs.size()), SFD_FEATURE_FRAME_T_CAPACITY);
        for (int i = 0; i < k; ++i) {
            const Obs &o = obs[size_t(i)];
            ff.track_id[i] = o.id;
            ff.u[i] = o.u + opt.pixel_noise_px * sfd_prng_gaussian(&rng);
            ff.v[i] = o.v + opt.pixel_noise_px * sfd_prng_gaussian(&rng);
            double zhat = o.depth;
            if (opt.depth_var > 0.0) zhat += std::sqrt(opt.depth_var) * sfd_prng_gaussian(&rng);
            ff.depth[i] = zhat > 0.1 ? zhat : 0.1;
            ff.depth_var[i] = opt.depth_var;
            tr.track_id[i] = o.id;
            tr.kind[i] = o.kind;
            tr.spurious[i] = o.kind != SFD_TRUTH_T_KIND_CLEAN ? 1 : 0;
        }
        if (worst) {
            // round(F * k) of this frame's features, drawn without replacement (partial
            // Fisher-Yates), move to uniformly random pixels: an outlier for every method.
            const int n_random = static_cast<int>(std::lround(opt.random_fraction * k));
            order.resize(size_t(k));
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
                last_random[ff.track_id[m]] = f;
            }
            st.events[SFD_TRUTH_T_KIND_MISMATCH] += n_random;
            // back on its point after a random pixel: a mismatch's return step, labelled for
            // the W frames from it, as in mistracking (the windows that still hold the pixel)
            for (int i = 0; i < k; ++i) {
                const auto it = last_random.find(ff.track_id[i]);
                if (it != last_random.end() && it->second < f && f - it->second <= W) {
                    tr.spurious[i] = 1;
                    tr.kind[i] = SFD_TRUTH_T_KIND_MISMATCH;
                }
            }
        }
        for (int i = 0; i < k; ++i) {
            st.spurious += tr.spurious[i];
            ++st.kind[tr.kind[i]];
        }
        st.features += k;
        ff.num_features = k;
        tr.num_features = k;
        int n = sfd_feature_frame_t_encode(buf.data(), 0, int(buf.size()), &ff);
        if (!emit("FEATURES", utime, n)) break;
        ++st.frames;
        n = sfd_truth_t_encode(buf.data(), 0, int(buf.size()), &tr);
        if (!emit("TRUTH", utime, n)) break;
    }
    st.imu = imu_index;
    return encode_failed ? 1 : 0;
}

namespace {

// The log file sink of sfd-sim -o.
class LogSink : public FlightSink {
  public:
    explicit LogSink(const std::string &path) : log_(path) {}
    bool ok() const { return log_.ok(); }
    bool finish() { return log_.finish(); }
    const std::string &error() const { return log_.error(); }
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
        std::fprintf(stderr, "sfd-sim: -o %s\n", log.error().c_str());
        return 1;
    }
    FlightStats st;
    const int rc = generate_flight(opt, log, &st);
    if (rc != 0 || !log.finish()) {
        std::fprintf(stderr, "sfd-sim: -o %s\n",
                     rc != 0 ? (opt.out_path + ": a message could not be encoded").c_str()
                             : log.error().c_str());
        return 1;
    }
    const double n = double(st.features ? st.features : 1);
    std::printf(
        "sfd-sim %s: wrote %s: %d frames (%.2f s at rest), %lld IMU samples, %.1f features per "
        "frame, %.2f%% spurious: jump %.2f%%, drift %.2f%%, moving %.2f%%, mismatch %.2f%% "
        "(events: %lld jumps, %lld drifts, %lld moving groups, %lld mismatches; seed %llu)\n",
        opt.scenario.c_str(), opt.out_path.c_str(), st.frames, std::max(0.0, opt.rest_s), st.imu,
        double(st.features) / (st.frames ? st.frames : 1), 100.0 * double(st.spurious) / n,
        100.0 * double(st.kind[SFD_TRUTH_T_KIND_JUMP]) / n,
        100.0 * double(st.kind[SFD_TRUTH_T_KIND_DRIFT]) / n,
        100.0 * double(st.kind[SFD_TRUTH_T_KIND_MOVING]) / n,
        100.0 * double(st.kind[SFD_TRUTH_T_KIND_MISMATCH]) / n, st.events[SFD_TRUTH_T_KIND_JUMP],
        st.events[SFD_TRUTH_T_KIND_DRIFT], st.events[SFD_TRUTH_T_KIND_MOVING],
        st.events[SFD_TRUTH_T_KIND_MISMATCH], static_cast<unsigned long long>(opt.seed));
    std::printf(
        "  IMU: initial gyro bias %.6f %.6f %.6f rad/s, accel bias %.5f %.5f %.5f m/s^2 "
        "(%s); noise %.3g rad/s/sqrt(Hz), %.3g m/s^2/sqrt(Hz); bias random walk %.3g "
        "rad/s^2/sqrt(Hz), %.3g m/s^3/sqrt(Hz)\n",
        st.gyro_bias0[0], st.gyro_bias0[1], st.gyro_bias0[2], st.accel_bias0[0], st.accel_bias0[1],
        st.accel_bias0[2],
        opt.gyro_bias_given && opt.accel_bias_given
            ? "given"
            : (opt.gyro_bias_given || opt.accel_bias_given ? "given/drawn" : "drawn"),
        opt.gyro_noise, opt.accel_noise, opt.gyro_bias_rw, opt.accel_bias_rw);
    return 0;
}

}  // namespace sfdsim
