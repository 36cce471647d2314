// SPDX-License-Identifier: MIT
// Small dense linear algebra on caller-provided row-major arrays of fixed capacity (stride K) and
// size n <= K: Cholesky factorization, triangular solves, SPD inverse, and the 2x2 symmetric
// pseudo-inverse. Loops are bounded by n <= K. Used where the sizes change per window (L, n at
// run time) and a fixed-size Eigen type would not fit. Also the core's one 2x2 determinant,
// adjugate inverse and inverse quadratic form (the innovation covariances of one observation).
//
// The size n is an `int`, or a compile-time `Dim<D>` (std::integral_constant): then every loop
// has a constant trip count and the compiler unrolls the small ones. Both give bit-identical
// results: the operations and their order are the same (no reassociation, -ffp-contract=off).
#ifndef SFD_SMALL_LINALG_HPP
#define SFD_SMALL_LINALG_HPP

#include <type_traits>

#include "core_private.hpp"

namespace sfd {
namespace la {

/// A matrix size known at compile time; converts to int wherever a size is used.
template <int D>
using Dim = std::integral_constant<int, D>;

/// L L^T = A for symmetric positive definite A (lower triangle read; L may alias A, then the
/// factorization is in place). Fails (false) when a pivot is not positive and finite, or is below
/// rel_tol times the largest diagonal entry of A. The strict upper triangle of L is set to zero.
template <std::size_t K, typename N>
bool cholesky(const double (*A)[K], N n, double (*L)[K], double rel_tol = 1e-13) {
    double max_diag = 0.0;
    for (int i = 0; i < n; ++i) max_diag = std::fmax(max_diag, std::fabs(A[i][i]));
    if (!(max_diag > 0.0) || !std::isfinite(max_diag)) return false;
    for (int j = 0; j < n; ++j) {
        double s = A[j][j];
        for (int k = 0; k < j; ++k) s -= L[j][k] * L[j][k];
        if (!(s > rel_tol * max_diag) || !std::isfinite(s)) return false;
        const double ljj = std::sqrt(s);
        L[j][j] = ljj;
        for (int i = j + 1; i < n; ++i) {
            double t = A[i][j];
            for (int k = 0; k < j; ++k) t -= L[i][k] * L[j][k];
            L[i][j] = t / ljj;
        }
    }
    for (int i = 0; i < n; ++i) {
        for (int j = i + 1; j < n; ++j) L[i][j] = 0.0;
    }
    return true;
}

/// x = L^{-1} b (forward substitution); x may alias b.
template <std::size_t K, typename N>
void forward_solve(const double (*L)[K], N n, const double *b, double *x) {
    for (int i = 0; i < n; ++i) {
        double s = b[i];
        for (int k = 0; k < i; ++k) s -= L[i][k] * x[k];
        x[i] = s / L[i][i];
    }
}

/// x = L^{-T} b (back substitution); x may alias b.
template <std::size_t K, typename N>
void backward_solve_transposed(const double (*L)[K], N n, const double *b, double *x) {
    for (int i = n - 1; i >= 0; --i) {
        double s = b[i];
        for (int k = i + 1; k < n; ++k) s -= L[k][i] * x[k];
        x[i] = s / L[i][i];
    }
}

/// x = A^{-1} b with A = L L^T.
template <std::size_t K, typename N>
void chol_solve(const double (*L)[K], N n, const double *b, double *x) {
    forward_solve(L, n, b, x);
    backward_solve_transposed(L, n, x, x);
}

/// Ainv = A^{-1} with A = L L^T (symmetric result).
template <std::size_t K, typename N>
void chol_inverse(const double (*L)[K], N n, double (*Ainv)[K]) {
    double col[K];
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) col[i] = (i == j) ? 1.0 : 0.0;
        chol_solve(L, n, col, col);
        for (int i = 0; i < n; ++i) Ainv[i][j] = col[i];
    }
    for (int i = 0; i < n; ++i) {
        for (int j = 0; j < i; ++j) {
            const double m = 0.5 * (Ainv[i][j] + Ainv[j][i]);
            Ainv[i][j] = m;
            Ainv[j][i] = m;
        }
    }
}

/// Quadratic form g^T G^+ g for a symmetric positive semi-definite 2x2 G, with its rank
/// (eigenvalues below rel_tol times the largest count as zero). Closed-form eigen-decomposition.
inline double pinv_quadratic_2x2(const double G[2][2], const double g[2], int *rank,
                                 double rel_tol = 1e-10) {
    const double a = G[0][0];
    const double b = 0.5 * (G[0][1] + G[1][0]);
    const double c = G[1][1];
    const double mean = 0.5 * (a + c);
    const double rad = std::sqrt(0.25 * (a - c) * (a - c) + b * b);
    const double l1 = mean + rad;  // l1 >= l2
    const double l2 = mean - rad;
    if (!(l1 > 0.0) || !std::isfinite(l1)) {
        *rank = 0;
        return 0.0;
    }
    // Unit eigenvector of l1: (b, l1 - a) or (l1 - c, b), whichever is better conditioned.
    double v1x = b;
    double v1y = l1 - a;
    const double alt_x = l1 - c;
    const double alt_y = b;
    if (alt_x * alt_x + alt_y * alt_y > v1x * v1x + v1y * v1y) {
        v1x = alt_x;
        v1y = alt_y;
    }
    double nv = std::sqrt(v1x * v1x + v1y * v1y);
    if (!(nv > 0.0)) {  // G is a multiple of I
        v1x = 1.0;
        v1y = 0.0;
        nv = 1.0;
    }
    v1x /= nv;
    v1y /= nv;
    const double p1 = v1x * g[0] + v1y * g[1];
    const double p2 = -v1y * g[0] + v1x * g[1];
    double q = p1 * p1 / l1;
    *rank = 1;
    if (l2 > rel_tol * l1) {
        q += p2 * p2 / l2;
        *rank = 2;
    }
    return q;
}

/// Determinant of [a00 a01; a10 a11]: a00 a11 - a01 a10 (bit-identical to Eigen's 2x2
/// determinant(), whose products are the same).
inline double det_2x2(double a00, double a01, double a10, double a11) {
    return a00 * a11 - a01 * a10;
}

/// Inverse of [a00 a01; a10 a11] by its adjugate over @p det, its determinant (det_2x2()); the
/// caller has checked that det is usable.
inline Mat2 inverse_2x2(double a00, double a01, double a10, double a11, double det) {
    Mat2 inv;
    inv << a11 / det, -a01 / det, -a10 / det, a00 / det;
    return inv;
}

/// *q = (x, y) A^-1 (x, y)^T for a symmetric 2x2 A = [a00 a01; a10 a11] by its adjugate,
/// (a11 x^2 - 2 a01 x y + a00 y^2) / det; false (q untouched) when det (det_2x2()) or a00 is not
/// positive (A not positive definite).
inline bool inv_quadratic_2x2(double a00, double a01, double a10, double a11, double x, double y,
                              double *q) {
    const double det = det_2x2(a00, a01, a10, a11);
    if (!(det > 0.0) || !(a00 > 0.0)) return false;
    *q = (a11 * x * x - 2.0 * a01 * x * y + a00 * y * y) / det;
    return true;
}

}  // namespace la
}  // namespace sfd

#endif  // SFD_SMALL_LINALG_HPP
