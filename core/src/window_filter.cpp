// SPDX-License-Identifier: MIT
// The sliding-window navigation filter (sfd_window.h, core/docs/window_filter.md): IMU
// propagation with observability-constrained (default) or first-estimate Jacobians, cloning,
// track bookkeeping, triangulation over the window, the gated null-space update
// (msckf_update.cpp) and marginalization of the oldest clone (or, with keyframes, of a middle one).
#include "float_round.h"
#include "core_private.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "rotation.hpp"
#include "sfd/sfd_chi2.h"
#include "sfd/sfd_window.h"
#include "small_linalg.hpp"
#include "track_index.h"

namespace sfd {
namespace {

constexpr int kImu = SFD_WINDOW_IMU_DIM;
constexpr int P_ = SFD_WINDOW_IDX_P, V_ = SFD_WINDOW_IDX_V, TH = SFD_WINDOW_IDX_THETA,
              BG = SFD_WINDOW_IDX_BG, BA = SFD_WINDOW_IDX_BA;

using Mat15 = Eigen::Matrix<double, kImu, kImu, Eigen::RowMajor>;
using Map15 = Eigen::Map<Mat15>;

/// A B for 15x15 operands, coefficient-based: Eigen's blocked GEMM kernel would otherwise be
/// chosen, whose blocking buffers are heap- or alloca-backed (proof.core_symbols and
/// proof.stack_usage pin that it never is).
template <typename A, typename B>
Mat15 mul15(const A &a, const B &b) {
    Mat15 c = a.lazyProduct(b);
    return c;
}

Vec3 v3(const double *p) {
    return Vec3(p[0], p[1], p[2]);
}

/// The transition of one IMU interval, eq. (5) of core/docs/window_filter.md: the identity plus
/// these six 3x3 blocks (rows, columns): (p, v) = dt I, (p, theta), (p, ba), (v, theta),
/// (v, ba), (theta, bg).
struct TransitionBlocks {
    double dt = 0.0;
    Mat3 p_th, p_ba, v_th, v_ba, th_bg;
};

/// F X for a 15x15 X, from F's blocks: X plus six 3x15 block products (a fifth of the dense
/// product's multiplications).
template <typename M>
Mat15 apply_transition(const TransitionBlocks &F, const M &X) {
    Mat15 Y = X;
    Y.template block<3, kImu>(P_, 0) += F.dt * X.template block<3, kImu>(V_, 0) +
                                        F.p_th * X.template block<3, kImu>(TH, 0) +
                                        F.p_ba * X.template block<3, kImu>(BA, 0);
    Y.template block<3, kImu>(V_, 0) +=
        F.v_th * X.template block<3, kImu>(TH, 0) + F.v_ba * X.template block<3, kImu>(BA, 0);
    Y.template block<3, kImu>(TH, 0) += F.th_bg * X.template block<3, kImu>(BG, 0);
    return Y;
}

Mat3 quat_rot(const double q[4]) {
    return Quat(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
}

void store_quat(const Mat3 &R, double q[4]) {
    const Quat qq = rotmat_to_quat(R);
    q[0] = qq.w();
    q[1] = qq.x();
    q[2] = qq.y();
    q[3] = qq.z();
}

int dim(const sfd_window_t &w) {
    return kImu + 6 * w.num_clones;
}

bool params_valid(const sfd_window_params_t &p) {
    const sfd_ekf_noise_t &n = p.noise;
    const double nz[6] = {
        n.gyro_noise_rad_s_rthz,   n.accel_noise_m_s2_rthz, n.gyro_bias_rw_rad_s2_rthz,
        n.accel_bias_rw_m_s3_rthz, n.gravity_m_s2,          n.max_dt_s};
    for (double v : nz) {
        if (!(v >= 0.0) || !std::isfinite(v)) return false;
    }
    if (!(n.gravity_m_s2 > 0.0) || !(n.max_dt_s > 0.0)) return false;
    for (double v : p.p0_diag) {
        if (!(v >= 0.0) || !std::isfinite(v)) return false;
    }
    return p.window >= 2 && p.window <= SFD_MAX_WINDOW && p.min_observations >= 2 &&
           p.min_observations <= p.window && p.gate_alpha > 0.0 && p.gate_alpha <= 0.5 &&
           p.min_depth_m > 0.0 && p.max_depth_m > p.min_depth_m && std::isfinite(p.max_depth_m) &&
           p.use_depth_prior >= 0 && p.use_depth_prior <= 2 && p.depth_var_floor_m2 > 0.0 &&
           std::isfinite(p.depth_var_floor_m2) && p.gauss_newton_iterations >= 1 &&
           p.gauss_newton_iterations <= 20 && (p.first_estimates == 0 || p.first_estimates == 1) &&
           (p.observability_constrained == 0 || p.observability_constrained == 1) &&
           p.keyframe_parallax_rad >= 0.0 && std::isfinite(p.keyframe_parallax_rad) &&
           (!(p.keyframe_parallax_rad > 0.0) ||
            (p.keyframe_recent >= 1 && p.keyframe_recent <= p.window - 2)) &&
           (p.flagged_earlier == 0 || p.flagged_earlier == 1);
}

/// Where the Jacobians are evaluated (core/docs/window_filter.md, "Consistency").
enum class Linearization {
    kCurrent,         ///< the current estimate, no treatment
    kFirstEstimates,  ///< Li & Mourikis 2013: the estimates before the last update
    kObservability,   ///< the current estimate, corrected along gravity (Hesch et al. 2014)
};

Linearization linearization(const sfd_window_params_t &p) {
    if (p.first_estimates) return Linearization::kFirstEstimates;
    return p.observability_constrained ? Linearization::kObservability : Linearization::kCurrent;
}

/// The rank-one correction of an observability-constrained Jacobian block A (3x3, acting on the
/// global attitude error): A' = A - (A g - u) g^T / |g|^2, the smallest change (Frobenius) with
/// A' g = u (the observability constraint of Hesch et al. 2014). Only A's column space along
/// gravity moves; roll and pitch (orthogonal to g) keep the current-estimate Jacobian.
Mat3 constrain_along(const Mat3 &A, const Vec3 &g, const Vec3 &u) {
    return A - (A * g - u) * g.transpose() / g.squaredNorm();
}

/// Resets the accumulated transition to the identity and its noise to zero.
void reset_pending(sfd_window_t *w) {
    for (int i = 0; i < kImu; ++i) {
        for (int j = 0; j < kImu; ++j) {
            w->Phi[i][j] = (i == j) ? 1.0 : 0.0;
            w->Qd[i][j] = 0.0;
        }
    }
    w->pending = 0;
}

/// Brings P up to date with the accumulated transition: P_II <- Phi P_II Phi^T + Qd, P_IC <- Phi
/// P_IC (the clones do not move between frames).
void flush(sfd_window_t *w) {
    if (!w->pending) return;
    const int n = dim(*w);
    const Map15 Phi(&w->Phi[0][0]);
    Mat15 PII;
    for (int i = 0; i < kImu; ++i) {
        for (int j = 0; j < kImu; ++j) PII(i, j) = w->P[i][j];
    }
    const Mat15 PIIn = mul15(mul15(Phi, PII), Phi.transpose()) + Map15(&w->Qd[0][0]);
    for (int i = 0; i < kImu; ++i) {
        for (int j = 0; j < kImu; ++j) w->P[i][j] = 0.5 * (PIIn(i, j) + PIIn(j, i));
    }
    for (int c = kImu; c < n; ++c) {
        double col[kImu];
        for (int i = 0; i < kImu; ++i) {
            double s = 0.0;
            for (int k = 0; k < kImu; ++k) s += Phi(i, k) * w->P[k][c];
            col[i] = s;
        }
        for (int i = 0; i < kImu; ++i) {
            w->P[i][c] = col[i];
            w->P[c][i] = col[i];
        }
    }
    reset_pending(w);
}

void start_common(sfd_window_t *w, int64_t utime) {
    w->started = 1;
    w->utime = utime;
    w->num_clones = 0;
    w->num_tracks = 0;
    for (int s = 0; s < SFD_WINDOW_INDEX_SLOTS; ++s) w->index[s] = -1;
    std::memset(w->P, 0, sizeof w->P);
    for (int i = 0; i < kImu; ++i) w->P[i][i] = w->prm.p0_diag[i];
    for (int k = 0; k < 3; ++k) {
        w->fe_p_IinW_m[k] = w->p_IinW_m[k];
        w->fe_v_IinW_m_s[k] = w->v_IinW_m_s[k];
    }
    reset_pending(w);
}

/// Index of track @p id in w->tracks, or -1 (track_index.h; the table has more than twice as
/// many slots as tracks, so every probe sequence reaches an empty slot).
int32_t find_track(const sfd_window_t &w, int64_t id) {
    const sfd_track_index_t t = sfd_track_index_view_i16(
        w.index, SFD_WINDOW_INDEX_SLOTS, &w.tracks[0].id, sizeof w.tracks[0], w.num_tracks);
    return sfd_track_index_find(&t, id);
}

void index_insert(sfd_window_t *w, int64_t id, int16_t k) {
    const sfd_track_index_t t =
        sfd_track_index_i16(w->index, SFD_WINDOW_INDEX_SLOTS, nullptr, 0, 0);
    (void)sfd_track_index_insert(&t, id, k);
}

/// Removes the tracks with used == 0 and rebuilds the index.
void compact_tracks(sfd_window_t *w) {
    int32_t m = 0;
    for (int32_t k = 0; k < w->num_tracks; ++k) {
        if (w->tracks[k].used <= 0) continue;
        if (m != k) w->tracks[m] = w->tracks[k];
        ++m;
    }
    w->num_tracks = m;
    for (int s = 0; s < SFD_WINDOW_INDEX_SLOTS; ++s) w->index[s] = -1;
    for (int32_t k = 0; k < m; ++k) index_insert(w, w->tracks[k].id, static_cast<int16_t>(k));
}

/// Camera pose of an IMU pose: R_CtoW = R_ItoW R_CtoI, p_CinW = p_IinW + R_ItoW p_CinI.
struct CamPose {
    Mat3 R_WtoC;
    Vec3 p_CinW;
};

CamPose cam_pose(const Mat3 &R_ItoW, const Vec3 &p_IinW, const sfd_extrinsics_t &ext) {
    const Mat3 R_CtoI = Eigen::Map<const Mat3>(ext.R_CtoI);
    CamPose c;
    c.R_WtoC = (R_ItoW * R_CtoI).transpose();
    c.p_CinW = p_IinW + R_ItoW * v3(ext.p_CinI);
    return c;
}

/// Inverse of a symmetric 2x2 given as (xx, xy, yy); false unless positive definite.
bool inv2(const double c[3], Mat2 *out) {
    const double det = la::det_2x2(c[0], c[1], c[1], c[2]);
    if (!(c[0] > 0.0) || !(det > 0.0) || !std::isfinite(det)) return false;
    *out = la::inverse_2x2(c[0], c[1], c[1], c[2], det);
    return true;
}

/// inv2() of a covariance stored as float.
bool inv2(const float c[3], Mat2 *out) {
    const double cd[3] = {static_cast<double>(c[0]), static_cast<double>(c[1]),
                          static_cast<double>(c[2])};
    return inv2(cd, out);
}

/// One observation into a track's float storage: false (nothing written) unless every value
/// is finite and within float's range and the stored covariance is positive definite.
bool store_observation(const double xn[2], const double cov[3], float xn_out[2], float cov_out[3]) {
    if (!fits_float(xn, 2) || !fits_float(cov, 3)) return false;
    float x[2], c[3];
    for (int e = 0; e < 2; ++e) x[e] = static_cast<float>(xn[e]);
    for (int e = 0; e < 3; ++e) c[e] = static_cast<float>(cov[e]);
    // variances below float's normal range (subnormal: fewer digits) are refused too
    if (!(c[0] >= std::numeric_limits<float>::min()) ||
        !(c[2] >= std::numeric_limits<float>::min())) {
        return false;
    }
    // positive definite as stored (sfd_float_round_trip: the compiler may not skip the rounding)
    const double stored[3] = {sfd_float_round_trip(cov[0]), sfd_float_round_trip(cov[1]),
                              sfd_float_round_trip(cov[2])};
    Mat2 W;
    if (!inv2(stored, &W)) return false;
    for (int e = 0; e < 2; ++e) xn_out[e] = x[e];
    for (int e = 0; e < 3; ++e) cov_out[e] = c[e];
    return true;
}

/// d(x/z, y/z)/d(x, y, z) at a point in the camera frame (z > 0).
Eigen::Matrix<double, 2, 3, Eigen::RowMajor> proj_jacobian(const Vec3 &pc) {
    Eigen::Matrix<double, 2, 3, Eigen::RowMajor> J;
    const double iz = 1.0 / pc.z();
    J << iz, 0.0, -pc.x() * iz * iz, 0.0, iz, -pc.y() * iz * iz;
    return J;
}

/// x = H^-1 g for a symmetric positive definite 3x3 H by Cholesky (la::cholesky's pivot test,
/// 1e-13 of the largest diagonal entry); false when H is not.
bool spd_solve3(const Mat3 &H, const Vec3 &g, Vec3 *x) {
    double A[3][3];
    double L[3][3];
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) A[i][j] = H(i, j);
    }
    if (!la::cholesky(A, la::Dim<3>{}, L)) return false;
    double y[3];
    la::chol_solve(L, la::Dim<3>{}, g.data(), y);
    *x = Vec3(y[0], y[1], y[2]);
    return true;
}

/// One depth-prior row of a track's residual (core/docs/window_filter.md "Depth priors"): the
/// prior of observation k, depth along that camera's optical axis (m) with variance var_m2 (the
/// wire's plus depth_var_floor_m2).
struct DepthRow {
    int k;
    double depth_m;
    double var_m2;
};
constexpr int kMaxDepthRows = 2;

/// The window's depth rows of track t: observation 0's prior (use_depth_prior >= 1) and the
/// newest observation's (use_depth_prior 2, another frame's measurement of the same point), each
/// when the track has it. Returns their number (0..kMaxDepthRows).
int window_depth_rows(const sfd_window_t &w, const sfd_window_track_t &t,
                      DepthRow (&rows)[kMaxDepthRows]) {
    int nd = 0;
    if (w.prm.use_depth_prior >= 1 && t.depth_m > 0.0F && std::isfinite(t.depth_m)) {
        rows[nd++] = {0, static_cast<double>(t.depth_m),
                      static_cast<double>(t.depth_var_m2) + w.prm.depth_var_floor_m2};
    }
    if (w.prm.use_depth_prior >= 2 && t.used >= 2 && t.depth_last_m > 0.0F &&
        std::isfinite(t.depth_last_m)) {
        rows[nd++] = {t.used - 1, static_cast<double>(t.depth_last_m),
                      static_cast<double>(t.depth_last_var_m2) + w.prm.depth_var_floor_m2};
    }
    return nd;
}

/// Triangulates a track over its clones (current estimates): from the point of its first depth
/// row when it has one (the window's tracks: observation 0's prior, else the newest's), else
/// from the linear least-squares point of the rays
/// (sum_k (I - b_k b_k^T)) p = sum_k (I - b_k b_k^T) c_k (refused when they are nearly parallel),
/// then at most gauss_newton_iterations Gauss-Newton steps on the whitened reprojection errors
/// plus the nd depth rows. False when the point is not finite or not within
/// [min_depth_m, max_depth_m] in front of every clone.
bool triangulate(const sfd_window_t &w, const sfd_window_track_t &t, const CamPose *pose,
                 const DepthRow *dr, int nd, Vec3 *p_out) {
    Vec3 p;
    if (nd > 0) {
        // The depth prior is a measurement of the point; the rays' point is not, at low parallax
        // (its depth is then set by the pixel noise, and Gauss-Newton from there may stop far
        // from the optimum, which biases the linearization): start from the prior.
        const int k0 = dr[0].k;
        p = pose[k0].p_CinW +
            pose[k0].R_WtoC.transpose() * (dr[0].depth_m * Vec3(t.xn[k0][0], t.xn[k0][1], 1.0));
    } else {
        // The rays' least-squares point: A p = b with A = sum (I - u u^T) over the unit rays u.
        Mat3 A = Mat3::Zero();
        Vec3 b = Vec3::Zero();
        for (int k = 0; k < t.used; ++k) {
            const Vec3 ray = pose[k].R_WtoC.transpose() * Vec3(t.xn[k][0], t.xn[k][1], 1.0);
            const Vec3 u = ray.normalized();
            const Mat3 M = Mat3::Identity() - u * u.transpose();
            A += M;
            b += M * pose[k].p_CinW;
        }
        // Parallax: the smallest eigenvalue of A is ~ sum of squared angles between the rays.
        Eigen::SelfAdjointEigenSolver<Mat3> es(A, Eigen::EigenvaluesOnly);
        const double lmin = es.eigenvalues()(0);
        if (!(lmin > 1e-6 && std::isfinite(lmin))) return false;
        p = A.ldlt().solve(b);
    }
    if (!all_finite(p.data(), 3)) return false;
    for (int it = 0; it < w.prm.gauss_newton_iterations; ++it) {
        Mat3 H = Mat3::Zero();
        Vec3 g = Vec3::Zero();
        for (int k = 0; k < t.used; ++k) {
            const Vec3 pc = pose[k].R_WtoC * (p - pose[k].p_CinW);
            if (!(pc.z() > w.prm.min_depth_m)) return false;
            const Eigen::Matrix<double, 2, 3, Eigen::RowMajor> J =
                proj_jacobian(pc) * pose[k].R_WtoC;
            const Vec2 r(t.xn[k][0] - pc.x() / pc.z(), t.xn[k][1] - pc.y() / pc.z());
            Mat2 W;
            if (!inv2(t.cov_xn[k], &W)) return false;
            H += J.transpose() * W * J;
            g += J.transpose() * W * r;
        }
        for (int i = 0; i < nd; ++i) {
            const int k = dr[i].k;
            const Vec3 pc = pose[k].R_WtoC * (p - pose[k].p_CinW);
            const Vec3 J = pose[k].R_WtoC.row(2).transpose();
            H += J * J.transpose() / dr[i].var_m2;
            g += J * (dr[i].depth_m - pc.z()) / dr[i].var_m2;
        }
        Vec3 dp;
        if (!spd_solve3(H, g, &dp)) return false;
        if (!all_finite(dp.data(), 3)) return false;
        p += dp;
        // Gauss-Newton converges about quadratically here (small pixel residuals): after a step
        // of 1e-6 (relative) what is left is ~1e-9 or less, below any effect on the tests.
        if (dp.norm() <= 1e-6 * (1.0 + p.norm())) break;
    }
    for (int k = 0; k < t.used; ++k) {
        const double z = (pose[k].R_WtoC * (p - pose[k].p_CinW)).z();
        if (!(z >= w.prm.min_depth_m && z <= w.prm.max_depth_m)) return false;
    }
    *p_out = p;
    return true;
}

/// S += H_x P H_x^T for a residual whose rows each depend on one pose only: frame f's error state
/// (dp, dtheta) at the columns cols[f][0] .. + 2 and cols[f][1] .. + 2 of P, through the 6-vector
/// hp[i]. Frame pair by frame pair (f <= g), with P_fg the 6x6 block of the two poses (read in
/// place, rows of P_gf = P_fg^T), the rows i of f and j of g receive hp_i^T P_fg hp_j (and its
/// mirror). frame_rows[f] lists frame f's frame_nrows[f] rows.
void add_pose_covariance(const sfd_window_t &w, int frames, const int (*cols)[2],
                         const double (*hp)[6], const int (*frame_rows)[3], const int *frame_nrows,
                         double (*S)[SFD_MSCKF_TRACK_ROWS]) {
    for (int k = 0; k < frames; ++k) {
        const int kp = cols[k][0], kt = cols[k][1];
        for (int l = k; l < frames; ++l) {
            const double *Prow[6];  // row b of P_lk = P_kl^T: P's row of l's state b, k's columns
            for (int b = 0; b < 3; ++b) {
                Prow[b] = w.P[cols[l][0] + b];
                Prow[3 + b] = w.P[cols[l][1] + b];
            }
            double T[3][6];  // P_kl hp_j for the rows j of frame l, summed over b in order
            for (int jj = 0; jj < frame_nrows[l]; ++jj) {
                const double *h = hp[frame_rows[l][jj]];
                for (int a = 0; a < 6; ++a) T[jj][a] = 0.0;
                for (int b = 0; b < 6; ++b) {
                    const double hb = h[b];
                    const double *pb = Prow[b];
                    for (int a = 0; a < 3; ++a) T[jj][a] += pb[kp + a] * hb;
                    for (int a = 0; a < 3; ++a) T[jj][3 + a] += pb[kt + a] * hb;
                }
            }
            for (int ii = 0; ii < frame_nrows[k]; ++ii) {
                const int i = frame_rows[k][ii];
                for (int jj = (l == k ? ii : 0); jj < frame_nrows[l]; ++jj) {
                    const int j = frame_rows[l][jj];
                    double v = 0.0;
                    for (int a = 0; a < 6; ++a) v += hp[i][a] * T[jj][a];
                    S[i][j] += v;
                    if (j != i) S[j][i] += v;
                }
            }
        }
    }
}

enum class TrackOutcome { kNoGeometry, kGated, kUsed, kNumeric };

/// The track's residual (1) at the current clones, its Jacobians (at the current clones,
/// observability-constrained, or at the first estimates), its rows whitened (R = I), the gate
/// (3) and, when it passes, the fold of its projection (2) into the stack (the Schur complement
/// of the point; sfd_msckf_stack_fold_unprojected).
TrackOutcome process_track(sfd_window_t *w, sfd_window_scratch_t *scratch,
                           const sfd_window_track_t &t, const sfd_extrinsics_t &ext,
                           double *gamma_out, int32_t *dof_out) {
    const uint32_t oldest = w->clones[0].seq;
    const int32_t c0 = static_cast<int32_t>(t.first_clone - oldest);
    if (c0 < 0 || c0 + t.used > w->num_clones) return TrackOutcome::kNoGeometry;
    const Linearization lin = linearization(w->prm);
    CamPose cur[SFD_MAX_WINDOW];
    CamPose fej[SFD_MAX_WINDOW];
    Mat3 R_fe[SFD_MAX_WINDOW];
    Vec3 p_fe[SFD_MAX_WINDOW];
    for (int k = 0; k < t.used; ++k) {
        const sfd_window_clone_t &c = w->clones[c0 + k];
        cur[k] = cam_pose(quat_rot(c.q_ItoW), v3(c.p_IinW_m), ext);
        if (lin == Linearization::kFirstEstimates) {
            R_fe[k] = Eigen::Map<const Mat3>(c.fe_R_ItoW);
            p_fe[k] = v3(c.fe_p_IinW_m);
        } else {
            R_fe[k] = quat_rot(c.q_ItoW);
            p_fe[k] = v3(c.p_IinW_m);
        }
        fej[k] = cam_pose(R_fe[k], p_fe[k], ext);
    }
    DepthRow dr[kMaxDepthRows];
    const int nd = window_depth_rows(*w, t, dr);
    Vec3 pf;
    if (!triangulate(*w, t, cur, dr, nd, &pf)) return TrackOutcome::kNoGeometry;

    sfd_msckf_track_t &tr = scratch->track;
    const int n = dim(*w);
    const int rows = 2 * t.used + nd;
    tr.rows = 0;  // rows once they are complete (the frame's last track unit.window reads)
    tr.n = n;
    tr.projected = 0;
    for (int i = 0; i < rows; ++i) {
        for (int j = 0; j < n; ++j) tr.Hx[i][j] = 0.0;
        for (int j = 0; j < rows; ++j) tr.R[i][j] = 0.0;
    }
    // d pc / d(dtheta_global) = R_CtoI^T R_ItoW^T [p_f - p_I]x = R_WtoC [p_f - p_I]x. With the
    // observability constraint, its column space along gravity is the one the clone's yaw
    // direction N = (dp, dtheta) = (g x p_I^fe, g) needs for H N = 0 with the point's
    // N_f = g x p_f: R_WtoC [p_f - p_I^fe]x g (p_I^fe: the position the clone was cloned at).
    const Mat3 R_CtoI = Eigen::Map<const Mat3>(ext.R_CtoI);
    const Vec3 g(0.0, 0.0, -w->prm.noise.gravity_m_s2);
    Mat3 dth[SFD_MAX_WINDOW];
    for (int k = 0; k < t.used; ++k) {
        const Mat3 R_WtoC = R_CtoI.transpose() * R_fe[k].transpose();
        dth[k] = R_WtoC * skew(pf - p_fe[k]);
        if (lin == Linearization::kObservability) {
            const Vec3 p_null = v3(w->clones[c0 + k].fe_p_IinW_m);
            dth[k] = constrain_along(dth[k], g, R_WtoC * skew(pf - p_null) * g);
        }
    }
    for (int k = 0; k < t.used; ++k) {
        const Vec3 pc = cur[k].R_WtoC * (pf - cur[k].p_CinW);
        if (!(pc.z() > 1e-6)) return TrackOutcome::kNoGeometry;
        // The perspective derivative at the point in the CURRENT camera, where the point was
        // triangulated and the residual is evaluated, with every linearization: it is a left
        // factor of the clone's and the point's rows, so H N = 0 does not depend on it, and the
        // projection onto the left null space of H_f removes the point's error from the residual
        // only if H_f is the residual's derivative there. At the point in the first-estimate
        // camera (displaced by the corrections the clone received, centimetres) the depth error
        // of a low-parallax point leaked into the projected residual: first-estimate NEES 22.6
        // under way and 121.6 from rest instead of about 3 (core/docs/window_filter.md).
        const Eigen::Matrix<double, 2, 3, Eigen::RowMajor> Jp = proj_jacobian(pc);
        // d pc / d p_I = -R_WtoC, d pc / d p_f = R_WtoC.
        const Eigen::Matrix<double, 2, 3, Eigen::RowMajor> Hth = Jp * dth[k];
        const Eigen::Matrix<double, 2, 3, Eigen::RowMajor> Hf = Jp * fej[k].R_WtoC;
        const int col = kImu + 6 * (c0 + k);
        for (int a = 0; a < 2; ++a) {
            const int r = 2 * k + a;
            for (int j = 0; j < 3; ++j) {
                tr.Hx[r][col + j] = -Hf(a, j);
                tr.Hx[r][col + 3 + j] = Hth(a, j);
                tr.Hf[r][j] = Hf(a, j);
            }
        }
        const int ru = 2 * k, rv = ru + 1;
        tr.r[ru] = t.xn[k][0] - pc.x() / pc.z();
        tr.r[rv] = t.xn[k][1] - pc.y() / pc.z();
        // Unit noise: the two rows times L^-1, L L^T = the observation's covariance (lower
        // Cholesky factor). store_observation checked its determinant in double; a second pivot
        // that rounds to zero or below is refused here (kNumeric, before the gate, where the old
        // fold's Cholesky of N^T R N refused a nearly singular R after it). R becomes I.
        const double l00 = std::sqrt(static_cast<double>(t.cov_xn[k][0]));
        const double l10 = static_cast<double>(t.cov_xn[k][1]) / l00;
        const double p11 = static_cast<double>(t.cov_xn[k][2]) - l10 * l10;
        if (!(p11 > 0.0)) return TrackOutcome::kNumeric;
        const double l11 = std::sqrt(p11);
        const auto whiten = [l00, l10, l11](double *u, double *v) {
            *u /= l00;
            *v = (*v - l10 * *u) / l11;
        };
        for (int j = 0; j < 6; ++j) whiten(&tr.Hx[ru][col + j], &tr.Hx[rv][col + j]);
        for (int j = 0; j < 3; ++j) whiten(&tr.Hf[ru][j], &tr.Hf[rv][j]);
        whiten(&tr.r[ru], &tr.r[rv]);
    }
    for (int i = 0; i < nd; ++i) {  // the depth rows: d z / d(p_I, theta, p_f) at clone k
        const int r = 2 * t.used + i;
        const int k = dr[i].k;
        const Vec3 pc = cur[k].R_WtoC * (pf - cur[k].p_CinW);
        const int col = kImu + 6 * (c0 + k);
        const double sd = std::sqrt(dr[i].var_m2);  // unit noise: the row over its deviation
        for (int j = 0; j < 3; ++j) {
            tr.Hx[r][col + j] = -fej[k].R_WtoC(2, j) / sd;
            tr.Hx[r][col + 3 + j] = dth[k](2, j) / sd;
            tr.Hf[r][j] = fej[k].R_WtoC(2, j) / sd;
        }
        tr.r[r] = (dr[i].depth_m - pc.z()) / sd;
    }
    for (int i = 0; i < rows; ++i) {
        tr.R[i][i] = 1.0;
        // a non-finite row has no geometry, as sfd_msckf_track_project() refuses it
        const int col = kImu + 6 * (c0 + (i < 2 * t.used ? i / 2 : dr[i - 2 * t.used].k));
        if (!all_finite(tr.Hx[i] + col, 6) || !all_finite(tr.Hf[i], 3) || !std::isfinite(tr.r[i])) {
            return TrackOutcome::kNoGeometry;
        }
    }
    tr.rows = rows;
    // The gate (3) from the unprojected track, as sfd_window_test_track computes it: S = H_x P
    // H_x^T + I (unit noise) from the 6x6 blocks of P the clones' rows touch, gamma by the
    // least-squares identity (sfd_msckf_track_statistic; equal to projecting, then
    // sfd_msckf_track_gate). The outcomes keep their order: an H_f without rank 3 (no
    // projection) is kNoGeometry, a failed gate kNumeric.
    double S[SFD_MSCKF_TRACK_ROWS][SFD_MSCKF_TRACK_ROWS];
    double hp[SFD_MSCKF_TRACK_ROWS][6];
    int cols[SFD_MAX_WINDOW][2];
    int frame_rows[SFD_MAX_WINDOW][3];
    int frame_nrows[SFD_MAX_WINDOW] =
        {};  // set below for every observation; zeroed for the analyzer
    for (int k = 0; k < t.used; ++k) {
        const int col = kImu + 6 * (c0 + k);
        cols[k][0] = col;
        cols[k][1] = col + 3;
        frame_nrows[k] = 2;
        for (int a = 0; a < 2; ++a) {
            const int r = 2 * k + a;
            frame_rows[k][a] = r;
            for (int j = 0; j < 6; ++j) hp[r][j] = tr.Hx[r][col + j];
        }
    }
    for (int i = 0; i < nd; ++i) {
        const int r = 2 * t.used + i;
        const int k = dr[i].k;
        frame_rows[k][frame_nrows[k]++] = r;
        for (int j = 0; j < 6; ++j) hp[r][j] = tr.Hx[r][kImu + 6 * (c0 + k) + j];
    }
    for (int i = 0; i < rows; ++i) {
        for (int j = 0; j < rows; ++j) S[i][j] = tr.R[i][j];
    }
    add_pose_covariance(*w, t.used, cols, hp, frame_rows, frame_nrows, S);
    double gamma = 0.0;
    int32_t dof = 0;
    const sfd_status_t gate_status = sfd_msckf_track_statistic(&tr, S, &gamma, &dof);
    // The projection (2) as the basis of H_f's range, N N^T = I - Q Q^T; the fold uses it
    // (sfd_msckf_stack_fold_unprojected without its checks: the rows are finite, checked above,
    // and have unit noise).
    double Q[SFD_MSCKF_TRACK_ROWS][3];
    if (!msckf_range_basis(tr, Q)) return TrackOutcome::kNoGeometry;
    if (gate_status != SFD_OK) return TrackOutcome::kNumeric;
    *gamma_out = gamma;
    *dof_out = dof;
    if (dof < 1 || dof >= SFD_MSCKF_TRACK_ROWS || gamma > w->gate[dof]) return TrackOutcome::kGated;
    if (msckf_fold_unit_noise(&scratch->stack, tr, Q) != SFD_OK) return TrackOutcome::kNumeric;
    return TrackOutcome::kUsed;
}

/// Adds dx to the nominal state (IMU and clones); first estimates stay. (Not inlined: its frame
/// would add to sfd_window_frame's.)
__attribute__((noinline)) bool inject(sfd_window_t *w, const double *dx) {
    if (!all_finite(dx, static_cast<std::size_t>(dim(*w)))) return false;
    for (int k = 0; k < 3; ++k) {
        w->p_IinW_m[k] += dx[P_ + k];
        w->v_IinW_m_s[k] += dx[V_ + k];
        w->bg_rad_s[k] += dx[BG + k];
        w->ba_m_s2[k] += dx[BA + k];
    }
    store_quat(so3_exp(v3(dx + TH)) * quat_rot(w->q_ItoW), w->q_ItoW);
    for (int c = 0; c < w->num_clones; ++c) {
        sfd_window_clone_t &cl = w->clones[c];
        const double *d = dx + kImu + 6 * static_cast<std::ptrdiff_t>(c);
        for (int k = 0; k < 3; ++k) cl.p_IinW_m[k] += d[k];
        store_quat(so3_exp(v3(d + 3)) * quat_rot(cl.q_ItoW), cl.q_ItoW);
    }
    return true;
}

/// Appends the current IMU pose as the newest clone: P gains the rows and columns of (dp, dtheta).
void augment(sfd_window_t *w, int64_t utime) {
    const int n = dim(*w);
    const int c = n;  // first index of the added clone
    const int src[6] = {P_, P_ + 1, P_ + 2, TH, TH + 1, TH + 2};
    for (int a = 0; a < 6; ++a) {
        for (int j = 0; j < n; ++j) {
            w->P[c + a][j] = w->P[src[a]][j];
            w->P[j][c + a] = w->P[j][src[a]];
        }
    }
    for (int a = 0; a < 6; ++a) {
        for (int b = 0; b < 6; ++b) w->P[c + a][c + b] = w->P[src[a]][src[b]];
    }
    sfd_window_clone_t &cl = w->clones[w->num_clones];
    std::memcpy(cl.p_IinW_m, w->p_IinW_m, sizeof cl.p_IinW_m);
    std::memcpy(cl.q_ItoW, w->q_ItoW, sizeof cl.q_ItoW);
    // The IMU's first estimate (equal to the current position unless no IMU sample came since
    // the last update): the point its yaw direction N was propagated at, which the clone keeps.
    std::memcpy(cl.fe_p_IinW_m, w->fe_p_IinW_m, sizeof cl.fe_p_IinW_m);
    const Mat3 R = quat_rot(w->q_ItoW);
    Eigen::Map<Mat3>(cl.fe_R_ItoW) = R;
    cl.utime = utime;
    cl.seq = w->next_seq++;
    w->num_clones++;
}

/// Position of clone sequence number s in a track whose first observation is in clone first:
/// s - first modulo 2^32 (sequence numbers wrap), or INT32_MAX when s is before first.
int32_t seq_offset(uint32_t s, uint32_t first) {
    const auto d = static_cast<int32_t>(s - first);
    return d < 0 ? INT32_MAX : d;
}

/// Deletes clone d (0 = the oldest): its rows and columns of P and the observations made in it.
/// The later clones move down one place. When the oldest leaves, sequence numbers stay as they
/// are (consecutive, never reused); when a middle clone leaves (keyframes), the later clones'
/// numbers drop by one, so a track's observations stay consecutive in window order although the
/// clones are no longer consecutive frames (a track seen across the deleted clone keeps its
/// other observations).
void marginalize_clone(sfd_window_t *w, int d) {
    const int n = dim(*w);
    const uint32_t gone = w->clones[d].seq;
    for (int32_t k = 0; k < w->num_tracks; ++k) {
        sfd_window_track_t &t = w->tracks[k];
        if (t.used <= 0) continue;
        const int32_t j = seq_offset(gone, t.first_clone);
        if (j == INT32_MAX) {  // starts after the deleted clone
            if (d > 0) t.first_clone -= 1;
            continue;
        }
        if (j >= t.used) continue;
        // Not used before its clone leaves: that observation goes (with observation 0 the
        // depth prior, which belongs to it).
        for (int i = j + 1; i < t.used; ++i) {
            t.xn[i - 1][0] = t.xn[i][0];
            t.xn[i - 1][1] = t.xn[i][1];
            for (int e = 0; e < 3; ++e) t.cov_xn[i - 1][e] = t.cov_xn[i][e];
        }
        if (j == t.used - 1) t.depth_last_m = 0.0F;  // the newest observation's prior goes with it
        t.used -= 1;
        if (j == 0) {
            t.depth_m = 0.0F;
            if (d == 0) t.first_clone += 1;  // the oldest: the later clones keep their numbers
        }
    }
    // Rows/columns b..b+5 removed: the later ones move up by 6.
    const int b = kImu + 6 * d;
    for (int i = 0; i < n; ++i) {
        if (i >= b && i < b + 6) continue;
        const int ri = (i >= b + 6) ? i - 6 : i;
        for (int j = 0; j < n; ++j) {
            if (j >= b && j < b + 6) continue;
            const int rj = (j >= b + 6) ? j - 6 : j;
            w->P[ri][rj] = w->P[i][j];
        }
    }
    // The oldest leaving keeps every number (consecutive, never reused); a middle clone leaving
    // renumbers the later ones so the window stays consecutive in sequence numbers.
    for (int c = d + 1; c < w->num_clones; ++c) {
        w->clones[c - 1] = w->clones[c];
        if (d > 0) w->clones[c - 1].seq -= 1;
    }
    w->num_clones--;
    if (d > 0) w->next_seq -= 1;
}

/// Mean rotation-compensated parallax (normalized image units) between clones a < b over the
/// tracks observed in both: |pi(R_CaCb (xb, 1)) - xa| with R_CaCb = R_WtoCa R_WtoCb^T, the
/// displacement that translation alone explains. Negative when no track joins them.
double clone_parallax(const sfd_window_t &w, int a, int b, const sfd_extrinsics_t &ext) {
    const sfd_window_clone_t &ca = w.clones[a];
    const sfd_window_clone_t &cb = w.clones[b];
    const Mat3 R_ab = cam_pose(quat_rot(ca.q_ItoW), v3(ca.p_IinW_m), ext).R_WtoC *
                      cam_pose(quat_rot(cb.q_ItoW), v3(cb.p_IinW_m), ext).R_WtoC.transpose();
    const uint32_t sa = w.clones[a].seq;
    const uint32_t sb = w.clones[b].seq;
    double sum = 0.0;
    int32_t count = 0;
    for (int32_t k = 0; k < w.num_tracks; ++k) {
        const sfd_window_track_t &t = w.tracks[k];
        if (t.used <= 0) continue;
        const int32_t ja = seq_offset(sa, t.first_clone);
        const int32_t jb = seq_offset(sb, t.first_clone);
        if (ja >= t.used || jb >= t.used) continue;
        const Vec3 v = R_ab * Vec3(t.xn[jb][0], t.xn[jb][1], 1.0);
        if (!(v(2) > 1e-6)) continue;
        const double dx = v(0) / v(2) - t.xn[ja][0];
        const double dy = v(1) / v(2) - t.xn[ja][1];
        sum += std::sqrt(dx * dx + dy * dy);
        ++count;
    }
    return count > 0 ? sum / count : -1.0;
}

/// Which clone leaves a full window: the oldest, or with keyframes (keyframe_parallax_rad > 0)
/// the one just older than the newest keyframe_recent when it moved less than
/// keyframe_parallax_rad from the clone before it (not a keyframe).
int clone_to_marginalize(const sfd_window_t &w, const sfd_extrinsics_t &ext) {
    if (!(w.prm.keyframe_parallax_rad > 0.0)) return 0;
    const int cand = w.num_clones - 1 - w.prm.keyframe_recent;
    if (cand < 1) return 0;
    const double par = clone_parallax(w, cand - 1, cand, ext);
    return (par >= 0.0 && par < w.prm.keyframe_parallax_rad) ? cand : 0;
}

bool obs_valid(const sfd_window_obs_t &o) {
    return std::isfinite(o.xn[0]) && std::isfinite(o.xn[1]) && std::isfinite(o.cov_xn[0]) &&
           std::isfinite(o.cov_xn[1]) && std::isfinite(o.cov_xn[2]) && o.cov_xn[0] > 0.0 &&
           o.cov_xn[2] > 0.0 && o.cov_xn[0] * o.cov_xn[2] - o.cov_xn[1] * o.cov_xn[1] > 0.0 &&
           std::isfinite(o.depth_m) && std::isfinite(o.depth_var_m2) && o.depth_var_m2 >= 0.0;
}

}  // namespace
}  // namespace sfd

