/* SPDX-License-Identifier: MIT */
/* unit.rest: rest detection from the IMU (sfd_rest.h): at rest with the modelled noise the
 * "moving" rate is alpha (binomial interval over 2000 windows) and the gyro mean estimates the
 * bias; vibration-free motion (a gyro oscillation, an acceleration ramp) and free fall are not
 * rest; gaps restart the window; bad input is a status code.
 * unit.rest_euroc (test_rest --euroc DIR): the real EuRoC V1_02 IMU (../shared/data): every window
 * before the take-off (ending before 3.5 s, rotors running on the ground) is rest, no window in
 * flight (ending after 4.5 s) is; the first window's gyro mean matches the ground truth's gyro
 * bias. Exit 77 (skipped) when the data is absent. */
#include "sfd_test.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <sfd/sfd_prng.h>
#include <sfd/sfd_rest.h>

static sfd_rest_t g_rest;

static void at_rest_the_false_alarm_rate_is_alpha_and_the_bias_is_found(void **state) {
    (void)state;
    sfd_rest_params_t p;
    assert_int_equal(sfd_rest_params_default(&p), SFD_OK);
    p.alpha = 0.05;
    assert_int_equal(sfd_rest_init(&g_rest, &p), SFD_OK);
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 21);
    /* Per-sample noise whose block mean has the configured sigma; a bias and a tilted gravity. */
    const double sg = p.gyro_block_sigma_rad_s * sqrt((double)p.block_samples);
    const double sa = p.accel_block_sigma_m_s2 * sqrt((double)p.block_samples);
    const double bias[3] = {0.004, -0.021, 0.077};
    const double f[3] = {9.2, 0.3, -3.3}; /* |f| = 9.78 */
    const int windows = 2000, per_window = p.block_samples * p.window_blocks;
    int moving = 0, bias_off = 0;
    int64_t t = 1000000;
    for (int w = 0; w < windows; ++w) {
        for (int s = 0; s < per_window; ++s) {
            double g[3], a[3];
            for (int k = 0; k < 3; ++k) {
                g[k] = bias[k] + sg * sfd_prng_gaussian(&rng);
                a[k] = f[k] + sa * sfd_prng_gaussian(&rng);
            }
            t += 5000;
            assert_int_equal(sfd_rest_push(&g_rest, t, g, a), SFD_OK);
        }
        sfd_rest_result_t r;
        assert_int_equal(sfd_rest_evaluate(&g_rest, &r), SFD_OK);
        assert_int_equal(r.ready, 1);
        assert_true(r.window_end_us == t &&
                    r.window_start_us == t - (int64_t)(per_window - 1) * 5000);
        moving += r.at_rest == 0;
        /* The window mean of the gyro: sd s_w / sqrt(K) per axis; 4 sd. */
        for (int k = 0; k < 3; ++k) {
            bias_off += fabs(r.gyro_mean_rad_s[k] - bias[k]) >
                        4.0 * p.gyro_block_sigma_rad_s / sqrt((double)p.window_blocks);
        }
    }
    /* Binomial(2000, 0.05): sd 9.7; 99.9 % interval about [69, 133]. */
    assert_true(moving >= 69 && moving <= 133);
    assert_true(bias_off <= 2); /* 6000 axis checks at 4 sd: expected 0.4 */
}

static sfd_rest_result_t run_motion(int kind) {
    sfd_rest_params_t p;
    sfd_rest_params_default(&p);
    sfd_rest_init(&g_rest, &p);
    sfd_prng_t rng;
    sfd_prng_seed(&rng, 22);
    const double sg = 0.5 * p.gyro_block_sigma_rad_s * sqrt((double)p.block_samples);
    const double sa = 0.5 * p.accel_block_sigma_m_s2 * sqrt((double)p.block_samples);
    for (int s = 0; s < p.block_samples * p.window_blocks; ++s) {
        const double ts = 0.005 * s;
        double g[3] = {0.01, 0.0, 0.0}, a[3] = {0.0, 0.0, 9.81};
        if (kind == 0) g[2] += 0.1 * sin(6.283185307179586 * ts); /* 0.1 rad/s at 1 Hz */
        if (kind == 1) a[0] += 2.0 * ts;                          /* a ramp: 2 m/s^3 */
        if (kind == 2) a[2] = 0.0;                                /* free fall */
        for (int k = 0; k < 3; ++k) {
            g[k] += sg * sfd_prng_gaussian(&rng);
            a[k] += sa * sfd_prng_gaussian(&rng);
        }
        sfd_rest_push(&g_rest, 1000000 + 5000 * (int64_t)s, g, a);
    }
    sfd_rest_result_t r;
    sfd_rest_evaluate(&g_rest, &r);
    return r;
}

