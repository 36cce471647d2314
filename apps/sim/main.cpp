// SPDX-License-Identifier: MIT
// sfd-sim: simulated sensor scenarios.
//
// paper-uav (Tornqvist et al. 2008, Section IV): a helicopter at 58 m with a downward-looking
// camera over features spread uniformly on 40 x 40 m, feature altitude ~ N(58, 1) below the
// camera's nominal height. Until the parity detector and the LCM log writer land, this command
// flies the scenario through the core's camera model and gyro integration and reports what the
// detectors will stand on: how well the IMU predicts the image motion, and the test thresholds.
//
// Assumptions the paper leaves open (written down here and in the help text):
//  - motion: 5 m/s along x at constant height, roll/pitch oscillating +-3 deg at 0.5/0.3 Hz, yaw
//    rate 0.1 rad/s; camera 20 Hz, IMU 200 Hz (camera = IMU frame, identity extrinsics);
//  - gyro: white noise 1.7e-4 rad/s/sqrt(Hz) (EuRoC's ADIS16448 datasheet figure), constant
//    bias known to the integrator (the node estimates it; see SPEC);
//  - camera: pinhole, f = 500 px, 752 x 480 px, so sigma = 0.005 normalized = 2.5 px.
#include <sys/stat.h>

#include <cerrno>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <list>
#include <string>
#include <vector>

#include "euroc_semireal.hpp"
#include "flight_log.hpp"
#include "paper_uav.hpp"
#include "thesis_loop.hpp"
#include "sfd/sfd.h"
#include "sfd_cli.hpp"
#include "sfd_opencv_quiet.hpp"

namespace {

constexpr double kPi = 3.14159265358979323846;

struct Options {
    const char *scenario = nullptr;
    uint64_t seed = 1;
    int frames = -1;    // scenario default
    int features = -1;  // scenario default
    double alpha = 0.01;
    int windows = 10000;
    int window_frames = 2;
    int group_size = 3;
    double outlier_ratio = 0.1;
    double jump_px = 8.0;
    const char *csv_dir = nullptr;
    const char *out_log = nullptr;
    double fault_magnitude = 0.02;
    double depth_var = 0.0;
    double pixel_noise = 1.0;
    int truth_window = 2;
    int runs = -1;  // scenario default
    bool quick = false;
    // euroc-semireal (apps/sim/euroc_semireal.hpp); negative: the scenario's default
    const char *euroc_dir = nullptr;
    const char *config_out = nullptr;
    double camera_hz = 20.0;
    double spurious_fraction = 0.1;
    double pixel_sigma = -1.0;
    double semireal_depth_var = -1.0;
    double track_loss = 0.02;
    double mover_speed = 0.5;
    double random_fraction = 1.0;  // worst-case
    // flight logs (-o): rest start and IMU model (apps/sim/SIMULATION.md)
    double rest_s = 2.0;
    double ramp_s = 3.0;
    double gyro_noise = 3.4e-4;
    double accel_noise = 4.0e-3;
    double gyro_bias_rw = 3.9e-5;
    double accel_bias_rw = 6.0e-3;
    bool gyro_bias_given = false;
    double gyro_bias[3] = {0.0, 0.0, 0.0};
    bool accel_bias_given = false;
    double accel_bias[3] = {0.0, 0.0, 0.0};
};

// Attitude of the camera (world <- camera) at time t: downward-looking (camera z = world -z),
// with the roll/pitch oscillation and yaw rate of the assumptions above.
void attitude(double t, double R_CtoW[9]) {
    const double roll = 3.0 * kPi / 180.0 * std::sin(2.0 * kPi * 0.5 * t);
    const double pitch = 3.0 * kPi / 180.0 * std::sin(2.0 * kPi * 0.3 * t);
    const double yaw = 0.1 * t;
    const double rpy[3] = {roll, pitch, yaw};
    double Ry[9], Rp[9], Rr[9], tmp[9], Rb[9];
    const double ez[3] = {0, 0, rpy[2]}, ey[3] = {0, rpy[1], 0}, ex[3] = {rpy[0], 0, 0};
    sfd_so3_exp(ez, Ry);
    sfd_so3_exp(ey, Rp);
    sfd_so3_exp(ex, Rr);
    auto mul = [](const double *A, const double *B, double *C) {
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) {
                double s = 0;
                for (int k = 0; k < 3; ++k) s += A[3 * r + k] * B[3 * k + c];
                C[3 * r + c] = s;
            }
    };
    mul(Ry, Rp, tmp);
    mul(tmp, Rr, Rb);
    // body -> camera mounting: camera x = body x, camera y = -body y, camera z = -body z.
    const double R_CtoB[9] = {1, 0, 0, 0, -1, 0, 0, 0, -1};
    mul(Rb, R_CtoB, R_CtoW);
}

