/* SPDX-License-Identifier: MIT */
/**
 * @file sfd_ransac.h
 * @brief Pieces shared by the RANSAC-type association methods (OPRF, 1-point RANSAC,
 *        fundamental-matrix RANSAC): the adaptive hypothesis count of Kilic 2014 eq. (27).
 */
#ifndef SFD_RANSAC_H
#define SFD_RANSAC_H
#include <stdint.h>
#include "sfd_status.h"
#ifdef __cplusplus
extern "C" {
#endif

/**
 * @brief Number of hypotheses needed so that, with probability @p confidence, at least one
 *        sample of @p sample_size matches is free of outliers: Kilic 2014 eq. (27),
 *        N = log(1 - p) / log(1 - (1 - eps)^m), with the inlier ratio 1 - eps given.
 *
 * Rounded up, then clamped to [1, @p budget]. Edge cases, where eq. (27) has no finite value:
 * inlier_ratio >= 1 gives 1 (every sample is clean); inlier_ratio <= 0 or a non-finite
 * argument gives @p budget (no sample can be known clean); (1 - eps)^m below the smallest
 * double gives @p budget.
 *
 * @param confidence   p in (0, 1); outside it the budget is returned.
 * @param inlier_ratio 1 - eps, the inlier fraction of the best hypothesis so far.
 * @param sample_size  m in [1, 64] (else the budget) matches per hypothesis (1 for OPRF and 1-point
 * RANSAC, 8 for the 8-point fundamental matrix).
 * @param budget       the configured ceiling (>= 1; values below 1 are treated as 1).
 * @return N in [1, budget].
 */
int32_t sfd_ransac_hypothesis_count(double confidence, double inlier_ratio, int32_t sample_size,
                                    int32_t budget);

#ifdef __cplusplus
}
#endif
#endif /* SFD_RANSAC_H */
