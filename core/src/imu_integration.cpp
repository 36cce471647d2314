// SPDX-License-Identifier: MIT
// Gyro integration between two frame times (sfd/sfd_imu.h).
#include "core_private.hpp"
#include "rotation.hpp"
#include "sfd/sfd_imu.h"

namespace sfd {
namespace {

Vec3 rate_at(const sfd_imu_sample_t &s0, const sfd_imu_sample_t &s1, int64_t t_us,
             const Vec3 &bias) {
    const Vec3 w0(s0.gyro_rad_s[0], s0.gyro_rad_s[1], s0.gyro_rad_s[2]);
    const Vec3 w1(s1.gyro_rad_s[0], s1.gyro_rad_s[1], s1.gyro_rad_s[2]);
    const double f = static_cast<double>(t_us - s0.t_us) / static_cast<double>(s1.t_us - s0.t_us);
    return w0 + f * (w1 - w0) - bias;
}

}  // namespace
}  // namespace sfd

using namespace sfd;

// For R' = R [w]x with w linear over [ta, tb] (h = tb - ta), the Magnus expansion truncated after
// its second term gives R(tb) = R(ta) exp(h (wa + wb)/2 + h^2/12 (wa x wb)); the next term is
// O(h^5 |w|^3 |dw|^2) (Iserles & Norsett 1999). The increments are composed with Hamilton
// products, so q is the orientation of the current IMU frame in the IMU frame at t0.
extern "C" sfd_status_t sfd_gyro_integrate_span(const sfd_imu_span_t *span, int64_t t0_us,
                                                int64_t t1_us, const double bias_rad_s[3],
                                                int64_t max_gap_us, double q_I1toI0[4]) {
    if (span == nullptr || q_I1toI0 == nullptr || max_gap_us < 0) return SFD_ERR_INVAL;
    const bool packed = span->packed[0] != nullptr;
    for (int p = 0; p < 2; ++p) {
        const void *piece = packed ? static_cast<const void *>(span->packed[p])
                                   : static_cast<const void *>(span->piece[p]);
        if (span->count[p] < 0 || (span->count[p] > 0 && piece == nullptr)) return SFD_ERR_INVAL;
    }
    const size_t n = static_cast<size_t>(span->count[0]) + static_cast<size_t>(span->count[1]);
    if (n < 2 || n > SFD_MAX_IMU_SAMPLES) return SFD_ERR_INVAL;
    const auto sample = [span](size_t i) -> sfd_imu_sample_t {
        return sfd_imu_span_at(span, static_cast<int32_t>(i));
    };
    if (t1_us <= t0_us) return SFD_ERR_ORDER;
    Vec3 bias = Vec3::Zero();
    if (bias_rad_s != nullptr) {
        if (!all_finite(bias_rad_s, 3)) return SFD_ERR_INVAL;
        bias = Vec3(bias_rad_s[0], bias_rad_s[1], bias_rad_s[2]);
    }
    for (size_t i = 0; i < n; ++i) {
        if (!all_finite(sample(i).gyro_rad_s, 3)) return SFD_ERR_INVAL;
        if (i > 0 && sample(i).t_us <= sample(i - 1).t_us) return SFD_ERR_ORDER;
    }
    if (sample(0).t_us > t0_us || sample(n - 1).t_us < t1_us) return SFD_ERR_RANGE;

    Quat q = Quat::Identity();
    for (size_t i = 0; i + 1 < n; ++i) {
        const sfd_imu_sample_t s0 = sample(i);
        const sfd_imu_sample_t s1 = sample(i + 1);
        const int64_t ta = (s0.t_us > t0_us) ? s0.t_us : t0_us;
        const int64_t tb = (s1.t_us < t1_us) ? s1.t_us : t1_us;
        if (tb <= ta) continue;  // segment outside [t0, t1]
        if (max_gap_us > 0 && s1.t_us - s0.t_us > max_gap_us) return SFD_ERR_RANGE;
        const Vec3 wa = rate_at(s0, s1, ta, bias);
        const Vec3 wb = rate_at(s0, s1, tb, bias);
        const double h = 1e-6 * static_cast<double>(tb - ta);
        const Vec3 phi = (0.5 * h) * (wa + wb) + (h * h / 12.0) * wa.cross(wb);
        q = q * quat_from_rotvec(phi);
        q.normalize();
    }
    if (!all_finite(q.coeffs().data(), 4)) return SFD_ERR_NUMERIC;
    if (q.w() < 0.0) q.coeffs() = -q.coeffs();
    q_I1toI0[0] = q.w();
    q_I1toI0[1] = q.x();
    q_I1toI0[2] = q.y();
    q_I1toI0[3] = q.z();
    return SFD_OK;
}

extern "C" sfd_status_t sfd_gyro_integrate(const sfd_imu_sample_t *samples, size_t n, int64_t t0_us,
                                           int64_t t1_us, const double bias_rad_s[3],
                                           int64_t max_gap_us, double q_I1toI0[4]) {
    if (samples == nullptr || n < 2 || n > SFD_MAX_IMU_SAMPLES) return SFD_ERR_INVAL;
    const sfd_imu_span_t span = {
        {samples, nullptr}, {static_cast<int32_t>(n), 0}, {nullptr, nullptr}};
    return sfd_gyro_integrate_span(&span, t0_us, t1_us, bias_rad_s, max_gap_us, q_I1toI0);
}
