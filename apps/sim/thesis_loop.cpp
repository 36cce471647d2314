// SPDX-License-Identifier: MIT
// sfd-sim thesis-loop: Kilic 2014 Chapter IV (Figures 3-9) through sfd's pipeline
// (sfd_pipeline.h, as sfd-node runs it). Association methods (OPRF, RANSAC1, RANSACF, NONE) run
// inside an EKF localization loop over a ground-truth trajectory and a known landmark map, with
// controlled noise. Three sweeps: (a) measurement noise, (b) control input (IMU) noise, (c)
// mismatch ratio. Per method and sweep point: the mean wall-clock time per frame of the
// pipeline's association and update stages (the association, the EKF camera update and the
// track bookkeeping) and the RMSE of the EKF position. The note apps/sim/THESIS_LOOP.md repeats
// these choices without core detail.
//
// The thesis fixes the loop (Figure 3: noise on the inputs, EKF predict, association, EKF
// update), the criteria (association time, position RMSE) and the ranges ("measurement noise and
// matching error from 5 to 20 percent, control input noise from 0 to 10 percent", no units). It
// used prerecorded ground truth; everything else is chosen here:
//
// Ground truth (analytic, so the IMU is exactly consistent with it):
//  - world z up, gravity (0, 0, -9.81). IMU position on an ellipse with semi-axes 3.5 m and 2.8 m
//    (perimeter ~19.9 m) at 1.5 m height with a +-0.3 m heave at twice the loop rate, one loop
//    per 40 s (0.5 m/s): p = (3.5 cos th, 2.8 sin th, 1.5 + 0.3 sin 2th), th = 2 pi t / 40 s.
//  - attitude R_ItoW = Rz(yaw) Ry(pitch) Rx(roll), IMU x forward, z up: yaw = th + pi/2 - 0.6
//    (looking 34 deg outward of the direction of travel) + 0.15 sin(2 pi 0.2 t), pitch =
//    0.08 sin(2 pi 0.35 t), roll = 0.06 sin(2 pi 0.5 t + 1) (rad): rates up to ~0.5 rad/s.
//  - IMU 200 Hz: gyro = body rate from the analytic Euler rates, accel = specific force
//    R^T (a - g) from the analytic acceleration; no bias. Sample k is taken at t_k = k / 200 s and
//    held over [t_k, t_k+1) by the EKF (sfd_ekf_propagate).
//  - camera 20 Hz (every 10th IMU sample), EuRoC cam0 pinhole intrinsics (fx 458.654, fy 457.296,
//    cx 367.215, cy 248.375, 752 x 480 px, undistorted pixels), camera z along IMU x, 5 cm ahead
//    of the IMU (the extrinsics of drivers/sim/sfd_pair_sim.h).
// Map: a 14 m x 12 m room, 3.5 m high (like EuRoC's Vicon room): 1000 landmarks uniform on the
// four walls and 300 on the floor. The filter knows every landmark with a 5 mm error per axis
// (drawn once per run) and that covariance (5 mm)^2 I. A landmark is observed when it is >= 0.3 m
// in front of the camera and projects inside the image; a match joins the previous and current
// observation of a landmark seen in both frames, in map order, at most 200 per frame (the frames
// have ~100-200). Every observation is the true projection plus N(0, sigma_px^2) per axis, drawn
// once per landmark and frame (the previous pixel of a match is the one drawn the frame before).
// Noise units (the thesis gives percentages without units):
//  - measurement noise p %: sigma_px = p / 100 * 10 px per axis; 5-20 % = 0.5-2 px. The 10 px
//    reference is a round figure of the order of the mean true image motion between frames of
//    this trajectory (7.0 px, printed), so p % reads roughly as a noise-to-signal ratio of what
//    the association judges, the motion of a feature between the two frames.
//  - control input noise p %: white noise on every IMU sample with per-sample sigma = p / 100 of
//    the RMS magnitude of that sensor's true signal over the loop: gyro p/100 * RMS|w| (rad/s),
//    accelerometer p/100 * RMS|f| (m/s^2, ~g). Density = sigma * sqrt(1/200 s).
//  - mismatch p %: in every frame, round(p / 100 * n) of its n matches (chosen at random, nested:
//    the mismatched set at a lower ratio is a subset of the one at a higher ratio) get as current
//    observation the current observation of another matched landmark, the first (cyclically from
//    a random one) whose pixel is >= 20 px from the true one (a matcher pairing the track with the
//    wrong feature). The previous observation and the landmark stay the track's own. Mismatches
//    are drawn independently per frame.
// Common random numbers: every random stream (map, IMU noise, pixel noise, mismatch choice, filter
// start) is seeded from (--seed, run) only and consumed identically at every sweep point and for
// every method; noise draws are standard normals scaled by the level. So the curves differ only
// by the level, and the four methods of a run see exactly the same data.
// Filter: sfd_ekf started at the truth perturbed by its P0 (1 cm, 1 cm/s, 1 mrad, gyro bias 1e-4
// rad/s, accel bias 1e-3 m/s^2 per axis). It knows the noise: pixel sigma = sigma_px, IMU
// densities = the injected ones but at least sfd_ekf_noise_default()'s (which also covers the
// zero-order hold at 0 % control noise), default bias random walks. Association: the defaults of
// sfd_assoc_params_default() (alpha 0.01, p 0.99, 100 hypotheses, 1 px minimum parallax), seeded
// per run. The previous camera pose the association gets is the filter's posterior.
// Through the pipeline: IMU samples and frames are pushed in time order (one more IMU sample, at
// the last frame's time, covers it); the single-state EKF is started at the perturbed truth with
// sfd_pipeline_start_at(); every feature's map point is given with sfd_pipeline_known_landmark()
// (never refined) before its frame. A frame holds the matches (map order, the mismatched current
// pixels included) and then the other visible landmarks, up to SFD_MAX_FEATURES. Two
// differences from a direct association call: a match's previous pixel is the previous frame's
// feature, which is a mismatched pixel when that landmark was mismatched (and accepted) in the
// previous frame; a feature judged SPURIOUS has no previous observation in the next frame (the
// pipeline keeps only non-SPURIOUS ones), so it is not matched there. A mismatch left UNTESTED
// counts as accepted.
// Sweeps (the other two levels at the nominal 10 % measurement, 5 % control, 10 % mismatch, the
// middles of the thesis's ranges): (a) 5, 10, 15, 20 and beyond 30, 40, 50 %; (b) 0, 2.5, 5, 7.5,
// 10 and beyond 15, 20, 30 %; (c) 0, 5, 10, 15, 20 and beyond 30, 40, 50 %. --quick: 5, 20 / 0,
// 10 / 0, 30 with 200 frames and 2 runs.
// Criteria: position RMSE = sqrt of the mean over all frames (after each update) and runs of
// |p_est - p_true|^2 (IMU position); its standard error from the per-run RMSEs. Time = wall clock
// (steady_clock) around sfd_pipeline_associate() + sfd_pipeline_update(), mean and median over
// all frames and runs, in a separate
// CSV: thesis_rmse.csv is byte-identical for the same binary and arguments, thesis_time.csv is not.
// Claim check (computed): at each point, "OPRF's RMSE below F-matrix RANSAC's and below no
// association's" holds when OPRF's pooled RMSE is below both; a difference smaller than twice the
// standard error of the paired per-run differences is marked as a tie.
#include "thesis_loop.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "sfd/sfd.h"
#include "sfd_cli.hpp"
#include "sfd_eval.hpp"

