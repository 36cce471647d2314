// SPDX-License-Identifier: MIT
// Error-state EKF, Kilic 2014 eqs. (14)-(22). Derivations and assumptions: core/docs/ekf.md.
#include "ekf.hpp"

#include "rotation.hpp"
#include "small_linalg.hpp"

namespace sfd {
namespace {

constexpr int N = SFD_EKF_DIM;
using MatN = Eigen::Matrix<double, N, N, Eigen::RowMajor>;
using MatN6 = Eigen::Matrix<double, N, 6, Eigen::RowMajor>;
using VecN = Eigen::Matrix<double, N, 1>;
using MapN = Eigen::Map<MatN>;
using CMapN = Eigen::Map<const MatN>;

bool noise_valid(const sfd_ekf_noise_t &n) {
    const double v[6] = {
        n.gyro_noise_rad_s_rthz,   n.accel_noise_m_s2_rthz, n.gyro_bias_rw_rad_s2_rthz,
        n.accel_bias_rw_m_s3_rthz, n.gravity_m_s2,          n.max_dt_s};
    if (!all_finite(v, 6)) return false;
    for (int i = 0; i < 4; ++i) {
        if (v[i] < 0.0) return false;
    }
    return n.gravity_m_s2 > 0.0 && n.max_dt_s > 0.0;
}

Vec3 vec3(const double *v) {
    return Vec3(v[0], v[1], v[2]);
}

void store_rotation(sfd_ekf_t *ekf, const Mat3 &R) {
    Quat q = rotmat_to_quat(R);
    q.normalize();
    ekf->q_ItoW[0] = q.w();
    ekf->q_ItoW[1] = q.x();
    ekf->q_ItoW[2] = q.y();
    ekf->q_ItoW[3] = q.z();
}

/// Symmetrizes P in place: (P + P^T) / 2.
void symmetrize(MatN *P) {
    for (int i = 0; i < N; ++i) {
        for (int j = 0; j < i; ++j) {
            const double m = 0.5 * ((*P)(i, j) + (*P)(j, i));
            (*P)(i, j) = m;
            (*P)(j, i) = m;
        }
    }
}

/// True when P is finite with a non-negative diagonal (a cheap sanity check; PD-ness of the
/// Joseph form holds by construction up to rounding).
bool covariance_sane(const MatN &P) {
    for (int i = 0; i < N; ++i) {
        if (!(P(i, i) >= 0.0)) return false;
    }
    return all_finite(P.data(), static_cast<std::size_t>(N) * N);
}

/// Applies an error-state correction to the nominal state (R = R^ Exp(dtheta)) and installs the
/// new covariance, or leaves the filter unchanged and returns false when the result is not
/// finite. The reset Jacobian of the orientation error, I - [dtheta/2]x, is neglected (second
/// order; core/docs/ekf.md).
bool inject(sfd_ekf_t *ekf, const VecN &dx, const MatN &Pn) {
    double p[3], v[3], bg[3], ba[3];
    for (int k = 0; k < 3; ++k) {
        p[k] = ekf->p_IinW_m[k] + dx(SFD_EKF_IDX_P + k);
        v[k] = ekf->v_IinW_m_s[k] + dx(SFD_EKF_IDX_V + k);
        bg[k] = ekf->bg_rad_s[k] + dx(SFD_EKF_IDX_BG + k);
        ba[k] = ekf->ba_m_s2[k] + dx(SFD_EKF_IDX_BA + k);
    }
    const Mat3 R = ekf_rotation(*ekf) * so3_exp(dx.segment<3>(SFD_EKF_IDX_THETA));
    if (!all_finite(p, 3) || !all_finite(v, 3) || !all_finite(bg, 3) || !all_finite(ba, 3) ||
        !all_finite(R.data(), 9) || !covariance_sane(Pn)) {
        return false;
    }
    for (int k = 0; k < 3; ++k) {
        ekf->p_IinW_m[k] = p[k];
        ekf->v_IinW_m_s[k] = v[k];
        ekf->bg_rad_s[k] = bg[k];
        ekf->ba_m_s2[k] = ba[k];
    }
    store_rotation(ekf, R);
    MapN Pm(ekf->P);
    Pm = Pn;
    return true;
}

}  // namespace

Mat3 ekf_rotation(const sfd_ekf_t &ekf) {
    const Quat q(ekf.q_ItoW[0], ekf.q_ItoW[1], ekf.q_ItoW[2], ekf.q_ItoW[3]);
    return q.normalized().toRotationMatrix();
}

CameraPose camera_pose(const Mat3 &R_ItoW, const Vec3 &p_IinW, const sfd_extrinsics_t &ext) {
    const Eigen::Map<const Mat3> R_CtoI(ext.R_CtoI);
    CameraPose pose;
    pose.R_WtoC = (R_ItoW * R_CtoI).transpose();
    pose.p_CinW = p_IinW + R_ItoW * vec3(ext.p_CinI);
    return pose;
}

bool project(const sfd_ekf_camera_t &cam, const CameraPose &pose, const Vec3 &p_W, Vec2 *uv) {
    const Vec3 c = pose.R_WtoC * (p_W - pose.p_CinW);
    if (!(c.z() > 1e-6)) return false;
    (*uv)(0) = cam.fx_px * c.x() / c.z() + cam.cx_px;
    (*uv)(1) = cam.fy_px * c.y() / c.z() + cam.cy_px;
    return std::isfinite((*uv)(0)) && std::isfinite((*uv)(1));
}

Linearizer::Linearizer(const sfd_ekf_t &ekf, const Mat3 &R_ItoW, const sfd_ekf_camera_t &cam)
    : fx(cam.fx_px),
      fy(cam.fy_px),
      cx(cam.cx_px),
      cy(cam.cy_px),
      sigma2(cam.pixel_sigma_px * cam.pixel_sigma_px) {
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
            RWI[3 * r + c] = R_ItoW(c, r);
            RIC[3 * r + c] = cam.ext.R_CtoI[3 * c + r];
        }
        pI[r] = ekf.p_IinW_m[r];
        pCI[r] = cam.ext.p_CinI[r];
    }
    for (int r = 0; r < 3; ++r) {
        const int row = 3 * r;
        for (int c = 0; c < 3; ++c) {
            RWC[row + c] =
                RIC[row] * RWI[c] + RIC[row + 1] * RWI[3 + c] + RIC[row + 2] * RWI[6 + c];
        }
        pC[r] = pI[r] + R_ItoW(r, 0) * pCI[0] + R_ItoW(r, 1) * pCI[1] + R_ItoW(r, 2) * pCI[2];
    }
}