using namespace sfd;

extern "C" sfd_status_t sfd_window_params_default(sfd_window_params_t *params) {
    if (params == nullptr) return SFD_ERR_INVAL;
    std::memset(params, 0, sizeof *params);
    sfd_ekf_noise_default(&params->noise);
    for (int k = 0; k < 3; ++k) {
        params->p0_diag[P_ + k] = 1e-6;
        params->p0_diag[V_ + k] = 1e-4;
        params->p0_diag[TH + k] = (k == 2) ? 1e-6 : 1e-4;
        params->p0_diag[BG + k] = 1e-6;
        params->p0_diag[BA + k] = 4e-3;
    }
    params->window = SFD_MAX_WINDOW;
    params->min_observations = 3;
    params->gate_alpha = 0.01;
    params->min_depth_m = 0.1;
    params->max_depth_m = 1e4;
    params->use_depth_prior = 2;
    params->depth_var_floor_m2 = 1e-4;
    params->gauss_newton_iterations = 5;
    params->first_estimates = 0;
    params->observability_constrained = 1;
    params->keyframe_parallax_rad = 0.0;
    params->keyframe_recent = 2;
    params->flagged_earlier = 1;
    return SFD_OK;
}

extern "C" sfd_status_t sfd_window_init(sfd_window_t *w, const sfd_window_params_t *params) {
    if (w == nullptr || params == nullptr || !params_valid(*params)) return SFD_ERR_INVAL;
    double gate[SFD_MSCKF_TRACK_ROWS] = {};
    for (int k = 1; k < SFD_MSCKF_TRACK_ROWS; ++k) {
        if (sfd_chi2_quantile_upper(params->gate_alpha, k, &gate[k]) != SFD_OK) {
            return SFD_ERR_INVAL;
        }
    }
    std::memset(w, 0, sizeof *w);
    w->prm = *params;
    std::memcpy(w->gate, gate, sizeof gate);
    w->started = 0;
    reset_pending(w);
    for (int s = 0; s < SFD_WINDOW_INDEX_SLOTS; ++s) w->index[s] = -1;
    return SFD_OK;
}