namespace sfdsim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kGravity = 9.81;

// Trajectory.
constexpr double kLoopPeriodS = 40.0;
constexpr double kEllipseA = 3.5, kEllipseB = 2.8, kPathHeight = 1.5, kHeave = 0.3;
constexpr double kLookOutward = 0.6;
constexpr double kYawAmp = 0.15, kYawHz = 0.2;
constexpr double kPitchAmp = 0.08, kPitchHz = 0.35;
constexpr double kRollAmp = 0.06, kRollHz = 0.5, kRollPhase = 1.0;

// Sensors.
constexpr int kImuPerFrame = 10;
constexpr double kImuDt = 0.005;
constexpr double kFrameDt = kImuPerFrame * kImuDt;
constexpr double kWidthPx = 752.0, kHeightPx = 480.0;
constexpr double kFx = 458.654, kFy = 457.296, kCx = 367.215, kCy = 248.375;
constexpr double kMinDepthM = 0.3;

// Map.
constexpr double kRoomX = 7.0, kRoomY = 6.0, kRoomZ = 3.5;
constexpr int kWallLandmarks = 1000, kFloorLandmarks = 300;
constexpr int kLandmarks = kWallLandmarks + kFloorLandmarks;
constexpr double kLandmarkSigmaM = 0.005;
// every landmark's covariance (sigma^2 I): the matches refer to it
constexpr double kLandmarkCov_m2[9] = {kLandmarkSigmaM * kLandmarkSigmaM, 0.0, 0.0, 0.0,
                                       kLandmarkSigmaM *kLandmarkSigmaM,  0.0, 0.0, 0.0,
                                       kLandmarkSigmaM *kLandmarkSigmaM};
constexpr int kMaxMatches = 200;
constexpr double kMismatchMinPx = 20.0;

// Units and nominal levels.
constexpr double kPixelRefPx = 10.0;
constexpr double kNominalMeasPct = 10.0, kNominalCtrlPct = 5.0, kNominalMismatchPct = 10.0;
constexpr double kDivergedM = 1.0;

constexpr int kNumMethods = 4;
const int kMethods[kNumMethods] = {SFD_METHOD_OPRF, SFD_METHOD_RANSAC1, SFD_METHOD_RANSACF,
                                   SFD_METHOD_NONE};
const char *const kMethodNames[kNumMethods] = {"OPRF", "RANSAC1", "RANSACF", "NONE"};
constexpr int kOprf = 0, kRansacF = 2, kNone = 3;

// ---- small 3x3 algebra (row-major) ----
void mul3(const double *A, const double *B, double *C) {
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
            double s = 0.0;
            for (int k = 0; k < 3; ++k) s += A[3 * r + k] * B[3 * k + c];
            C[3 * r + c] = s;
        }
    }
}
void mulv(const double *A, const double *x, double *y) {
    for (size_t r = 0; r < 3; ++r)
        y[r] = A[3 * r] * x[0] + A[3 * r + 1] * x[1] + A[3 * r + 2] * x[2];
}
void tmulv(const double *A, const double *x, double *y) {
    for (int r = 0; r < 3; ++r) y[r] = A[r] * x[0] + A[3 + r] * x[1] + A[6 + r] * x[2];
}
void rot_x(double a, double *R) {
    const double c = std::cos(a), s = std::sin(a);
    const double M[9] = {1, 0, 0, 0, c, -s, 0, s, c};
    std::copy(M, M + 9, R);
}
void rot_y(double a, double *R) {
    const double c = std::cos(a), s = std::sin(a);
    const double M[9] = {c, 0, s, 0, 1, 0, -s, 0, c};
    std::copy(M, M + 9, R);
}
void rot_z(double a, double *R) {
    const double c = std::cos(a), s = std::sin(a);
    const double M[9] = {c, -s, 0, s, c, 0, 0, 0, 1};
    std::copy(M, M + 9, R);
}

// ---- ground truth ----
struct Truth {
    double R_ItoW[9];
    double p[3];
    double v[3];
    double gyro[3];   // body rate, IMU frame (rad/s)
    double accel[3];  // specific force, IMU frame (m/s^2)
};

Truth truth_at(double t) {
    Truth T{};
    const double w0 = 2.0 * kPi / kLoopPeriodS, th = w0 * t;
    T.p[0] = kEllipseA * std::cos(th);
    T.p[1] = kEllipseB * std::sin(th);
    T.p[2] = kPathHeight + kHeave * std::sin(2.0 * th);
    T.v[0] = -kEllipseA * w0 * std::sin(th);
    T.v[1] = kEllipseB * w0 * std::cos(th);
    T.v[2] = 2.0 * kHeave * w0 * std::cos(2.0 * th);
    const double a[3] = {-kEllipseA * w0 * w0 * std::cos(th), -kEllipseB * w0 * w0 * std::sin(th),
                         -4.0 * kHeave * w0 * w0 * std::sin(2.0 * th)};
    const double wy = 2.0 * kPi * kYawHz, wp = 2.0 * kPi * kPitchHz, wr = 2.0 * kPi * kRollHz;
    const double yaw = th + 0.5 * kPi - kLookOutward + kYawAmp * std::sin(wy * t);
    const double yaw_d = w0 + kYawAmp * wy * std::cos(wy * t);
    const double pitch = kPitchAmp * std::sin(wp * t);
    const double pitch_d = kPitchAmp * wp * std::cos(wp * t);
    const double roll = kRollAmp * std::sin(wr * t + kRollPhase);
    const double roll_d = kRollAmp * wr * std::cos(wr * t + kRollPhase);
    double Rz[9], Ry[9], Rx[9], Rzy[9];
    rot_z(yaw, Rz);
    rot_y(pitch, Ry);
    rot_x(roll, Rx);
    mul3(Rz, Ry, Rzy);
    mul3(Rzy, Rx, T.R_ItoW);
    // R' = R [w]x with R = Rz Ry Rx: w = Rx^T Ry^T (0, 0, yaw') + Rx^T (0, pitch', 0) + (roll', 0,
    // 0)
    const double ez[3] = {0.0, 0.0, yaw_d}, ey[3] = {0.0, pitch_d, 0.0};
    double t1[3], t2[3], t3[3];
    tmulv(Ry, ez, t1);
    for (int k = 0; k < 3; ++k) t1[k] += ey[k];
    tmulv(Rx, t1, t2);
    t2[0] += roll_d;
    std::copy(t2, t2 + 3, T.gyro);
    const double a_minus_g[3] = {a[0], a[1], a[2] + kGravity};
    tmulv(T.R_ItoW, a_minus_g, t3);
    std::copy(t3, t3 + 3, T.accel);
    return T;
}