bool Linearizer::camera_point(const double L_W[3], double c[3]) const {
    const double d0 = L_W[0] - pC[0], d1 = L_W[1] - pC[1], d2 = L_W[2] - pC[2];
    c[0] = RWC[0] * d0 + RWC[1] * d1 + RWC[2] * d2;
    c[1] = RWC[3] * d0 + RWC[4] * d1 + RWC[5] * d2;
    c[2] = RWC[6] * d0 + RWC[7] * d1 + RWC[8] * d2;
    return c[2] > 1e-6 && std::isfinite(c[0]) && std::isfinite(c[1]) && std::isfinite(c[2]);
}

bool Linearizer::linearize(const double uv_px[2], const double *L_W, const double *C_L,
                           Linearized *out) const {
    if (L_W == nullptr || C_L == nullptr) return false;
    // y = R^T (L - p) (landmark in the IMU frame); c = R_CtoI^T (y - p_CinI).
    const double *L = L_W;
    const double d0 = L[0] - pI[0], d1 = L[1] - pI[1], d2 = L[2] - pI[2];
    const double y0 = RWI[0] * d0 + RWI[1] * d1 + RWI[2] * d2;
    const double y1 = RWI[3] * d0 + RWI[4] * d1 + RWI[5] * d2;
    const double y2 = RWI[6] * d0 + RWI[7] * d1 + RWI[8] * d2;
    const double e0 = y0 - pCI[0], e1 = y1 - pCI[1], e2 = y2 - pCI[2];
    const double c0 = RIC[0] * e0 + RIC[1] * e1 + RIC[2] * e2;
    const double c1 = RIC[3] * e0 + RIC[4] * e1 + RIC[5] * e2;
    const double c2 = RIC[6] * e0 + RIC[7] * e1 + RIC[8] * e2;
    if (!(c2 > 1e-6) || !std::isfinite(c0) || !std::isfinite(c1) || !std::isfinite(c2)) {
        return false;
    }
    // Jpi = [[a, 0, b], [0, e, f]] (pinhole derivative).
    const double iz = 1.0 / c2;
    const double a = fx * iz, b = -fx * c0 * iz * iz, e = fy * iz, f = -fy * c1 * iz * iz;
    // B = Jpi R_CtoI^T (2x3): d pixel / d (point in the IMU frame).
    double B[6];
    for (int k = 0; k < 3; ++k) {
        B[k] = a * RIC[k] + b * RIC[6 + k];
        B[3 + k] = e * RIC[3 + k] + f * RIC[6 + k];
    }
    // JL = B R^T (d pixel / d L); H_p = -JL; H_theta = B [y]x.
    double JL[6];
    for (int r = 0; r < 2; ++r) {
        const int row = 3 * r;
        const double *Br = &B[row];
        for (int k = 0; k < 3; ++k) {
            JL[3 * r + k] = Br[0] * RWI[k] + Br[1] * RWI[3 + k] + Br[2] * RWI[6 + k];
        }
        out->H(r, 0) = -JL[row];
        out->H(r, 1) = -JL[row + 1];
        out->H(r, 2) = -JL[row + 2];
        // row of B times [y]x = (B1 y2 - B2 y1, B2 y0 - B0 y2, B0 y1 - B1 y0)
        out->H(r, 3) = Br[1] * y2 - Br[2] * y1;
        out->H(r, 4) = Br[2] * y0 - Br[0] * y2;
        out->H(r, 5) = Br[0] * y1 - Br[1] * y0;
    }
    // R = sigma^2 I + JL C_L JL^T (C_L symmetrized).
    const double *C = C_L;
    double JC[6];
    for (int r = 0; r < 2; ++r) {
        for (int k = 0; k < 3; ++k) {
            double acc = 0.0;
            for (int j = 0; j < 3; ++j) acc += JL[3 * r + j] * 0.5 * (C[3 * j + k] + C[3 * k + j]);
            JC[3 * r + k] = acc;
        }
    }
    const double r00 = JC[0] * JL[0] + JC[1] * JL[1] + JC[2] * JL[2] + sigma2;
    const double r01 = JC[0] * JL[3] + JC[1] * JL[4] + JC[2] * JL[5];
    const double r11 = JC[3] * JL[3] + JC[4] * JL[4] + JC[5] * JL[5] + sigma2;
    out->R << r00, r01, r01, r11;
    out->nu(0) = uv_px[0] - (fx * c0 * iz + cx);
    out->nu(1) = uv_px[1] - (fy * c1 * iz + cy);
    out->p_LinC << c0, c1, c2;
    return std::isfinite(out->nu(0)) && std::isfinite(out->nu(1)) && std::isfinite(r00) &&
           std::isfinite(r01) && std::isfinite(r11) && all_finite(out->H.data(), 12);
}

