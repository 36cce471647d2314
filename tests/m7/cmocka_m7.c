/* SPDX-License-Identifier: MIT */
/* The runner behind tests/m7/include/cmocka.h (the cmocka API subset of the core unit tests) on
 * the emulated Cortex-M7. Output follows cmocka's default format; a failed assertion prints what
 * differed and where, then longjmps back to the runner, which runs the next test. */
#include <cmocka.h>

#include <inttypes.h>
#include <stdlib.h>
#include <stdio.h>
#include <string.h>

enum { M7_RESULT_PASS = 0, M7_RESULT_FAIL = 1, M7_RESULT_SKIP = 2 };

static jmp_buf m7_test_env;
static int m7_in_test;

void print_message(const char *format, ...) {
    va_list args;
    va_start(args, format);
    (void)vprintf(format, args);
    va_end(args);
}

/* Like cmocka's print_error, but to stdout: the semihosting console is one stream, and keeping
 * one stdio stream keeps the order of the lines. */
void print_error(const char *format, ...) {
    va_list args;
    va_start(args, format);
    (void)vprintf(format, args);
    va_end(args);
}

static void m7_stop(int result) {
    if (m7_in_test) longjmp(m7_test_env, result);
    /* An assertion outside a test (in main, before the runner): nothing to return to. */
    printf("[  ERROR   ] --- assertion outside a test\n");
    (void)fflush(stdout);
    _Exit(1);
}

void _fail(const char *file, int line) {
    printf("[   LINE   ] --- %s:%d: error: Failure!\n", file, line);
    m7_stop(M7_RESULT_FAIL);
    for (;;) {
    }
}

void _skip(const char *file, int line) {
    (void)file;
    (void)line;
    m7_stop(M7_RESULT_SKIP);
    for (;;) {
    }
}

void _assert_true(LargestIntegralType result, const char *expression, const char *file, int line) {
    if (!result) {
        printf("[  ERROR   ] --- %s\n", expression);
        _fail(file, line);
    }
}

void _assert_int_equal(LargestIntegralType a, LargestIntegralType b, const char *file, int line) {
    if (a != b) {
        printf("[  ERROR   ] --- %#llx != %#llx (%lld != %lld)\n", a, b, (long long)a,
               (long long)b);
        _fail(file, line);
    }
}

void _assert_int_not_equal(LargestIntegralType a, LargestIntegralType b, const char *file,
                           int line) {
    if (a == b) {
        printf("[  ERROR   ] --- %#llx == %#llx (%lld == %lld)\n", a, a, (long long)a,
               (long long)b);
        _fail(file, line);
    }
}

void _assert_in_range(LargestIntegralType value, LargestIntegralType minimum,
                      LargestIntegralType maximum, const char *file, int line) {
    if (value < minimum || value > maximum) {
        printf("[  ERROR   ] --- %#llx is not within the range [%#llx, %#llx]\n", value, minimum,
               maximum);
        _fail(file, line);
    }
}

void _assert_string_equal(const char *a, const char *b, const char *file, int line) {
    /* cmocka: two NULLs are equal, one NULL is a failure. */
    if (a == NULL && b == NULL) return;
    if (a == NULL || b == NULL || strcmp(a, b) != 0) {
        printf("[  ERROR   ] --- \"%s\" != \"%s\"\n", a ? a : "(null)", b ? b : "(null)");
        _fail(file, line);
    }
}

void _assert_memory_equal(const void *a, const void *b, size_t size, const char *file, int line) {
    const unsigned char *pa = (const unsigned char *)a;
    const unsigned char *pb = (const unsigned char *)b;
    size_t differ = 0;
    size_t first = 0;
    for (size_t i = 0; i < size; ++i) {
        if (pa[i] != pb[i]) {
            if (differ == 0) first = i;
            ++differ;
        }
    }
    if (differ != 0) {
        printf("[  ERROR   ] --- %u of %u bytes differ, the first at offset %u: 0x%02x != 0x%02x\n",
               (unsigned)differ, (unsigned)size, (unsigned)first, pa[first], pb[first]);
        _fail(file, line);
    }
}

