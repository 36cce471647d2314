/* SPDX-License-Identifier: MIT */
/**
 * @file sfd_imu_ring.h
 * @brief Fixed-capacity IMU ring buffer and frame-motion assembly (gyro integration between two
 *        frame times, through the camera-IMU extrinsics). Caller-owned, heap-free, bounded.
 */
#ifndef SFD_IMU_RING_H
#define SFD_IMU_RING_H

#include <stdint.h>

#include "sfd_imu.h"
#include "sfd_parity.h"
#include "sfd_reject.h"
#include "sfd_rotation.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Samples kept: 512 = 2.56 s at 200 Hz (packed in float, sfd_imu_packed_t: 32 B each, 16 KiB). The
 * ring must span the rest window of the filter's start (filter.init_rest_s, 1 s as shipped) plus
 * one frame interval and the transport's lead of IMU over features. A faster IMU needs a larger
 *  -DSFD_IMU_RING_CAPACITY (at 1 kHz, 512 samples are 0.51 s: less than the rest window, so the
 *  filter could not start; 2048 would do). Readers take the samples in place
 *  (sfd_imu_ring_span), so no copy of them is kept. */
#ifndef SFD_IMU_RING_CAPACITY
#define SFD_IMU_RING_CAPACITY 512
#endif

typedef struct {
    sfd_imu_packed_t samples[SFD_IMU_RING_CAPACITY];
    int32_t head;           /* index of the oldest sample */
    int32_t count;          /* samples held */
    int64_t overwritten;    /* samples dropped because the ring was full (oldest first) */
    int64_t lost;           /* of those, the ones a later frame might still have needed */
    int64_t needed_from_us; /* frames need no sample before the last one at or before this */
    int32_t need_known;     /* 0 until the first sfd_imu_ring_set_needed: no frame waits yet */
} sfd_imu_ring_t;

/** @brief Empties the ring. */
void sfd_imu_ring_init(sfd_imu_ring_t *ring);

/**
 * @brief Appends a sample. When the ring is full the oldest sample is overwritten and counted in
 *        `overwritten` (the new sample is stored). The drop is a loss, counted in `lost` and
 *        returned as SFD_REJECT_IMU_OVERFLOW so the caller can count it too, when a frame may
 *        still need it: the consumer has declared what it needs (sfd_imu_ring_set_needed) and
 *        the next sample is after `needed_from_us`, so an interval starting there would begin at
 *        the dropped one. In steady state the ring wraps over samples consumed long ago, and
 *        before the first declaration (no frame judged yet) over samples older than the ring's
 *        span, which no first frame needs; neither is reported (a first frame that finds its
 *        interval gone is judged UNTESTED and counted as imu_gap).
 * @return SFD_REJECT_NONE; SFD_REJECT_ORDER if t_us is not after the newest sample (not stored);
 *         SFD_REJECT_NONFINITE for a value that is not finite or beyond float's range (the ring
 *         stores floats; not stored); SFD_REJECT_IMU_OVERFLOW as above.
 */
int sfd_imu_ring_push(sfd_imu_ring_t *ring, const sfd_imu_sample_t *sample);

/**
 * @brief Declares that no frame to come needs a sample before the last one at or before t_us
 *        (the caller's consumers read intervals [t0, t1] with t0 >= t_us). The caller restates
 *        it after each frame, and lowers it when a consumer starts from an earlier time.
 */
void sfd_imu_ring_set_needed(sfd_imu_ring_t *ring, int64_t t_us);

/** @brief Time of the newest sample, or INT64_MIN when empty. */
int64_t sfd_imu_ring_newest(const sfd_imu_ring_t *ring);

/**
 * @brief The samples that cover [t0_us, t1_us], in place: from the last sample at or before t0
 *        to the first at or after t1, as a span (valid until the next push).
 * @return SFD_REJECT_NONE (*span set); SFD_REJECT_IMU_LATE when no sample at or after t1 has
 *         arrived yet (wait, or give up after the configured time); SFD_REJECT_IMU_GAP when the
 *         ring no longer (or never) held a sample at or before t0; SFD_REJECT_CAPACITY when more
 *         than @p cap samples would be needed.
 */
int sfd_imu_ring_span(const sfd_imu_ring_t *ring, int64_t t0_us, int64_t t1_us, int32_t cap,
                      sfd_imu_span_t *span);

/**
 * @brief Copies the samples that cover [t0_us, t1_us]: from the last sample at or before t0 to
 *        the first at or after t1, into @p out (capacity @p cap).
 * @return SFD_REJECT_NONE (*n set); SFD_REJECT_IMU_LATE when no sample at or after t1 has arrived
 *         yet (wait, or give up after the configured time); SFD_REJECT_IMU_GAP when the ring
 *         no longer (or never) held a sample at or before t0; SFD_REJECT_CAPACITY when more
 *         than @p cap samples would be needed.
 */
int sfd_imu_ring_window(const sfd_imu_ring_t *ring, int64_t t0_us, int64_t t1_us,
                        sfd_imu_sample_t *out, int32_t cap, int32_t *n);

/**
 * @brief Camera motion between two frames for the detector: the IMU rotation integrated from the
 *        gyro (bias subtracted, ends interpolated) over [t_prev_us, t_cur_us] from the ring's
 *        samples in place, expressed for the camera through the extrinsics. Translation is left
 *        unknown.
 * @return SFD_REJECT_NONE; the reasons of sfd_imu_ring_span() (SFD_REJECT_CAPACITY: more than
 *         SFD_MAX_IMU_SAMPLES in the interval); SFD_REJECT_IMU_GAP also for a gap between samples
 *         larger than @p max_gap_us inside the interval.
 */
int sfd_assemble_motion(const sfd_imu_ring_t *ring, const sfd_extrinsics_t *ext,
                        const double gyro_bias_rad_s[3], int64_t t_prev_us, int64_t t_cur_us,
                        int64_t max_gap_us, sfd_frame_motion_t *motion);

#ifdef __cplusplus
}
#endif

#endif /* SFD_IMU_RING_H */