bool linearize(const sfd_ekf_t &ekf, const Mat3 &R_ItoW, const sfd_ekf_camera_t &cam,
               const sfd_ekf_obs_t &obs, Linearized *out) {
    const Linearizer lz(ekf, R_ItoW, cam);
    return lz.linearize(obs, out);
}

Mat6 pose_covariance(const sfd_ekf_t &ekf) {
    Mat6 P;
    for (int i = 0; i < 6; ++i) {
        for (int j = 0; j < 6; ++j) P(i, j) = ekf.P[N * kPoseIdx[i] + kPoseIdx[j]];
    }
    return P;
}

bool single_update_pose(const sfd_ekf_t &ekf, const Mat3 &R_ItoW, const Mat6 &P_ss,
                        const Linearized &lin, Mat3 *R_ItoW_out, Vec3 *p_IinW_out) {
    const Eigen::Matrix<double, 6, 2> PHt = P_ss * lin.H.transpose();
    Mat2 S = lin.H * PHt + lin.R;
    const double det = la::det_2x2(S(0, 0), S(0, 1), S(1, 0), S(1, 1));
    if (!(S(0, 0) > 0.0) || !(det > 0.0) || !std::isfinite(det)) return false;
    const Vec2 Sinv_nu((S(1, 1) * lin.nu(0) - S(0, 1) * lin.nu(1)) / det,
                       (-S(1, 0) * lin.nu(0) + S(0, 0) * lin.nu(1)) / det);
    const Vec6 d = PHt * Sinv_nu;
    *p_IinW_out = vec3(ekf.p_IinW_m) + d.head<3>();
    *R_ItoW_out = R_ItoW * so3_exp(d.tail<3>());
    return all_finite(d.data(), 6);
}

}  // namespace sfd

using namespace sfd;

extern "C" sfd_status_t sfd_ekf_noise_default(sfd_ekf_noise_t *noise) {
    if (noise == nullptr) return SFD_ERR_INVAL;
    noise->gyro_noise_rad_s_rthz = 3.4e-4;
    noise->accel_noise_m_s2_rthz = 4.0e-3;
    noise->gyro_bias_rw_rad_s2_rthz = 3.9e-5;
    noise->accel_bias_rw_m_s3_rthz = 6.0e-3;
    noise->gravity_m_s2 = 9.81;
    noise->max_dt_s = 0.1;
    return SFD_OK;
}

