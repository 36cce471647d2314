// SPDX-License-Identifier: MIT
// SO(3) and quaternion helpers; conventions in sfd/sfd_rotation.h.
#include "core_private.hpp"
#include "rotation.hpp"
#include "sfd/sfd_rotation.h"

namespace sfd {

Mat3 skew(const Vec3 &v) {
    Mat3 S;
    S << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
    return S;
}

// Rodrigues: exp([phi]x) = I + a [phi]x + b [phi]x^2, a = sin(t)/t, b = (1 - cos t)/t^2.
// Below t = 1e-4 the truncated series (error O(t^4) relative) is used for a and b.
Mat3 so3_exp(const Vec3 &phi) {
    const double t2 = phi.squaredNorm();
    const double t = std::sqrt(t2);
    double a;
    double b;
    if (t < 1e-4) {
        a = 1.0 - t2 / 6.0;
        b = 0.5 - t2 / 24.0;
    } else {
        a = std::sin(t) / t;
        b = (1.0 - std::cos(t)) / t2;
    }
    const Mat3 K = skew(phi);
    return Mat3::Identity() + a * K + b * (K * K);
}

// log via the quaternion of R: phi = 2 atan2(|v|, w) v/|v| is well conditioned at every angle,
// unlike acos((tr R - 1)/2) near 0 and pi.
Vec3 so3_log(const Mat3 &R) {
    return quat_to_rotvec(rotmat_to_quat(R));
}

Quat quat_from_rotvec(const Vec3 &phi) {
    const double t = phi.norm();
    const double half = 0.5 * t;
    // sin(t/2)/t -> 1/2 - t^2/48 for small t.
    const double s = (t < 1e-4) ? (0.5 - t * t / 48.0) : std::sin(half) / t;
    Quat q(std::cos(half), s * phi.x(), s * phi.y(), s * phi.z());
    if (q.w() < 0.0) q.coeffs() = -q.coeffs();
    return q;
}

Vec3 quat_to_rotvec(const Quat &q_in) {
    Quat q = q_in;
    if (q.w() < 0.0) q.coeffs() = -q.coeffs();
    const Vec3 v = q.vec();
    const double vn = v.norm();
    if (vn < 1e-8) {
        // angle = 2 atan2(vn, w) ~ 2 vn / w for small vn: phi ~ 2 v / w.
        return (2.0 / q.w()) * v;
    }
    const double angle = 2.0 * std::atan2(vn, q.w());
    return (angle / vn) * v;
}

// Shepperd (1978): pick the largest of 4w^2, 4x^2, 4y^2, 4z^2 as the pivot.
Quat rotmat_to_quat(const Mat3 &R) {
    const double tr = R.trace();
    double w;
    double x;
    double y;
    double z;
    if (tr >= R(0, 0) && tr >= R(1, 1) && tr >= R(2, 2)) {
        const double s = 2.0 * std::sqrt(1.0 + tr);
        w = 0.25 * s;
        x = (R(2, 1) - R(1, 2)) / s;
        y = (R(0, 2) - R(2, 0)) / s;
        z = (R(1, 0) - R(0, 1)) / s;
    } else if (R(0, 0) >= R(1, 1) && R(0, 0) >= R(2, 2)) {
        const double s = 2.0 * std::sqrt(1.0 + R(0, 0) - R(1, 1) - R(2, 2));
        w = (R(2, 1) - R(1, 2)) / s;
        x = 0.25 * s;
        y = (R(0, 1) + R(1, 0)) / s;
        z = (R(0, 2) + R(2, 0)) / s;
    } else if (R(1, 1) >= R(2, 2)) {
        const double s = 2.0 * std::sqrt(1.0 + R(1, 1) - R(0, 0) - R(2, 2));
        w = (R(0, 2) - R(2, 0)) / s;
        x = (R(0, 1) + R(1, 0)) / s;
        y = 0.25 * s;
        z = (R(1, 2) + R(2, 1)) / s;
    } else {
        const double s = 2.0 * std::sqrt(1.0 + R(2, 2) - R(0, 0) - R(1, 1));
        w = (R(1, 0) - R(0, 1)) / s;
        x = (R(0, 2) + R(2, 0)) / s;
        y = (R(1, 2) + R(2, 1)) / s;
        z = 0.25 * s;
    }
    Quat q(w, x, y, z);
    q.normalize();
    if (q.w() < 0.0) q.coeffs() = -q.coeffs();
    return q;
}

bool is_rotation(const Mat3 &R, double tol) {
    if (!all_finite(R.data(), 9)) return false;
    const double orth = (R * R.transpose() - Mat3::Identity()).cwiseAbs().maxCoeff();
    return orth <= tol && std::fabs(R.determinant() - 1.0) <= tol;
}

namespace {
constexpr double kRotTol = 1e-6;

Mat3 load_mat3(const double *m) {
    return Eigen::Map<const Mat3>(m);
}
void store_mat3(const Mat3 &R, double *out) {
    Eigen::Map<Mat3> m(out);
    m = R;
}
Quat load_quat(const double *q) {
    return Quat(q[0], q[1], q[2], q[3]);
}
void store_quat(const Quat &q, double *out) {
    out[0] = q.w();
    out[1] = q.x();
    out[2] = q.y();
    out[3] = q.z();
}
bool unit_quat(const double *q) {
    if (!all_finite(q, 4)) return false;
    const double n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
    return std::fabs(std::sqrt(n2) - 1.0) <= kRotTol;
}
}  // namespace

}  // namespace sfd