extern "C" sfd_status_t sfd_window_start_at_rest(sfd_window_t *w, int64_t utime,
                                                 const double accel_m_s2[3],
                                                 const double gyro_bias_rad_s[3]) {
    if (w == nullptr || accel_m_s2 == nullptr || gyro_bias_rad_s == nullptr) return SFD_ERR_INVAL;
    if (!all_finite(accel_m_s2, 3) || !all_finite(gyro_bias_rad_s, 3)) return SFD_ERR_INVAL;
    // The attitude of sfd_ekf_init_from_gravity (roll, pitch from the specific force, yaw 0).
    sfd_ekf_t tmp;
    double p0[SFD_EKF_DIM];
    for (int i = 0; i < SFD_EKF_DIM; ++i) p0[i] = w->prm.p0_diag[i];
    const sfd_status_t st =
        sfd_ekf_init_from_gravity(&tmp, &w->prm.noise, accel_m_s2, gyro_bias_rad_s, p0);
    if (st != SFD_OK) return st;
    // At rest the specific force is gravity's magnitude along the measured direction, so the
    // accelerometer bias is observable along that direction only: (|f| - g) f / |f|. Across it,
    // a bias cannot be told from a tilt; it starts at 0.
    const double fn = std::sqrt(accel_m_s2[0] * accel_m_s2[0] + accel_m_s2[1] * accel_m_s2[1] +
                                accel_m_s2[2] * accel_m_s2[2]);
    const double along = fn > 0.0 ? (fn - w->prm.noise.gravity_m_s2) / fn : 0.0;
    for (int k = 0; k < 3; ++k) {
        w->p_IinW_m[k] = 0.0;
        w->v_IinW_m_s[k] = 0.0;
        w->bg_rad_s[k] = gyro_bias_rad_s[k];
        w->ba_m_s2[k] = along * accel_m_s2[k];
    }
    std::memcpy(w->q_ItoW, tmp.q_ItoW, sizeof w->q_ItoW);
    start_common(w, utime);
    return SFD_OK;
}