extern "C" sfd_status_t sfd_ekf_init(sfd_ekf_t *ekf, const sfd_ekf_noise_t *noise,
                                     const double p_m[3], const double v_m_s[3],
                                     const double q_ItoW[4], const double bg_rad_s[3],
                                     const double ba_m_s2[3], const double P0_diag[SFD_EKF_DIM]) {
    if (ekf == nullptr || noise == nullptr || p_m == nullptr || v_m_s == nullptr ||
        q_ItoW == nullptr || bg_rad_s == nullptr || ba_m_s2 == nullptr || P0_diag == nullptr) {
        return SFD_ERR_INVAL;
    }
    if (!noise_valid(*noise) || !all_finite(p_m, 3) || !all_finite(v_m_s, 3) ||
        !all_finite(q_ItoW, 4) || !all_finite(bg_rad_s, 3) || !all_finite(ba_m_s2, 3) ||
        !all_finite(P0_diag, N)) {
        return SFD_ERR_INVAL;
    }
    for (int i = 0; i < N; ++i) {
        if (P0_diag[i] < 0.0) return SFD_ERR_INVAL;
    }
    const double qn = std::sqrt(q_ItoW[0] * q_ItoW[0] + q_ItoW[1] * q_ItoW[1] +
                                q_ItoW[2] * q_ItoW[2] + q_ItoW[3] * q_ItoW[3]);
    if (!(std::fabs(qn - 1.0) <= 1e-6)) return SFD_ERR_INVAL;
    *ekf = sfd_ekf_t{};
    ekf->noise = *noise;
    for (int k = 0; k < 3; ++k) {
        ekf->p_IinW_m[k] = p_m[k];
        ekf->v_IinW_m_s[k] = v_m_s[k];
        ekf->bg_rad_s[k] = bg_rad_s[k];
        ekf->ba_m_s2[k] = ba_m_s2[k];
    }
    for (int k = 0; k < 4; ++k) ekf->q_ItoW[k] = q_ItoW[k] / qn;
    for (int i = 0; i < N; ++i) ekf->P[N * i + i] = P0_diag[i];
    ekf->initialized = 1;
    return SFD_OK;
}

extern "C" sfd_status_t sfd_ekf_init_from_gravity(sfd_ekf_t *ekf, const sfd_ekf_noise_t *noise,
                                                  const double accel_mean_m_s2[3],
                                                  const double gyro_bias_rad_s[3],
                                                  const double P0_diag[SFD_EKF_DIM]) {
    if (ekf == nullptr || noise == nullptr || accel_mean_m_s2 == nullptr ||
        gyro_bias_rad_s == nullptr || P0_diag == nullptr) {
        return SFD_ERR_INVAL;
    }
    if (!noise_valid(*noise) || !all_finite(accel_mean_m_s2, 3)) return SFD_ERR_INVAL;
    const Vec3 f = vec3(accel_mean_m_s2);
    const double fn = f.norm();
    if (!(std::fabs(fn - noise->gravity_m_s2) <= 0.3 * noise->gravity_m_s2)) return SFD_ERR_DOMAIN;
    // At rest the specific force is R_ItoW^T (0, 0, g): f_x = -g sin(pitch),
    // f_y = g cos(pitch) sin(roll), f_z = g cos(pitch) cos(roll); yaw is set to 0.
    const double roll = std::atan2(f.y(), f.z());
    const double pitch = std::atan2(-f.x(), std::sqrt(f.y() * f.y() + f.z() * f.z()));
    const Mat3 R = so3_exp(Vec3(0.0, pitch, 0.0)) * so3_exp(Vec3(roll, 0.0, 0.0));
    const Quat q = rotmat_to_quat(R);
    const double qv[4] = {q.w(), q.x(), q.y(), q.z()};
    const double zero[3] = {0.0, 0.0, 0.0};
    return sfd_ekf_init(ekf, noise, zero, zero, qv, gyro_bias_rad_s, zero, P0_diag);
}

namespace sfd {
namespace {

/// The error-state transition of eq. (18) by its blocks (the rest of F is the identity):
///   p:  [I  dt I  p_theta  0      p_ba]
///   v:  [0  I     v_theta  0      v_ba]
///   th: [0  0     theta_theta  -dt I  0]
///   bg, ba: identity rows.
struct Transition {
    double dt;
    double p_theta[3][3];
    double p_ba[3][3];
    double v_theta[3][3];
    double v_ba[3][3];
    double theta_theta[3][3];
};

/// Y = F X for a 15x15 X (row-major; read transposed when @p transposed), over F's nonzero
/// blocks: 810 multiplications instead of the dense 3375.
void left_multiply(const Transition &F, const double *X, bool transposed, double Y[N][N]) {
    constexpr int P = SFD_EKF_IDX_P, V = SFD_EKF_IDX_V, TH = SFD_EKF_IDX_THETA, BG = SFD_EKF_IDX_BG,
                  BA = SFD_EKF_IDX_BA;
    for (int j = 0; j < N; ++j) {
        double x[N] = {};
        for (int k = 0; k < N; ++k) x[k] = transposed ? X[N * j + k] : X[N * k + j];
        for (int r = 0; r < 3; ++r) {
            double yp = x[P + r] + F.dt * x[V + r];
            double yv = x[V + r];
            double yth = -F.dt * x[BG + r];
            for (int c = 0; c < 3; ++c) {
                yp += F.p_theta[r][c] * x[TH + c] + F.p_ba[r][c] * x[BA + c];
                yv += F.v_theta[r][c] * x[TH + c] + F.v_ba[r][c] * x[BA + c];
                yth += F.theta_theta[r][c] * x[TH + c];
            }
            Y[P + r][j] = yp;
            Y[V + r][j] = yv;
            Y[TH + r][j] = yth;
            Y[BG + r][j] = x[BG + r];
            Y[BA + r][j] = x[BA + r];
        }
    }
}

}  // namespace
}  // namespace sfd

