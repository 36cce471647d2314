// SPDX-License-Identifier: MIT
// Simulated flights (IMU, CAMERA_INFO, FEATURES, TRUTH) as a stream of LCM-encoded messages
// (library sfd_sim_flight): generate_flight() hands each message, in time order, to a sink as it
// is made, so memory stays bounded whatever the number of frames. write_flight_log() is the sink
// that writes LCM's log format through lcm_eventlog (sfd-sim -o); sfd-hil --sim publishes the
// same stream over LCM.
#ifndef SFD_SIM_FLIGHT_LOG_HPP
#define SFD_SIM_FLIGHT_LOG_HPP

#include <cstdint>
#include <string>

namespace sfdsim {

struct FlightOptions {
    std::string scenario;  // paper-uav, mistracking, moving-object, worst-case
    std::string out_path;  // .lcmlog (write_flight_log only)
    uint64_t seed = 1;
    int frames = 400;  // 20 Hz camera frames in all, the rest at the start included
    // static tracks in view per frame (capped at the wire capacity, 512; moving-object: the
    // moving groups' points share this budget); <= 0: the scenario's default, SFD_MAX_FEATURES
    // for worst-case (the node's capacity), 200 otherwise
    int features = 0;
    // target fraction of spurious observations (mistracking, moving-object; paper-uav: the
    // paper's fault rate, see flight_log.cpp); measured fractions: FlightStats::kind
    double outlier_ratio = 0.1;
    double fault_magnitude = 0.02;  // paper-uav: k of k(-1, 1)^T in normalized coordinates
    double depth_var = 0.0;         // variance of the depth priors written (m^2)
    double pixel_noise_px = 1.0;
    // Start: rest_s seconds at rest (camera frames keep coming), then a C2 ramp of ramp_s
    // seconds into the trajectory; rest_s = 0: no rest and no ramp (the flight starts in motion).
    double rest_s = 2.0;
    double ramp_s = 3.0;
    // IMU (200 Hz): white-noise densities and bias random walks (apps/config/sfd.yaml's values);
    // per sample sigma = density / sqrt(dt), bias += rw * sqrt(dt) * N(0, 1).
    double gyro_noise = 3.4e-4;     // rad/s/sqrt(Hz)
    double accel_noise = 4.0e-3;    // m/s^2/sqrt(Hz)
    double gyro_bias_rw = 3.9e-5;   // rad/s^2/sqrt(Hz)
    double accel_bias_rw = 6.0e-3;  // m/s^3/sqrt(Hz)
    // Initial biases (IMU frame): the values below when *_given, else drawn per axis from
    // N(0, 0.002^2) rad/s and N(0, 0.02^2) m/s^2.
    bool gyro_bias_given = false;
    double gyro_bias[3] = {0.0, 0.0, 0.0};  // rad/s
    bool accel_bias_given = false;
    double accel_bias[3] = {0.0, 0.0, 0.0};  // m/s^2
    int truth_window = 2;  // frames a step (jump, drift step, mismatch) labels spurious (L - 1)
    // worst-case: the fraction of each frame's features replaced by uniformly random pixels
    // (labelled spurious); 1 = every feature of every frame.
    double random_fraction = 1.0;
};

/// True for the scenarios generate_flight() knows.
bool is_flight_scenario(const std::string &scenario);

/// Receives the generated messages one at a time, in time order.
class FlightSink {
  public:
    virtual ~FlightSink() = default;
    /// One message: channel (IMU, CAMERA_INFO, FEATURES, TRUTH), its utime (us; also the log
    /// event's timestamp) and the LCM encoding (valid only during the call). Return false to stop
    /// the generation.
    virtual bool message(const char *channel, int64_t utime, const uint8_t *data, int size) = 0;
};

struct FlightStats {
    int frames = 0;                          // FEATURES messages generated
    long long imu = 0;                       // IMU samples generated
    long long features = 0;                  // features over all frames
    long long spurious = 0;                  // of those, labelled spurious in TRUTH
    long long kind[6] = {0, 0, 0, 0, 0, 0};  // features per TRUTH kind (truth_t KIND_*)
    long long events[5] = {0, 0, 0, 0, 0};   // fault events per kind (jumps, drifts, moving
                                             // groups spawned, mismatches; [0] unused)
    double gyro_bias0[3] = {0.0, 0.0, 0.0};  // initial IMU biases (given or drawn)
    double accel_bias0[3] = {0.0, 0.0, 0.0};
    bool stopped = false;  // the sink asked to stop
};

/// Generates the flight into `sink`. Returns 0 (done, or stopped by the sink: stats->stopped),
/// 2 for an unknown scenario, 1 when a message cannot be encoded. `stats` may be null.
int generate_flight(const FlightOptions &opt, FlightSink &sink, FlightStats *stats);

/// Writes the log to opt.out_path and prints a one-line summary; returns a process exit code
/// (2: bad path or scenario, 1: write failure).
int write_flight_log(const FlightOptions &opt);

}  // namespace sfdsim

#endif
