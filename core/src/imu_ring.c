/* SPDX-License-Identifier: MIT */
#include "sfd/sfd_imu_ring.h"

#include <string.h>

#include "float_round.h"

void sfd_imu_ring_init(sfd_imu_ring_t *ring) {
    ring->head = 0;
    ring->count = 0;
    ring->overwritten = 0;
    ring->lost = 0;
    ring->needed_from_us = INT64_MIN;
    ring->need_known = 0;
}

void sfd_imu_ring_set_needed(sfd_imu_ring_t *ring, int64_t t_us) {
    ring->needed_from_us = t_us;
    ring->need_known = 1;
}

static const sfd_imu_packed_t *at(const sfd_imu_ring_t *ring, int32_t i) {
    return &ring->samples[(ring->head + i) % SFD_IMU_RING_CAPACITY];
}

int64_t sfd_imu_ring_newest(const sfd_imu_ring_t *ring) {
    return ring->count > 0 ? at(ring, ring->count - 1)->t_us : INT64_MIN;
}

int sfd_imu_ring_push(sfd_imu_ring_t *ring, const sfd_imu_sample_t *sample) {
    if (ring->count > 0 && sample->t_us <= sfd_imu_ring_newest(ring)) return SFD_REJECT_ORDER;
    sfd_imu_packed_t packed;
    packed.t_us = sample->t_us;
    if (!sfd_fits_float(sample->gyro_rad_s, 3) || !sfd_fits_float(sample->accel_m_s2, 3)) {
        return SFD_REJECT_NONFINITE;
    }
    for (int k = 0; k < 3; ++k) {
        packed.gyro_rad_s[k] = (float)sample->gyro_rad_s[k];
        packed.accel_m_s2[k] = (float)sample->accel_m_s2[k];
    }
    int result = SFD_REJECT_NONE;
    if (ring->count == SFD_IMU_RING_CAPACITY) {
        /* harmless when no frame waits yet, or a newer sample is still at or before the first
         * time a frame needs */
        const int harmless =
            !ring->need_known || (ring->count >= 2 && at(ring, 1)->t_us <= ring->needed_from_us);
        ring->head = (ring->head + 1) % SFD_IMU_RING_CAPACITY;
        ring->count--;
        ring->overwritten++;
        if (!harmless) {
            ring->lost++;
            result = SFD_REJECT_IMU_OVERFLOW;
        }
    }
    ring->samples[(ring->head + ring->count) % SFD_IMU_RING_CAPACITY] = packed;
    ring->count++;
    return result;
}

int sfd_imu_ring_span(const sfd_imu_ring_t *ring, int64_t t0_us, int64_t t1_us, int32_t cap,
                      sfd_imu_span_t *span) {
    if (ring->count == 0 || sfd_imu_ring_newest(ring) < t1_us) return SFD_REJECT_IMU_LATE;
    if (at(ring, 0)->t_us > t0_us) return SFD_REJECT_IMU_GAP;
    /* first: last sample at or before t0 (binary search over the time-ordered ring) */
    int32_t lo = 0, hi = ring->count - 1;
    while (lo < hi) { /* invariant: at(lo) <= t0; terminates in log2(capacity) steps */
        const int32_t mid = lo + (hi - lo + 1) / 2;
        if (at(ring, mid)->t_us <= t0_us) {
            lo = mid;
        } else {
            hi = mid - 1;
        }
    }
    const int32_t first = lo;
    /* last: first sample at or after t1 (binary search; newest >= t1 was checked above) */
    lo = first;
    hi = ring->count - 1;
    while (lo < hi) { /* invariant: at(hi) >= t1 */
        const int32_t mid = lo + (hi - lo) / 2;
        if (at(ring, mid)->t_us < t1_us) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    const int32_t count = hi - first + 1;
    if (count > cap) return SFD_REJECT_CAPACITY;
    const int32_t start = (ring->head + first) % SFD_IMU_RING_CAPACITY;
    const int32_t tail = SFD_IMU_RING_CAPACITY - start; /* samples before the array wraps */
    span->piece[0] = NULL;
    span->piece[1] = NULL;
    span->packed[0] = &ring->samples[start];
    span->count[0] = count < tail ? count : tail;
    span->count[1] = count - span->count[0];
    span->packed[1] = span->count[1] > 0 ? &ring->samples[0] : NULL;
    return SFD_REJECT_NONE;
}

int sfd_imu_ring_window(const sfd_imu_ring_t *ring, int64_t t0_us, int64_t t1_us,
                        sfd_imu_sample_t *out, int32_t cap, int32_t *n) {
    sfd_imu_span_t span;
    const int r = sfd_imu_ring_span(ring, t0_us, t1_us, cap, &span);
    if (r != SFD_REJECT_NONE) return r;
    const int32_t count = sfd_imu_span_count(&span);
    for (int32_t i = 0; i < count; ++i) out[i] = sfd_imu_span_at(&span, i);
    *n = count;
    return SFD_REJECT_NONE;
}

int sfd_assemble_motion(const sfd_imu_ring_t *ring, const sfd_extrinsics_t *ext,
                        const double gyro_bias_rad_s[3], int64_t t_prev_us, int64_t t_cur_us,
                        int64_t max_gap_us, sfd_frame_motion_t *motion) {
    if (t_cur_us <= t_prev_us) return SFD_REJECT_ORDER;
    sfd_imu_span_t span;
    const int w = sfd_imu_ring_span(ring, t_prev_us, t_cur_us, SFD_MAX_IMU_SAMPLES, &span);
    if (w != SFD_REJECT_NONE) return w;
    double q[4], R_I[9], R_C[9];
    const sfd_status_t st =
        sfd_gyro_integrate_span(&span, t_prev_us, t_cur_us, gyro_bias_rad_s, max_gap_us, q);
    if (st == SFD_ERR_RANGE) return SFD_REJECT_IMU_GAP;
    if (st != SFD_OK) return SFD_REJECT_CORE;
    if (sfd_quat_to_rotmat(q, R_I) != SFD_OK ||
        sfd_extrinsics_camera_rotation(ext, R_I, R_C) != SFD_OK) {
        return SFD_REJECT_CORE;
    }
    memcpy(motion->R_CcurToCprev, R_C, sizeof R_C);
    motion->translation_known = 0;
    motion->p_CcurInCprev_m[0] = motion->p_CcurInCprev_m[1] = motion->p_CcurInCprev_m[2] = 0.0;
    return SFD_REJECT_NONE;
}