extern "C" sfd_status_t sfd_ekf_propagate(sfd_ekf_t *ekf, const double gyro_rad_s[3],
                                          const double accel_m_s2[3], double dt_s) {
    if (ekf == nullptr || gyro_rad_s == nullptr || accel_m_s2 == nullptr) return SFD_ERR_INVAL;
    if (ekf->initialized != 1) return SFD_ERR_STATE;
    if (!all_finite(gyro_rad_s, 3) || !all_finite(accel_m_s2, 3) || !std::isfinite(dt_s) ||
        !(dt_s > 0.0) || dt_s > ekf->noise.max_dt_s) {
        return SFD_ERR_INVAL;
    }
    const double dt = dt_s;
    const Mat3 R = ekf_rotation(*ekf);
    const Vec3 w = vec3(gyro_rad_s) - vec3(ekf->bg_rad_s);
    const Vec3 a = vec3(accel_m_s2) - vec3(ekf->ba_m_s2);
    const Vec3 g(0.0, 0.0, -ekf->noise.gravity_m_s2);
    const Vec3 acc_W = R * a + g;

    // Error-state transition F (eq. (18)), first order in dt except the rotation factor.
    const Mat3 Rax = R * skew(a);
    Transition F;
    F.dt = dt;
    const Mat3 Rw = so3_exp(-dt * w);
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
            F.p_theta[r][c] = -0.5 * dt * dt * Rax(r, c);
            F.p_ba[r][c] = -0.5 * dt * dt * R(r, c);
            F.v_theta[r][c] = -dt * Rax(r, c);
            F.v_ba[r][c] = -dt * R(r, c);
            F.theta_theta[r][c] = Rw(r, c);
        }
    }
    // P' = F P F^T = (F (F P)^T)^T, each product over F's nonzero blocks only.
    double FP[N][N];
    left_multiply(F, ekf->P, false, FP);
    double FPFt_T[N][N];
    left_multiply(F, &FP[0][0], true, FPFt_T);
    MatN Pn;
    for (int i = 0; i < N; ++i) {
        for (int j = 0; j < N; ++j) Pn(i, j) = FPFt_T[j][i];
    }
    // Q (eq. (17)): white accelerometer noise integrated into v and p (with their correlation),
    // white gyro noise into theta, random walks into the biases. Isotropic, so R drops out.
    const sfd_ekf_noise_t &nz = ekf->noise;
    const double qa = nz.accel_noise_m_s2_rthz * nz.accel_noise_m_s2_rthz;
    const double qg = nz.gyro_noise_rad_s_rthz * nz.gyro_noise_rad_s_rthz;
    const double qbg = nz.gyro_bias_rw_rad_s2_rthz * nz.gyro_bias_rw_rad_s2_rthz;
    const double qba = nz.accel_bias_rw_m_s3_rthz * nz.accel_bias_rw_m_s3_rthz;
    for (int k = 0; k < 3; ++k) {
        Pn(SFD_EKF_IDX_P + k, SFD_EKF_IDX_P + k) += qa * dt * dt * dt / 3.0;
        Pn(SFD_EKF_IDX_P + k, SFD_EKF_IDX_V + k) += qa * dt * dt / 2.0;
        Pn(SFD_EKF_IDX_V + k, SFD_EKF_IDX_P + k) += qa * dt * dt / 2.0;
        Pn(SFD_EKF_IDX_V + k, SFD_EKF_IDX_V + k) += qa * dt;
        Pn(SFD_EKF_IDX_THETA + k, SFD_EKF_IDX_THETA + k) += qg * dt;
        Pn(SFD_EKF_IDX_BG + k, SFD_EKF_IDX_BG + k) += qbg * dt;
        Pn(SFD_EKF_IDX_BA + k, SFD_EKF_IDX_BA + k) += qba * dt;
    }
    symmetrize(&Pn);

    // Nominal state (eq. (16)).
    const Vec3 v0 = vec3(ekf->v_IinW_m_s);
    const Vec3 p1 = vec3(ekf->p_IinW_m) + v0 * dt + 0.5 * dt * dt * acc_W;
    const Vec3 v1 = v0 + dt * acc_W;
    const Mat3 R1 = R * so3_exp(dt * w);
    if (!covariance_sane(Pn) || !all_finite(p1.data(), 3) || !all_finite(v1.data(), 3) ||
        !all_finite(R1.data(), 9)) {
        ekf->numeric_faults += 1U;
        return SFD_ERR_NUMERIC;
    }
    for (int k = 0; k < 3; ++k) {
        ekf->p_IinW_m[k] = p1(k);
        ekf->v_IinW_m_s[k] = v1(k);
    }
    store_rotation(ekf, R1);
    MapN Pm(ekf->P);
    Pm = Pn;
    return SFD_OK;
}

