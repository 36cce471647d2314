// SPDX-License-Identifier: MIT
// sfd-sim: the pieces every log scenario shares: an LCM log file written through LCM's own
// lcm_eventlog API, and the CAMERA_INFO message of a camera model and its extrinsics.
#ifndef SFD_SIM_LCM_LOG_HPP
#define SFD_SIM_LCM_LOG_HPP

#include <lcm/eventlog.h>

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "sfd/sfd.h"
#include "sfd_camera_info_t.h"
#include "sfd_output.h"

namespace sfdsim {

/// An LCM log opened for writing; write() records failures, ok() reports them. The log is written
/// to a temporary file next to `path` and renamed into place by finish() (sfd_output.h): a run
/// that fails before finish() leaves no output (and an older one as it was).
class LogWriter {
  public:
    explicit LogWriter(const std::string &path) {
        char err[8192];
        if (sfd_out_begin(&out_, path.c_str(), err, sizeof err) != 0) {
            error_ = err;
            return;
        }
        log_ = lcm_eventlog_create(out_.write_path, "w");
        if (log_ == nullptr) error_ = path + ": cannot open for writing";
    }
    ~LogWriter() {
        if (log_ != nullptr) lcm_eventlog_destroy(log_);
        sfd_out_discard(&out_);
    }
    LogWriter(const LogWriter &) = delete;
    LogWriter &operator=(const LogWriter &) = delete;
    bool ok() const { return log_ != nullptr && !failed_; }
    /// Why the log could not be opened or written ("PATH: reason").
    const std::string &error() const { return error_; }
    /// Flushes (checked: liblcm's destroy does not report it), closes and renames the log into
    /// place; false (with error()) on any failure.
    bool finish() {
        if (!ok()) return false;
        if (std::fflush(log_->f) != 0 || std::ferror(log_->f) != 0) {
            failed_ = true;
            error_ = std::string(out_.path) + ": write failed (" + std::strerror(errno) + ")";
        }
        lcm_eventlog_destroy(log_);
        log_ = nullptr;
        if (failed_) return false;
        char err[8192];
        if (sfd_out_commit(&out_, err, sizeof err) != 0) {
            error_ = err;
            return false;
        }
        return true;
    }
    /// One event: channel, its timestamp (us), the first `size` bytes of `data` (an encode's
    /// return; a negative size is an encode failure and is recorded as a write failure).
    void write(const char *channel, int64_t utime, const std::vector<uint8_t> &data, int size) {
        write(channel, utime, data.data(), size);
    }
    void write(const char *channel, int64_t utime, const uint8_t *data, int size) {
        if (log_ == nullptr || size < 0) {
            if (log_ != nullptr && !failed_) {
                error_ = std::string(out_.path) + ": a message could not be encoded";
            }
            failed_ = true;
            return;
        }
        lcm_eventlog_event_t ev;
        std::memset(&ev, 0, sizeof ev);
        ev.timestamp = utime;
        ev.channellen = static_cast<int32_t>(std::strlen(channel));
        ev.datalen = size;
        ev.channel = const_cast<char *>(channel);
        ev.data = const_cast<uint8_t *>(data);
        if (lcm_eventlog_write_event(log_, &ev) != 0) {
            failed_ = true;
            error_ = std::string(out_.path) + ": write failed (" + std::strerror(errno) + ")";
        }
    }

  private:
    sfd_out_t out_{};
    lcm_eventlog_t *log_ = nullptr;
    bool failed_ = false;
    std::string error_;
};

/// CAMERA_INFO of camera 0: the calibration and T_imu_cam (row-major 4x4, camera pose in the IMU
/// frame); utime is set by the caller at each publication.
static_assert(SFD_CAMERA_INFO_T_PINHOLE == SFD_DISTORTION_PINHOLE &&
                  SFD_CAMERA_INFO_T_RADTAN == SFD_DISTORTION_RADTAN &&
                  SFD_CAMERA_INFO_T_EQUIDISTANT == SFD_DISTORTION_EQUIDISTANT,
              "camera_info_of copies the core's distortion model as the wire's");

inline sfd_camera_info_t camera_info_of(const sfd_camera_t &cam, const double T_imu_cam[16]) {
    sfd_camera_info_t ci;
    std::memset(&ci, 0, sizeof ci);
    ci.camera_id = 0;
    ci.width = cam.width_px;
    ci.height = cam.height_px;
    ci.fx = cam.fx_px;
    ci.fy = cam.fy_px;
    ci.cx = cam.cx_px;
    ci.cy = cam.cy_px;
    ci.distortion_model = static_cast<int8_t>(cam.model);
    std::memcpy(ci.distortion, cam.dist, sizeof ci.distortion);
    std::memcpy(ci.T_imu_cam, T_imu_cam, sizeof ci.T_imu_cam);
    return ci;
}

}  // namespace sfdsim

#endif
