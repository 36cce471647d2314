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
    int frames = 400;  // 20 Hz camera frames
    // features in view per frame (capped at the wire capacity, 512); <= 0: the scenario's
    // default, SFD_MAX_FEATURES for worst-case (the node's capacity), 200 otherwise
    int features = 0;
    double outlier_ratio = 0.1;
    double fault_magnitude = 0.02;  // paper-uav: k of k(-1, 1)^T in normalized coordinates
    double jump_px = 8.0;           // mistracking: jump size (px)
    double depth_var = 0.0;         // variance of the depth priors written (m^2)
    double pixel_noise_px = 1.0;
    double gyro_noise = 1.7e-4;             // rad/s/sqrt(Hz)
    double gyro_bias[3] = {0.0, 0.0, 0.0};  // rad/s
    int truth_window = 2;  // frames a mistracked track is labelled spurious (L - 1)
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
    int frames = 0;          // FEATURES messages generated
    long long imu = 0;       // IMU samples generated
    long long features = 0;  // features over all frames
    long long spurious = 0;  // of those, labelled spurious in TRUTH
    bool stopped = false;    // the sink asked to stop
};

/// Generates the flight into `sink`. Returns 0 (done, or stopped by the sink: stats->stopped),
/// 2 for an unknown scenario, 1 when a message cannot be encoded. `stats` may be null.
int generate_flight(const FlightOptions &opt, FlightSink &sink, FlightStats *stats);

/// Writes the log to opt.out_path and prints a one-line summary; returns a process exit code
/// (2: bad path or scenario, 1: write failure).
int write_flight_log(const FlightOptions &opt);

}  // namespace sfdsim

#endif
