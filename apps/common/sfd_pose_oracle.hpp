// SPDX-License-Identifier: MIT
// The pose oracle (evaluation only, `sfd-replay --oracle-poses`): the parity detector's test with
// the filter's translation, sfd_parity_push_frame_filter(), the product's own code path, but
// with the window filter replaced by the TRUE poses of TRUTH. It answers how much of the
// detector's miss rate the filter's pose errors cause, and what the test itself can see
// (docs/evaluation.md "What the test can see with true poses").
//
// How the filter is replaced: an sfd_window_t is started once and then, before every frame,
// written directly (it is plain caller-owned data, sfd/sfd_window.h): its clones are the true
// IMU poses of the previous frames (up to SFD_MAX_WINDOW; the tests read at most the newest
// evidence_frames - 1 of them, as with the real filter),
// its current IMU state the true pose of the frame being judged, no propagation pending, and
// its covariance kPoseVariance on the diagonal (poses known to 1 um and 1 urad: Cov(z) is the
// pixel noise alone, and the matrix stays positive definite). The frame motion handed to the
// detector is the true one as well (rotation and translation). Every other setting is the
// node's: the same sfd_params_t (pixel noise scale, evidence test, depth priors, alpha).
#ifndef SFD_APP_POSE_ORACLE_HPP
#define SFD_APP_POSE_ORACLE_HPP

#include <cstdint>
#include <memory>
#include <vector>

#include <sfd/sfd.h>
#include <sfd/sfd_parity.h>
#include <sfd/sfd_window.h>

namespace sfdoracle {

constexpr double kPoseVariance = 1e-12;  // m^2 and rad^2

class PoseOracle {
  public:
    PoseOracle();
    ~PoseOracle();
    PoseOracle(const PoseOracle &) = delete;
    PoseOracle &operator=(const PoseOracle &) = delete;

    // (Re)starts with a camera: an empty window. SFD_OK, or the status of sfd_parity_init()
    // (parameters the detector refuses) or sfd_window_init().
    sfd_status_t start(const sfd_params_t &params, const sfd_camera_t &camera,
                       const sfd_extrinsics_t &ext);
    bool started() const { return started_; }

    // Judges @p frame (frames in time order) at the true IMU pose @p p_IinW_m, @p q_ItoW
    // (w, x, y, z) of its time. SFD_ERR_STATE before start(); else the status of
    // sfd_parity_push_frame_filter() (@p out filled on SFD_OK).
    sfd_status_t judge(const sfd_frame_t &frame, const double p_IinW_m[3], const double q_ItoW[4],
                       sfd_verdict_t *out);

    // Frames judged by the unknown-translation fallback (SFD_FLAG_TRANSLATION_UNKNOWN) although
    // the window held the previous frame: 0 unless the oracle's window was refused.
    long fallbacks() const { return fallbacks_; }

  private:
    struct Pose {
        int64_t utime;
        uint32_t seq;  // the clone's sequence number, kept while the frame is in the window
        double p[3], q[4];
    };
    struct Storage;
    std::unique_ptr<Storage> s_;
    std::vector<Pose> history_;  // the newest SFD_MAX_WINDOW judged frames, oldest first
    uint32_t next_seq_ = 0;
    bool started_ = false;
    long fallbacks_ = 0;
};

}  // namespace sfdoracle

#endif  // SFD_APP_POSE_ORACLE_HPP