/* Runs one fixture or test body under the longjmp target; returns its M7_RESULT_*. */
static int m7_run_test(CMUnitTestFunction test, void **state) {
    volatile int result = M7_RESULT_PASS;
    m7_in_test = 1;
    int jumped = setjmp(m7_test_env);
    if (jumped == 0) {
        test(state);
    } else {
        result = jumped;
    }
    m7_in_test = 0;
    return result;
}

static CMFixtureFunction m7_fixture;
static int m7_fixture_rc;
static void m7_fixture_body(void **state) {
    m7_fixture_rc = m7_fixture(state);
}

static int m7_run_fixture(CMFixtureFunction fixture, void **state) {
    if (fixture == NULL) return 0;
    m7_fixture = fixture;
    m7_fixture_rc = 0;
    if (m7_run_test(m7_fixture_body, state) != M7_RESULT_PASS) return -1;
    return m7_fixture_rc;
}

int _cmocka_run_group_tests(const char *group_name, const struct CMUnitTest *tests, size_t count,
                            CMFixtureFunction group_setup, CMFixtureFunction group_teardown) {
    static unsigned char result[256];
    (void)group_name;
    if (count > sizeof result) {
        printf("[  ERROR   ] --- %u tests in one group, the runner holds %u\n", (unsigned)count,
               (unsigned)sizeof result);
        return (int)count;
    }
    void *group_state = NULL;
    printf("[==========] Running %u test(s).\n", (unsigned)count);
    if (m7_run_fixture(group_setup, &group_state) != 0) {
        printf("[  ERROR   ] --- group setup failed\n");
        return (int)count;
    }
    size_t passed = 0, failed = 0, skipped = 0;
    for (size_t i = 0; i < count; ++i) {
        const struct CMUnitTest *t = &tests[i];
        void *state = t->initial_state ? t->initial_state : group_state;
        printf("[ RUN      ] %s\n", t->name);
        int r = M7_RESULT_PASS;
        if (m7_run_fixture(t->setup_func, &state) != 0) {
            printf("[  ERROR   ] --- setup of %s failed\n", t->name);
            r = M7_RESULT_FAIL;
        } else {
            r = m7_run_test(t->test_func, &state);
            if (m7_run_fixture(t->teardown_func, &state) != 0) {
                printf("[  ERROR   ] --- teardown of %s failed\n", t->name);
                r = M7_RESULT_FAIL;
            }
        }
        result[i] = (unsigned char)r;
        if (r == M7_RESULT_PASS) {
            printf("[       OK ] %s\n", t->name);
            ++passed;
        } else if (r == M7_RESULT_SKIP) {
            printf("[  SKIPPED ] %s\n", t->name);
            ++skipped;
        } else {
            printf("[  FAILED  ] %s\n", t->name);
            ++failed;
        }
        (void)fflush(stdout);
    }
    if (m7_run_fixture(group_teardown, &group_state) != 0) {
        printf("[  ERROR   ] --- group teardown failed\n");
        ++failed;
    }
    printf("[==========] %u test(s) run.\n", (unsigned)count);
    printf("[  PASSED  ] %u test(s).\n", (unsigned)passed);
    if (skipped != 0) {
        printf("[  SKIPPED ] %u test(s), listed below:\n", (unsigned)skipped);
        for (size_t i = 0; i < count; ++i) {
            if (result[i] == M7_RESULT_SKIP) printf("[  SKIPPED ] %s\n", tests[i].name);
        }
    }
    if (failed != 0) {
        printf("[  FAILED  ] %u test(s), listed below:\n", (unsigned)failed);
        for (size_t i = 0; i < count; ++i) {
            if (result[i] == M7_RESULT_FAIL) printf("[  FAILED  ] %s\n", tests[i].name);
        }
        printf("\n %u FAILED TEST(S)\n", (unsigned)failed);
    }
    (void)fflush(stdout);
    return (int)failed;
}