static void motion_and_free_fall_are_not_rest(void **state) {
    (void)state;
    for (int kind = 0; kind < 3; ++kind) {
        const sfd_rest_result_t r = run_motion(kind);
        assert_int_equal(r.ready, 1);
        assert_int_equal(r.at_rest, 0);
        if (kind < 2) assert_true(r.statistic > 5.0 * r.threshold);
    }
    /* The same run without the motion is rest (the noise alone is well inside). */
    const sfd_rest_result_t r = run_motion(3);
    assert_int_equal(r.at_rest, 1);
}

static void gaps_restart_the_window_and_bad_input_is_refused(void **state) {
    (void)state;
    sfd_rest_params_t p;
    sfd_rest_params_default(&p);
    assert_int_equal(sfd_rest_init(&g_rest, &p), SFD_OK);
    const double g[3] = {0, 0, 0}, a[3] = {0, 0, 9.81};
    int64_t t = 0;
    for (int s = 0; s < p.block_samples * p.window_blocks - 1; ++s) {
        t += 5000;
        assert_int_equal(sfd_rest_push(&g_rest, t, g, a), SFD_OK);
    }
    sfd_rest_result_t r;
    assert_int_equal(sfd_rest_evaluate(&g_rest, &r), SFD_OK);
    assert_int_equal(r.ready, 0); /* one sample short */
    t += p.max_gap_us + 1;        /* a gap: the window starts again */
    assert_int_equal(sfd_rest_push(&g_rest, t, g, a), SFD_OK);
    assert_int_equal(g_rest.restarts, 1);
    assert_int_equal(sfd_rest_evaluate(&g_rest, &r), SFD_OK);
    assert_int_equal(r.ready, 0);
    assert_int_equal(sfd_rest_push(&g_rest, t, g, a), SFD_ERR_ORDER);
    const double bad[3] = {0, NAN, 0};
    assert_int_equal(sfd_rest_push(&g_rest, t + 5000, bad, a), SFD_ERR_INVAL);
    assert_int_equal(sfd_rest_push(&g_rest, INT64_MAX, g, a), SFD_OK); /* no overflow */
    assert_int_equal(sfd_rest_push(NULL, t, g, a), SFD_ERR_INVAL);
    assert_int_equal(sfd_rest_evaluate(NULL, &r), SFD_ERR_INVAL);
    sfd_rest_params_t q = p;
    q.window_blocks = SFD_REST_MAX_BLOCKS + 1;
    assert_int_equal(sfd_rest_init(&g_rest, &q), SFD_ERR_INVAL);
    q = p;
    q.alpha = 0.0;
    assert_int_equal(sfd_rest_init(&g_rest, &q), SFD_ERR_INVAL);
    q = p;
    q.accel_block_sigma_m_s2 = NAN;
    assert_int_equal(sfd_rest_init(&g_rest, &q), SFD_ERR_INVAL);
}

/* ---- real data ---- */

/* One EuRoC CSV row: the integer timestamp (ns) and n numbers after it; 1 when all parse. */
static int parse_row(const char *line, long long *ns, double *v, int n) {
    char *end = NULL;
    errno = 0;
    *ns = strtoll(line, &end, 10);
    if (errno != 0 || end == line) return 0;
    for (int i = 0; i < n; ++i) {
        if (*end != ',') return 0;
        const char *start = end + 1;
        v[i] = strtod(start, &end);
        if (end == start) return 0;
    }
    return 1;
}

