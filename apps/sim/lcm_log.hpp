// SPDX-License-Identifier: MIT
// sfd-sim: the pieces every log scenario shares: an LCM log file written through LCM's own
// lcm_eventlog API, and the CAMERA_INFO message of a camera model and its extrinsics.
#ifndef SFD_SIM_LCM_LOG_HPP
#define SFD_SIM_LCM_LOG_HPP

#include <lcm/eventlog.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "sfd/sfd.h"
#include "sfd_camera_info_t.h"

namespace sfdsim {

/// An LCM log opened for writing; write() records failures, ok() reports them.
class LogWriter {
  public:
    explicit LogWriter(const std::string &path) : log_(lcm_eventlog_create(path.c_str(), "w")) {}
    ~LogWriter() {
        if (log_ != nullptr) lcm_eventlog_destroy(log_);
    }
    LogWriter(const LogWriter &) = delete;
    LogWriter &operator=(const LogWriter &) = delete;
    bool ok() const { return log_ != nullptr && !failed_; }
    /// One event: channel, its timestamp (us), the first `size` bytes of `data` (an encode's
    /// return; a negative size is an encode failure and is recorded as a write failure).
    void write(const char *channel, int64_t utime, const std::vector<uint8_t> &data, int size) {
        write(channel, utime, data.data(), size);
    }
    void write(const char *channel, int64_t utime, const uint8_t *data, int size) {
        if (log_ == nullptr || size < 0) {
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
        if (lcm_eventlog_write_event(log_, &ev) != 0) failed_ = true;
    }

  private:
    lcm_eventlog_t *log_;
    bool failed_ = false;
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
