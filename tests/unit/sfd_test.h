/* SPDX-License-Identifier: MIT */
/* Shared helpers of the cmocka unit tests. Include after <setjmp.h>, <stdarg.h>, <stddef.h>,
 * <stdint.h> as cmocka requires (this header does that). */
#ifndef SFD_TEST_H
#define SFD_TEST_H

#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <cmocka.h>

/* Traceability: names the requirement a test pins down; `grep SFD_REQ` lists them. */
#define SFD_REQ(id) ((void)(id))

/* |actual - expected| <= tol, with both values printed on failure. */
#define assert_near(actual, expected, tol)                                                       \
    do {                                                                                         \
        double sfd_a_ = (double)(actual), sfd_e_ = (double)(expected), sfd_t_ = (double)(tol);   \
        if (!(fabs(sfd_a_ - sfd_e_) <= sfd_t_)) {                                                \
            fail_msg("%s = %.17g, expected %.17g within %.3g", #actual, sfd_a_, sfd_e_, sfd_t_); \
        }                                                                                        \
    } while (0)

#define assert_status(call, expected) assert_int_equal((int)(call), (int)(expected))

#endif /* SFD_TEST_H */