extern "C" sfd_status_t sfd_window_start_at(sfd_window_t *w, int64_t utime, const double p_m[3],
                                            const double v_m_s[3], const double q_ItoW[4],
                                            const double bg_rad_s[3], const double ba_m_s2[3]) {
    if (w == nullptr || p_m == nullptr || v_m_s == nullptr || q_ItoW == nullptr ||
        bg_rad_s == nullptr || ba_m_s2 == nullptr) {
        return SFD_ERR_INVAL;
    }
    if (!all_finite(p_m, 3) || !all_finite(v_m_s, 3) || !all_finite(q_ItoW, 4) ||
        !all_finite(bg_rad_s, 3) || !all_finite(ba_m_s2, 3)) {
        return SFD_ERR_INVAL;
    }
    const double qn = std::sqrt(q_ItoW[0] * q_ItoW[0] + q_ItoW[1] * q_ItoW[1] +
                                q_ItoW[2] * q_ItoW[2] + q_ItoW[3] * q_ItoW[3]);
    if (!(std::fabs(qn - 1.0) <= 1e-6)) return SFD_ERR_INVAL;
    for (int k = 0; k < 3; ++k) {
        w->p_IinW_m[k] = p_m[k];
        w->v_IinW_m_s[k] = v_m_s[k];
        w->bg_rad_s[k] = bg_rad_s[k];
        w->ba_m_s2[k] = ba_m_s2[k];
    }
    for (int k = 0; k < 4; ++k) w->q_ItoW[k] = q_ItoW[k] / qn;
    start_common(w, utime);
    return SFD_OK;
}