// Camera: looks along IMU x (camera z = IMU x, camera x = -IMU y, camera y = -IMU z), 5 cm ahead.
sfd_ekf_camera_t make_camera(double sigma_px) {
    sfd_ekf_camera_t cam{};
    const double T_imu_cam[16] = {0, 0, 1, 0.05, -1, 0, 0, 0.0, 0, -1, 0, 0.0, 0, 0, 0, 1};
    sfd_extrinsics_from_matrix(&cam.ext, T_imu_cam);
    cam.fx_px = kFx;
    cam.fy_px = kFy;
    cam.cx_px = kCx;
    cam.cy_px = kCy;
    cam.pixel_sigma_px = std::max(sigma_px, 0.05);
    return cam;
}

struct CamPose {
    double R_CtoW[9];
    double p[3];
};

CamPose camera_of(const sfd_ekf_camera_t &cam, const double R_ItoW[9], const double p_I[3]) {
    CamPose c{};
    mul3(R_ItoW, cam.ext.R_CtoI, c.R_CtoW);
    double o[3];
    mulv(R_ItoW, cam.ext.p_CinI, o);
    for (int k = 0; k < 3; ++k) c.p[k] = p_I[k] + o[k];
    return c;
}

/// True pixel of world point L; false when behind/too close or outside the image.
bool project(const CamPose &c, const double *L, double uv[2]) {
    const double d[3] = {L[0] - c.p[0], L[1] - c.p[1], L[2] - c.p[2]};
    double x[3];
    tmulv(c.R_CtoW, d, x);
    if (!(x[2] >= kMinDepthM)) return false;
    uv[0] = kFx * x[0] / x[2] + kCx;
    uv[1] = kFy * x[1] / x[2] + kCy;
    return uv[0] >= 0.0 && uv[0] < kWidthPx && uv[1] >= 0.0 && uv[1] < kHeightPx;
}

// ---- noise levels ----
struct Reference {
    double gyro_rms_rad_s = 0.0;  // RMS |w| over one loop
    double accel_rms_m_s2 = 0.0;  // RMS |f| over one loop
    double flow_mean_px = 0.0;    // mean true inter-frame image motion of the matches (run 0)
    double matches_mean = 0.0;    // mean matches per frame (run 0)
    int matches_min = 0, matches_max = 0;
};

struct Levels {
    double meas_pct, ctrl_pct, mismatch_pct;
};

struct Sigmas {
    double px, gyro, accel, mismatch_frac;
};

Sigmas sigmas_of(const Levels &lv, const Reference &ref) {
    return Sigmas{lv.meas_pct / 100.0 * kPixelRefPx, lv.ctrl_pct / 100.0 * ref.gyro_rms_rad_s,
                  lv.ctrl_pct / 100.0 * ref.accel_rms_m_s2, lv.mismatch_pct / 100.0};
}

uint64_t stream_seed(uint64_t base, int run, int stream) {
    return base * 1000003ULL + static_cast<uint64_t>(run) * 64ULL + static_cast<uint64_t>(stream);
}

// ---- one run's data (identical for every method) ----
// One feature of a frame handed to the pipeline: the landmark it observes (its track id) and the
// observed pixel (a mismatch's is another landmark's).
struct FrameFeature {
    int32_t landmark;
    double uv[2];
    uint8_t mismatched;
};

struct RunData {
    sfd_ekf_t ekf0{};
    sfd_ekf_noise_t noise{};         // the filter's IMU noise
    double P0[SFD_EKF_DIM] = {};     // its initial variances
    std::vector<double> lmap;        // the filter's map: 3 per landmark
    std::vector<FrameFeature> feat;  // frame f (0..frames) in [fbegin[f], fbegin[f + 1])
    std::vector<size_t> fbegin;
    std::vector<double> imu;          // 6 per sample: gyro, accel (noisy)
    std::vector<sfd_match_t> m;       // matches of every frame, frame f in [begin[f-1], begin[f])
    std::vector<uint8_t> mismatched;  // per match
    std::vector<size_t> begin;        // frames + 1 offsets
    std::vector<double> truth_p;      // 3 per frame (frame 0 = start)
    double flow_sum_px = 0.0;         // true image motion of the matches
    long flow_count = 0;
};

