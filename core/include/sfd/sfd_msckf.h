/* SPDX-License-Identifier: MIT */
/**
 * @file sfd_msckf.h
 * @brief The measurement side of a sliding-window (multi-state constraint) Kalman filter
 *        (Mourikis & Roumeliotis 2007; core/docs/msckf.md): one track's residual projected onto
 *        the left null space of its landmark Jacobian, its chi-square gate, the compression of
 *        every accepted track into at most n rows (normal equations, factored once), and the
 *        Kalman update from the compressed rows.
 *
 * A track seen in m clones of the window gives the linearized, stacked reprojection residual
 *
 *     r = H_x dx + H_f dp_f + n,   n ~ N(0, R),                                     (1)
 *
 * (2m rows; one more when the wire's depth prior enters as a measurement), with dx the filter's
 * error state (n <= SFD_MSCKF_DIM: IMU state and the window's clones, in the caller's order), dp_f
 * the error of the track's triangulated point and R the pixel noise carried through the camera's
 * distortion Jacobian (block diagonal, not isotropic). With N an orthonormal basis of the left null
 * space of H_f (N^T H_f = 0, rank H_f = 3):
 *
 *     r_o = N^T r = N^T H_x dx + N^T n,   S_o = N^T H_x P H_x^T N + N^T R N,            (2)
 *     gamma = r_o^T S_o^-1 r_o ~ chi2(rows - 3) for a consistent track,                (3)
 *
 * the parity-space test of Tornqvist et al. 2008 (Section III) with the translation known from
 * the filter and Cov(z) from its covariance. Accepted tracks are whitened by N^T R N and folded
 * into the normal equations (Y = sum w w^T, b = sum w r over the whitened rows w); the update
 * factors Y = U^T U once (T = U, q = U^-T b: the least-squares compression into at most n rows)
 * and uses those rows with unit noise:
 *
 *     S = T P T^T + I,  K = P T^T S^-1,  dx = K q,  P <- P - K (P T^T)^T.                    (4)
 *
 * Every array has a fixed capacity (SFD_MSCKF_DIM, SFD_MSCKF_TRACK_ROWS); sizes beyond it are a
 * status code, never a write past an array. No heap, no global state, no recursion; the large
 * scratch matrices of the update live in a caller-owned sfd_msckf_work_t, not on the stack.
 */
