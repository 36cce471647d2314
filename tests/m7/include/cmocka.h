/* SPDX-License-Identifier: MIT */
/* cmocka-compatible test runner for the emulated Cortex-M7 (tests/m7, docs/embedded.md).
 *
 * Debian ships no arm-none-eabi build of cmocka, so the target unit tests compile against this
 * header instead of <cmocka.h>: it implements exactly the part of cmocka's API that the core unit
 * tests (tests/unit) use, with the same signatures and the same semantics (integers compared
 * as cmocka's LargestIntegralType, a failed assertion ends the test through longjmp, skip()
 * marks it skipped, cmocka_run_group_tests returns the number of failed tests). Anything else
 * of cmocka (mocks, expect_*, test_malloc, ...) is absent on purpose: a test that starts using it
 * fails to compile in the cortex-m7 preset instead of running against a half-done stand-in.
 * The host builds keep the real cmocka (Debian libcmocka-dev). */
#ifndef SFD_M7_CMOCKA_H
#define SFD_M7_CMOCKA_H

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* cmocka 1.1's integer type of every integer assertion (64 bits on this 32-bit target too). */
#define LargestIntegralType unsigned long long
#define cast_to_largest_integral_type(value) ((LargestIntegralType)(value))
#define cast_ptr_to_largest_integral_type(value) ((LargestIntegralType)(uintptr_t)(value))

typedef void (*CMUnitTestFunction)(void **state);
typedef int (*CMFixtureFunction)(void **state);

struct CMUnitTest {
    const char *name;
    CMUnitTestFunction test_func;
    CMFixtureFunction setup_func;
    CMFixtureFunction teardown_func;
    void *initial_state;
};

#define cmocka_unit_test(f) \
    { #f, f, NULL, NULL, NULL }
#define cmocka_run_group_tests(group_tests, group_setup, group_teardown)                 \
    _cmocka_run_group_tests(#group_tests, group_tests,                                   \
                            sizeof(group_tests) / sizeof((group_tests)[0]), group_setup, \
                            group_teardown)

#define assert_true(c) _assert_true(cast_to_largest_integral_type(c), #c, __FILE__, __LINE__)
#define assert_false(c) _assert_true(!(cast_to_largest_integral_type(c)), #c, __FILE__, __LINE__)
#define assert_non_null(c) \
    _assert_true(cast_ptr_to_largest_integral_type(c), #c, __FILE__, __LINE__)
#define assert_null(c) _assert_true(!(cast_ptr_to_largest_integral_type(c)), #c, __FILE__, __LINE__)
#define assert_int_equal(a, b)                                                            \
    _assert_int_equal(cast_to_largest_integral_type(a), cast_to_largest_integral_type(b), \
                      __FILE__, __LINE__)
#define assert_int_not_equal(a, b)                                                            \
    _assert_int_not_equal(cast_to_largest_integral_type(a), cast_to_largest_integral_type(b), \
                          __FILE__, __LINE__)
#define assert_in_range(value, minimum, maximum)                                                   \
    _assert_in_range(cast_to_largest_integral_type(value), cast_to_largest_integral_type(minimum), \
                     cast_to_largest_integral_type(maximum), __FILE__, __LINE__)
#define assert_string_equal(a, b) _assert_string_equal((a), (b), __FILE__, __LINE__)
#define assert_memory_equal(a, b, size) \
    _assert_memory_equal((const void *)(a), (const void *)(b), (size), __FILE__, __LINE__)

#define fail() _fail(__FILE__, __LINE__)
#define skip() _skip(__FILE__, __LINE__)
#define fail_msg(msg, ...)                              \
    do {                                                \
        print_error("ERROR: " msg "\n", ##__VA_ARGS__); \
        fail();                                         \
    } while (0)

void print_message(const char *format, ...) __attribute__((format(printf, 1, 2)));
void print_error(const char *format, ...) __attribute__((format(printf, 1, 2)));

void _assert_true(LargestIntegralType result, const char *expression, const char *file, int line);
void _assert_int_equal(LargestIntegralType a, LargestIntegralType b, const char *file, int line);
void _assert_int_not_equal(LargestIntegralType a, LargestIntegralType b, const char *file,
                           int line);
void _assert_in_range(LargestIntegralType value, LargestIntegralType minimum,
                      LargestIntegralType maximum, const char *file, int line);
void _assert_string_equal(const char *a, const char *b, const char *file, int line);
void _assert_memory_equal(const void *a, const void *b, size_t size, const char *file, int line);
__attribute__((noreturn)) void _fail(const char *file, int line);
__attribute__((noreturn)) void _skip(const char *file, int line);
int _cmocka_run_group_tests(const char *group_name, const struct CMUnitTest *tests, size_t count,
                            CMFixtureFunction group_setup, CMFixtureFunction group_teardown);

#ifdef __cplusplus
}
#endif

#endif /* SFD_M7_CMOCKA_H */