bool make_run(const Sigmas &sg, uint64_t base, int run, int frames, RunData *rd) {
    sfd_prng_t map_rng, imu_rng, px_rng, mm_rng, init_rng;
    sfd_prng_seed(&map_rng, stream_seed(base, run, 1));
    sfd_prng_seed(&imu_rng, stream_seed(base, run, 2));
    sfd_prng_seed(&px_rng, stream_seed(base, run, 3));
    sfd_prng_seed(&mm_rng, stream_seed(base, run, 4));
    sfd_prng_seed(&init_rng, stream_seed(base, run, 5));
    const sfd_ekf_camera_t cam = make_camera(sg.px);

    // Map: truth on the walls and floor, the filter's copy with a 5 mm error.
    std::vector<double> L(3 * static_cast<size_t>(kLandmarks)), Lmap(L.size());
    const double perimeter = 4.0 * (kRoomX + kRoomY);
    for (int i = 0; i < kLandmarks; ++i) {
        double *x = &L[3 * static_cast<size_t>(i)];
        if (i < kWallLandmarks) {
            double s = perimeter * sfd_prng_uniform(&map_rng);
            const double z = kRoomZ * sfd_prng_uniform(&map_rng);
            if (s < 2.0 * kRoomX) {  // wall y = -kRoomY
                x[0] = -kRoomX + s;
                x[1] = -kRoomY;
            } else if ((s -= 2.0 * kRoomX) < 2.0 * kRoomY) {  // wall x = +kRoomX
                x[0] = kRoomX;
                x[1] = -kRoomY + s;
            } else if ((s -= 2.0 * kRoomY) < 2.0 * kRoomX) {  // wall y = +kRoomY
                x[0] = kRoomX - s;
                x[1] = kRoomY;
            } else {  // wall x = -kRoomX
                s -= 2.0 * kRoomX;
                x[0] = -kRoomX;
                x[1] = kRoomY - s;
            }
            x[2] = z;
        } else {
            x[0] = kRoomX * (2.0 * sfd_prng_uniform(&map_rng) - 1.0);
            x[1] = kRoomY * (2.0 * sfd_prng_uniform(&map_rng) - 1.0);
            x[2] = 0.0;
        }
        for (int k = 0; k < 3; ++k) {
            Lmap[3 * static_cast<size_t>(i) + static_cast<size_t>(k)] =
                x[k] + kLandmarkSigmaM * sfd_prng_gaussian(&map_rng);
        }
    }

    // Filter start: truth perturbed by P0.
    const Truth t0 = truth_at(0.0);
    sfd_ekf_noise_t nz;
    sfd_ekf_noise_default(&nz);
    const double rt_dt = std::sqrt(kImuDt);
    nz.gyro_noise_rad_s_rthz = std::max(nz.gyro_noise_rad_s_rthz, sg.gyro * rt_dt);
    nz.accel_noise_m_s2_rthz = std::max(nz.accel_noise_m_s2_rthz, sg.accel * rt_dt);
    const double sd0[5] = {0.01, 0.01, 0.001, 1e-4, 1e-3};  // p, v, theta, bg, ba
    double P0[SFD_EKF_DIM], p0[3], v0[3], dth[3], bg[3], ba[3];
    for (int b = 0; b < 5; ++b) {
        for (int k = 0; k < 3; ++k) P0[3 * b + k] = sd0[b] * sd0[b];
    }
    for (int k = 0; k < 3; ++k) {
        p0[k] = t0.p[k] + sd0[0] * sfd_prng_gaussian(&init_rng);
        v0[k] = t0.v[k] + sd0[1] * sfd_prng_gaussian(&init_rng);
        dth[k] = sd0[2] * sfd_prng_gaussian(&init_rng);
        bg[k] = sd0[3] * sfd_prng_gaussian(&init_rng);
        ba[k] = sd0[4] * sfd_prng_gaussian(&init_rng);
    }
    double dR[9], R0[9], q0[4];
    sfd_so3_exp(dth, dR);
    mul3(t0.R_ItoW, dR, R0);
    sfd_rotmat_to_quat(R0, q0);
    if (sfd_ekf_init(&rd->ekf0, &nz, p0, v0, q0, bg, ba, P0) != SFD_OK) return false;
    rd->noise = nz;
    std::copy(P0, P0 + SFD_EKF_DIM, rd->P0);
    rd->lmap = Lmap;

    // IMU: truth + white noise, sample k at t_k; one more than the frames consume, at the last
    // frame's time, so that the IMU covers it (its value is held after that frame only).
    const size_t n_imu = static_cast<size_t>(frames) * kImuPerFrame + 1;
    rd->imu.assign(6 * n_imu, 0.0);
    for (size_t k = 0; k < n_imu; ++k) {
        const Truth tk = truth_at(static_cast<double>(k) * kImuDt);
        double *s = &rd->imu[6 * k];
        for (int a = 0; a < 3; ++a) s[a] = tk.gyro[a] + sg.gyro * sfd_prng_gaussian(&imu_rng);
        for (int a = 0; a < 3; ++a) s[3 + a] = tk.accel[a] + sg.accel * sfd_prng_gaussian(&imu_rng);
    }

    // Camera frames: noisy observations of every landmark (drawn for all, used when visible).
    rd->m.clear();
    rd->mismatched.clear();
    rd->begin.assign(1, 0);
    rd->feat.clear();
    rd->fbegin.assign(1, 0);
    std::vector<uint8_t> in_frame(static_cast<size_t>(kLandmarks));
    rd->truth_p.assign(3 * (static_cast<size_t>(frames) + 1), 0.0);
    rd->flow_sum_px = 0.0;
    rd->flow_count = 0;
    const size_t nL = static_cast<size_t>(kLandmarks);
    std::vector<double> uv_true(2 * nL), uv_obs(2 * nL), prev_true(2 * nL), prev_obs(2 * nL);
    std::vector<uint8_t> vis(nL), prev_vis(nL);
    std::vector<int> idx;
    std::vector<double> key;
    std::vector<uint32_t> partner;
    std::vector<int> order;
    for (int f = 0; f <= frames; ++f) {
        const Truth tf = truth_at(static_cast<double>(f) * kFrameDt);
        std::copy(tf.p, tf.p + 3, &rd->truth_p[3 * static_cast<size_t>(f)]);
        const CamPose cp = camera_of(cam, tf.R_ItoW, tf.p);
        for (size_t i = 0; i < nL; ++i) {
            const double n0 = sfd_prng_gaussian(&px_rng), n1 = sfd_prng_gaussian(&px_rng);
            vis[i] = project(cp, &L[3 * i], &uv_true[2 * i]) ? 1U : 0U;
            uv_obs[2 * i] = uv_true[2 * i] + sg.px * n0;
            uv_obs[2 * i + 1] = uv_true[2 * i + 1] + sg.px * n1;
        }
        if (f > 0) {
            idx.clear();
            for (size_t i = 0; i < nL && static_cast<int>(idx.size()) < kMaxMatches; ++i) {
                if (vis[i] != 0U && prev_vis[i] != 0U) idx.push_back(static_cast<int>(i));
            }
            const int n = static_cast<int>(idx.size());
            const size_t first = rd->m.size();
            for (int j = 0; j < n; ++j) {
                const size_t i = static_cast<size_t>(idx[static_cast<size_t>(j)]);
                sfd_match_t mt{};
                mt.prev_uv_px[0] = prev_obs[2 * i];
                mt.prev_uv_px[1] = prev_obs[2 * i + 1];
                mt.uv_px[0] = uv_obs[2 * i];
                mt.uv_px[1] = uv_obs[2 * i + 1];
                mt.landmark_W_m = &rd->lmap[3 * i];  // rd->lmap is set once, above
                mt.landmark_cov_m2 = kLandmarkCov_m2;
                rd->m.push_back(mt);
                rd->mismatched.push_back(0U);
                rd->flow_sum_px += std::hypot(uv_true[2 * i] - prev_true[2 * i],
                                              uv_true[2 * i + 1] - prev_true[2 * i + 1]);
                ++rd->flow_count;
            }
            // Mismatches: keys and partners drawn for every match whatever the ratio.
            key.resize(static_cast<size_t>(n));
            partner.resize(static_cast<size_t>(n));
            order.resize(static_cast<size_t>(n));
            for (int j = 0; j < n; ++j) {
                key[static_cast<size_t>(j)] = sfd_prng_uniform(&mm_rng);
                partner[static_cast<size_t>(j)] =
                    sfd_prng_uniform_index(&mm_rng, static_cast<uint32_t>(n > 1 ? n - 1 : 1));
                order[static_cast<size_t>(j)] = j;
            }
            std::sort(order.begin(), order.end(), [&key](int x, int y) {
                const double kx = key[static_cast<size_t>(x)], ky = key[static_cast<size_t>(y)];
                return kx < ky || (kx == ky && x < y);
            });
            const long n_bad = std::lround(sg.mismatch_frac * n);
            for (long r = 0; r < n_bad && n > 1; ++r) {
                const int j = order[static_cast<size_t>(r)];
                const size_t i = static_cast<size_t>(idx[static_cast<size_t>(j)]);
                for (int s = 0; s < n - 1; ++s) {
                    int o = (static_cast<int>(partner[static_cast<size_t>(j)]) + s) % (n - 1);
                    if (o >= j) ++o;  // every other match, cyclically
                    const size_t io = static_cast<size_t>(idx[static_cast<size_t>(o)]);
                    const double du = uv_obs[2 * io] - uv_true[2 * i];
                    const double dv = uv_obs[2 * io + 1] - uv_true[2 * i + 1];
                    if (du * du + dv * dv >= kMismatchMinPx * kMismatchMinPx) {
                        sfd_match_t &mt = rd->m[first + static_cast<size_t>(j)];
                        mt.uv_px[0] = uv_obs[2 * io];
                        mt.uv_px[1] = uv_obs[2 * io + 1];
                        rd->mismatched[first + static_cast<size_t>(j)] = 1U;
                        break;
                    }
                }
            }
            rd->begin.push_back(rd->m.size());
        }
        // The frame for the pipeline: the matches (current pixels, mismatches included) in map
        // order, then every other visible landmark in map order, up to SFD_MAX_FEATURES.
        std::fill(in_frame.begin(), in_frame.end(), 0U);
        if (f > 0) {
            const size_t first = rd->begin[rd->begin.size() - 2];
            for (size_t j = first; j < rd->m.size(); ++j) {
                const size_t i = static_cast<size_t>(idx[j - first]);
                const sfd_match_t &mt = rd->m[j];
                rd->feat.push_back(FrameFeature{
                    static_cast<int32_t>(i), {mt.uv_px[0], mt.uv_px[1]}, rd->mismatched[j]});
                in_frame[i] = 1U;
            }
        }
        for (size_t i = 0; i < nL; ++i) {
            if (rd->feat.size() - rd->fbegin.back() >= static_cast<size_t>(SFD_MAX_FEATURES)) break;
            if (vis[i] == 0U || in_frame[i] != 0U) continue;
            rd->feat.push_back(
                FrameFeature{static_cast<int32_t>(i), {uv_obs[2 * i], uv_obs[2 * i + 1]}, 0U});
        }
        rd->fbegin.push_back(rd->feat.size());
        std::swap(vis, prev_vis);
        std::swap(uv_true, prev_true);
        std::swap(uv_obs, prev_obs);
    }
    return true;
}