#ifndef SFD_MSCKF_H
#define SFD_MSCKF_H
#include <stdint.h>
#include "sfd_config.h"
#include "sfd_status.h"
#ifdef __cplusplus
extern "C" {
#endif

/** Largest error-state dimension: 15 IMU error states and 6 per clone of a full window. */
#define SFD_MSCKF_DIM (15 + 6 * SFD_MAX_WINDOW)
/** Largest number of rows of one track: 2 per clone and two depth priors (first and newest). */
#define SFD_MSCKF_TRACK_ROWS (2 * SFD_MAX_WINDOW + 2)

/** One track's linearized residual (1), then (after sfd_msckf_track_project) its projection (2).
 *  Caller-owned; fill rows, n, Hx, Hf, r and R, rows and columns beyond them are not read. */
typedef struct {
    int32_t rows; /**< measurement rows in use: 4..SFD_MSCKF_TRACK_ROWS before the projection */
    int32_t n;    /**< error-state columns in use, 1..SFD_MSCKF_DIM */
    int32_t projected; /**< 1 once sfd_msckf_track_project() succeeded (rows = rows - 3) */
    double Hx[SFD_MSCKF_TRACK_ROWS][SFD_MSCKF_DIM];       /**< Jacobian of r on dx */
    double Hf[SFD_MSCKF_TRACK_ROWS][3];                   /**< Jacobian of r on the point (m) */
    double r[SFD_MSCKF_TRACK_ROWS];                       /**< residual z - h(x^, p^_f) (px, m) */
    double R[SFD_MSCKF_TRACK_ROWS][SFD_MSCKF_TRACK_ROWS]; /**< noise covariance of r, SPD */
} sfd_msckf_track_t;

/** The accepted tracks of one update, folded into their normal equations (caller-owned). */
typedef struct {
    int32_t n;          /**< error-state dimension */
    int32_t folded;     /**< whitened rows folded in since the reset */
    double residual_ss; /**< sum of the whitened residuals' squares (r^T r over the rows) */
    uint8_t used[SFD_MSCKF_DIM];                 /**< 1: some folded row touches column k */
    double Tq[SFD_MSCKF_DIM][SFD_MSCKF_DIM + 1]; /**< row k: Y's upper triangle (k..n-1), b_k */
} sfd_msckf_stack_t;

/** Scratch of sfd_msckf_update() (caller-owned; no content is kept between calls). S = T P T^T
 *  + I, its factor L and the new P are formed in the stack's rows, which the update consumes. */
typedef struct {
    double B[SFD_MSCKF_DIM][SFD_MSCKF_DIM]; /**< P T^T, then C = P T^T L^-T */
} sfd_msckf_work_t;

/**
 * @brief Projects the track's residual onto the left null space of H_f, eq. (2): Givens rotations
 *        Q^T (applied to Hx, Hf, r and from both sides to R) make H_f upper triangular; the last
 *        rows - 3 rows are N^T H_x, N^T r, N^T R N, moved to the top (rows becomes rows - 3).
 * @return SFD_OK; SFD_ERR_INVAL (null, rows outside 4..SFD_MSCKF_TRACK_ROWS, n outside
 *         1..SFD_MSCKF_DIM, already projected, a non-finite entry; nothing written);
 *         SFD_ERR_NUMERIC when H_f has rank below 3 (no parallax: a pivot below 1e-9 times the
 *         Frobenius norm of H_f); then the rows hold Q^T of the inputs and the track must be
 *         discarded (projected stays 0).
 */
sfd_status_t sfd_msckf_track_project(sfd_msckf_track_t *track);

/**
 * @brief The gate statistic of a projected track, eq. (3): gamma = r_o^T S_o^-1 r_o with
 *        S_o = H_o P H_o^T + R_o, and its degrees of freedom (the projected rows).
 * @param P error-state covariance, row-major with row stride SFD_MSCKF_DIM, n x n, symmetric.
 * @return SFD_OK; SFD_ERR_INVAL (null, not projected, no rows); SFD_ERR_NUMERIC when S_o is not
 *         positive definite or gamma is not finite (*gamma, *dof unchanged).
 */
sfd_status_t sfd_msckf_track_gate(const sfd_msckf_track_t *track, const double *P, double *gamma,
                                  int32_t *dof);

/**
 * @brief Eq. (3) without forming N, from the track's residual covariance with the poses' part
 *        in it, S = H_x P H_x^T + R (rows x rows, SPD; the caller forms it, e.g. from the blocks
 *        of P its rows touch): for any N spanning the left null space of H_f (rank 3),
 *            r^T N (N^T S N)^-1 N^T r = r^T S^-1 r - b^T A^-1 b,  A = H_f^T S^-1 H_f,
 *            b = H_f^T S^-1 r,
 *        the residual of the weighted least-squares fit of the point. With S = L L^T,
 *        w = L^-1 r, G = L^-1 H_f and G^T G = M M^T: gamma = |w|^2 - |M^-1 G^T w|^2, chi2(rows - 3)
 *        for a consistent track; equal to sfd_msckf_track_project() then sfd_msckf_track_gate()
 *        up to rounding (unit.msckf), at a fraction of their work. Reads rows, H_f and r of the
 *        unprojected @p track (Hx and R are not read; nothing is written to it).
 * @param S row stride SFD_MSCKF_TRACK_ROWS, rows x rows, lower triangle read.
 * @return SFD_OK with gamma >= 0 and dof = rows - 3; SFD_ERR_INVAL for null, a projected track
 *         or rows outside 4..SFD_MSCKF_TRACK_ROWS; SFD_ERR_NUMERIC when S is not positive
 *         definite, H_f has rank below 3 (a pivot of A below 1e-14 of its largest diagonal
 *         entry: A is formed from squares, so it cannot resolve the 1e-18 that
 *         sfd_msckf_track_project()'s 1e-9 on H_f's triangular factor would be; a window
 *         filter's tracks are far from either, their triangulation needs parallax or a depth
 *         prior) or an input is not finite (*gamma, *dof unchanged).
 */
sfd_status_t sfd_msckf_track_statistic(const sfd_msckf_track_t *track,
                                       const double (*S)[SFD_MSCKF_TRACK_ROWS], double *gamma,
                                       int32_t *dof);

/** @brief Empties the compression for an n-dimensional error state (1..SFD_MSCKF_DIM). */
sfd_status_t sfd_msckf_stack_reset(sfd_msckf_stack_t *stack, int32_t n);

/**
 * @brief Folds a projected track into the normal equations: whitens its rows by the Cholesky
 *        factor L of R_o (w = L^-1 [H_o | r_o]: unit noise), then Y += w w^T, b += w r over the
 *        columns the track touches.
 * @return SFD_OK; SFD_ERR_INVAL (null, not projected, n differs from the stack's);
 *         SFD_ERR_NUMERIC when R_o is not positive definite (stack unchanged).
 */
sfd_status_t sfd_msckf_stack_fold(sfd_msckf_stack_t *stack, const sfd_msckf_track_t *track);

/**
 * @brief Folds an unprojected track whose rows have unit noise (R exactly the identity: the
 *        caller whitened them) into the normal equations as sfd_msckf_track_project() then
 *        sfd_msckf_stack_fold() would, up to rounding (unit.msckf), without forming N. With Q_1
 *        an orthonormal basis of H_f's range (Householder reflections), N N^T = I - Q_1 Q_1^T,
 *        so the projected rows' information and its right-hand side are
 *            Y += H_x^T H_x - Z^T Z,  b += H_x^T r - Z^T z,  Z = Q_1^T H_x,  z = Q_1^T r,
 *        the Schur complement of the point in the information of (1). Rows of H_x that touch
 *        few columns (a window filter's: one clone's six) keep H_x^T H_x block diagonal, and
 *        Z^T Z has rank 3: a fraction of the rotations of the projection and of the rows - 3
 *        dense outer products of the fold. folded grows by rows - 3.
 * @return SFD_OK; SFD_ERR_INVAL (null, a projected track, rows outside 4..SFD_MSCKF_TRACK_ROWS,
 *         n differs from the stack's, R not exactly the identity, a non-finite entry);
 *         SFD_ERR_NUMERIC when H_f has rank below 3 (sfd_msckf_track_project()'s criterion) or
 *         Q_1^T H_x is not finite (stack unchanged on every error).
 */
sfd_status_t sfd_msckf_stack_fold_unprojected(sfd_msckf_stack_t *stack,
                                              const sfd_msckf_track_t *track);

/**
 * @brief The Kalman update (4): Y = U^T U (Cholesky over the touched columns; a pivot below
 *        1e-12 of its diagonal is an unobserved direction and its row is dropped), T = U,
 *        q = U^-T b, then dx (n values) and P in place (P - K (P T^T)^T, symmetrized). With no
 *        row folded, dx = 0 and P is unchanged. The stack is consumed (U replaces Y in place):
 *        reset it before folding again.
 * @param P row stride SFD_MSCKF_DIM, n x n, symmetric positive semi-definite.
 * @return SFD_OK; SFD_ERR_INVAL (null); SFD_ERR_NUMERIC when S is not positive definite, the
 *         result is not finite or a variance would become negative (P and dx unchanged).
 */
sfd_status_t sfd_msckf_update(sfd_msckf_stack_t *stack, double *P, double *dx,
                              sfd_msckf_work_t *work);

#ifdef __cplusplus
}
#endif
#endif /* SFD_MSCKF_H */