// Body rate in the camera frame by central difference of the attitude (exact enough at 1e-6 s).
void body_rate(double t, double w_C[3]) {
    const double h = 1e-6;
    double Ra[9], Rb[9], dR[9];
    attitude(t - h, Ra);
    attitude(t + h, Rb);
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
            double s = 0;
            for (int k = 0; k < 3; ++k) s += Ra[3 * k + r] * Rb[3 * k + c];
            dR[3 * r + c] = s;
        }
    double phi[3];
    sfd_so3_log(dR, phi);
    for (int k = 0; k < 3; ++k) w_C[k] = phi[k] / (2.0 * h);
}

int run_uav_imu(const Options &opt) {
    sfd_prng_t rng;
    sfd_prng_seed(&rng, opt.seed);
    sfd_camera_t cam;
    const double nodist[4] = {0, 0, 0, 0};
    if (sfd_camera_init(&cam, SFD_DISTORTION_PINHOLE, 752, 480, 500.0, 500.0, 376.0, 240.0,
                        nodist) != SFD_OK) {
        std::fprintf(stderr, "sfd-sim: camera init failed\n");
        return 1;
    }
    // Map: uniform over 40 x 40 m around the track's start, altitude 58 m below the camera.
    std::vector<double> map(3 * static_cast<size_t>(opt.features));
    for (int i = 0; i < opt.features; ++i) {
        map[3 * i + 0] = -20.0 + 40.0 * sfd_prng_uniform(&rng);
        map[3 * i + 1] = -20.0 + 40.0 * sfd_prng_uniform(&rng);
        map[3 * i + 2] = -(58.0 + sfd_prng_gaussian(&rng));  // N(58, 1) below the camera
    }
    const double speed = 5.0, dt_cam = 0.05, dt_imu = 0.005, noise_density = 1.7e-4;
    const double bias[3] = {0.02, -0.01, 0.005};
    const double sigma_imu = noise_density / std::sqrt(dt_imu);
    std::vector<sfd_imu_sample_t> imu;
    const int n_imu = static_cast<int>(opt.frames * dt_cam / dt_imu) + 3;
    imu.resize(static_cast<size_t>(n_imu));
    for (int k = 0; k < n_imu; ++k) {
        const double t = k * dt_imu;
        imu[k].t_us = static_cast<int64_t>(std::llround(t * 1e6));
        double w[3];
        body_rate(t, w);
        for (int a = 0; a < 3; ++a) {
            imu[k].gyro_rad_s[a] = w[a] + bias[a] + sigma_imu * sfd_prng_gaussian(&rng);
            imu[k].accel_m_s2[a] = 0.0;
        }
    }
    double sum_rot2 = 0, max_rot = 0, sum_px2 = 0, max_px = 0;
    long n_pred = 0, n_visible_total = 0, n_status_err = 0;
    const int per_seg = static_cast<int>(std::llround(dt_cam / dt_imu));
    for (int f = 1; f < opt.frames; ++f) {
        const double t0 = (f - 1) * dt_cam, t1 = f * dt_cam;
        double R0[9], R1[9], q[4], Rimu[9];
        attitude(t0, R0);
        attitude(t1, R1);
        const size_t first = static_cast<size_t>(f - 1) * static_cast<size_t>(per_seg);
        const size_t count = static_cast<size_t>(per_seg) + 1U;
        if (sfd_gyro_integrate(&imu[first], count, imu[first].t_us, imu[first + count - 1].t_us,
                               bias, 20000, q) != SFD_OK ||
            sfd_quat_to_rotmat(q, Rimu) != SFD_OK) {
            ++n_status_err;
            continue;
        }
        // True relative rotation R_C1toC0 = R0^T R1; error angle of the IMU's.
        double Rtrue[9], E[9], phi[3];
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) {
                double s = 0;
                for (int k = 0; k < 3; ++k) s += R0[3 * k + r] * R1[3 * k + c];
                Rtrue[3 * r + c] = s;
            }
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) {
                double s = 0;
                for (int k = 0; k < 3; ++k) s += Rimu[3 * k + r] * Rtrue[3 * k + c];
                E[3 * r + c] = s;
            }
        sfd_so3_log(E, phi);
        const double err = std::sqrt(phi[0] * phi[0] + phi[1] * phi[1] + phi[2] * phi[2]);
        sum_rot2 += err * err;
        if (err > max_rot) max_rot = err;
        // Prediction of frame f's pixels from frame f-1 with the true translation and IMU rotation.
        const double p0[3] = {speed * t0, 0, 0}, p1[3] = {speed * t1, 0, 0};
        int visible = 0;
        for (int i = 0; i < opt.features; ++i) {
            double c0[3], c1[3], uv0[2], uv1[2], pred[2];
            for (int r = 0; r < 3; ++r) {
                c0[r] = 0;
                c1[r] = 0;
                for (int k = 0; k < 3; ++k) {
                    c0[r] += R0[3 * k + r] * (map[3 * i + k] - p0[k]);
                    c1[r] += R1[3 * k + r] * (map[3 * i + k] - p1[k]);
                }
            }
            if (sfd_camera_project(&cam, c0, uv0, nullptr) != SFD_OK ||
                sfd_camera_project(&cam, c1, uv1, nullptr) != SFD_OK)
                continue;
            if (uv1[0] < 0 || uv1[0] >= 752 || uv1[1] < 0 || uv1[1] >= 480) continue;
            ++visible;
            // c1 = Rtrue^T (c0 - d) with d the translation in C0; predicted with Rimu instead.
            double d[3], cp[3];
            for (int r = 0; r < 3; ++r) {
                d[r] = 0;
                for (int k = 0; k < 3; ++k) d[r] += R0[3 * k + r] * (p1[k] - p0[k]);
            }
            for (int r = 0; r < 3; ++r) {
                cp[r] = 0;
                for (int k = 0; k < 3; ++k) cp[r] += Rimu[3 * k + r] * (c0[k] - d[k]);
            }
            if (sfd_camera_project(&cam, cp, pred, nullptr) != SFD_OK) continue;
            const double e = std::hypot(pred[0] - uv1[0], pred[1] - uv1[1]);
            sum_px2 += e * e;
            if (e > max_px) max_px = e;
            ++n_pred;
        }
        n_visible_total += visible;
    }
    std::printf("sfd-sim uav-imu: seed %" PRIu64 ", %d frames at 20 Hz, %d map features\n",
                opt.seed, opt.frames, opt.features);
    std::printf("  features in view per frame (mean)   %.1f\n",
                opt.frames > 1 ? static_cast<double>(n_visible_total) / (opt.frames - 1) : 0.0);
    std::printf("  gyro integration error, RMS / max   %.3g / %.3g mrad per frame\n",
                1e3 * std::sqrt(sum_rot2 / std::max(1, opt.frames - 1)), 1e3 * max_rot);
    std::printf("  IMU-predicted pixel error, RMS / max %.3g / %.3g px (%ld predictions)\n",
                n_pred ? std::sqrt(sum_px2 / static_cast<double>(n_pred)) : 0.0, max_px, n_pred);
    std::printf("  integration failures                %ld\n", n_status_err);
    std::printf("  parity thresholds at alpha = %.3g (chi-square upper quantiles):\n", opt.alpha);
    const int dofs[4] = {2, 3, 6, 9};
    const char *what[4] = {"n=3 L=2 unknown translation", "n=3 L=2 known translation",
                           "n=3 L=3 unknown translation", "n=3 L=3 known translation"};
    for (int k = 0; k < 4; ++k) {
        double thr = 0;
        if (sfd_chi2_quantile_upper(opt.alpha, dofs[k], &thr) != SFD_OK) return 1;
        std::printf("    dof %d (%s): %.4f\n", dofs[k], what[k], thr);
    }
    return n_status_err == 0 ? 0 : 1;
}