extern "C" sfd_status_t sfd_window_propagate(sfd_window_t *w, const double gyro_rad_s[3],
                                             const double accel_m_s2[3], double dt_s) {
    if (w == nullptr || gyro_rad_s == nullptr || accel_m_s2 == nullptr) return SFD_ERR_INVAL;
    if (!w->started) return SFD_ERR_STATE;
    if (!all_finite(gyro_rad_s, 3) || !all_finite(accel_m_s2, 3) || !std::isfinite(dt_s) ||
        !(dt_s > 0.0) || dt_s > w->prm.noise.max_dt_s) {
        return SFD_ERR_INVAL;
    }
    const double dt = dt_s;
    const Mat3 R = quat_rot(w->q_ItoW);
    const Vec3 om = v3(gyro_rad_s) - v3(w->bg_rad_s);
    const Vec3 a = v3(accel_m_s2) - v3(w->ba_m_s2);
    const Vec3 g(0.0, 0.0, -w->prm.noise.gravity_m_s2);
    const Vec3 acc_W = R * a + g;
    const Vec3 p0 = v3(w->p_IinW_m), v0 = v3(w->v_IinW_m_s);
    const Vec3 p1 = p0 + v0 * dt + 0.5 * dt * dt * acc_W;
    const Vec3 v1 = v0 + dt * acc_W;
    const Mat3 R1 = R * so3_exp(dt * om);
    // Transition of the global-error state over dt, eq. (5) of core/docs/window_filter.md.
    // First estimates: at fe_p, fe_v (the state before the last update), so that
    // Phi_vtheta = -[v1 - v0^fe - g dt]x and Phi_ptheta = -[p1 - p0^fe - v0^fe dt - g dt^2/2]x
    // chain exactly over steps. Observability-constrained: at the current estimate, with the
    // column along gravity corrected so that Phi maps the yaw direction at (fe_p, fe_v) to the
    // one at (p1, v1): Phi_ptheta g = -[p1 - p0^fe - v0^fe dt]x g, Phi_vtheta g = -[v1 - v0^fe]x g.
    const Linearization lin = linearization(w->prm);
    const Vec3 ep = v3(w->fe_p_IinW_m), ev = v3(w->fe_v_IinW_m_s);
    const Vec3 fp = (lin == Linearization::kFirstEstimates) ? ep : p0;
    const Vec3 fv = (lin == Linearization::kFirstEstimates) ? ev : v0;
    TransitionBlocks F;
    F.dt = dt;
    F.p_th = -skew(p1 - fp - fv * dt - 0.5 * dt * dt * g);
    F.p_ba = -0.5 * dt * dt * R;
    F.v_th = -skew(v1 - fv - dt * g);
    if (lin == Linearization::kObservability) {
        F.p_th = constrain_along(F.p_th, g, -skew(p1 - ep - ev * dt) * g);
        F.v_th = constrain_along(F.v_th, g, -skew(v1 - ev) * g);
    }
    F.v_ba = -dt * R;
    F.th_bg = -dt * R1;
    // Discrete noise: white accelerometer noise into v and p (with their correlation), white gyro
    // noise into theta (isotropic, so the rotation drops out), random walks into the biases.
    const sfd_ekf_noise_t &nz = w->prm.noise;
    const double qa = nz.accel_noise_m_s2_rthz * nz.accel_noise_m_s2_rthz;
    const double qg = nz.gyro_noise_rad_s_rthz * nz.gyro_noise_rad_s_rthz;
    const double qbg = nz.gyro_bias_rw_rad_s2_rthz * nz.gyro_bias_rw_rad_s2_rthz;
    const double qba = nz.accel_bias_rw_m_s3_rthz * nz.accel_bias_rw_m_s3_rthz;
    Mat15 Q = Mat15::Zero();
    for (int k = 0; k < 3; ++k) {
        Q(P_ + k, P_ + k) = qa * dt * dt * dt / 3.0;
        Q(P_ + k, V_ + k) = qa * dt * dt / 2.0;
        Q(V_ + k, P_ + k) = qa * dt * dt / 2.0;
        Q(V_ + k, V_ + k) = qa * dt;
        Q(TH + k, TH + k) = qg * dt;
        Q(BG + k, BG + k) = qbg * dt;
        Q(BA + k, BA + k) = qba * dt;
    }
    Map15 Phi(&w->Phi[0][0]);
    Map15 Qd(&w->Qd[0][0]);
    const Mat15 Phin = apply_transition(F, Phi);
    const Mat15 FQd = apply_transition(F, Qd);
    const Mat15 Qn = apply_transition(F, FQd.transpose()) + Q;  // F Qd F^T = F (F Qd)^T
    if (!all_finite(p1.data(), 3) || !all_finite(v1.data(), 3) || !all_finite(R1.data(), 9) ||
        !all_finite(Phin.data(), Mat15::SizeAtCompileTime) ||
        !all_finite(Qn.data(), Mat15::SizeAtCompileTime)) {
        w->numeric_faults++;
        return SFD_ERR_NUMERIC;
    }
    Phi = Phin;
    Qd = 0.5 * (Qn + Qn.transpose());
    w->pending = 1;
    for (int k = 0; k < 3; ++k) {
        w->p_IinW_m[k] = p1(k);
        w->v_IinW_m_s[k] = v1(k);
        w->fe_p_IinW_m[k] = p1(k);
        w->fe_v_IinW_m_s[k] = v1(k);
    }
    store_quat(R1, w->q_ItoW);
    w->utime += static_cast<int64_t>(std::llround(dt * 1e6));
    return SFD_OK;
}

