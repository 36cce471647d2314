/* SPDX-License-Identifier: MIT */
/* Float storage: the value a double takes once stored as float and read back. */
#ifndef SFD_FLOAT_ROUND_H
#define SFD_FLOAT_ROUND_H

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

/* (double)(float)x, computed so that the compiler cannot drop the rounding. GCC 12.2 (Debian's
 * gcc 12.2.0-14) at -O2 and -O3 value-numbers an SLP-vectorized pair of double -> float ->
 * double conversions as the identity: `y[0] = (double)(float)x[0]; y[1] = (double)(float)x[1];`
 * copies x unrounded (found 2026-11-26; reproduced in tests/unit/test_float_round.c). A check
 * "still valid once stored as float" written the plain way would then test the unrounded
 * values. The float's bits pass through an integer register behind an empty asm statement,
 * which no optimizer sees through; elsewhere (no GNU asm) the plain conversion is used. */
#ifdef __cplusplus
#define SFD_FLOAT_ROUND_CAST(type, value) static_cast<type>(value)
#else
#define SFD_FLOAT_ROUND_CAST(type, value) ((type)(value))
#endif
static inline double sfd_float_round_trip(double x) {
    float f = SFD_FLOAT_ROUND_CAST(float, x);
    uint32_t u;
    memcpy(&u, &f, sizeof u);
#if defined(__GNUC__)
    __asm__("" : "+r"(u));
#endif
    memcpy(&f, &u, sizeof f);
    return SFD_FLOAT_ROUND_CAST(double, f);
}

/* 1 when each of the @p n doubles is finite and within float's range (float storage can hold
 * it), else 0 (NaN included). */
static inline int sfd_fits_float(const double *v, int n) {
    for (int i = 0; i < n; ++i) {
        if (!(fabs(v[i]) <= FLT_MAX)) return 0;
    }
    return 1;
}

#endif /* SFD_FLOAT_ROUND_H */