// mkdir -p: every missing directory of @p path, mode 0777 & ~umask. False with errno set.
bool make_dirs(const char *path) {
    const std::string p(path);
    for (size_t k = 1; k <= p.size(); ++k) {
        if (k < p.size() && p[k] != '/') continue;
        const std::string prefix = p.substr(0, k);
        if (::mkdir(prefix.c_str(), 0777) != 0 && errno != EEXIST) return false;
    }
    struct stat st;
    return ::stat(path, &st) == 0 && S_ISDIR(st.st_mode) ? true : (errno = ENOTDIR, false);
}

// The scenarios, what each does, and which options apply to it (the help of
// `sfd-sim SCENARIO --help` lists those; every option is accepted with every scenario).
struct Scenario {
    const char *name;
    const char *help;
};
const Scenario kScenarios[] = {
    {"paper-uav",
     "  Summary (no -o): Tornqvist et al. 2008 Section IV: helicopter at 58 m, downward\n"
     "  camera, features over 40x40 m; parity test Monte Carlo: P_fa and P_d against the\n"
     "  non-central chi-square, Figure 1 and ROC CSVs (--csv-dir).\n"
     "  Log (-o): the same flight over flat ground, the paper's fault k(-1,1) (normalized)\n"
     "  as a step of a track onto the ground point under the shifted pixel, followed from\n"
     "  then on (--fault-magnitude)."},
    {"mistracking",
     "  Log (-o): 20 m altitude over ground with relief; static tracker faults, each a third\n"
     "  of the spurious observations: jump onto another static point 5-30 px away (own\n"
     "  depth, followed for good), drift 0.3-2 px/frame for 3-10 frames then locked onto the\n"
     "  point under it, one-frame mismatch with a point 15-60 px away; --outlier-ratio of\n"
     "  the observations."},
    {"moving-object",
     "  Log (-o): as mistracking, plus 2-4 rigid moving groups (walkers 1-2 m/s, vehicles\n"
     "  5-15 m/s) crossing the view: half of --outlier-ratio moving, half static tracker\n"
     "  faults."},
    {"worst-case",
     "  Log (-o): the node at full capacity (sfd-hil): the mistracking flight with --features\n"
     "  N (default and max SFD_MAX_FEATURES of this build) per frame, of which round(F * N),\n"
     "  drawn anew every frame, are replaced by pixels uniform over the image (same track\n"
     "  ids; TRUTH: spurious), F = --random-fraction (1.0). At F = 1 every match is an\n"
     "  outlier. No tracker faults (--outlier-ratio ignored)."},
    {"euroc-semireal", ""},  // semireal_help()
    {"isolation",
     "  Summary: sfd isolation vs the paper's discard-the-group rule at equal detection\n"
     "  probability, simulated flight with mistracks."},
    {"uav-imu",
     "  Summary: gyro integration and IMU-predicted pixel motion over the paper's flight\n"
     "  (camera model + gyro integration check)."},
    {"thesis-loop",
     "  Summary: Kilic 2014 Chapter IV: OPRF, 1-point RANSAC, F-matrix RANSAC and no\n"
     "  association in an EKF localization loop (ground-truth loop, map, 200 Hz IMU, 20 Hz\n"
     "  camera); sweeps of measurement noise, IMU (control input) noise and mismatch ratio;\n"
     "  association time and position RMSE per method (Figures 4-9): thesis_rmse.csv,\n"
     "  thesis_time.csv (--csv-dir)."},
};