using namespace sfd;

extern "C" sfd_status_t sfd_so3_exp(const double phi_rad[3], double R[9]) {
    if (phi_rad == nullptr || R == nullptr || !all_finite(phi_rad, 3)) return SFD_ERR_INVAL;
    store_mat3(so3_exp(Vec3(phi_rad[0], phi_rad[1], phi_rad[2])), R);
    return SFD_OK;
}

extern "C" sfd_status_t sfd_so3_log(const double R[9], double phi_rad[3]) {
    if (R == nullptr || phi_rad == nullptr) return SFD_ERR_INVAL;
    const Mat3 M = load_mat3(R);
    if (!is_rotation(M, kRotTol)) return SFD_ERR_INVAL;
    const Vec3 phi = so3_log(M);
    phi_rad[0] = phi.x();
    phi_rad[1] = phi.y();
    phi_rad[2] = phi.z();
    return SFD_OK;
}

extern "C" sfd_status_t sfd_quat_from_rotvec(const double phi_rad[3], double q[4]) {
    if (phi_rad == nullptr || q == nullptr || !all_finite(phi_rad, 3)) return SFD_ERR_INVAL;
    store_quat(quat_from_rotvec(Vec3(phi_rad[0], phi_rad[1], phi_rad[2])), q);
    return SFD_OK;
}

extern "C" sfd_status_t sfd_quat_to_rotvec(const double q[4], double phi_rad[3]) {
    if (q == nullptr || phi_rad == nullptr || !unit_quat(q)) return SFD_ERR_INVAL;
    const Vec3 phi = quat_to_rotvec(load_quat(q));
    phi_rad[0] = phi.x();
    phi_rad[1] = phi.y();
    phi_rad[2] = phi.z();
    return SFD_OK;
}

extern "C" sfd_status_t sfd_quat_multiply(const double a[4], const double b[4], double q[4]) {
    if (a == nullptr || b == nullptr || q == nullptr || !all_finite(a, 4) || !all_finite(b, 4)) {
        return SFD_ERR_INVAL;
    }
    store_quat(load_quat(a) * load_quat(b), q);
    return SFD_OK;
}

extern "C" sfd_status_t sfd_quat_normalize(double q[4]) {
    if (q == nullptr || !all_finite(q, 4)) return SFD_ERR_INVAL;
    Quat v = load_quat(q);
    const double n = v.norm();
    if (n < 1e-12) return SFD_ERR_INVAL;
    v.coeffs() /= n;
    if (v.w() < 0.0) v.coeffs() = -v.coeffs();
    store_quat(v, q);
    return SFD_OK;
}

extern "C" sfd_status_t sfd_quat_to_rotmat(const double q[4], double R[9]) {
    if (q == nullptr || R == nullptr || !unit_quat(q)) return SFD_ERR_INVAL;
    store_mat3(load_quat(q).normalized().toRotationMatrix(), R);
    return SFD_OK;
}

extern "C" sfd_status_t sfd_rotmat_to_quat(const double R[9], double q[4]) {
    if (R == nullptr || q == nullptr) return SFD_ERR_INVAL;
    const Mat3 M = load_mat3(R);
    if (!is_rotation(M, kRotTol)) return SFD_ERR_INVAL;
    store_quat(rotmat_to_quat(M), q);
    return SFD_OK;
}

extern "C" sfd_status_t sfd_extrinsics_from_matrix(sfd_extrinsics_t *ext,
                                                   const double T_imu_cam[16]) {
    if (ext == nullptr || T_imu_cam == nullptr || !all_finite(T_imu_cam, 16)) {
        return SFD_ERR_INVAL;
    }
    // Row-major 4x4: rotation in rows 0-2, columns 0-2; translation in column 3.
    if (std::fabs(T_imu_cam[12]) > kRotTol || std::fabs(T_imu_cam[13]) > kRotTol ||
        std::fabs(T_imu_cam[14]) > kRotTol || std::fabs(T_imu_cam[15] - 1.0) > kRotTol) {
        return SFD_ERR_INVAL;
    }
    Mat3 R;
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) R(r, c) = T_imu_cam[4 * r + c];
    }
    if (!is_rotation(R, kRotTol)) return SFD_ERR_INVAL;
    store_mat3(R, ext->R_CtoI);
    ext->p_CinI[0] = T_imu_cam[3];
    ext->p_CinI[1] = T_imu_cam[7];
    ext->p_CinI[2] = T_imu_cam[11];
    return SFD_OK;
}

extern "C" sfd_status_t sfd_extrinsics_camera_rotation(const sfd_extrinsics_t *ext,
                                                       const double R_I1toI0[9],
                                                       double R_C1toC0[9]) {
    if (ext == nullptr || R_I1toI0 == nullptr || R_C1toC0 == nullptr || !all_finite(R_I1toI0, 9)) {
        return SFD_ERR_INVAL;
    }
    // v_C0 = R_ItoC v_I0 = R_ItoC R_I1toI0 v_I1 = R_ItoC R_I1toI0 R_CtoI v_C1.
    const Mat3 R_CtoI = load_mat3(ext->R_CtoI);
    store_mat3(R_CtoI.transpose() * load_mat3(R_I1toI0) * R_CtoI, R_C1toC0);
    return SFD_OK;
}