extern "C" sfd_status_t sfd_ekf_predict_observation(const sfd_ekf_t *ekf,
                                                    const sfd_ekf_camera_t *cam,
                                                    const sfd_ekf_obs_t *obs, double uv_pred_px[2],
                                                    double H_pose[12], double R_px2[4]) {
    if (ekf == nullptr || cam == nullptr || obs == nullptr || uv_pred_px == nullptr) {
        return SFD_ERR_INVAL;
    }
    if (!all_finite(obs->landmark_W_m, 3) || !all_finite(obs->landmark_cov_m2, 9) ||
        !all_finite(obs->uv_px, 2)) {
        return SFD_ERR_INVAL;
    }
    Linearized lin;
    if (!linearize(*ekf, ekf_rotation(*ekf), *cam, *obs, &lin)) return SFD_ERR_DOMAIN;
    uv_pred_px[0] = obs->uv_px[0] - lin.nu(0);
    uv_pred_px[1] = obs->uv_px[1] - lin.nu(1);
    if (H_pose != nullptr) {
        Eigen::Map<Mat26> Hm(H_pose);
        Hm = lin.H;
    }
    if (R_px2 != nullptr) {
        Eigen::Map<Mat2> Rm(R_px2);
        Rm = lin.R;
    }
    return SFD_OK;
}

namespace {

/// Inverse of a 6x6 matrix by Gauss-Jordan elimination with partial pivoting; false when a pivot
/// is not finite or below 1e-300 in magnitude (singular) or the result is not finite.
bool invert6(const Mat6 &A_in, Mat6 *inv) {
    double A[6][12];
    for (int i = 0; i < 6; ++i) {
        for (int j = 0; j < 6; ++j) {
            A[i][j] = A_in(i, j);
            A[i][6 + j] = (i == j) ? 1.0 : 0.0;
        }
    }
    for (int c = 0; c < 6; ++c) {
        int piv = c;
        for (int r = c + 1; r < 6; ++r) {
            if (std::fabs(A[r][c]) > std::fabs(A[piv][c])) piv = r;
        }
        if (!(std::fabs(A[piv][c]) > 1e-300) || !std::isfinite(A[piv][c])) return false;
        if (piv != c) {
            for (int k = 0; k < 12; ++k) {
                const double t = A[c][k];
                A[c][k] = A[piv][k];
                A[piv][k] = t;
            }
        }
        const double d = 1.0 / A[c][c];
        for (int k = 0; k < 12; ++k) A[c][k] *= d;
        for (int r = 0; r < 6; ++r) {
            if (r == c) continue;
            const double f = A[r][c];
            for (int k = 0; k < 12; ++k) A[r][k] -= f * A[c][k];
        }
    }
    for (int i = 0; i < 6; ++i) {
        for (int j = 0; j < 6; ++j) (*inv)(i, j) = A[i][6 + j];
    }
    return all_finite(inv->data(), 36);
}

/// Joseph-form covariance (I - K H) P (I - K H)^T + K R K^T for a gain acting only through the
/// pose columns: K H has its non-zero columns at kPoseIdx, given as KHs = U Y (N x 6), and
/// K R K^T = U Y U^T = KHs U^T.
void joseph(const MatN &P, const MatN6 &KHs, const MatN6 &U, MatN *out) {
    MatN A = P;  // (I - K H) P
    for (int i = 0; i < N; ++i) {
        for (int j = 0; j < N; ++j) {
            double s = 0.0;
            for (int k = 0; k < 6; ++k) s += KHs(i, k) * P(kPoseIdx[k], j);
            A(i, j) -= s;
        }
    }
    for (int i = 0; i < N; ++i) {  // A (I - K H)^T + KHs U^T
        for (int j = 0; j < N; ++j) {
            double s = A(i, j);
            for (int k = 0; k < 6; ++k) s += KHs(j, k) * (U(i, k) - A(i, kPoseIdx[k]));
            (*out)(i, j) = s;
        }
    }
    symmetrize(out);
}

}  // namespace