// ---- one method over one run ----
struct MethodRun {
    double sum_sq = 0.0;
    long n_err = 0;
    double max_err = 0.0;
    double final_err = 0.0;
    long mism_total = 0, mism_accepted = 0, inl_total = 0, inl_rejected = 0;
    long hypotheses = 0;
    uint32_t numeric_faults = 0;
    std::vector<double> times_us;
    double rmse() const { return n_err > 0 ? std::sqrt(sum_sq / static_cast<double>(n_err)) : 0.0; }
};

struct Workspace {
    sfd_pipeline_t pipe;
    sfd_frame_t frame;
};

// One method over one run through the pipeline (sfd_pipeline.h), as sfd-node runs it: IMU
// samples and frames of features pushed in time order, the single-state EKF started at the run's
// perturbed truth (sfd_pipeline_start_at) and the filter's map given as known landmarks
// (sfd_pipeline_known_landmark) before each frame. Timed: the association and update stages.
bool run_method(int method, const RunData &rd, int frames, const sfd_ekf_camera_t &ecam,
                uint64_t assoc_seed, Workspace *ws, MethodRun *out) {
    sfd_pipeline_config_t cfg;
    sfd_pipeline_config_default(&cfg);
    cfg.params.method = method;
    cfg.params.seed = assoc_seed;
    cfg.params.pixel_sigma_px = ecam.pixel_sigma_px;
    cfg.nav.window_filter = 0;      // the thesis's filter: one EKF state, a known map
    cfg.nav.consider_position = 0;  // the known map holds absolute position information
    cfg.nav.noise = rd.noise;
    sfd_pipeline_t *p = &ws->pipe;
    if (sfd_pipeline_init(p, &cfg) != SFD_OK) return false;
    sfd_camera_t cam;
    const double no_dist[4] = {0.0, 0.0, 0.0, 0.0};
    if (sfd_camera_init(&cam, SFD_DISTORTION_PINHOLE, static_cast<int32_t>(kWidthPx),
                        static_cast<int32_t>(kHeightPx), kFx, kFy, kCx, kCy, no_dist) != SFD_OK ||
        sfd_pipeline_set_camera(p, &cam, &ecam.ext) != SFD_REJECT_NONE) {
        return false;
    }
    const sfd_ekf_t &e0 = rd.ekf0;
    if (sfd_pipeline_start_at(p, 0, e0.p_IinW_m, e0.v_IinW_m_s, e0.q_ItoW, e0.bg_rad_s, e0.ba_m_s2,
                              rd.P0) != SFD_OK) {
        return false;
    }
    double lm_cov[9] = {};
    for (size_t k = 0; k < 3; ++k) lm_cov[4 * k] = kLandmarkSigmaM * kLandmarkSigmaM;
    out->times_us.reserve(static_cast<size_t>(frames));
    size_t next_imu = 0;
    for (int f = 0; f <= frames; ++f) {
        const int64_t t_us = static_cast<int64_t>(f) * kImuPerFrame * 5000;
        for (; next_imu <= static_cast<size_t>(f) * kImuPerFrame; ++next_imu) {
            sfd_imu_sample_t s{};
            s.t_us = static_cast<int64_t>(next_imu) * 5000;
            std::copy(&rd.imu[6 * next_imu], &rd.imu[6 * next_imu] + 3, s.gyro_rad_s);
            std::copy(&rd.imu[6 * next_imu] + 3, &rd.imu[6 * next_imu] + 6, s.accel_m_s2);
            if (sfd_pipeline_push_imu(p, &s) != SFD_REJECT_NONE) return false;
        }
        const size_t b = rd.fbegin[static_cast<size_t>(f)];
        const int n = static_cast<int>(rd.fbegin[static_cast<size_t>(f) + 1] - b);
        sfd_frame_t &fr = ws->frame;
        fr.utime = t_us;
        fr.num_features = n;
        for (int j = 0; j < n; ++j) {
            const FrameFeature &ff = rd.feat[b + static_cast<size_t>(j)];
            sfd_feature_t &ft = fr.features[j];
            ft.track_id = ff.landmark;
            ft.u_px = ff.uv[0];
            ft.v_px = ff.uv[1];
            ft.depth_m = 0.0;
            ft.depth_var_m2 = 0.0;
            const double *L = &rd.lmap[3 * static_cast<size_t>(ff.landmark)];
            if (sfd_pipeline_known_landmark(p, ff.landmark, L, lm_cov, t_us) != SFD_OK) {
                return false;
            }
        }
        if (sfd_pipeline_push_frame(p, &fr) != SFD_REJECT_NONE || sfd_pipeline_frames_due(p) != 1 ||
            sfd_pipeline_detect(p) != SFD_OK) {
            return false;
        }
        const auto t0 = std::chrono::steady_clock::now();
        const sfd_status_t st1 = sfd_pipeline_associate(p);
        const sfd_status_t st2 = sfd_pipeline_update(p);
        const auto t1 = std::chrono::steady_clock::now();
        const sfd_pipeline_output_t *o = sfd_pipeline_output(p);
        if (st1 != SFD_OK || st2 != SFD_OK || o == nullptr || !o->has_state) {
            std::fprintf(stderr, "sfd-sim thesis-loop: the pipeline failed at frame %d\n", f);
            return false;
        }
        if (f == 0) continue;  // the start: no previous frame to match
        out->times_us.push_back(
            static_cast<double>(
                std::chrono::duration_cast<std::chrono::nanoseconds>(t1 - t0).count()) /
            1000.0);
        out->hypotheses += o->hypotheses_used;
        // The thesis's matches are the frame's first features (those seen in the previous frame
        // too); a mismatch left UNTESTED counts as accepted (the strict rule).
        const int n_match = static_cast<int>(rd.begin[static_cast<size_t>(f)] -
                                             rd.begin[static_cast<size_t>(f) - 1]);
        for (int j = 0; j < n_match && j < n; ++j) {
            const bool bad = rd.feat[b + static_cast<size_t>(j)].mismatched != 0U;
            const int8_t s = o->verdict.features[j].status;
            if (bad) {
                ++out->mism_total;
                out->mism_accepted += (s != SFD_VERDICT_SPURIOUS) ? 1 : 0;
            } else {
                ++out->inl_total;
                out->inl_rejected += (s == SFD_VERDICT_SPURIOUS) ? 1 : 0;
            }
        }
        const double *tp = &rd.truth_p[3 * static_cast<size_t>(f)];
        double e2 = 0.0;
        for (int k = 0; k < 3; ++k) e2 += (o->p_IinW_m[k] - tp[k]) * (o->p_IinW_m[k] - tp[k]);
        out->sum_sq += e2;
        ++out->n_err;
        out->max_err = std::max(out->max_err, std::sqrt(e2));
        out->final_err = std::sqrt(e2);
    }
    out->numeric_faults = p->nav.ekf.numeric_faults;
    return true;
}

