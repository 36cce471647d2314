/* SPDX-License-Identifier: MIT */
/* Small helpers of the synthetic feeds (drivers/sim): row-major 3x3 product, in place allowed. */
#ifndef SFD_SIM_MATH_H
#define SFD_SIM_MATH_H

#include <string.h>

/* C = A B (3x3, row-major); C may alias A or B. */
static inline void sfd_sim_mat3_mul(const double *A, const double *B, double *C) {
    double T[9];
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
            double s = 0;
            for (int k = 0; k < 3; ++k) s += A[3 * r + k] * B[3 * k + c];
            T[3 * r + c] = s;
        }
    }
    memcpy(C, T, sizeof T);
}

#endif /* SFD_SIM_MATH_H */