namespace sfd {

bool PoseInformation::add(const Linearized &lin) {
    const double det = la::det_2x2(lin.R(0, 0), lin.R(0, 1), lin.R(1, 0), lin.R(1, 1));
    if (!(det > 0.0) || !(lin.R(0, 0) > 0.0)) return false;
    const Mat2 Rinv = la::inverse_2x2(lin.R(0, 0), lin.R(0, 1), lin.R(1, 0), lin.R(1, 1), det);
    const Eigen::Matrix<double, 6, 2> HtRinv = lin.H.transpose() * Rinv;
    Y.noalias() += HtRinv * lin.H;
    b.noalias() += HtRinv * lin.nu;
    nu_Rinv_nu += lin.nu.dot(Rinv * lin.nu);
    used += 1;
    return true;
}

sfd_status_t apply_pose_information(sfd_ekf_t *ekf, const PoseInformation &info_in,
                                    double *nis_out) {
    if (info_in.used == 0) return SFD_OK;
    const Mat6 Y = 0.5 * (info_in.Y + info_in.Y.transpose());
    const Vec6 &b = info_in.b;
    const CMapN P(ekf->P);
    const Mat6 Pss = pose_covariance(*ekf);
    MatN6 Pxs;
    for (int i = 0; i < N; ++i) {
        for (int k = 0; k < 6; ++k) Pxs(i, k) = P(i, kPoseIdx[k]);
    }
    // M = (I + Y P_ss)^-1: its eigenvalues are those of 1 + Y^1/2 P_ss Y^1/2 >= 1, so it exists
    // for any PSD P_ss (a singular P_ss, e.g. an exactly known pose, included).
    const Mat6 IYP = Mat6::Identity() + Y * Pss;
    Mat6 M;
    if (!invert6(IYP, &M)) {
        ekf->numeric_faults += 1U;
        return SFD_ERR_NUMERIC;
    }
    MatN6 U = Pxs * M;  // K = U H^T R^-1
    // Consider states: a zero gain row. K R K^T = U Y U^T and K H = U Y hold for any U, so the
    // Joseph form below stays the exact covariance of this suboptimal gain.
    for (int i = 0; i < N; ++i) {
        if (ekf->consider[i] != 0U) U.row(i).setZero();
    }
    const VecN dx = U * b;    // K nu
    const MatN6 KHs = U * Y;  // K H on the pose columns
    MatN Pn;
    joseph(P, KHs, U, &Pn);
    // NIS = nu^T S^-1 nu = nu^T R^-1 nu - b^T (P_ss^-1 + Y)^-1 b, with (P_ss^-1 + Y)^-1 = P_ss M.
    const double nis = info_in.nu_Rinv_nu - b.dot(Pss * (M * b));
    if (!all_finite(dx.data(), N) || !std::isfinite(nis) || !inject(ekf, dx, Pn)) {
        ekf->numeric_faults += 1U;
        return SFD_ERR_NUMERIC;
    }
    if (nis_out != nullptr) *nis_out = nis;
    return SFD_OK;
}

template <typename View>
sfd_status_t update_camera(sfd_ekf_t *ekf, const sfd_ekf_camera_t &cam, const View &view,
                           const uint8_t *use, int32_t n, sfd_ekf_update_info_t *info) {
    if (n < 0 || n > SFD_MAX_FEATURES) return SFD_ERR_INVAL;
    if (ekf->initialized != 1) return SFD_ERR_STATE;
    sfd_ekf_update_info_t local{};
    sfd_ekf_update_info_t *out = (info != nullptr) ? info : &local;
    *out = sfd_ekf_update_info_t{};
    const Linearizer lz(*ekf, ekf_rotation(*ekf), cam);
    // Information over the pose: Y = sum H^T R^-1 H, b = sum H^T R^-1 nu (eq. (19) regrouped).
    PoseInformation pi;
    for (int32_t i = 0; i < n; ++i) {
        if (use != nullptr && use[i] == 0U) continue;
        Linearized lin;
        const ObsParts o = view[i];
        if (o.landmark_W_m == nullptr || o.landmark_cov_m2 == nullptr || !all_finite(o.uv_px, 2) ||
            !all_finite(o.landmark_W_m, 3) || !all_finite(o.landmark_cov_m2, 9) ||
            !lz.linearize(o.uv_px, o.landmark_W_m, o.landmark_cov_m2, &lin) || !pi.add(lin)) {
            out->skipped += 1;
        }
    }
    out->used = pi.used;
    return apply_pose_information(ekf, pi, &out->nis);
}

template sfd_status_t update_camera<ObsArray>(sfd_ekf_t *, const sfd_ekf_camera_t &,
                                              const ObsArray &, const uint8_t *, int32_t,
                                              sfd_ekf_update_info_t *);
template sfd_status_t update_camera<MatchObs>(sfd_ekf_t *, const sfd_ekf_camera_t &,
                                              const MatchObs &, const uint8_t *, int32_t,
                                              sfd_ekf_update_info_t *);

}  // namespace sfd

extern "C" sfd_status_t sfd_ekf_update_camera(sfd_ekf_t *ekf, const sfd_ekf_camera_t *cam,
                                              const sfd_ekf_obs_t *obs, const uint8_t *use,
                                              int32_t n, sfd_ekf_update_info_t *info) {
    if (ekf == nullptr || cam == nullptr || (obs == nullptr && n > 0)) return SFD_ERR_INVAL;
    const ObsArray view{obs};
    return update_camera(ekf, *cam, view, use, n, info);
}

