// SPDX-License-Identifier: MIT
// The pose oracle: parity's filter-path test with the true poses (sfd_pose_oracle.hpp).
#include "sfd_pose_oracle.hpp"

#include <cstring>

#include <sfd/sfd_rotation.h>

namespace sfdoracle {

struct PoseOracle::Storage {
    sfd_parity_t det;
    sfd_window_t win;
    sfd_window_scratch_t scratch;
    sfd_extrinsics_t ext;
};

PoseOracle::PoseOracle() : s_(new Storage()) {}
PoseOracle::~PoseOracle() = default;

sfd_status_t PoseOracle::start(const sfd_params_t &params, const sfd_camera_t &camera,
                               const sfd_extrinsics_t &ext) {
    started_ = false;
    history_.clear();
    next_seq_ = 0;
    sfd_status_t st = sfd_parity_init(&s_->det, &params, &camera);
    if (st != SFD_OK) return st;
    sfd_window_params_t wp;
    sfd_window_params_default(&wp);
    wp.window = SFD_MAX_WINDOW;
    st = sfd_window_init(&s_->win, &wp);
    if (st != SFD_OK) return st;
    s_->ext = ext;
    started_ = true;
    return SFD_OK;
}

namespace {

// Camera pose in the world from the IMU pose: R_CtoW = R_ItoW R_CtoI, p_C = p_I + R_ItoW p_CinI.
void camera_pose(const double R_ItoW[9], const double p_IinW[3], const sfd_extrinsics_t &ext,
                 double R_CtoW[9], double p_CinW[3]) {
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            double s = 0.0;
            for (int k = 0; k < 3; ++k) s += R_ItoW[3 * i + k] * ext.R_CtoI[3 * k + j];
            R_CtoW[3 * i + j] = s;
        }
        double s = p_IinW[i];
        for (int k = 0; k < 3; ++k) s += R_ItoW[3 * i + k] * ext.p_CinI[k];
        p_CinW[i] = s;
    }
}

}  // namespace

sfd_status_t PoseOracle::judge(const sfd_frame_t &frame, const double p_IinW_m[3],
                               const double q_ItoW[4], sfd_verdict_t *out) {
    if (!started_) return SFD_ERR_STATE;
    double q[4] = {q_ItoW[0], q_ItoW[1], q_ItoW[2], q_ItoW[3]};
    double R_ItoW[9];
    if (sfd_quat_normalize(q) != SFD_OK || sfd_quat_to_rotmat(q, R_ItoW) != SFD_OK) {
        return SFD_ERR_INVAL;
    }
    sfd_window_t &w = s_->win;
    if (!w.started) {
        const double zero[3] = {0.0, 0.0, 0.0};
        const sfd_status_t st = sfd_window_start_at(&w, frame.utime, p_IinW_m, zero, q, zero, zero);
        if (st != SFD_OK) return st;
    }
    // The oracle's filter: the true poses, known to kPoseVariance (sfd_pose_oracle.hpp).
    w.utime = frame.utime;
    w.pending = 0;
    std::memcpy(w.p_IinW_m, p_IinW_m, sizeof w.p_IinW_m);
    std::memcpy(w.fe_p_IinW_m, p_IinW_m, sizeof w.fe_p_IinW_m);
    std::memcpy(w.q_ItoW, q, sizeof w.q_ItoW);
    const size_t nc = history_.size();
    w.num_clones = static_cast<int32_t>(nc);
    for (size_t c = 0; c < nc; ++c) {
        const Pose &h = history_[c];
        sfd_window_clone_t &cl = w.clones[c];
        std::memcpy(cl.p_IinW_m, h.p, sizeof cl.p_IinW_m);
        std::memcpy(cl.fe_p_IinW_m, h.p, sizeof cl.fe_p_IinW_m);
        std::memcpy(cl.q_ItoW, h.q, sizeof cl.q_ItoW);
        (void)sfd_quat_to_rotmat(h.q, cl.fe_R_ItoW);  // normalized when stored
        cl.utime = h.utime;
        cl.seq = h.seq;  // consecutive: the oracle keeps the last frames (no keyframes)
    }
    w.next_seq = next_seq_;
    std::memset(w.P, 0, sizeof w.P);
    for (int k = 0; k < SFD_MSCKF_DIM; ++k) w.P[k][k] = kPoseVariance;

    sfd_frame_motion_t m;
    std::memset(&m, 0, sizeof m);
    const bool have_prev = nc > 0;
    if (have_prev) {
        // R_CcurToCprev = R_CprevToW^T R_CcurToW, p_CcurInCprev = R_CprevToW^T (p_Ccur - p_Cprev)
        const Pose &h = history_.back();
        double R_prev_ItoW[9], R_prev[9], p_prev[3], R_cur[9], p_cur[3];
        (void)sfd_quat_to_rotmat(h.q, R_prev_ItoW);
        camera_pose(R_prev_ItoW, h.p, s_->ext, R_prev, p_prev);
        camera_pose(R_ItoW, p_IinW_m, s_->ext, R_cur, p_cur);
        for (int i = 0; i < 3; ++i) {
            double t = 0.0;
            for (int j = 0; j < 3; ++j) {
                double r = 0.0;
                for (int k = 0; k < 3; ++k) r += R_prev[3 * k + i] * R_cur[3 * k + j];
                m.R_CcurToCprev[3 * i + j] = r;
                t += R_prev[3 * j + i] * (p_cur[j] - p_prev[j]);
            }
            m.p_CcurInCprev_m[i] = t;
        }
        m.translation_known = 1;
    }
    const sfd_status_t st = sfd_parity_push_frame_filter(&s_->det, &frame, have_prev ? &m : nullptr,
                                                         &w, &s_->scratch, &s_->ext, out);
    if (st != SFD_OK) return st;
    if (have_prev && (out->flags & SFD_FLAG_TRANSLATION_UNKNOWN) != 0U) ++fallbacks_;
    Pose now;
    now.utime = frame.utime;
    now.seq = next_seq_++;
    std::memcpy(now.p, p_IinW_m, sizeof now.p);
    std::memcpy(now.q, q, sizeof now.q);
    history_.push_back(now);
    if (history_.size() > static_cast<size_t>(SFD_MAX_WINDOW)) history_.erase(history_.begin());
    return SFD_OK;
}

}  // namespace sfdoracle