// ---- sweeps ----
struct PointResult {
    Levels lv{};
    Sigmas sg{};
    MethodRun total[kNumMethods];
    std::vector<double> run_rmse[kNumMethods];
    int diverged[kNumMethods] = {0, 0, 0, 0};
    uint32_t faults[kNumMethods] = {0, 0, 0, 0};
};

struct Sweep {
    const char *name;   // CSV key
    const char *title;  // table heading
    int which;          // 0 measurement, 1 control, 2 mismatch
    double lo, hi;      // the thesis's range
    std::vector<double> levels;
    std::vector<PointResult> points;
};

double mean_of(const std::vector<double> &v) {
    double s = 0.0;
    for (double x : v) s += x;
    return v.empty() ? 0.0 : s / static_cast<double>(v.size());
}

// Nearest-rank median, the one percentile rule of every sfd tool (sfd_eval.hpp); 0 for none.
double median_of(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    return sfdeval::percentile_sorted(v, 0.5);
}

/// Standard error of the mean of a sample (0 for fewer than two values).
double std_error(const std::vector<double> &v) {
    if (v.size() < 2) return 0.0;
    const double m = mean_of(v);
    double s = 0.0;
    for (double x : v) s += (x - m) * (x - m);
    return std::sqrt(s / static_cast<double>(v.size() - 1) / static_cast<double>(v.size()));
}

bool run_point(const ThesisOptions &opt, const Reference &ref, const Levels &lv, PointResult *pr,
               Workspace *ws, const std::function<void()> &run_done) {
    pr->lv = lv;
    pr->sg = sigmas_of(lv, ref);
    const sfd_ekf_camera_t cam = make_camera(pr->sg.px);
    RunData rd;
    for (int r = 0; r < opt.runs; ++r) {
        if (!make_run(pr->sg, opt.seed, r, opt.frames, &rd)) {
            std::fprintf(stderr, "sfd-sim thesis-loop: filter start refused (run %d)\n", r);
            return false;
        }
        for (int mi = 0; mi < kNumMethods; ++mi) {
            MethodRun one;
            if (!run_method(kMethods[mi], rd, opt.frames, cam, stream_seed(opt.seed, r, 6), ws,
                            &one)) {
                return false;
            }
            MethodRun &t = pr->total[mi];
            t.sum_sq += one.sum_sq;
            t.n_err += one.n_err;
            t.max_err = std::max(t.max_err, one.max_err);
            t.mism_total += one.mism_total;
            t.mism_accepted += one.mism_accepted;
            t.inl_total += one.inl_total;
            t.inl_rejected += one.inl_rejected;
            t.hypotheses += one.hypotheses;
            t.times_us.insert(t.times_us.end(), one.times_us.begin(), one.times_us.end());
            pr->run_rmse[mi].push_back(one.rmse());
            pr->diverged[mi] += (one.final_err > kDivergedM) ? 1 : 0;
            pr->faults[mi] += one.numeric_faults;
        }
        run_done();
    }
    return true;
}

Reference compute_reference(const ThesisOptions &opt) {
    Reference ref;
    const int n = static_cast<int>(std::lround(kLoopPeriodS / kImuDt));
    double sg = 0.0, sa = 0.0;
    for (int k = 0; k < n; ++k) {
        const Truth t = truth_at(static_cast<double>(k) * kImuDt);
        sg += t.gyro[0] * t.gyro[0] + t.gyro[1] * t.gyro[1] + t.gyro[2] * t.gyro[2];
        sa += t.accel[0] * t.accel[0] + t.accel[1] * t.accel[1] + t.accel[2] * t.accel[2];
    }
    ref.gyro_rms_rad_s = std::sqrt(sg / n);
    ref.accel_rms_m_s2 = std::sqrt(sa / n);
    // Image statistics of run 0 (noise-free).
    RunData rd;
    const Sigmas zero{0.0, 0.0, 0.0, 0.0};
    if (make_run(zero, opt.seed, 0, opt.frames, &rd) && rd.flow_count > 0) {
        ref.flow_mean_px = rd.flow_sum_px / static_cast<double>(rd.flow_count);
        ref.matches_min = kMaxMatches;
        long sum = 0;
        for (size_t f = 1; f < rd.begin.size(); ++f) {
            const int c = static_cast<int>(rd.begin[f] - rd.begin[f - 1]);
            sum += c;
            ref.matches_min = std::min(ref.matches_min, c);
            ref.matches_max = std::max(ref.matches_max, c);
        }
        ref.matches_mean = static_cast<double>(sum) / static_cast<double>(rd.begin.size() - 1);
    }
    return ref;
}

