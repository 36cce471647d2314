/* SPDX-License-Identifier: MIT */
/* unit.prng: xoshiro256** stream pinned against an independent implementation of the published
 * algorithm; draws' ranges and moments; identical on every platform (this test also runs under
 * qemu-aarch64). */
#include "sfd_test.h"

#include <string.h>

#include <sfd/sfd_prng.h>

/* GIVEN seed 0 and 42 WHEN drawing 64-bit words THEN the sequence equals the reference computed
 * by an independent Python implementation of splitmix64 seeding + xoshiro256**. */
static void prng_seeded_sequence_matches_reference(void **state) {
    (void)state;
    SFD_REQ("SFD-RNG-001");
    static const uint64_t ref0[6] = {0x99ec5f36cb75f2b4ULL, 0xbf6e1f784956452aULL,
                                     0x1a5f849d4933e6e0ULL, 0x6aa594f1262d2d2cULL,
                                     0xbba5ad4a1f842e59ULL, 0xffef8375d9ebcacaULL};
    static const uint64_t ref42[6] = {0x15780b2e0c2ec716ULL, 0x6104d9866d113a7eULL,
                                      0xae17533239e499a1ULL, 0xecb8ad4703b360a1ULL,
                                      0xfde6dc7fe2ec5e64ULL, 0xc50da53101795238ULL};
    sfd_prng_t rng;
    assert_status(sfd_prng_seed(&rng, 0), SFD_OK);
    for (int i = 0; i < 6; ++i) assert_true(sfd_prng_next_u64(&rng) == ref0[i]);
    assert_status(sfd_prng_seed(&rng, 42), SFD_OK);
    for (int i = 0; i < 6; ++i) assert_true(sfd_prng_next_u64(&rng) == ref42[i]);
}

/* GIVEN seed 42 WHEN drawing uniforms THEN they are the top 53 bits of the stream, exactly. */
static void prng_uniform_is_top53_bits_exactly(void **state) {
    (void)state;
    SFD_REQ("SFD-RNG-001");
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 42);
    assert_true(sfd_prng_uniform(&rng) == 0.08386297105988216);
    assert_true(sfd_prng_uniform(&rng) == 0.3789802506626686);
    assert_true(sfd_prng_uniform(&rng) == 0.6800434110281394);
}

/* GIVEN seed 7 WHEN drawing Gaussians THEN they equal the polar method computed independently
 * (Python, libm log) to 1 ulp-level tolerance, and the bit pattern pinned below exactly: the
 * pin is what makes a platform difference visible (the same test runs on aarch64 under qemu). */
static void prng_gaussian_sequence_pinned_and_matches_reference(void **state) {
    (void)state;
    SFD_REQ("SFD-RNG-002");
    static const double ref[5] = {0.9643618527255184, -0.3039301238656567, 0.30479435832638674,
                                  -1.7010190714940672, -1.6701700371775816};
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 7);
    double got[5];
    for (int i = 0; i < 5; ++i) {
        got[i] = sfd_prng_gaussian(&rng);
        assert_near(got[i], ref[i], 4e-16 * (1.0 + fabs(ref[i])));
    }
    /* Exact pin of this implementation (portable log): identical on every target. */
    sfd_prng_seed(&rng, 7);
    uint64_t h = 1469598103934665603ULL;
    for (int i = 0; i < 1000; ++i) {
        double g = sfd_prng_gaussian(&rng);
        uint64_t bits;
        memcpy(&bits, &g, sizeof bits);
        h = (h ^ bits) * 1099511628211ULL;
    }
    print_message("gaussian stream hash (seed 7, 1000 draws): 0x%016llx\n", (unsigned long long)h);
    assert_true(h == 0xf852a3a5564150dbULL);
}

/* GIVEN 10^6 draws WHEN computing moments THEN uniform mean 1/2 and variance 1/12, Gaussian mean 0
 * and variance 1, within 5 standard errors (a false failure has probability < 1e-6). */
static void prng_draws_have_expected_moments(void **state) {
    (void)state;
    SFD_REQ("SFD-RNG-003");
    enum { N = 1000000 };
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 12345);
    double su = 0, suu = 0, sg = 0, sgg = 0;
    for (int i = 0; i < N; ++i) {
        double u = sfd_prng_uniform(&rng);
        assert_true(u >= 0.0 && u < 1.0);
        su += u;
        suu += u * u;
        double g = sfd_prng_gaussian(&rng);
        sg += g;
        sgg += g * g;
    }
    double mu = su / N, vu = suu / N - mu * mu;
    double mg = sg / N, vg = sgg / N - mg * mg;
    assert_near(mu, 0.5, 5.0 * sqrt(1.0 / 12.0 / N));
    assert_near(vu, 1.0 / 12.0, 5.0 * sqrt(1.0 / 180.0 / N));
    assert_near(mg, 0.0, 5.0 / sqrt((double)N));
    assert_near(vg, 1.0, 5.0 * sqrt(2.0 / N));
}

/* GIVEN n in {1, 3, 7, 1000} WHEN drawing indices THEN all are in [0, n) and every value of a small
 * range appears with frequency 1/n within 5 standard errors; n = 0 returns 0. */
static void prng_uniform_index_in_range_and_unbiased(void **state) {
    (void)state;
    SFD_REQ("SFD-RNG-003");
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 99);
    const uint32_t ns[4] = {1, 3, 7, 1000};
    for (int k = 0; k < 4; ++k) {
        for (int i = 0; i < 10000; ++i) assert_true(sfd_prng_uniform_index(&rng, ns[k]) < ns[k]);
    }
    enum { N = 700000 };
    unsigned count[7] = {0};
    for (int i = 0; i < N; ++i) count[sfd_prng_uniform_index(&rng, 7)]++;
    for (int j = 0; j < 7; ++j) {
        double p = 1.0 / 7.0;
        assert_near(count[j] / (double)N, p, 5.0 * sqrt(p * (1 - p) / N));
    }
    assert_int_equal(sfd_prng_uniform_index(&rng, 0), 0);
}

/* GIVEN two generators with the same seed WHEN drawn in lockstep THEN identical; a null generator
 * is rejected at seeding. */
static void prng_same_seed_same_stream_null_rejected(void **state) {
    (void)state;
    SFD_REQ("SFD-RNG-001");
    sfd_prng_t a, b;
    sfd_prng_seed(&a, 2026);
    sfd_prng_seed(&b, 2026);
    for (int i = 0; i < 1000; ++i) assert_true(sfd_prng_next_u64(&a) == sfd_prng_next_u64(&b));
    assert_status(sfd_prng_seed(NULL, 1), SFD_ERR_INVAL);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(prng_seeded_sequence_matches_reference),
        cmocka_unit_test(prng_uniform_is_top53_bits_exactly),
        cmocka_unit_test(prng_gaussian_sequence_pinned_and_matches_reference),
        cmocka_unit_test(prng_draws_have_expected_moments),
        cmocka_unit_test(prng_uniform_index_in_range_and_unbiased),
        cmocka_unit_test(prng_same_seed_same_stream_null_rejected),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
