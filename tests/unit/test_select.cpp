/* SPDX-License-Identifier: MIT */
/* unit.select: select_kth and median_in_place (core/src/core_private.hpp), the order statistics
 * behind OPRF's noise scale and the parity detector's pixel noise scale. Checked against a full
 * sort on random and adversarial arrays. */
#include <algorithm>

#include "core_private.hpp" /* before cmocka.h, whose fail() macro C++ headers would meet */
#include "sfd/sfd_prng.h"

extern "C" {
#include "sfd_test.h"
}

using sfd::median_in_place;
using sfd::select_kth;

namespace {

constexpr int kMaxN = 300;

/* The array shapes that break naive partitions: random (few or many distinct values), sorted,
 * reversed, all equal, organ pipe, alternating. */
void fill(int shape, int n, sfd_prng_t *rng, float *v) {
    for (int i = 0; i < n; ++i) {
        switch (shape) {
            case 0:
                v[i] = static_cast<float>(sfd_prng_gaussian(rng));
                break;
            case 1:
                v[i] = static_cast<float>(sfd_prng_uniform_index(rng, 4));
                break;
            case 2:
                v[i] = static_cast<float>(i);
                break;
            case 3:
                v[i] = static_cast<float>(n - i);
                break;
            case 4:
                v[i] = 7.0F;
                break;
            case 5:
                v[i] = static_cast<float>(i < n / 2 ? i : n - i);
                break;
            default:
                v[i] = static_cast<float>((i % 2 == 0) ? i : -i);
                break;
        }
    }
}

}  // namespace

/* GIVEN arrays of 1..300 values of seven shapes WHEN the k-th smallest is selected, for every k
 * THEN it is the sorted array's k-th value, and the array is partitioned around it (nothing
 * larger before k, nothing smaller after). */
static void select_kth_is_the_sorted_kth_value_and_partitions(void **state) {
    (void)state;
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 28);
    float v[kMaxN];
    float ref[kMaxN];
    long checked = 0;
    for (int shape = 0; shape < 7; ++shape) {
        for (int n = 1; n <= kMaxN; n += (n < 40 ? 1 : 37)) {
            for (int k = 0; k < n; ++k) {
                fill(shape, n, &rng, v);
                std::copy(v, v + n, ref);
                std::sort(ref, ref + n);
                const float got = select_kth(v, n, k);
                assert_true(got == ref[k]);
                assert_true(v[k] == ref[k]);
                for (int i = 0; i < k; ++i) assert_true(v[i] <= v[k]);
                for (int i = k + 1; i < n; ++i) assert_true(v[i] >= v[k]);
                std::sort(v, v + n); /* a permutation of the input */
                for (int i = 0; i < n; ++i) assert_true(v[i] == ref[i]);
                ++checked;
            }
        }
    }
    assert_true(checked > 10000);
}

/* GIVEN arrays of 1..300 values WHEN their median is taken THEN it is the sorted array's middle
 * value (odd n) or the mean of its two middle values (even n), computed in double. */
static void median_is_the_middle_of_the_sorted_array(void **state) {
    (void)state;
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 29);
    float v[kMaxN];
    float ref[kMaxN];
    for (int shape = 0; shape < 7; ++shape) {
        for (int n = 1; n <= kMaxN; ++n) {
            fill(shape, n, &rng, v);
            std::copy(v, v + n, ref);
            std::sort(ref, ref + n);
            const double want =
                (n % 2 == 1)
                    ? static_cast<double>(ref[n / 2])
                    : 0.5 * (static_cast<double>(ref[n / 2 - 1]) + static_cast<double>(ref[n / 2]));
            assert_true(median_in_place(v, n) == want);
        }
    }
}

/* GIVEN arrays holding NaNs (outside the stated domain) WHEN selected THEN the call returns an
 * entry of the array and leaves a permutation of it: no endless loop, no access outside. */
static void a_nan_neither_hangs_nor_escapes_the_array(void **state) {
    (void)state;
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 30);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    float v[kMaxN];
    for (int n = 1; n <= 64; ++n) {
        for (int k = 0; k < n; ++k) {
            for (int i = 0; i < n; ++i) {
                v[i] = (sfd_prng_uniform_index(&rng, 3) == 0)
                           ? nan
                           : static_cast<float>(sfd_prng_gaussian(&rng));
            }
            int nans = 0;
            for (int i = 0; i < n; ++i) nans += std::isnan(v[i]) ? 1 : 0;
            const float got = select_kth(v, n, k);
            bool found = false;
            int nans_after = 0;
            for (int i = 0; i < n; ++i) {
                found = found || (v[i] == got) || (std::isnan(v[i]) && std::isnan(got));
                nans_after += std::isnan(v[i]) ? 1 : 0;
            }
            assert_true(found);
            assert_int_equal(nans, nans_after);
        }
    }
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(select_kth_is_the_sorted_kth_value_and_partitions),
        cmocka_unit_test(median_is_the_middle_of_the_sorted_array),
        cmocka_unit_test(a_nan_neither_hangs_nor_escapes_the_array),
    };
    return cmocka_run_group_tests(tests, nullptr, nullptr);
}