extern "C" sfd_status_t sfd_window_frame(sfd_window_t *w, int64_t utime,
                                         const sfd_window_obs_t *obs, int32_t n,
                                         const sfd_extrinsics_t *ext, sfd_window_scratch_t *scratch,
                                         sfd_window_result_t *result) {
    if (w == nullptr || result == nullptr || ext == nullptr || scratch == nullptr || n < 0 ||
        n > SFD_WINDOW_MAX_TRACKS || (n > 0 && obs == nullptr)) {
        return SFD_ERR_INVAL;
    }
    if (!w->started) return SFD_ERR_STATE;
    std::memset(result, 0, offsetof(sfd_window_result_t, gated_ids));
    scratch->track.rows = 0;  // set again by a track of this frame whose rows are complete
    flush(w);
    if (w->num_clones >= w->prm.window) marginalize_clone(w, 0);  // defensive: invariant
    augment(w, utime);
    w->utime = utime;
    const uint32_t newest = w->clones[w->num_clones - 1].seq;
    for (int32_t k = 0; k < w->num_tracks; ++k) w->tracks[k].seen = 0;

    // Observations: a flagged one ends its track (its earlier observations due now, or deleted),
    // the others appended to their track or started.
    for (int32_t i = 0; i < n; ++i) {
        const sfd_window_obs_t &o = obs[i];
        const int32_t k = find_track(*w, o.track_id);
        if (o.drop) {
            if (k >= 0 && w->tracks[k].used > 0) {
                sfd_window_track_t &ft = w->tracks[k];
                // The observations before the flagged one, of a track not already seen in this
                // frame (a duplicate id), are an ended track: due below, through the gate.
                const bool ends = o.drop == 1 && w->prm.flagged_earlier == 1 && ft.seen == 0;
                if (!ends) ft.used = 0;  // deleted at the compaction below
                ft.seen = ends ? 2 : 1;  // 2: due, and refuses this frame's duplicates
                result->dropped++;
            }
            continue;
        }
        if (!obs_valid(o)) {
            result->overflow++;
            continue;
        }
        sfd_window_track_t *t = nullptr;
        if (k >= 0) {
            t = &w->tracks[k];
            if (t->seen || t->used <= 0 || t->used >= SFD_MAX_WINDOW ||
                t->first_clone + static_cast<uint32_t>(t->used) != newest) {
                result->overflow++;  // duplicate id in the frame, or a deleted track
                continue;
            }
        } else {
            if (w->num_tracks >= SFD_WINDOW_MAX_TRACKS) {
                result->overflow++;
                continue;
            }
            t = &w->tracks[w->num_tracks];
            std::memset(t, 0, sizeof *t);
            t->id = o.track_id;
            t->first_clone = newest;
            // a prior float can hold, or none (core_private.hpp)
            const bool prior = o.depth_m > 0.0 && depth_prior_fits_float(o.depth_m, o.depth_var_m2);
            t->depth_m = prior ? static_cast<float>(o.depth_m) : 0.0F;
            t->depth_var_m2 = prior ? static_cast<float>(o.depth_var_m2) : 0.0F;
            index_insert(w, o.track_id, static_cast<int16_t>(w->num_tracks));
            w->num_tracks++;
        }
        const int u = t->used;
        if (!store_observation(o.xn, o.cov_xn, t->xn[u], t->cov_xn[u])) {
            result->overflow++;  // beyond float's range (a new track stays empty: deleted)
            continue;
        }
        t->used = u + 1;
        t->seen = 1;
        // the newest observation's prior (a prior float can hold, or none)
        const bool last = o.depth_m > 0.0 && depth_prior_fits_float(o.depth_m, o.depth_var_m2);
        t->depth_last_m = last ? static_cast<float>(o.depth_m) : 0.0F;
        t->depth_last_var_m2 = last ? static_cast<float>(o.depth_var_m2) : 0.0F;
        result->added++;
    }

    // Every observation is read (obs may be scratch->u.obs, which the update below overwrites).
    // The clone that leaves a full window after the update, chosen from the observations before
    // the due tracks below are used and deleted.
    const bool full = w->num_clones >= w->prm.window;
    const int leaving = full ? clone_to_marginalize(*w, *ext) : 0;
    // Tracks due: ended (not seen now), or starting in the oldest clone when it leaves a full
    // window. With keyframes a middle clone that leaves takes its observations unused (tracks
    // through it keep their others and stay, so the keyframes keep tracks that join them; a track
    // started between keyframes can lose its first observations this way while the camera
    // hovers: core/docs/window_filter.md "Keyframes").
    const uint32_t oldest = w->clones[0].seq;
    sfd_msckf_stack_reset(&scratch->stack, dim(*w));
    for (int32_t k = 0; k < w->num_tracks; ++k) {
        sfd_window_track_t &t = w->tracks[k];
        if (t.used <= 0) continue;
        const bool due = t.seen != 1 || (full && leaving == 0 && t.first_clone == oldest);
        if (!due) continue;
        result->candidates++;
        if (t.used < w->prm.min_observations) {
            result->too_short++;
            t.used = 0;
            continue;
        }
        double gamma = 0.0;
        int32_t dof = 0;
        const TrackOutcome out = process_track(w, scratch, t, *ext, &gamma, &dof);
        switch (out) {
            case TrackOutcome::kUsed:
                result->used++;
                result->rows += dof;
                result->nis += gamma;
                break;
            case TrackOutcome::kGated:
                result->gated++;
                if (result->num_gated_ids < SFD_WINDOW_MAX_TRACKS) {
                    result->gated_ids[result->num_gated_ids++] = t.id;
                }
                break;
            case TrackOutcome::kNumeric:
                w->numeric_faults++;
                result->no_geometry++;
                break;
            default:
                result->no_geometry++;
                break;
        }
        t.used = 0;  // each observation informs the filter once; a gated one never
    }
    result->update_status = SFD_OK;
    if (scratch->stack.folded > 0) {
        const sfd_status_t st =
            sfd_msckf_update(&scratch->stack, &w->P[0][0], scratch->dx, &scratch->u.work);
        if (st != SFD_OK || !inject(w, scratch->dx)) {
            w->numeric_faults++;
            result->update_status = (st != SFD_OK) ? st : SFD_ERR_NUMERIC;
        }
    }
    if (w->num_clones >= w->prm.window) marginalize_clone(w, leaving);
    compact_tracks(w);
    return SFD_OK;
}