extern "C" sfd_status_t sfd_ekf_update_linear(sfd_ekf_t *ekf, const double *H,
                                              const double *residual, const double *R, int32_t m) {
    if (ekf == nullptr || H == nullptr || residual == nullptr || R == nullptr) return SFD_ERR_INVAL;
    if (m < 1 || m > 6) return SFD_ERR_INVAL;
    if (ekf->initialized != 1) return SFD_ERR_STATE;
    if (!all_finite(H, static_cast<std::size_t>(m) * N) ||
        !all_finite(residual, static_cast<std::size_t>(m)) ||
        !all_finite(R, static_cast<std::size_t>(m) * static_cast<std::size_t>(m))) {
        return SFD_ERR_INVAL;
    }
    // S = H P H^T + R (eq. (11)), factored by Cholesky.
    const double *P = ekf->P;
    double HP[6][N];
    for (int i = 0; i < m; ++i) {
        for (int j = 0; j < N; ++j) {
            double acc = 0.0;
            for (int k = 0; k < N; ++k) acc += H[N * i + k] * P[N * k + j];
            HP[i][j] = acc;
        }
    }
    double S[6][6], L[6][6];
    for (int i = 0; i < m; ++i) {
        for (int j = 0; j < m; ++j) {
            double acc = 0.5 * (R[m * i + j] + R[m * j + i]);
            for (int k = 0; k < N; ++k) acc += HP[i][k] * H[N * j + k];
            S[i][j] = acc;
        }
    }
    if (!la::cholesky<6>(S, m, L, 0.0)) {
        ekf->numeric_faults += 1U;
        return SFD_ERR_NUMERIC;
    }
    // K = P H^T S^-1: row i of K solves S k = (H P)_{:, i}.
    double K[N][6];
    for (int i = 0; i < N; ++i) {
        double col[6];
        for (int r = 0; r < m; ++r) col[r] = HP[r][i];
        la::chol_solve<6>(L, m, col, col);
        for (int r = 0; r < m; ++r) K[i][r] = col[r];
    }
    VecN dx;
    for (int i = 0; i < N; ++i) {
        double acc = 0.0;
        for (int r = 0; r < m; ++r) acc += K[i][r] * residual[r];
        dx(i) = acc;
    }
    // Joseph form: A = (I - K H) P = P - K (H P); P+ = A (I - K H)^T + K R K^T.
    MatN A;
    for (int i = 0; i < N; ++i) {
        for (int j = 0; j < N; ++j) {
            double acc = P[N * i + j];
            for (int r = 0; r < m; ++r) acc -= K[i][r] * HP[r][j];
            A(i, j) = acc;
        }
    }
    double AHt[N][6];
    for (int i = 0; i < N; ++i) {
        for (int r = 0; r < m; ++r) {
            double acc = 0.0;
            for (int k = 0; k < N; ++k) acc += A(i, k) * H[N * r + k];
            AHt[i][r] = acc;
        }
    }
    double KR[N][6];
    for (int i = 0; i < N; ++i) {
        for (int c = 0; c < m; ++c) {
            double acc = 0.0;
            for (int r = 0; r < m; ++r) acc += K[i][r] * 0.5 * (R[m * r + c] + R[m * c + r]);
            KR[i][c] = acc;
        }
    }
    MatN Pn;
    for (int i = 0; i < N; ++i) {
        for (int j = 0; j < N; ++j) {
            double acc = A(i, j);
            for (int r = 0; r < m; ++r) acc += (KR[i][r] - AHt[i][r]) * K[j][r];
            Pn(i, j) = acc;
        }
    }
    symmetrize(&Pn);
    if (!all_finite(dx.data(), N) || !inject(ekf, dx, Pn)) {
        ekf->numeric_faults += 1U;
        return SFD_ERR_NUMERIC;
    }
    return SFD_OK;
}

extern "C" sfd_status_t sfd_ekf_camera_pose(const sfd_ekf_t *ekf, const sfd_extrinsics_t *ext,
                                            double R_CtoW[9], double p_CinW_m[3]) {
    if (ekf == nullptr || ext == nullptr || R_CtoW == nullptr || p_CinW_m == nullptr) {
        return SFD_ERR_INVAL;
    }
    const CameraPose pose = camera_pose(ekf_rotation(*ekf), vec3(ekf->p_IinW_m), *ext);
    Eigen::Map<Mat3> Rm(R_CtoW);
    Rm = pose.R_WtoC.transpose();
    for (int k = 0; k < 3; ++k) p_CinW_m[k] = pose.p_CinW(k);
    return SFD_OK;
}
