/* SPDX-License-Identifier: MIT */
/**
 * @file sfd_chi2.h
 * @brief Chi-square distribution: CDF, upper tail and quantile of the central distribution for
 *        integer dof in [1, SFD_CHI2_MAX_DOF], the non-central CDF (for tests and tools), and a
 *        threshold table computed once at initialization (never per frame).
 *
 * All functions are pure, reentrant, heap-free and loop-bounded. They use only +, -, *, /,
 * sqrt, exp and log (no lgamma: newlib's sets the global `signgam`).
 */
#ifndef SFD_CHI2_H
#define SFD_CHI2_H

#include "sfd_config.h"
#include "sfd_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/**
 * @brief P(X <= x) and P(X > x) for X ~ chi2(dof): the regularized incomplete gamma functions
 *        P(dof/2, x/2) and Q(dof/2, x/2). Whichever tail is small in the region is computed
 *        directly by its own expansion (series for x/2 < dof/2 + 1, continued fraction beyond),
 *        never as 1 - the other, so a tail such as Q(200; 2) = e^-100 keeps full relative
 *        precision; the large one (>= 0.08) is its complement. Relative error < 1e-12 (~1e-15
 *        for tails above 1e-10, a few 1e-13 for tails near 1e-250).
 * @param x      Value (>= 0; x = 0 gives cdf 0).
 * @param dof    Degrees of freedom, 1 <= dof <= SFD_CHI2_MAX_DOF.
 * @param cdf    Out (nullable): lower tail.
 * @param upper  Out (nullable): upper tail (survival function).
 * @return SFD_OK; SFD_ERR_INVAL for dof out of range or x negative/non-finite (outputs untouched);
 *         SFD_ERR_NUMERIC if a bounded expansion did not converge (not reachable in range).
 */
sfd_status_t sfd_chi2_cdf(double x, int dof, double *cdf, double *upper);

/**
 * @brief Quantile: the x with P(X > x) = alpha for X ~ chi2(dof) (the test threshold at false-alarm
 *        rate alpha; for the lower-tail quantile p use alpha = 1 - p). Relative accuracy ~1e-12.
 * @param alpha  Upper-tail probability, 1e-300 < alpha < 1.
 * @param dof    1 <= dof <= SFD_CHI2_MAX_DOF.
 * @param x      Out: the quantile.
 * @return SFD_OK; SFD_ERR_INVAL for arguments out of range; SFD_ERR_NUMERIC if the bounded
 *         solver did not reach the accuracy (not observed over the supported range).
 */
sfd_status_t sfd_chi2_quantile_upper(double alpha, int dof, double *x);

/**
 * @brief CDF of the non-central chi-square, P(X <= x) for X ~ chi2'(dof, lambda), as the Poisson
 *        mixture sum_j Pois(j; lambda/2) P(X_{dof+2j} <= x). Used to predict detection
 *        probability; bounded to 2048 mixture terms (enough for lambda <= 1000 to ~1e-12).
 * @param dof     1 <= dof <= SFD_CHI2_MAX_DOF.
 * @param lambda  Non-centrality, 0 <= lambda <= 1000.
 * @return SFD_OK; SFD_ERR_INVAL for arguments out of range (x negative or non-finite, null
 *         @p cdf included; output untouched); SFD_ERR_NUMERIC as for sfd_chi2_cdf().
 */
sfd_status_t sfd_ncchi2_cdf(double x, int dof, double lambda, double *cdf);

/** Thresholds for one false-alarm rate at every dof, filled once by sfd_chi2_table_init(). */
typedef struct {
    double alpha;                           /**< design false-alarm rate */
    double threshold[SFD_CHI2_MAX_DOF + 1]; /**< threshold[k] = quantile at dof k; [0] = 0 */
} sfd_chi2_table_t;

/**
 * @brief Fills @p table with the upper-alpha quantiles for dof 1..SFD_CHI2_MAX_DOF.
 *        Call at initialization; costs about SFD_CHI2_MAX_DOF quantile solves.
 * @return SFD_OK; SFD_ERR_INVAL for a null table or alpha outside the quantile's domain
 *         (1e-300, 1) (table untouched); a solver failure propagates its status and leaves the
 *         table marked unusable (alpha = 0).
 */
sfd_status_t sfd_chi2_table_init(sfd_chi2_table_t *table, double alpha);

#ifdef __cplusplus
}
#endif

#endif /* SFD_CHI2_H */
