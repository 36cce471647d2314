/* SPDX-License-Identifier: MIT */
/* unit.status: every status code has a distinct, stable name. */
#include "sfd_test.h"

#include <string.h>

#include <sfd/sfd_status.h>
#include <sfd/sfd_version.h>

/* GIVEN each defined code WHEN asking its name THEN the name is the enumerator's spelling. */
static void status_str_known_codes_named(void **state) {
    (void)state;
    SFD_REQ("SFD-API-001");
    assert_string_equal(sfd_status_str(SFD_OK), "SFD_OK");
    assert_string_equal(sfd_status_str(SFD_ERR_INVAL), "SFD_ERR_INVAL");
    assert_string_equal(sfd_status_str(SFD_ERR_CAPACITY), "SFD_ERR_CAPACITY");
    assert_string_equal(sfd_status_str(SFD_ERR_ORDER), "SFD_ERR_ORDER");
    assert_string_equal(sfd_status_str(SFD_ERR_NUMERIC), "SFD_ERR_NUMERIC");
    assert_string_equal(sfd_status_str(SFD_ERR_STATE), "SFD_ERR_STATE");
    assert_string_equal(sfd_status_str(SFD_ERR_RANGE), "SFD_ERR_RANGE");
    assert_string_equal(sfd_status_str(SFD_ERR_DOMAIN), "SFD_ERR_DOMAIN");
}

/* GIVEN a value outside the enum WHEN asking its name THEN a non-null "unknown" name. */
static void status_str_unknown_code_not_null(void **state) {
    (void)state;
    SFD_REQ("SFD-API-001");
    assert_string_equal(sfd_status_str((sfd_status_t)-99), "SFD_ERR_UNKNOWN");
    assert_string_equal(sfd_status_str((sfd_status_t)7), "SFD_ERR_UNKNOWN");
}

/* GIVEN the error codes THEN all are negative (counts may be returned as non-negative). */
static void status_errors_negative(void **state) {
    (void)state;
    SFD_REQ("SFD-API-001");
    const sfd_status_t errs[] = {SFD_ERR_INVAL, SFD_ERR_CAPACITY, SFD_ERR_ORDER, SFD_ERR_NUMERIC,
                                 SFD_ERR_STATE, SFD_ERR_RANGE,    SFD_ERR_DOMAIN};
    for (size_t i = 0; i < sizeof errs / sizeof errs[0]; ++i) assert_true(errs[i] < 0);
}

/* GIVEN the library THEN sfd_version() is the SFD_VERSION of the headers it was built with (here
 * the same headers): 0.1 as (major << 16) | minor. */
static void library_version_is_the_headers(void **state) {
    (void)state;
    assert_int_equal(sfd_version(), SFD_VERSION);
    assert_int_equal(sfd_version() >> 16, SFD_VERSION_MAJOR);
    assert_int_equal(sfd_version() & 0xFFFFu, SFD_VERSION_MINOR);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(status_str_known_codes_named),
        cmocka_unit_test(status_str_unknown_code_not_null),
        cmocka_unit_test(status_errors_negative),
        cmocka_unit_test(library_version_is_the_headers),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
