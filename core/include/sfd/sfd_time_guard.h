/* SPDX-License-Identifier: MIT */
/**
 * @file sfd_time_guard.h
 * @brief The time-glitch policy of one input stream (IMU samples or feature frames): a message
 *        stamped too far from its stream is refused and never becomes the stream's reference; a
 *        sustained jump (a restarted sensor, publisher or log) is accepted as the new time base
 *        after a stated number of consistent messages. docs/time_glitches.md states the rules
 *        with examples; sfd_pipeline.h applies them to both of its streams.
 *
 * Rules for a message at t, with H = horizon_us, N = resync_messages:
 *  - the reference r is the stream's newest accepted time; a stream without one takes the other
 *    stream's (nullable); with neither, the message is accepted and becomes the reference;
 *  - ahead: t > max(r, r_other) + H is a JUMP (the other stream's time counts, so that a camera
 *    that pauses longer than H while the IMU runs is not a jump);
 *  - r < t <= max(r, r_other) + H is ACCEPTED and becomes the reference;
 *  - r - H < t <= r is ORDER (a duplicate or a reordered message: refused);
 *  - t <= r - H is a JUMP (backwards);
 *  - JUMP messages form a run when each is after the previous one by at most H (an accepted
 *    message ends the run); the N-th message of a run is accepted as the new reference:
 *    RESYNC (the caller re-initializes what depends on the old time base).
 * So one glitched message is refused and costs nothing else; a stream that restarts loses its
 * first N - 1 messages; a message accepted wrongly (at most H ahead) refuses at most H of the
 * stream. Times are compared without overflow for any int64 value.
 */
#ifndef SFD_TIME_GUARD_H
#define SFD_TIME_GUARD_H

#include <stdint.h>

#include "sfd_status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    int64_t horizon_us;      /**< H: farthest a message may lie from its stream, > 0 (500 000) */
    int32_t resync_messages; /**< N: consistent jumped messages that make another time base,
                                  2..1000 (5) */
} sfd_time_guard_params_t;

typedef enum {
    SFD_TIME_ACCEPT = 0, /**< in order: use it */
    SFD_TIME_ORDER = 1,  /**< not after the reference, within H: refuse (duplicate, reordered) */
    SFD_TIME_JUMP = 2,   /**< more than H from the stream: refuse (counted in the run) */
    SFD_TIME_RESYNC = 3  /**< the N-th consistent jumped message: use it as the next time base */
} sfd_time_verdict_t;

typedef struct {
    sfd_time_guard_params_t prm;
    int32_t have_ref;
    int64_t ref_us;      /**< newest accepted time */
    int32_t run;         /**< jumped messages in the current run */
    int64_t run_last_us; /**< newest of them */
} sfd_time_guard_t;

/** @brief Defaults: H = 0.5 s, N = 5. */
void sfd_time_guard_params_default(sfd_time_guard_params_t *prm);

/** @brief SFD_OK; SFD_ERR_INVAL for null or a parameter out of range. */
sfd_status_t sfd_time_guard_params_validate(const sfd_time_guard_params_t *prm);

/** @brief No reference, no run. @return as sfd_time_guard_params_validate (guard unchanged). */
sfd_status_t sfd_time_guard_init(sfd_time_guard_t *g, const sfd_time_guard_params_t *prm);

/** @brief Forgets the reference and the run (parameters kept). */
void sfd_time_guard_reset(sfd_time_guard_t *g);

/**
 * @brief Judges a message at @p t_us by the rules of the file comment and updates the guard
 *        (ACCEPT and RESYNC make t_us the reference).
 * @param other the other stream's guard, or NULL.
 */
sfd_time_verdict_t sfd_time_guard_check(sfd_time_guard_t *g, int64_t t_us,
                                        const sfd_time_guard_t *other);

#ifdef __cplusplus
}
#endif

#endif /* SFD_TIME_GUARD_H */