extern "C" sfd_status_t sfd_window_to_ekf(sfd_window_t *w, sfd_ekf_t *ekf) {
    if (w == nullptr || ekf == nullptr) return SFD_ERR_INVAL;
    if (!w->started) return SFD_ERR_STATE;
    flush(w);
    std::memset(ekf, 0, sizeof *ekf);
    std::memcpy(ekf->p_IinW_m, w->p_IinW_m, sizeof ekf->p_IinW_m);
    std::memcpy(ekf->v_IinW_m_s, w->v_IinW_m_s, sizeof ekf->v_IinW_m_s);
    std::memcpy(ekf->q_ItoW, w->q_ItoW, sizeof ekf->q_ItoW);
    std::memcpy(ekf->bg_rad_s, w->bg_rad_s, sizeof ekf->bg_rad_s);
    std::memcpy(ekf->ba_m_s2, w->ba_m_s2, sizeof ekf->ba_m_s2);
    ekf->noise = w->prm.noise;
    ekf->initialized = 1;
    // dtheta_local = R^T dtheta_global: P_local = T P T^T with T = diag(I, I, R^T, I, I), i.e.
    // the theta rows multiplied by R^T from the left, then the theta columns by R from the right
    // (one 3 x 15 block at a time: no 15 x 15 temporaries on the stack).
    const Mat3 R = quat_rot(w->q_ItoW);
    double *Pl = ekf->P;
    for (int i = 0; i < kImu; ++i) {
        for (int j = 0; j < kImu; ++j) Pl[i * kImu + j] = w->P[i][j];
    }
    for (int j = 0; j < kImu; ++j) {  // rows: (R^T P)_(theta, j)
        double c[3];
        for (int a = 0; a < 3; ++a) {
            c[a] = 0.0;
            for (int b = 0; b < 3; ++b) c[a] += R(b, a) * w->P[TH + b][j];
        }
        for (int a = 0; a < 3; ++a) Pl[(TH + a) * kImu + j] = c[a];
    }
    for (int i = 0; i < kImu; ++i) {  // columns: (X R)_(i, theta)
        double c[3];
        for (int a = 0; a < 3; ++a) {
            c[a] = 0.0;
            for (int b = 0; b < 3; ++b) c[a] += Pl[i * kImu + TH + b] * R(b, a);
        }
        for (int a = 0; a < 3; ++a) Pl[i * kImu + TH + a] = c[a];
    }
    for (int i = 0; i < kImu; ++i) {
        for (int j = i + 1; j < kImu; ++j) {
            const double v = 0.5 * (Pl[i * kImu + j] + Pl[j * kImu + i]);
            Pl[i * kImu + j] = v;
            Pl[j * kImu + i] = v;
        }
    }
    return SFD_OK;
}

extern "C" sfd_status_t sfd_window_position_var(sfd_window_t *w, double var_m2[3]) {
    if (w == nullptr || var_m2 == nullptr) return SFD_ERR_INVAL;
    if (!w->started) return SFD_ERR_STATE;
    flush(w);
    for (int k = 0; k < 3; ++k) var_m2[k] = w->P[P_ + k][P_ + k];
    return SFD_OK;
}

namespace sfd {
namespace {

/// sfd_window_test_track() over obs's m frames (gamma[1], dof[1]) and, when 2 <= inner < m, the
/// statistic of the newest `inner` frames' rows in the same linearization (gamma[0], dof[0];
/// sfd_window_test_track_nested()); with ramp_glr, the ramp's GLR over the m frames
/// (sfd_window_test_track_evidence(); -1 when not available); with motion, the ramp's fit over
/// the newest `inner` frames, or the m frames without an inner test
/// (sfd_window_test_track_motion()). Arguments checked by the callers, except obs's content.
sfd_status_t test_track(sfd_window_t *w, const sfd_extrinsics_t *ext,
                        const sfd_window_test_obs_t *obs, sfd_window_scratch_t *scratch, int inner,
                        double gamma[2], int32_t dof[2], double *ramp_glr,
                        sfd_window_motion_t *motion) {
    const int m = obs->frames;
    if (m < 2 || m > SFD_MAX_WINDOW) return SFD_ERR_INVAL;
    if (!w->started || w->num_clones < m - 1) return SFD_ERR_STATE;
    // The frames are the newest m - 1 clones and the current state, at the caller's times.
    const int c0 = w->num_clones - (m - 1);
    for (int k = 0; k + 1 < m; ++k) {
        if (w->clones[c0 + k].utime != obs->utime[k]) return SFD_ERR_STATE;
    }
    if (w->utime != obs->utime[m - 1]) return SFD_ERR_STATE;
    sfd_window_track_t t;
    std::memset(&t, 0, sizeof t);
    t.used = m;
    for (int k = 0; k < m; ++k) {
        if (!all_finite(obs->xn[k], 2) || !all_finite(obs->cov_xn[k], 3) ||
            !store_observation(obs->xn[k], obs->cov_xn[k], t.xn[k], t.cov_xn[k])) {
            return SFD_ERR_INVAL;
        }
    }
    // a prior float can hold, as the window's tracks keep it (core_private.hpp)
    const bool depth_row = w->prm.use_depth_prior >= 1 && obs->depth_m > 0.0 &&
                           depth_prior_fits_float(obs->depth_m, obs->depth_var_m2);
    t.depth_m = depth_row ? static_cast<float>(obs->depth_m) : 0.0F;
    t.depth_var_m2 = depth_row ? static_cast<float>(obs->depth_var_m2) : 0.0F;
    flush(w);
    CamPose pose[SFD_MAX_WINDOW];
    Vec3 p_I[SFD_MAX_WINDOW];
    Mat3 R_I[SFD_MAX_WINDOW];
    // The poses' error state: dp and dtheta of frame k at columns cols[k][0], cols[k][1] (+0..2).
    int cols[SFD_MAX_WINDOW][2];
    for (int k = 0; k < m; ++k) {
        const bool cur = (k == m - 1);
        const double *q = cur ? w->q_ItoW : w->clones[c0 + k].q_ItoW;
        R_I[k] = quat_rot(q);
        p_I[k] = v3(cur ? w->p_IinW_m : w->clones[c0 + k].p_IinW_m);
        pose[k] = cam_pose(R_I[k], p_I[k], *ext);
        const int cp = cur ? P_ : kImu + 6 * (c0 + k);
        const int ct = cur ? TH : kImu + 6 * (c0 + k) + 3;
        cols[k][0] = cp;
        cols[k][1] = ct;
    }
    // The newest observation's prior, the one depth row of the test.
    const int dk = m - 1;
    const DepthRow dr[1] = {{dk, static_cast<double>(t.depth_m),
                             static_cast<double>(t.depth_var_m2) + w->prm.depth_var_floor_m2}};
    const int nd = depth_row ? 1 : 0;
    Vec3 pf;
    if (!triangulate(*w, t, pose, dr, nd, &pf)) return SFD_ERR_NUMERIC;
    // Row i of the residual depends on one frame's pose through the 6-vector hp[i] (dp, dtheta)
    // and on the point through Hf. S = H_x P H_x^T + R is formed from the 6x6 blocks of P that
    // each pair of frames touches (H_x is block sparse), in the scratch track's R; the track's
    // Hx is not used (sfd_msckf_track_statistic reads rows, Hf and r).
    sfd_msckf_track_t &tr = scratch->track;
    const int rows = 2 * m + nd;
    double hp[SFD_MSCKF_TRACK_ROWS][6];
    int frame_rows[SFD_MAX_WINDOW][3];  // the rows of frame k: 2k, 2k + 1 (and the depth row)
    int frame_nrows[SFD_MAX_WINDOW];
    double(*S)[SFD_MSCKF_TRACK_ROWS] = tr.R;
    tr.rows = rows;
    tr.projected = 0;
    for (int i = 0; i < rows; ++i) {
        for (int j = 0; j < rows; ++j) S[i][j] = 0.0;
    }
    // Jacobians at the current estimates (a detection test over one window needs the right
    // covariance, not the consistency treatment of the update): d pc / d dp_I = -R_WtoC,
    // d pc / d dtheta_I = R_WtoC [p_f - p_I]x, d pc / d p_f = R_WtoC.
    for (int k = 0; k < m; ++k) {
        const Vec3 pc = pose[k].R_WtoC * (pf - pose[k].p_CinW);
        if (!(pc.z() > 1e-6)) return SFD_ERR_NUMERIC;
        const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> dth = pose[k].R_WtoC * skew(pf - p_I[k]);
        const Eigen::Matrix<double, 2, 3, Eigen::RowMajor> Jp = proj_jacobian(pc);
        const Eigen::Matrix<double, 2, 3, Eigen::RowMajor> Hth = Jp * dth;
        const Eigen::Matrix<double, 2, 3, Eigen::RowMajor> Hf = Jp * pose[k].R_WtoC;
        frame_nrows[k] = 2;
        for (int a = 0; a < 2; ++a) {
            const int r = 2 * k + a;
            frame_rows[k][a] = r;
            for (int j = 0; j < 3; ++j) {
                hp[r][j] = -Hf(a, j);
                hp[r][3 + j] = Hth(a, j);
                tr.Hf[r][j] = Hf(a, j);
            }
        }
        const std::size_t ru = 2U * static_cast<std::size_t>(k), rv = ru + 1U;
        tr.r[ru] = t.xn[k][0] - pc.x() / pc.z();
        tr.r[rv] = t.xn[k][1] - pc.y() / pc.z();
        S[ru][ru] = t.cov_xn[k][0];
        S[ru][rv] = t.cov_xn[k][1];
        S[rv][ru] = t.cov_xn[k][1];
        S[rv][rv] = t.cov_xn[k][2];
    }
    if (nd > 0) {  // the depth row dr[0], the newest frame's
        const int r = 2 * m;
        const Vec3 pc = pose[dk].R_WtoC * (pf - pose[dk].p_CinW);
        const Mat3 dth = pose[dk].R_WtoC * skew(pf - p_I[dk]);
        frame_rows[dk][frame_nrows[dk]++] = r;
        for (int j = 0; j < 3; ++j) {
            hp[r][j] = -pose[dk].R_WtoC(2, j);
            hp[r][3 + j] = dth(2, j);
            tr.Hf[r][j] = pose[dk].R_WtoC(2, j);
        }
        tr.r[r] = dr[0].depth_m - pc.z();
        S[r][r] = dr[0].var_m2;
    }
    add_pose_covariance(*w, m, cols, hp, frame_rows, frame_nrows, S);
    // The rows of the newest `inner` frames are the last ones (the depth row, when there is one,
    // is the newest frame's and comes last): both statistics from one factorization.
    const int tail_first = (inner >= 2 && inner < m) ? 2 * (m - inner) : 0;
    // The motion over the test's frames (parity_space.md "Directional hold"): frame k's pixel
    // rows shifted by (k - k0) v, k0 the test's oldest frame; the depth row and the frames before
    // k0 carry none.
    double motion_cols[SFD_MSCKF_TRACK_ROWS][2];
    if (motion != nullptr) {
        const int k0 = tail_first / 2;
        for (int i = 0; i < rows; ++i) {
            motion_cols[i][0] = 0.0;
            motion_cols[i][1] = 0.0;
        }
        for (int k = k0; k < m; ++k) {
            const std::size_t ru = 2U * static_cast<std::size_t>(k), rv = ru + 1U;
            motion_cols[ru][0] = static_cast<double>(k - k0);
            motion_cols[rv][1] = static_cast<double>(k - k0);
        }
    }
    const double(*mcols)[2] = (motion != nullptr) ? motion_cols : nullptr;
    if (ramp_glr == nullptr) {
        return msckf_statistic_tail(tr, tr.R, tail_first, gamma, dof, nullptr, nullptr, mcols,
                                    motion);
    }
    // The ramp (parity_space.md "Ramp"): frame k's pixel rows (oldest k = 0) shifted by k v in
    // normalized coordinates, v unknown; the depth row carries none.
    double ramp[SFD_MSCKF_TRACK_ROWS][2];
    for (int k = 0; k < m; ++k) {
        const std::size_t ru = 2U * static_cast<std::size_t>(k), rv = ru + 1U;
        ramp[ru][0] = static_cast<double>(k);
        ramp[ru][1] = 0.0;
        ramp[rv][0] = 0.0;
        ramp[rv][1] = static_cast<double>(k);
    }
    for (int i = 2 * m; i < rows; ++i) {
        ramp[i][0] = 0.0;
        ramp[i][1] = 0.0;
    }
    return msckf_statistic_tail(tr, tr.R, tail_first, gamma, dof, ramp, ramp_glr, mcols, motion);
}

}  // namespace
}  // namespace sfd