static int euroc_v1_02(const char *data_dir) {
    char path[1024];
    snprintf(path, sizeof path, "%s/euroc_v1_02_imu_gt/mav0/imu0/data.csv", data_dir);
    FILE *f = fopen(path, "r");
    char gpath[1024];
    snprintf(gpath, sizeof gpath, "%s/euroc_v1_02_imu_gt/mav0/state_groundtruth_estimate0/data.csv",
             data_dir);
    FILE *fg = fopen(gpath, "r");
    if (f == NULL || fg == NULL) {
        printf("unit.rest_euroc: skipped: %s not found (../shared/data absent)\n", path);
        if (f != NULL) fclose(f);
        if (fg != NULL) fclose(fg);
        return 77;
    }
    /* The ground truth's first gyro bias (columns 11-13: b_w). */
    char line[512];
    double bw[3] = {0, 0, 0};
    int have_bw = 0;
    while (!have_bw && fgets(line, sizeof line, fg) != NULL) {
        double c[16];
        long long ns = 0;
        if (line[0] == '#') continue;
        if (parse_row(line, &ns, c, 16)) {
            bw[0] = c[10];
            bw[1] = c[11];
            bw[2] = c[12];
            have_bw = 1;
        }
    }
    fclose(fg);
    sfd_rest_params_t p;
    sfd_rest_params_default(&p);
    sfd_rest_init(&g_rest, &p);
    long long t0 = -1;
    int windows_before = 0, rest_before = 0, windows_after = 0, rest_after = 0, first = 1,
        fails = 0;
    double max_T_rest = 0.0, min_T_flight = 1e300, first_non_rest_s = -1.0;
    while (fgets(line, sizeof line, f) != NULL) {
        long long ns = 0;
        double v[6], g[3], a[3];
        if (line[0] == '#') continue;
        if (!parse_row(line, &ns, v, 6)) continue;
        for (int k = 0; k < 3; ++k) {
            g[k] = v[k];
            a[k] = v[3 + k];
        }
        if (t0 < 0) t0 = ns;
        const int blocks_before = g_rest.blocks, next_before = g_rest.next;
        if (sfd_rest_push(&g_rest, (int64_t)(ns / 1000), g, a) != SFD_OK) ++fails;
        if (g_rest.blocks == blocks_before && g_rest.next == next_before) continue;
        sfd_rest_result_t r;
        sfd_rest_evaluate(&g_rest, &r);
        if (!r.ready) continue;
        const double end_s = (double)r.window_end_us * 1e-6 - (double)t0 * 1e-9;
        if (first) {
            printf(
                "unit.rest_euroc: first window (ends %.2f s): T %.1f (threshold %.1f), gyro mean "
                "%.5f %.5f %.5f rad/s, ground-truth b_w %.5f %.5f %.5f\n",
                end_s, r.statistic, r.threshold, r.gyro_mean_rad_s[0], r.gyro_mean_rad_s[1],
                r.gyro_mean_rad_s[2], bw[0], bw[1], bw[2]);
            for (int k = 0; k < 3; ++k) {
                if (fabs(r.gyro_mean_rad_s[k] - bw[k]) > 0.005) ++fails;
            }
            first = 0;
        }
        if (r.at_rest == 0 && first_non_rest_s < 0.0) first_non_rest_s = end_s;
        if (end_s < 3.5) {
            ++windows_before;
            rest_before += r.at_rest;
            if (r.statistic > max_T_rest) max_T_rest = r.statistic;
        } else if (end_s > 4.5) {
            ++windows_after;
            rest_after += r.at_rest;
            if (r.statistic < min_T_flight) min_T_flight = r.statistic;
        }
    }
    fclose(f);
    printf(
        "unit.rest_euroc: windows ending before 3.5 s (on the ground, rotors running): %d of %d "
        "at rest, max T %.1f; ending after 4.5 s (flying): %d of %d at rest, min T %.0f; first "
        "window not at rest ends at %.2f s\n",
        rest_before, windows_before, max_T_rest, rest_after, windows_after, min_T_flight,
        first_non_rest_s);
    const int ok = have_bw && fails == 0 && windows_before >= 20 && rest_before == windows_before &&
                   windows_after >= 300 && rest_after == 0;
    printf("unit.rest_euroc: %s\n", ok ? "ok" : "FAILED");
    return ok ? 0 : 1;
}

int main(int argc, char **argv) {
    if (argc == 3 && strcmp(argv[1], "--euroc") == 0) return euroc_v1_02(argv[2]);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(at_rest_the_false_alarm_rate_is_alpha_and_the_bias_is_found),
        cmocka_unit_test(motion_and_free_fall_are_not_rest),
        cmocka_unit_test(gaps_restart_the_window_and_bad_input_is_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
