/* SPDX-License-Identifier: MIT */
/* Private to the core (C and C++ sources): bit-for-bit equality of doubles. -0.0 and 0.0 differ,
 * and a NaN equals a NaN of the same payload: the test for "the same value again" (a republished
 * calibration, a cache key, a filter state untouched since it was read), not numeric equality. */
#ifndef SFD_BITS_EQUAL_H
#define SFD_BITS_EQUAL_H

#include <stdint.h>
#include <string.h>

static inline int sfd_bits_equal(const double *a, const double *b, int n) {
    uint64_t diff = 0;
    for (int i = 0; i < n; ++i) {
        uint64_t x = 0;
        uint64_t y = 0;
        memcpy(&x, a + i, sizeof x);
        memcpy(&y, b + i, sizeof y);
        diff |= x ^ y;
    }
    return diff == 0;
}

#endif /* SFD_BITS_EQUAL_H */
