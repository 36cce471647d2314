/* SPDX-License-Identifier: MIT */
/**
 * @file sfd_prng.h
 * @brief Seeded pseudo-random numbers: xoshiro256** (Blackman & Vigna 2018) seeded through
 *        splitmix64, uniform and Gaussian draws. The sequence for a seed is identical on every
 *        platform: integer arithmetic for the generator, and for the Gaussian draw only IEEE
 *        +, -, *, / and sqrt with a logarithm of sfd's own (no libm call whose last bit may
 *        differ between C libraries), compiled with -ffp-contract=off.
 *
 * State is caller-owned; one generator per thread. No global state.
 */
#ifndef SFD_PRNG_H
#define SFD_PRNG_H

#include <stdint.h>

#include "sfd_status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    uint64_t s[4]; /**< xoshiro256** state (never all zero) */
} sfd_prng_t;

/** @brief Seeds the generator: s[i] = successive splitmix64 outputs of @p seed (any value).
 *  @return SFD_OK; SFD_ERR_INVAL for a null pointer. */
sfd_status_t sfd_prng_seed(sfd_prng_t *rng, uint64_t seed);

/** @brief Next 64 random bits. @p rng must be seeded (it is invalid to pass an unseeded one). */
uint64_t sfd_prng_next_u64(sfd_prng_t *rng);

/** @brief Uniform double in [0, 1) with 53 random bits. */
double sfd_prng_uniform(sfd_prng_t *rng);

/** @brief Uniform integer in [0, n) for n >= 1 (0 for n = 0), without modulo bias: rejection of
 *         the top partial range, at most 64 tries (probability of reaching the cap < 2^-64 for
 *         any n), then the modulo value. */
uint32_t sfd_prng_uniform_index(sfd_prng_t *rng, uint32_t n);

/** @brief Standard normal draw by Marsaglia's polar method, at most 64 rejection rounds
 *         (probability of the cap < 1e-42; the capped draw returns 0). */
double sfd_prng_gaussian(sfd_prng_t *rng);

#ifdef __cplusplus
}
#endif

#endif /* SFD_PRNG_H */