extern "C" sfd_status_t sfd_window_test_track(sfd_window_t *w, const sfd_extrinsics_t *ext,
                                              const sfd_window_test_obs_t *obs,
                                              sfd_window_scratch_t *scratch, double *gamma,
                                              int32_t *dof) {
    if (w == nullptr || ext == nullptr || obs == nullptr || scratch == nullptr ||
        gamma == nullptr || dof == nullptr) {
        return SFD_ERR_INVAL;
    }
    double g[2] = {0.0, 0.0};
    int32_t d[2] = {0, 0};
    const sfd_status_t st = test_track(w, ext, obs, scratch, 0, g, d, nullptr, nullptr);
    if (st != SFD_OK) return st;
    *gamma = g[1];
    *dof = d[1];
    return SFD_OK;
}

namespace sfd {
namespace {

/// test_track() over obs's frames with the newest `inner` of them as the inner test, after the
/// argument checks of sfd_window_test_track_nested() and sfd_window_test_track_evidence()
/// (outputs_given: their gamma and dof are not null).
sfd_status_t test_track_inner(sfd_window_t *w, const sfd_extrinsics_t *ext,
                              const sfd_window_test_obs_t *obs, int32_t inner,
                              sfd_window_scratch_t *scratch, bool outputs_given, double g[2],
                              int32_t d[2], double *ramp_glr) {
    if (w == nullptr || ext == nullptr || obs == nullptr || scratch == nullptr || !outputs_given) {
        return SFD_ERR_INVAL;
    }
    if (inner < 2 || inner >= obs->frames) return SFD_ERR_INVAL;
    return test_track(w, ext, obs, scratch, inner, g, d, ramp_glr, nullptr);
}

}  // namespace
}  // namespace sfd

extern "C" sfd_status_t sfd_window_test_track_nested(sfd_window_t *w, const sfd_extrinsics_t *ext,
                                                     const sfd_window_test_obs_t *obs,
                                                     int32_t inner, sfd_window_scratch_t *scratch,
                                                     double gamma[2], int32_t dof[2]) {
    double g[2] = {0.0, 0.0};
    int32_t d[2] = {0, 0};
    const sfd_status_t st = test_track_inner(w, ext, obs, inner, scratch,
                                             gamma != nullptr && dof != nullptr, g, d, nullptr);
    if (st != SFD_OK) return st;
    for (int k = 0; k < 2; ++k) {
        gamma[k] = g[k];
        dof[k] = d[k];
    }
    return SFD_OK;
}

extern "C" sfd_status_t sfd_window_test_track_evidence(sfd_window_t *w, const sfd_extrinsics_t *ext,
                                                       const sfd_window_test_obs_t *obs,
                                                       int32_t inner, sfd_window_scratch_t *scratch,
                                                       double gamma[3], int32_t dof[3]) {
    double g[2] = {0.0, 0.0};
    int32_t d[2] = {0, 0};
    double ramp = -1.0;
    const sfd_status_t st = test_track_inner(w, ext, obs, inner, scratch,
                                             gamma != nullptr && dof != nullptr, g, d, &ramp);
    if (st != SFD_OK) return st;
    for (int k = 0; k < 2; ++k) {
        gamma[k] = g[k];
        dof[k] = d[k];
    }
    gamma[2] = ramp >= 0.0 ? ramp : 0.0;
    dof[2] = ramp >= 0.0 ? 2 : 0;
    return SFD_OK;
}

extern "C" sfd_status_t sfd_window_test_track_motion(sfd_window_t *w, const sfd_extrinsics_t *ext,
                                                     const sfd_window_test_obs_t *obs,
                                                     int32_t inner, int32_t ramp,
                                                     sfd_window_scratch_t *scratch, double gamma[3],
                                                     int32_t dof[3], sfd_window_motion_t *motion) {
    if (w == nullptr || ext == nullptr || obs == nullptr || scratch == nullptr ||
        gamma == nullptr || dof == nullptr) {
        return SFD_ERR_INVAL;
    }
    const bool nested = inner != 0;
    if (nested && (inner < 2 || inner >= obs->frames)) return SFD_ERR_INVAL;
    if ((ramp != 0 && ramp != 1) || (ramp == 1 && !nested)) return SFD_ERR_INVAL;
    double g[2] = {0.0, 0.0};
    int32_t d[2] = {0, 0};
    double ramp_glr = -1.0;
    sfd_window_motion_t fit{};
    const sfd_status_t st =
        test_track(w, ext, obs, scratch, inner, g, d, ramp == 1 ? &ramp_glr : nullptr,
                   motion != nullptr ? &fit : nullptr);
    if (st != SFD_OK) return st;
    gamma[0] = nested ? g[0] : g[1];
    dof[0] = nested ? d[0] : d[1];
    gamma[1] = nested ? g[1] : 0.0;
    dof[1] = nested ? d[1] : 0;
    gamma[2] = ramp_glr >= 0.0 ? ramp_glr : 0.0;
    dof[2] = ramp_glr >= 0.0 ? 2 : 0;
    if (motion != nullptr) *motion = fit;
    return SFD_OK;
}
