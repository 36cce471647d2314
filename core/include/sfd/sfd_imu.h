/* SPDX-License-Identifier: MIT */
/**
 * @file sfd_imu.h
 * @brief IMU samples and the gyro integration between two frame times.
 */
#ifndef SFD_IMU_H
#define SFD_IMU_H

#include <stddef.h>
#include <stdint.h>

#include "sfd_config.h"
#include "sfd_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Largest magnitude per axis of an IMU sample the pipeline accepts (sfd_pipeline_push_imu):
 *  far beyond any IMU's full scale (MEMS gyros reach about 35 rad/s, high-g accelerometers about
 *  4000 m/s^2), and far below what the filter's arithmetic overflows at (a finite 1e160 m/s^2
 *  made its covariance NaN: fuzz.sequence). */
#define SFD_IMU_MAX_GYRO_RAD_S 1.0e3
#define SFD_IMU_MAX_ACCEL_M_S2 1.0e5

/** One IMU sample, IMU frame. */
typedef struct {
    int64_t t_us;         /**< sample time (microseconds) */
    double gyro_rad_s[3]; /**< angular rate (rad/s) */
    double accel_m_s2[3]; /**< specific force (m/s^2) */
} sfd_imu_sample_t;

/** One IMU sample as the ring stores it (32 B instead of 56): the rates and specific forces
 *  in float, a relative 6e-8 (1e-7 rad/s at 1 rad/s, 6e-7 m/s^2 at 1 g: three orders below the
 *  noise of one sample of a navigation-grade MEMS IMU at 200 Hz). */
typedef struct {
    int64_t t_us;
    float gyro_rad_s[3];
    float accel_m_s2[3];
} sfd_imu_packed_t;

/** @brief The sample a packed one holds (every float is exactly a double). */
static inline sfd_imu_sample_t sfd_imu_unpack(const sfd_imu_packed_t *p) {
    sfd_imu_sample_t s;
    s.t_us = p->t_us;
    for (int k = 0; k < 3; ++k) {
        s.gyro_rad_s[k] = p->gyro_rad_s[k]; /* float to double: exact */
        s.accel_m_s2[k] = p->accel_m_s2[k];
    }
    return s;
}

/** A time-ordered run of samples held in at most two contiguous pieces (a ring buffer that
 *  wraps: the tail of its array, then its head), read in place without a copy. The pieces are
 *  either full samples (piece) or the ring's packed ones (packed, when packed[0] is not NULL). */
typedef struct {
    const sfd_imu_sample_t *piece[2];  /**< piece[1] may be NULL when count[1] is 0 */
    int32_t count[2];                  /**< samples in each piece, >= 0 */
    const sfd_imu_packed_t *packed[2]; /**< instead of piece when packed[0] is not NULL */
} sfd_imu_span_t;

/** @brief Sample i (0 <= i < count[0] + count[1]) of a span, by value. */
static inline sfd_imu_sample_t sfd_imu_span_at(const sfd_imu_span_t *span, int32_t i) {
    const int p = (i < span->count[0]) ? 0 : 1;
    const int32_t k = p ? i - span->count[0] : i;
    if (span->packed[0] != NULL) return sfd_imu_unpack(&span->packed[p][k]);
    return span->piece[p][k];
}

/** @brief Samples in a span. */
static inline int32_t sfd_imu_span_count(const sfd_imu_span_t *span) {
    return span->count[0] + span->count[1];
}

/**
 * @brief Orientation change of the IMU between t0_us and t1_us from gyro samples: the unit
 *        quaternion q_I1toI0 (IMU frame at t1 expressed in the IMU frame at t0).
 *
 * Model: the bias-corrected rate w(t) - b is linear between consecutive samples and linearly
 * interpolated at the interval ends t0 and t1 (which need not fall on samples). Each sub-interval
 * [ta, tb] contributes exp(h (wa + wb)/2 + h^2/12 (wa x wb)), h = tb - ta: the Magnus expansion of
 * the linear-rate solution truncated after its second (commutator) term. Exact for a constant
 * rate; the remainder is the third Magnus term, O(h^3 |w|^2 |wb - wa|) (~1e-12 rad for 5 ms
 * segments at the rates of a hand-held rig).
 *
 * @param samples     Samples sorted by strictly increasing t_us (caller-owned, read-only).
 * @param n           Number of samples, 2 <= n <= SFD_MAX_IMU_SAMPLES.
 * @param t0_us       Interval start; @p t1_us > t0_us.
 * @param bias_rad_s  Gyro bias subtracted from every sample (nullable = zero).
 * @param max_gap_us  Largest gap between consecutive samples allowed inside [t0, t1]; 0 = no check.
 * @param q_I1toI0    Out: (w, x, y, z), w >= 0.
 * @return SFD_OK; SFD_ERR_INVAL for null/non-finite input or n out of range; SFD_ERR_ORDER for
 *         timestamps not strictly increasing or t1 <= t0; SFD_ERR_RANGE when the samples do not
 *         cover [t0, t1] (first sample after t0 or last before t1) or a gap exceeds max_gap_us.
 *         On error the output is untouched.
 */
sfd_status_t sfd_gyro_integrate(const sfd_imu_sample_t *samples, size_t n, int64_t t0_us,
                                int64_t t1_us, const double bias_rad_s[3], int64_t max_gap_us,
                                double q_I1toI0[4]);

/** @brief sfd_gyro_integrate() over a span (the samples in place in a ring buffer); the same
 *         model, checks and results bit for bit. SFD_ERR_INVAL also for a negative piece count
 *         or a null piece with a positive count. */
sfd_status_t sfd_gyro_integrate_span(const sfd_imu_span_t *span, int64_t t0_us, int64_t t1_us,
                                     const double bias_rad_s[3], int64_t max_gap_us,
                                     double q_I1toI0[4]);

#ifdef __cplusplus
}
#endif

#endif /* SFD_IMU_H */
