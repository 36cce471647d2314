// SPDX-License-Identifier: MIT
// Readers of the EuRoC / ASL dataset format shared by sfd-euroc (apps/euroc) and
// `sfd-sim euroc-semireal` (apps/sim): the CSV files (imu0/data.csv, cam0/data.csv,
// state_groundtruth_estimate0/data.csv) and a camera's sensor.yaml. Every error names the file,
// and for a CSV the line and field: "path:line: field 5: not a finite number: '9.8x1'".
#ifndef SFD_APPS_EUROC_IO_HPP
#define SFD_APPS_EUROC_IO_HPP

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "sfd/sfd_camera.h"
#include "sfd/sfd_rotation.h"

namespace sfdapp {

/// One data row of a EuRoC CSV: the timestamp (ns) and the fields after it, trimmed.
struct EurocRow {
    int64_t t_ns = 0;
    std::vector<std::string> fields;
    long line = 0;  // 1-based line in the file
};

/// max_cols of read_euroc_csv for "no upper bound".
constexpr std::size_t kAnyCols = static_cast<std::size_t>(-1);

/// Reads a EuRoC CSV: lines starting with '#' and blank lines are skipped; every other line holds
/// between min_cols and max_cols comma-separated fields (the timestamp included; a trailing comma
/// makes an empty last field), the first an integer timestamp in ns, >= 0 and strictly
/// increasing. False, with "path[:line]: reason" in err, for an unreadable file, a malformed row
/// or no data row at all.
bool read_euroc_csv(const std::string &path, std::size_t min_cols, std::size_t max_cols,
                    std::vector<EurocRow> *rows, std::string *err);

/// Parses fields [first, first + count) of a row (0 = the first field after the timestamp) as
/// finite numbers into out. False, with "path:line: field K: not a finite number: 'x'" (K the
/// 1-based column in the file), for a missing or malformed field.
bool euroc_row_numbers(const std::string &path, const EurocRow &row, std::size_t first,
                       std::size_t count, double *out, std::string *err);

/// A camera's sensor.yaml (Kalibr / EuRoC): camera_model pinhole, resolution [w, h], intrinsics
/// [fu, fv, cu, cv], distortion_model radial-tangential (or radtan) or equidistant,
/// distortion_coefficients (4), T_BS.data (16, row-major: the camera's pose in the body (IMU)
/// frame). Read with OpenCV's cv::FileStorage (the file must begin with %YAML:1.0); the camera is
/// checked by sfd_camera_init and T_BS by sfd_extrinsics_from_matrix. A whole-number resolution
/// is required (EuRoC writes [752, 480]).
struct EurocCamera {
    sfd_camera_t camera{};
    double T_BS[16] = {};
    sfd_extrinsics_t ext{};  // T_BS as the core's extrinsics
};

/// Reads and checks a sensor.yaml; false with "path: reason" in err.
bool read_euroc_sensor_yaml(const std::string &path, EurocCamera *out, std::string *err);

}  // namespace sfdapp

#endif  // SFD_APPS_EUROC_IO_HPP