const Scenario *find_scenario(const std::string &name) {
    for (const Scenario &s : kScenarios) {
        if (name == s.name) return &s;
    }
    return nullptr;
}

// The scenarios an option applies to (space-separated; "log" = the flight-log scenarios with -o).
bool applies(const char *scope, const std::string &scenario) {
    if (scenario.empty()) return true;
    const std::string sc = std::string(" ") + scope + " ";
    const bool log = sfdsim::is_flight_scenario(scenario);
    return sc.find(" " + scenario + " ") != std::string::npos ||
           (log && sc.find(" log ") != std::string::npos) || sc.find(" all ") != std::string::npos;
}

}  // namespace

int main(int argc, char **argv) {
    sfdapp::quiet_opencv();  // euroc-semireal reads sensor.yaml through cv::FileStorage
    Options opt;
    // `sfd-sim SCENARIO ...`: the scenario is a subcommand with its own help; its name is the
    // first word that is not an option (an option's value aside).
    std::string scenario_word;
    if (argc > 1 && argv[1][0] != '-') scenario_word = argv[1];
    const Scenario *scenario = find_scenario(scenario_word);
    const std::string shown = scenario != nullptr ? scenario_word : "";
    sfdcli::Parser cli(
        "sfd-sim", shown.empty() ? "sfd-sim" : "sfd-sim " + shown,
        shown.empty() ? "SCENARIO [options]          (a summary, no log)\n"
                        "       sfd-sim SCENARIO -o OUT.lcmlog [...] (a sensor log for "
                        "sfd-replay/node)\n"
                        "       sfd-sim SCENARIO --help              (the scenario's options)"
                      : "[options]",
        scenario == nullptr
            ? "Log scenarios (-o): IMU 200 Hz, CAMERA_INFO, FEATURES 20 Hz, TRUTH (with the kind\n"
              "of each spurious feature). Every flight starts at rest (--rest-s), then ramps\n"
              "smoothly into its trajectory; IMU with white noise and random-walk biases. Faults\n"
              "as a tracker makes them (apps/sim/SIMULATION.md). Scenarios:\n"
              "  log (-o):  paper-uav, mistracking, moving-object, worst-case, euroc-semireal\n"
              "  summary:   paper-uav, isolation, uav-imu, thesis-loop"
            : scenario->help);
    // add(name, metavar, scope, help, setter)
    const auto add = [&cli, &shown](const char *name, const char *metavar, const char *scope,
                                    const std::string &help, sfdcli::Setter set) {
        sfdcli::Option o;
        o.name = name;
        o.metavar = metavar;
        o.help = help;
        o.set = std::move(set);
        o.hidden = !applies(scope, shown);
        if (!std::strcmp(name, "output")) o.short_name = 'o';
        cli.add(o);
    };
    std::list<std::string> texts;  // the values the const char * options point to
    const auto text_opt = [&texts](const char **dst) -> sfdcli::Setter {
        return [&texts, dst](const std::string &v, std::string *) {
            texts.push_back(v);
            *dst = texts.back().c_str();
            return true;
        };
    };
    const std::string max_f = std::to_string(SFD_MAX_FEATURES);
    cli.section("Options");
    add("output", "OUT.lcmlog", "log euroc-semireal", "write a sensor log (log scenarios)",
        text_opt(&opt.out_log));
    add("seed", "N", "all", "PRNG seed (1)", [&opt](const std::string &v, std::string *why) {
        errno = 0;
        opt.seed = std::strtoull(v.c_str(), nullptr, 10);
        if (v.empty() || v.find_first_not_of("0123456789") != std::string::npos || errno != 0) {
            *why = "is not an unsigned 64-bit integer";
            return false;
        }
        return true;
    });
    add("frames", "N", "log isolation uav-imu thesis-loop",
        "frames at 20 Hz: flight logs 400 (the rest included); isolation /\n"
        "uav-imu 200; thesis-loop: per run (800 = one 40 s loop; --quick 200)",
        sfdcli::int_setter(&opt.frames, 1, 100000));
    add("features", "N", "log euroc-semireal isolation uav-imu",
        "features (tracks) per frame: flight logs 200 (worst-case " + max_f +
            "),\neuroc-semireal 200, isolation 240, uav-imu 200; max " + max_f,
        sfdcli::int_setter(&opt.features, 1, SFD_MAX_FEATURES));
    add("windows", "N", "paper-uav", "paper-uav summary: Monte Carlo windows per case (10000)",
        sfdcli::int_setter(&opt.windows, 10, 10000000));
    add("window-frames", "L", "paper-uav", "paper-uav summary: window length (2, the paper's)",
        sfdcli::int_setter(&opt.window_frames, 2, SFD_MAX_WINDOW));
    add("group-size", "n", "paper-uav", "paper-uav summary: group size (3)",
        sfdcli::int_setter(&opt.group_size, 1, SFD_MAX_GROUP));
    add("false-alarm-rate", "A", "uav-imu",
        "uav-imu: false-alarm rate of the printed thresholds (0.01)",
        [&opt](const std::string &v, std::string *why) {
            if (!sfdcli::parse_real(v, 0.0, 1.0, &opt.alpha, why) || opt.alpha <= 0.0 ||
                opt.alpha >= 1.0) {
                *why = "is not in (0, 1)";
                return false;
            }
            return true;
        });
    add("runs", "N", "thesis-loop", "thesis-loop: Monte Carlo runs per sweep point (5; --quick 2)",
        sfdcli::int_setter(&opt.runs, 1, 10000));
    {
        sfdcli::Option q;
        q.name = "quick";
        q.help = "thesis-loop: two levels per sweep (5/20, 0/10, 0/30 %)";
        q.set = [&opt](const std::string &, std::string *) {
            opt.quick = true;
            return true;
        };
        q.hidden = !applies("thesis-loop", shown);
        cli.add(q);
    }
    add("outlier-ratio", "R", "log isolation",
        "target fraction of spurious observations (0.1); paper-uav log: a\n"
        "fraction R / (W - 1) of the tracks get the fault each frame",
        sfdcli::real_setter(&opt.outlier_ratio, 0.0, 1.0));
    add("jump-px", "P", "isolation euroc-semireal",
        "mistrack jump (8 px; flight logs draw 5-30 px)",
        sfdcli::real_setter(&opt.jump_px, 0.0, 1000.0));
    add("csv-dir", "DIR", "paper-uav isolation thesis-loop",
        "write the scenario's CSV files into DIR (created if missing)", text_opt(&opt.csv_dir));
    add("fault-magnitude", "K", "paper-uav",
        "paper-uav log: k of k(-1,1) in normalized units (0.02)",
        sfdcli::real_setter(&opt.fault_magnitude, 0.0, 1e4));
    add("depth-var-m2", "V", "log euroc-semireal",
        "depth prior variance written with the features (m^2; flight\nlogs 0, euroc-semireal 0.01)",
        [&opt](const std::string &v, std::string *why) {
            if (!sfdcli::parse_real(v, 0.0, 1e4, &opt.depth_var, why)) return false;
            opt.semireal_depth_var = opt.depth_var;
            return true;
        });
    add("pixel-sigma-px", "S", "log euroc-semireal",
        "pixel noise per axis (px; flight logs 1, euroc-semireal 0.5)",
        [&opt](const std::string &v, std::string *why) {
            if (!sfdcli::parse_real(v, 0.0, 100.0, &opt.pixel_noise, why)) return false;
            opt.pixel_sigma = opt.pixel_noise;
            return true;
        });
    add("truth-window", "W", "log euroc-semireal",
        "frames a step (jump, drift step, mismatch and its return) labels\n"
        "the track spurious, from the step: the windows that mix both sides\n"
        "of it, L - 1 (2); moving points: every frame",
        sfdcli::int_setter(&opt.truth_window, 1, 100));
    add("rest-s", "T", "log", "seconds at rest at the start (2.0; 0: start in motion, no ramp)",
        sfdcli::real_setter(&opt.rest_s, 0.0, 3600.0));
    add("ramp-s", "T", "log", "seconds of the C2 ramp from rest into the trajectory (3.0)",
        sfdcli::real_setter(&opt.ramp_s, 0.1, 600.0));
    add("gyro-noise-rad-s-rthz", "D", "log",
        "gyro white noise density (3.4e-4 rad/s/sqrt(Hz)); the IMU model's\n"
        "densities are sfd_ekf_noise_default()'s (the shipped filter.* keys assume\n"
        "three times the white noise, for a real IMU)\n"
        "(per 5 ms sample: sigma = D / sqrt(dt), bias += D_rw sqrt(dt) N(0, 1))",
        sfdcli::real_setter(&opt.gyro_noise, 0.0, 1.0));
    add("accel-noise-m-s2-rthz", "D", "log",
        "accelerometer white noise density (4.0e-3 m/s^2/sqrt(Hz))",
        sfdcli::real_setter(&opt.accel_noise, 0.0, 10.0));
    add("gyro-bias-rw-rad-s2-rthz", "D", "log", "gyro bias random walk (3.9e-5 rad/s^2/sqrt(Hz))",
        sfdcli::real_setter(&opt.gyro_bias_rw, 0.0, 1.0));
    add("accel-bias-rw-m-s3-rthz", "D", "log",
        "accelerometer bias random walk (6.0e-3 m/s^3/sqrt(Hz))",
        sfdcli::real_setter(&opt.accel_bias_rw, 0.0, 10.0));
    const auto bias_opt = [&opt](bool gyro) -> sfdcli::Setter {
        return [&opt, gyro](const std::string &v, std::string *why) {
            const double lim = gyro ? 1.0 : 10.0;
            double b[3];
            if (!sfdcli::parse_vec3(v, b, why)) return false;
            for (int k = 0; k < 3; ++k) {
                if (!(std::fabs(b[k]) <= lim)) {
                    char buf[64];
                    std::snprintf(buf, sizeof buf, "is not within +-%g per axis", lim);
                    *why = buf;
                    return false;
                }
            }
            for (int k = 0; k < 3; ++k) (gyro ? opt.gyro_bias : opt.accel_bias)[k] = b[k];
            (gyro ? opt.gyro_bias_given : opt.accel_bias_given) = true;
            return true;
        };
    };
    add("gyro-bias-rad-s", "X,Y,Z", "log",
        "initial gyro bias (rad/s; default drawn, N(0, 0.002^2))", bias_opt(true));
    add("accel-bias-m-s2", "X,Y,Z", "log",
        "initial accelerometer bias (m/s^2; default drawn, N(0, 0.02^2))", bias_opt(false));
    add("random-fraction", "F", "worst-case",
        "worst-case: fraction of features replaced by random pixels every\nframe, 0..1 (1.0)",
        sfdcli::real_setter(&opt.random_fraction, 0.0, 1.0));
    add("euroc", "DIR", "euroc-semireal",
        "euroc-semireal: folder with mav0/ (imu0, state_groundtruth_estimate0,\ncam0)",
        text_opt(&opt.euroc_dir));
    add("camera-hz", "F", "euroc-semireal", "euroc-semireal: camera rate (20 Hz)",
        sfdcli::real_setter(&opt.camera_hz, 0.1, 200.0));
    add("spurious-fraction", "R", "euroc-semireal",
        "euroc-semireal: target fraction of spurious features, a third per\nkind (0.1)",
        sfdcli::real_setter(&opt.spurious_fraction, 0.0, 0.9));
    add("track-loss", "P", "euroc-semireal",
        "euroc-semireal: probability per frame that a track ends (0.02)",
        sfdcli::real_setter(&opt.track_loss, 0.0, 1.0));
    add("mover-speed-m-s", "V", "euroc-semireal",
        "euroc-semireal: speed of the moving group (0.5 m/s)",
        sfdcli::real_setter(&opt.mover_speed, 0.0, 100.0));
    add("config-out", "F", "euroc-semireal",
        "euroc-semireal: also write an sfd-replay configuration for the log:\n"
        "filter.init_from_truth 1, the ground truth's gyro and accelerometer\n"
        "biases at the start, pixel_sigma_px S",
        text_opt(&opt.config_out));
    // The spellings of sfd 0.1 (deprecated).
    cli.alias("alpha", "false-alarm-rate");
    cli.alias("depth-var", "depth-var-m2");
    cli.alias("pixel-noise", "pixel-sigma-px");
    cli.alias("pixel-sigma", "pixel-sigma-px");
    cli.alias("gyro-noise", "gyro-noise-rad-s-rthz");
    cli.alias("accel-noise", "accel-noise-m-s2-rthz");
    cli.alias("gyro-bias-rw", "gyro-bias-rw-rad-s2-rthz");
    cli.alias("accel-bias-rw", "accel-bias-rw-m-s3-rthz");
    cli.alias("gyro-bias", "gyro-bias-rad-s");
    cli.alias("accel-bias", "accel-bias-m-s2");
    cli.alias("mover-speed", "mover-speed-m-s");
    if (scenario != nullptr && !std::strcmp(scenario->name, "thesis-loop")) {
        cli.extra_help(sfdsim::thesis_loop_help);
    } else if (scenario != nullptr && !std::strcmp(scenario->name, "euroc-semireal")) {
        cli.extra_help(sfdsim::semireal_help);
    }
    cli.epilog(scenario == nullptr ? "sfd-sim SCENARIO --help lists the options of SCENARIO.\n"
                                     "Exit: 0 ok, 2 bad usage, 1 internal failure."
                                   : "Exit: 0 ok, 2 bad usage, 1 internal failure.");
    std::vector<std::string> positional;
    if (const int rc = cli.parse(argc, argv, &positional); rc >= 0) return rc;
    if (positional.empty()) return cli.fail("missing SCENARIO (sfd-sim --help)");
    if (positional.size() > 1) return cli.fail("unexpected argument " + positional[1]);
    texts.push_back(positional[0]);
    opt.scenario = texts.back().c_str();
    if (opt.csv_dir != nullptr && !make_dirs(opt.csv_dir)) {  // like `mkdir -p`
        std::fprintf(stderr, "sfd-sim: --csv-dir %s: cannot create: %s\n", opt.csv_dir,
                     std::strerror(errno));
        return 2;
    }
    if (!std::strcmp(opt.scenario, "euroc-semireal")) {
        if (opt.euroc_dir == nullptr || opt.out_log == nullptr) {
            std::fprintf(stderr, "sfd-sim: euroc-semireal needs --euroc DIR and -o OUT.lcmlog\n");
            return 2;
        }
        sfdsim::SemirealOptions so;
        so.euroc_dir = opt.euroc_dir;
        so.out_path = opt.out_log;
        so.config_out = opt.config_out ? opt.config_out : "";
        so.seed = opt.seed;
        so.features = opt.features > 0 ? opt.features : 200;
        so.camera_hz = opt.camera_hz;
        so.spurious_fraction = opt.spurious_fraction;
        if (opt.pixel_sigma >= 0.0) so.pixel_sigma_px = opt.pixel_sigma;
        if (opt.semireal_depth_var >= 0.0) so.depth_var_m2 = opt.semireal_depth_var;
        so.jump_px = opt.jump_px;
        so.track_loss = opt.track_loss;
        so.mover_speed_m_s = opt.mover_speed;
        so.truth_window = opt.truth_window;
        return sfdsim::write_semireal_log(so);
    }
    if (opt.out_log != nullptr) {
        if (!sfdsim::is_flight_scenario(opt.scenario)) {
            std::fprintf(stderr,
                         "sfd-sim: -o: scenario %s writes no log (paper-uav, mistracking, "
                         "moving-object, worst-case, euroc-semireal do)\n",
                         opt.scenario);
            return 2;
        }
        sfdsim::FlightOptions fo;
        fo.scenario = opt.scenario;
        fo.out_path = opt.out_log;
        fo.seed = opt.seed;
        fo.frames = opt.frames > 0 ? opt.frames : 400;
        fo.features = opt.features;  // <= 0: the scenario's default
        fo.random_fraction = opt.random_fraction;
        fo.outlier_ratio = opt.outlier_ratio;
        fo.fault_magnitude = opt.fault_magnitude;
        fo.depth_var = opt.depth_var;
        fo.pixel_noise_px = opt.pixel_noise;
        fo.truth_window = opt.truth_window;
        fo.rest_s = opt.rest_s;
        fo.ramp_s = opt.ramp_s;
        fo.gyro_noise = opt.gyro_noise;
        fo.accel_noise = opt.accel_noise;
        fo.gyro_bias_rw = opt.gyro_bias_rw;
        fo.accel_bias_rw = opt.accel_bias_rw;
        fo.gyro_bias_given = opt.gyro_bias_given;
        fo.accel_bias_given = opt.accel_bias_given;
        for (int k = 0; k < 3; ++k) {
            fo.gyro_bias[k] = opt.gyro_bias[k];
            fo.accel_bias[k] = opt.accel_bias[k];
        }
        return sfdsim::write_flight_log(fo);
    }
    if (!std::strcmp(opt.scenario, "paper-uav")) {
        sfdsim::PaperOptions po;
        po.seed = opt.seed;
        po.windows = opt.windows;
        po.window_frames = opt.window_frames;
        po.group_size = opt.group_size;
        po.out_dir = opt.csv_dir ? opt.csv_dir : "";
        return sfdsim::run_paper_uav(po);
    }
    if (!std::strcmp(opt.scenario, "isolation")) {
        sfdsim::IsolationOptions io;
        io.seed = opt.seed;
        io.frames = opt.frames > 0 ? opt.frames : 200;
        io.features = opt.features > 0 ? opt.features : 240;
        io.outlier_ratio = opt.outlier_ratio;
        io.jump_px = opt.jump_px;
        io.out_dir = opt.csv_dir ? opt.csv_dir : "";
        return sfdsim::run_isolation(io);
    }
    if (!std::strcmp(opt.scenario, "uav-imu")) {
        if (opt.frames < 0) opt.frames = 200;
        if (opt.features < 0) opt.features = 200;
        return run_uav_imu(opt);
    }
    if (!std::strcmp(opt.scenario, "thesis-loop")) {
        sfdsim::ThesisOptions to;
        to.seed = opt.seed;
        to.quick = opt.quick;
        to.frames = opt.frames > 0 ? opt.frames : (opt.quick ? 200 : 800);
        to.runs = opt.runs > 0 ? opt.runs : (opt.quick ? 2 : 5);
        to.out_dir = opt.csv_dir ? opt.csv_dir : "";
        return sfdsim::run_thesis_loop(to);
    }
    std::fprintf(stderr,
                 "sfd-sim: unknown scenario: %s (available: paper-uav, isolation, uav-imu, "
                 "thesis-loop, euroc-semireal; mistracking, moving-object, worst-case with -o)\n",
                 opt.scenario);
    return 2;
}
