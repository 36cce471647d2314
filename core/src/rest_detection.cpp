// SPDX-License-Identifier: MIT
// Rest detection from the IMU (sfd_rest.h, core/docs/rest_detection.md): block means of gyro and
// accelerometer over a sliding window, their scatter against a chi-square threshold, eq. (1).
#include "core_private.hpp"
#include "sfd/sfd_chi2.h"
#include "sfd/sfd_rest.h"

namespace {

void clear_window(sfd_rest_t *r) {
    r->in_block = 0;
    r->blocks = 0;
    r->next = 0;
    r->block_start_us = 0;
    for (double &s : r->sum) s = 0.0;
}

}  // namespace

extern "C" sfd_status_t sfd_rest_params_default(sfd_rest_params_t *p) {
    if (p == nullptr) return SFD_ERR_INVAL;
    p->block_samples = 20;
    p->window_blocks = 10;
    p->gyro_block_sigma_rad_s = 0.005;
    p->accel_block_sigma_m_s2 = 0.05;
    p->alpha = 0.001;
    p->gravity_m_s2 = 9.81;
    p->gravity_tol_m_s2 = 0.5;
    p->max_gap_us = 50000;
    return SFD_OK;
}

extern "C" sfd_status_t sfd_rest_init(sfd_rest_t *r, const sfd_rest_params_t *p) {
    if (r == nullptr || p == nullptr || p->block_samples < 1 || p->block_samples > 1000 ||
        p->window_blocks < 2 || p->window_blocks > SFD_REST_MAX_BLOCKS ||
        !(p->gyro_block_sigma_rad_s > 0.0) || !std::isfinite(p->gyro_block_sigma_rad_s) ||
        !(p->accel_block_sigma_m_s2 > 0.0) || !std::isfinite(p->accel_block_sigma_m_s2) ||
        !(p->alpha > 0.0 && p->alpha <= 0.5) || !(p->gravity_m_s2 > 0.0) ||
        !std::isfinite(p->gravity_m_s2) || !(p->gravity_tol_m_s2 > 0.0) ||
        !std::isfinite(p->gravity_tol_m_s2) || p->max_gap_us < 1) {
        return SFD_ERR_INVAL;
    }
    double thr = 0.0;
    if (sfd_chi2_quantile_upper(p->alpha, 6 * (p->window_blocks - 1), &thr) != SFD_OK) {
        return SFD_ERR_INVAL;
    }
    std::memset(r, 0, sizeof *r);
    r->p = *p;
    r->threshold = thr;
    r->last_t_us = std::numeric_limits<int64_t>::min();
    clear_window(r);
    return SFD_OK;
}

extern "C" sfd_status_t sfd_rest_push(sfd_rest_t *r, int64_t t_us, const double g[3],
                                      const double a[3]) {
    if (r == nullptr || g == nullptr || a == nullptr || !sfd::all_finite(g, 3) ||
        !sfd::all_finite(a, 3)) {
        return SFD_ERR_INVAL;
    }
    const bool first = r->last_t_us == std::numeric_limits<int64_t>::min();
    if (!first && t_us <= r->last_t_us) return SFD_ERR_ORDER;
    // The difference of two int64 times can overflow: compare without subtracting past the range.
    if (!first && t_us > r->last_t_us + r->p.max_gap_us &&
        r->last_t_us <= std::numeric_limits<int64_t>::max() - r->p.max_gap_us) {
        clear_window(r);
        ++r->restarts;
    }
    r->last_t_us = t_us;
    if (r->in_block == 0) r->block_start_us = t_us;
    for (int k = 0; k < 3; ++k) {
        r->sum[k] += g[k];
        r->sum[3 + k] += a[k];
    }
    if (++r->in_block < r->p.block_samples) return SFD_OK;
    const double inv = 1.0 / double(r->p.block_samples);
    for (int k = 0; k < 6; ++k) {
        r->mean[r->next][k] = r->sum[k] * inv;
        r->sum[k] = 0.0;
    }
    r->start_us[r->next] = r->block_start_us;
    r->end_us[r->next] = t_us;
    r->next = (r->next + 1) % r->p.window_blocks;
    if (r->blocks < r->p.window_blocks) ++r->blocks;
    r->in_block = 0;
    return SFD_OK;
}

extern "C" sfd_status_t sfd_rest_evaluate(const sfd_rest_t *r, sfd_rest_result_t *out) {
    if (r == nullptr || out == nullptr) return SFD_ERR_INVAL;
    std::memset(out, 0, sizeof *out);
    const int K = r->p.window_blocks;
    if (r->blocks < K) return SFD_OK;
    double m[6] = {0, 0, 0, 0, 0, 0};
    for (int b = 0; b < K; ++b) {
        for (int k = 0; k < 6; ++k) m[k] += r->mean[b][k];
    }
    for (double &v : m) v /= double(K);
    double sg = 0.0, sa = 0.0;
    for (int b = 0; b < K; ++b) {
        for (int k = 0; k < 3; ++k) {
            const double dg = r->mean[b][k] - m[k], da = r->mean[b][3 + k] - m[3 + k];
            sg += dg * dg;
            sa += da * da;
        }
    }
    const double T = sg / (r->p.gyro_block_sigma_rad_s * r->p.gyro_block_sigma_rad_s) +
                     sa / (r->p.accel_block_sigma_m_s2 * r->p.accel_block_sigma_m_s2);
    const double fa = std::sqrt(m[3] * m[3] + m[4] * m[4] + m[5] * m[5]);
    out->ready = 1;
    out->statistic = T;
    out->threshold = r->threshold;
    out->at_rest =
        (T <= r->threshold && std::fabs(fa - r->p.gravity_m_s2) <= r->p.gravity_tol_m_s2) ? 1 : 0;
    for (int k = 0; k < 3; ++k) {
        out->gyro_mean_rad_s[k] = m[k];
        out->accel_mean_m_s2[k] = m[3 + k];
    }
    // The oldest block is the one the next complete block will overwrite (the ring is full).
    out->window_start_us = r->start_us[r->next];
    out->window_end_us = r->end_us[(r->next + K - 1) % K];
    return SFD_OK;
}