Levels levels_for(int which, double level) {
    Levels lv{kNominalMeasPct, kNominalCtrlPct, kNominalMismatchPct};
    if (which == 0) lv.meas_pct = level;
    if (which == 1) lv.ctrl_pct = level;
    if (which == 2) lv.mismatch_pct = level;
    return lv;
}

double level_of(const Sweep &s, const Levels &lv) {
    return s.which == 0 ? lv.meas_pct : (s.which == 1 ? lv.ctrl_pct : lv.mismatch_pct);
}

std::string units_line(const Reference &ref) {
    char buf[640];
    std::snprintf(buf, sizeof buf,
                  "measurement noise p%% -> pixel sigma = p/100 * %g px per axis; control noise "
                  "p%% -> IMU white noise per 200 Hz sample, sigma = p/100 * RMS of the true "
                  "signal (gyro %.6g rad/s, specific force %.6g m/s^2); mismatch p%% -> "
                  "round(p/100 * n) of each frame's n matches take another landmark's current "
                  "observation (>= %g px from the true one)",
                  kPixelRefPx, ref.gyro_rms_rad_s, ref.accel_rms_m_s2, kMismatchMinPx);
    return buf;
}

/// Verdict of the thesis's claim at one point: 0 holds, 1 does not; ties noted in @p note.
int claim_at(const PointResult &p, std::string *note) {
    const double o = p.total[kOprf].rmse();
    const int others[2] = {kRansacF, kNone};
    int holds = 1;
    note->clear();
    for (int k : others) {
        const double x = p.total[k].rmse();
        if (!(o < x)) holds = 0;
        std::vector<double> d;
        for (size_t r = 0; r < p.run_rmse[kOprf].size(); ++r) {
            d.push_back(p.run_rmse[k][r] - p.run_rmse[kOprf][r]);
        }
        const double md = mean_of(d), se = std_error(d);
        const char *who = kMethodNames[k];
        char buf[96];
        if (!(o < x)) {
            std::snprintf(buf, sizeof buf, "%s%s not below %s", note->empty() ? "" : "; ",
                          kMethodNames[kOprf], who);
            *note += buf;
        }
        if (std::fabs(md) <= 2.0 * se) {
            std::snprintf(buf, sizeof buf, "%stie with %s within 2 SE", note->empty() ? "" : "; ",
                          who);
            *note += buf;
        }
    }
    return holds != 0 ? 0 : 1;
}

void print_sweep(const Sweep &s) {
    const char *col =
        s.which == 0 ? "meas. noise %" : (s.which == 1 ? "control noise %" : "mismatch %");
    std::printf("\n### %s\n\n", s.title);
    std::printf(
        "| %s | RMSE OPRF (mm) | RANSAC1 | RANSACF | NONE | time OPRF (us) | RANSAC1 | "
        "RANSACF | NONE | OPRF < RANSACF and < NONE |\n",
        col);
    std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
    std::string in_range, beyond, fails;
    for (const PointResult &p : s.points) {
        const double lvl = level_of(s, p.lv);
        std::printf("| %g |", lvl);
        for (const MethodRun &m : p.total) std::printf(" %.3g |", 1e3 * m.rmse());
        for (const MethodRun &m : p.total) std::printf(" %.0f |", mean_of(m.times_us));
        std::string note;
        const int v = claim_at(p, &note);
        std::printf(" %s%s%s%s |\n", v == 0 ? "yes" : "no", note.empty() ? "" : " (", note.c_str(),
                    note.empty() ? "" : ")");
        char buf[32];
        std::snprintf(buf, sizeof buf, "%s%g", "", lvl);
        std::string &dst = (v != 0) ? fails : ((lvl >= s.lo && lvl <= s.hi) ? in_range : beyond);
        if (!dst.empty()) dst += ", ";
        dst += buf;
    }
    std::printf(
        "\nClaim \"OPRF RMSE below F-matrix RANSAC and below no association\", %s sweep: "
        "holds inside the thesis's range (%g-%g %%) at %s; holds beyond it at %s; "
        "does not hold at %s.\n",
        s.name, s.lo, s.hi, in_range.empty() ? "no level" : in_range.c_str(),
        beyond.empty() ? "no level" : beyond.c_str(), fails.empty() ? "no level" : fails.c_str());
    // The thesis also says OPRF is slower than the F-matrix RANSAC (Chapter IV, last paragraph).
    int faster = 0;
    for (const PointResult &p : s.points) {
        faster += (mean_of(p.total[kOprf].times_us) < mean_of(p.total[kRansacF].times_us)) ? 1 : 0;
    }
    std::printf(
        "Time: OPRF's mean time per frame is below RANSACF's at %d of %zu levels (the "
        "thesis found OPRF slower than F-matrix RANSAC).\n",
        faster, s.points.size());
}

void write_csvs(FILE *rm, FILE *tm, const std::vector<Sweep> &sweeps, const ThesisOptions &opt,
                const Reference &ref) {
    const std::string units = units_line(ref);
    std::fprintf(rm,
                 "# sfd-sim thesis-loop (Kilic 2014 Chapter IV): EKF position RMSE per association "
                 "method; deterministic for the same binary and arguments (seed %llu, %d runs, %d "
                 "frames)\n# units: %s\n# nominal levels: measurement %g%%, control %g%%, "
                 "mismatch %g%%\n",
                 static_cast<unsigned long long>(opt.seed), opt.runs, opt.frames, units.c_str(),
                 kNominalMeasPct, kNominalCtrlPct, kNominalMismatchPct);
    std::fprintf(rm,
                 "sweep,level_pct,meas_noise_pct,control_noise_pct,mismatch_pct,sigma_px,"
                 "gyro_sigma_rad_s,accel_sigma_m_s2,method,runs,frames,rmse_m,rmse_se_m,max_err_m,"
                 "mismatch_accept_rate,inlier_reject_rate,hypotheses_mean,diverged_runs,"
                 "numeric_faults\n");
    std::fprintf(
        tm,
        "# sfd-sim thesis-loop: wall-clock time per frame of the pipeline's association and "
        "update stages (the EKF camera update included), microseconds; not "
        "deterministic\n# units: %s\n",
        units.c_str());
    std::fprintf(tm, "sweep,level_pct,method,runs,frames,time_mean_us,time_median_us\n");
    for (const Sweep &s : sweeps) {
        for (const PointResult &p : s.points) {
            for (int mi = 0; mi < kNumMethods; ++mi) {
                const MethodRun &m = p.total[mi];
                const double mar = m.mism_total > 0 ? static_cast<double>(m.mism_accepted) /
                                                          static_cast<double>(m.mism_total)
                                                    : 0.0;
                const double irr = m.inl_total > 0 ? static_cast<double>(m.inl_rejected) /
                                                         static_cast<double>(m.inl_total)
                                                   : 0.0;
                std::fprintf(
                    rm,
                    "%s,%g,%g,%g,%g,%.6g,%.6g,%.6g,%s,%d,%d,%.6g,%.3g,%.6g,%.6g,%.6g,"
                    "%.4g,%d,%u\n",
                    s.name, level_of(s, p.lv), p.lv.meas_pct, p.lv.ctrl_pct, p.lv.mismatch_pct,
                    p.sg.px, p.sg.gyro, p.sg.accel, kMethodNames[mi], opt.runs, opt.frames,
                    m.rmse(), std_error(p.run_rmse[mi]), m.max_err, mar, irr,
                    m.n_err > 0 ? static_cast<double>(m.hypotheses) / static_cast<double>(m.n_err)
                                : 0.0,
                    p.diverged[mi], p.faults[mi]);
                std::fprintf(tm, "%s,%g,%s,%d,%d,%.2f,%.2f\n", s.name, level_of(s, p.lv),
                             kMethodNames[mi], opt.runs, opt.frames, mean_of(m.times_us),
                             median_of(m.times_us));
            }
        }
    }
}

