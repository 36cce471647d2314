/* SPDX-License-Identifier: MIT */
/* Small dense linear algebra of the unit tests, independent of the core's (a reference the core is
 * checked against): X = A^-1 B by Gauss-Jordan elimination with partial pivoting. */
#ifndef SFD_TEST_DENSE_H
#define SFD_TEST_DENSE_H

#include <math.h>
#include <string.h>

/** Largest n (rows of A) and m (columns of B) test_solve_dense takes. */
#define TEST_DENSE_MAX 72

/* X = A^-1 B for an n x n A (row-major, stride n) and an n x m B (stride m); 0 when A is
 * singular or a size is out of range. Scratch is static: one call at a time. */
static int test_solve_dense(int n, int m, const double *A_in, const double *B_in, double *X) {
    static double A[TEST_DENSE_MAX * TEST_DENSE_MAX], B[TEST_DENSE_MAX * TEST_DENSE_MAX];
    if (n < 1 || m < 1 || n > TEST_DENSE_MAX || m > TEST_DENSE_MAX) return 0;
    memcpy(A, A_in, sizeof(double) * (size_t)n * (size_t)n);
    memcpy(B, B_in, sizeof(double) * (size_t)n * (size_t)m);
    for (int c = 0; c < n; ++c) {
        int piv = c;
        for (int r = c + 1; r < n; ++r) {
            if (fabs(A[r * n + c]) > fabs(A[piv * n + c])) piv = r;
        }
        if (fabs(A[piv * n + c]) < 1e-300) return 0;
        for (int k = 0; k < n; ++k) {
            const double t = A[c * n + k];
            A[c * n + k] = A[piv * n + k];
            A[piv * n + k] = t;
        }
        for (int k = 0; k < m; ++k) {
            const double t = B[c * m + k];
            B[c * m + k] = B[piv * m + k];
            B[piv * m + k] = t;
        }
        for (int r = 0; r < n; ++r) {
            if (r == c) continue;
            const double f = A[r * n + c] / A[c * n + c];
            for (int k = 0; k < n; ++k) A[r * n + k] -= f * A[c * n + k];
            for (int k = 0; k < m; ++k) B[r * m + k] -= f * B[c * m + k];
        }
    }
    for (int r = 0; r < n; ++r) {
        for (int k = 0; k < m; ++k) X[r * m + k] = B[r * m + k] / A[r * n + r];
    }
    return 1;
}

#endif /* SFD_TEST_DENSE_H */
