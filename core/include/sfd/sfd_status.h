/* SPDX-License-Identifier: MIT */
/**
 * @file sfd_status.h
 * @brief Status codes returned by every fallible sfd function.
 *
 * Errors are negative so that a function may return a non-negative count on success
 * (littlefs convention). Detection results (a feature judged SPURIOUS, an untested window)
 * are data, never status codes.
 */
#ifndef SFD_STATUS_H
#define SFD_STATUS_H

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    SFD_OK = 0,            /**< Success. */
    SFD_ERR_INVAL = -1,    /**< Invalid argument: null pointer, non-finite or out-of-range value. */
    SFD_ERR_CAPACITY = -2, /**< A fixed capacity (SFD_MAX_*) would be exceeded; nothing written. */
    SFD_ERR_ORDER = -3,    /**< Timestamps not strictly increasing where they must be. */
    SFD_ERR_NUMERIC = -4,  /**< Numerical trouble (singular, non-finite, no convergence). */
    SFD_ERR_STATE = -5,    /**< Object not initialized or used out of sequence. */
    SFD_ERR_RANGE = -6,    /**< Requested interval not covered by the data (e.g. IMU gap). */
    SFD_ERR_DOMAIN = -7    /**< Input outside the model's domain (e.g. point behind camera). */
} sfd_status_t;

/**
 * @brief Human-readable, static name of a status code ("SFD_OK", "SFD_ERR_INVAL", ...).
 * @return A pointer to a string literal; "SFD_ERR_UNKNOWN" for a value not listed above.
 *         Never NULL. Reentrant.
 */
const char *sfd_status_str(sfd_status_t status);

#ifdef __cplusplus
}
#endif

#endif /* SFD_STATUS_H */
