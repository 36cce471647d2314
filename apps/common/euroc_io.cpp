// SPDX-License-Identifier: MIT
#include "euroc_io.hpp"
#include "sfd_opencv_quiet.hpp"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <opencv2/core.hpp>

#include "sfd/sfd_rotation.h"

namespace sfdapp {
namespace {

// The parts joined, for error messages built inside loops (one string, appended to).
template <typename... Parts>
std::string cat(const Parts &...parts) {
    std::string s;
    ((s += parts), ...);
    return s;
}

std::string trim(const std::string &s) {
    std::size_t a = 0, b = s.size();
    while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
    while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
    return s.substr(a, b - a);
}

// The comma-separated fields of a line, trimmed; "a,b," has three (the last empty).
std::vector<std::string> split_fields(const std::string &line) {
    std::vector<std::string> fields;
    std::size_t start = 0;
    for (;;) {
        const std::size_t comma = line.find(',', start);
        fields.push_back(trim(
            line.substr(start, comma == std::string::npos ? std::string::npos : comma - start)));
        if (comma == std::string::npos) break;
        start = comma + 1;
    }
    return fields;
}

// A list of `count` numbers at n; false with "where: reason".
bool read_numbers(const cv::FileNode &n, const std::string &where, std::size_t count, double *out,
                  std::string *err) {
    if (!n.isSeq() || n.size() != count) {
        *err = where + ": expected a list of " + std::to_string(count) + " numbers";
        return false;
    }
    for (std::size_t k = 0; k < count; ++k) {
        const cv::FileNode e = n[static_cast<int>(k)];
        out[k] = (e.isReal() || e.isInt()) ? static_cast<double>(e) : NAN;
        if (!std::isfinite(out[k])) {
            *err = cat(where, ": element ", std::to_string(k + 1), " is not a finite number");
            return false;
        }
    }
    return true;
}

}  // namespace

bool read_euroc_csv(const std::string &path, std::size_t min_cols, std::size_t max_cols,
                    std::vector<EurocRow> *rows, std::string *err) {
    std::ifstream in(path);
    if (!in) {
        *err = path + ": cannot open";
        return false;
    }
    rows->clear();
    std::string line;
    long line_no = 0;
    while (std::getline(in, line)) {
        ++line_no;
        const std::string t = trim(line);
        if (t.empty() || t[0] == '#') continue;
        std::vector<std::string> fields = split_fields(t);
        const std::string where = path + ":" + std::to_string(line_no);
        if (fields.size() < min_cols || fields.size() > max_cols) {
            const std::string want =
                min_cols == max_cols ? std::to_string(min_cols)
                : max_cols == kAnyCols
                    ? cat("at least ", std::to_string(min_cols))
                    : cat(std::to_string(min_cols), " to ", std::to_string(max_cols));
            *err = cat(where, ": expected ", want, " comma-separated fields, got ",
                       std::to_string(fields.size()));
            return false;
        }
        char *end = nullptr;
        errno = 0;
        const long long stamp = std::strtoll(fields[0].c_str(), &end, 10);
        if (fields[0].empty() || *end != '\0' || errno != 0 || stamp < 0) {
            *err = cat(where, ": field 1: not a timestamp in ns (a non-negative integer): '",
                       fields[0], "'");
            return false;
        }
        if (!rows->empty() && stamp <= rows->back().t_ns) {
            *err = cat(where, ": timestamp ", fields[0], " is not after the previous row's");
            return false;
        }
        fields.erase(fields.begin());
        EurocRow row;
        row.t_ns = stamp;
        row.fields = std::move(fields);
        row.line = line_no;
        rows->push_back(std::move(row));
    }
    if (rows->empty()) {
        *err = path + ": no data rows";
        return false;
    }
    return true;
}

bool euroc_row_numbers(const std::string &path, const EurocRow &row, std::size_t first,
                       std::size_t count, double *out, std::string *err) {
    const std::string where = path + ":" + std::to_string(row.line);
    for (std::size_t i = 0; i < count; ++i) {
        const std::size_t k = first + i;
        const std::string column = std::to_string(k + 2);  // the timestamp is column 1
        if (k >= row.fields.size()) {
            *err = cat(where, ": field ", column, ": missing");
            return false;
        }
        char *end = nullptr;
        out[i] = std::strtod(row.fields[k].c_str(), &end);
        if (row.fields[k].empty() || *end != '\0' || !std::isfinite(out[i])) {
            *err = cat(where, ": field ", column, ": not a finite number: '", row.fields[k], "'");
            return false;
        }
    }
    return true;
}

bool read_euroc_sensor_yaml(const std::string &path, EurocCamera *out, std::string *err) {
    if (!std::ifstream(path)) {  // before OpenCV, which would print its own line about it
        *err = path + ": cannot open";
        return false;
    }
    cv::FileStorage fs;
    try {
        if (!fs.open(path, cv::FileStorage::READ)) {
            *err = path +
                   ": not readable as YAML (cv::FileStorage; the file must begin with "
                   "%YAML:1.0)";
            return false;
        }
        const cv::FileNode root = fs.root();
        if (!root["T_BS"].isMap()) {
            *err = path + ": T_BS: expected a map with data: [16 numbers] (row-major 4x4)";
            return false;
        }
        double res[2], intr[4], dist[4];
        if (!read_numbers(root["T_BS"]["data"], path + ": T_BS.data", 16, out->T_BS, err) ||
            !read_numbers(root["resolution"], path + ": resolution", 2, res, err) ||
            !read_numbers(root["intrinsics"], path + ": intrinsics", 4, intr, err) ||
            !read_numbers(root["distortion_coefficients"], path + ": distortion_coefficients", 4,
                          dist, err)) {
            return false;
        }
        const cv::FileNode cm = root["camera_model"], dm = root["distortion_model"];
        const std::string cms = cm.isString() ? static_cast<std::string>(cm) : std::string();
        if (cms != "pinhole") {
            *err = path + ": camera_model: expected \"pinhole\", got '" + cms + "'";
            return false;
        }
        const std::string dms = dm.isString() ? static_cast<std::string>(dm) : std::string();
        int model = -1;
        if (dms == "radial-tangential" || dms == "radtan") model = SFD_DISTORTION_RADTAN;
        if (dms == "equidistant") model = SFD_DISTORTION_EQUIDISTANT;
        if (model < 0) {
            *err = path + ": distortion_model: expected radial-tangential or equidistant, got '" +
                   dms + "'";
            return false;
        }
        if (res[0] != std::floor(res[0]) || res[1] != std::floor(res[1]) || res[0] < 1.0 ||
            res[1] < 1.0 || res[0] > 1e6 || res[1] > 1e6) {
            *err = path + ": resolution: expected two positive whole numbers";
            return false;
        }
        if (sfd_camera_init(&out->camera, model, static_cast<int>(res[0]), static_cast<int>(res[1]),
                            intr[0], intr[1], intr[2], intr[3], dist) != SFD_OK) {
            *err = path +
                   ": intrinsics/resolution/distortion_coefficients rejected by the "
                   "camera model (non-positive focal length or size?)";
            return false;
        }
        if (sfd_extrinsics_from_matrix(&out->ext, out->T_BS) != SFD_OK) {
            *err = path +
                   ": T_BS is not a rigid transform (rotation orthonormal within 1e-6, last row "
                   "0 0 0 1)";
            return false;
        }
    } catch (const cv::Exception &e) {
        *err = opencv_yaml_error(path, e);
        return false;
    }
    return true;
}

}  // namespace sfdapp
