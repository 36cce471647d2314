/* SPDX-License-Identifier: MIT */
/* Smallest use of the installed core from C: the library's version against the headers',
 * parameters, the chi-square threshold, the seeded PRNG, and the eq. (27) hypothesis count.
 * Prints them and exits 0 when every call succeeded. */
#include <stdio.h>

#include <sfd/sfd.h>

int main(void) {
    if (sfd_version() != SFD_VERSION) { /* a library that is not the headers' */
        fprintf(stderr, "sfd: library %u.%u, headers %d.%d\n", (unsigned)(sfd_version() >> 16),
                (unsigned)(sfd_version() & 0xFFFFu), SFD_VERSION_MAJOR, SFD_VERSION_MINOR);
        return 1;
    }
    sfd_params_t p;
    if (sfd_params_default(&p) != SFD_OK || sfd_params_validate(&p) != SFD_OK) return 1;
    double thr = 0.0;
    if (sfd_chi2_quantile_upper(p.false_alarm_rate, 2, &thr) != SFD_OK) return 1;
    sfd_prng_t rng;
    if (sfd_prng_seed(&rng, p.seed) != SFD_OK) return 1;
    const int32_t n = sfd_ransac_hypothesis_count(p.ransac_confidence, 0.7, 1, p.max_hypotheses);
    printf("sfd %d.%d: chi2_2(0.99) = %.6f, first draw %.6f, eq. (27) at 70%% inliers: %d, %s\n",
           SFD_VERSION_MAJOR, SFD_VERSION_MINOR, thr, sfd_prng_uniform(&rng), (int)n,
           sfd_status_str(SFD_OK));
    return (thr > 9.2 && thr < 9.22 && n == 4) ? 0 : 1;
}
