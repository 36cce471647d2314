// SPDX-License-Identifier: MIT
// xoshiro256** with splitmix64 seeding (Blackman & Vigna, "Scrambled linear pseudorandom number
// generators", ACM TOMS 2021), and platform-independent uniform and Gaussian draws.
#include "core_private.hpp"
#include "sfd/sfd_prng.h"

namespace sfd {
namespace {

inline uint64_t rotl(uint64_t x, int k) {
    return (x << k) | (x >> (64 - k));
}

inline uint64_t splitmix64(uint64_t *x) {
    uint64_t z = (*x += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

// Natural logarithm from IEEE arithmetic only, so the Gaussian stream does not depend on the C
// library's log(): x = m 2^e with m in [sqrt(1/2), sqrt(2)) (exact), then
// log m = 2 atanh(s), s = (m - 1)/(m + 1), |s| <= 0.1716, summed to s^29 (next term < 1e-23
// relative). Valid for finite x > 0; the callers pass x in (0, 1].
double portable_log(double x) {
    int e = 0;
    double m = std::frexp(x, &e);  // x = m 2^e, m in [0.5, 1): exact
    if (m < 0.70710678118654752440) {
        m *= 2.0;
        e -= 1;
    }
    const double s = (m - 1.0) / (m + 1.0);
    const double s2 = s * s;
    double term = s;
    double sum = 0.0;
    for (int k = 0; k < 15; ++k) {
        sum += term / static_cast<double>(2 * k + 1);
        term *= s2;
    }
    return 2.0 * sum + static_cast<double>(e) * 0.69314718055994530942;
}

}  // namespace
}  // namespace sfd

using namespace sfd;

extern "C" sfd_status_t sfd_prng_seed(sfd_prng_t *rng, uint64_t seed) {
    if (rng == nullptr) return SFD_ERR_INVAL;
    uint64_t x = seed;
    for (int i = 0; i < 4; ++i) rng->s[i] = splitmix64(&x);
    // splitmix64 is a bijection of its counter, so four successive outputs are never all zero.
    return SFD_OK;
}

extern "C" uint64_t sfd_prng_next_u64(sfd_prng_t *rng) {
    uint64_t *s = rng->s;
    const uint64_t result = rotl(s[1] * 5, 7) * 9;
    const uint64_t t = s[1] << 17;
    s[2] ^= s[0];
    s[3] ^= s[1];
    s[1] ^= s[2];
    s[0] ^= s[3];
    s[2] ^= t;
    s[3] = rotl(s[3], 45);
    return result;
}

extern "C" double sfd_prng_uniform(sfd_prng_t *rng) {
    return static_cast<double>(sfd_prng_next_u64(rng) >> 11) * 0x1.0p-53;
}

extern "C" uint32_t sfd_prng_uniform_index(sfd_prng_t *rng, uint32_t n) {
    if (n == 0U) return 0U;
    // Accept x < limit = the largest multiple of n not above 2^32; reject the partial top range.
    const uint64_t range = 0x100000000ULL;
    const uint64_t limit = range - (range % n);
    uint32_t x = 0U;
    for (int tries = 0; tries < 64; ++tries) {
        x = static_cast<uint32_t>(sfd_prng_next_u64(rng) >> 32);
        if (static_cast<uint64_t>(x) < limit) return x % n;
    }
    return x % n;
}

// Marsaglia's polar method: (u, v) uniform in the unit disc, s = u^2 + v^2, then
// u sqrt(-2 ln s / s) is standard normal. The second normal (v ...) is not kept, so the
// generator stays the whole state.
extern "C" double sfd_prng_gaussian(sfd_prng_t *rng) {
    for (int round = 0; round < 64; ++round) {
        const double u = 2.0 * sfd_prng_uniform(rng) - 1.0;
        const double v = 2.0 * sfd_prng_uniform(rng) - 1.0;
        const double s = u * u + v * v;
        if (s > 0.0 && s < 1.0) {
            return u * std::sqrt(-2.0 * portable_log(s) / s);
        }
    }
    return 0.0;
}