FILE *open_out(const std::string &dir, const char *name) {
    const std::string path = dir + "/" + name;
    FILE *f = std::fopen(path.c_str(), "w");
    if (f == nullptr) std::fprintf(stderr, "sfd-sim: cannot write %s\n", path.c_str());
    return f;
}

}  // namespace

void thesis_loop_help(FILE *out) {
    std::fprintf(
        out,
        "thesis-loop units (Kilic 2014 gives percentages without units):\n"
        "  measurement noise p%%  pixel noise sigma = p/100 * %g px per axis (5-20%% = 0.5-2 px)\n"
        "  control noise p%%      IMU white noise per 200 Hz sample, sigma = p/100 * the RMS\n"
        "                        magnitude of the true signal (gyro |w|, accelerometer |f| ~ g)\n"
        "  mismatch p%%           round(p/100 * n) of a frame's n matches get another matched\n"
        "                        landmark's current observation (>= %g px from the true one)\n"
        "  sweeps: measurement 5..20%% and 30, 40, 50; control 0..10%% and 15, 20, 30; mismatch\n"
        "  0..20%% and 30, 40, 50 (others at 10%% / 5%% / 10%%). Design: apps/sim/THESIS_LOOP.md\n",
        kPixelRefPx, kMismatchMinPx);
}

int run_thesis_loop(const ThesisOptions &opt) {
    const auto wall0 = std::chrono::steady_clock::now();
    // Open the outputs first: a bad --csv-dir fails before the sweep, not after it.
    FILE *rm = nullptr, *tm = nullptr;
    if (!opt.out_dir.empty()) {
        rm = open_out(opt.out_dir, "thesis_rmse.csv");
        tm = (rm != nullptr) ? open_out(opt.out_dir, "thesis_time.csv") : nullptr;
        if (tm == nullptr) {
            if (rm != nullptr) std::fclose(rm);
            return 2;
        }
    }
    const Reference ref = compute_reference(opt);
    std::vector<Sweep> sweeps;
    if (opt.quick) {
        sweeps.push_back(
            Sweep{"measurement", "(a) measurement noise (Figures 4-5)", 0, 5, 20, {5, 20}, {}});
        sweeps.push_back(
            Sweep{"control", "(b) control input noise (Figures 6-7)", 1, 0, 10, {0, 10}, {}});
        sweeps.push_back(
            Sweep{"mismatch", "(c) mismatch ratio (Figures 8-9)", 2, 5, 20, {0, 30}, {}});
    } else {
        sweeps.push_back(Sweep{"measurement",
                               "(a) measurement noise (Figures 4-5)",
                               0,
                               5,
                               20,
                               {5, 10, 15, 20, 30, 40, 50},
                               {}});
        sweeps.push_back(Sweep{"control",
                               "(b) control input noise (Figures 6-7)",
                               1,
                               0,
                               10,
                               {0, 2.5, 5, 7.5, 10, 15, 20, 30},
                               {}});
        sweeps.push_back(Sweep{"mismatch",
                               "(c) mismatch ratio (Figures 8-9)",
                               2,
                               5,
                               20,
                               {0, 5, 10, 15, 20, 30, 40, 50},
                               {}});
    }
    std::printf(
        "sfd-sim thesis-loop: Kilic 2014 Chapter IV, EKF localization loop; seed %llu, "
        "%d runs x %d frames (20 Hz, %.1f s) per point%s\n",
        static_cast<unsigned long long>(opt.seed), opt.runs, opt.frames, opt.frames * kFrameDt,
        opt.quick ? " (--quick)" : "");
    std::printf(
        "trajectory: %.1f m ellipse loop in %.0f s; RMS |w| %.4g rad/s, RMS |f| %.4g "
        "m/s^2; matches per frame %.0f (min %d, max %d); mean true image motion %.3g "
        "px/frame\n",
        kPi * std::sqrt(2.0 * (kEllipseA * kEllipseA + kEllipseB * kEllipseB)), kLoopPeriodS,
        ref.gyro_rms_rad_s, ref.accel_rms_m_s2, ref.matches_mean, ref.matches_min, ref.matches_max,
        ref.flow_mean_px);
    std::printf("units: %s\n", units_line(ref).c_str());
    std::printf(
        "nominal levels (the two not swept): measurement %g%%, control %g%%, mismatch "
        "%g%%; RMSE pooled over runs and frames; time = mean wall clock of the pipeline's "
        "association and update stages (association + EKF update)\n",
        kNominalMeasPct, kNominalCtrlPct, kNominalMismatchPct);
    auto ws = std::make_unique<Workspace>();
    // A progress line on a terminal (stderr, CI unset): runs done (one run = every method over
    // --frames frames at one sweep point), cleared before each sweep's table on stdout.
    long long runs_total = 0, runs_done = 0;
    for (const Sweep &s : sweeps) runs_total += static_cast<long long>(s.levels.size()) * opt.runs;
    sfdcli::Progress progress("sfd-sim thesis-loop", "runs");
    const std::function<void()> run_done = [&] {
        ++runs_done;
        progress.update(runs_done, double(runs_done) / double(runs_total));
    };
    for (Sweep &s : sweeps) {
        for (double level : s.levels) {
            PointResult p;
            if (!run_point(opt, ref, levels_for(s.which, level), &p, ws.get(), run_done)) {
                progress.clear();
                if (rm != nullptr) std::fclose(rm);
                if (tm != nullptr) std::fclose(tm);
                return 1;
            }
            s.points.push_back(std::move(p));
        }
        progress.clear();
        print_sweep(s);
    }
    progress.finish(runs_done);
    if (rm != nullptr && tm != nullptr) {
        write_csvs(rm, tm, sweeps, opt, ref);
        const bool ok = std::fclose(rm) == 0;
        if (std::fclose(tm) != 0 || !ok) return 1;
    }
    const double secs =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    std::printf("\n(%.1f s wall clock)\n", secs);
    return 0;
}

}  // namespace sfdsim
