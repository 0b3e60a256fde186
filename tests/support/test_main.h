/* test_main.h: cmocka boilerplate shared by the test executables. Each
   executable takes an optional test name so that ctest runs every case as
   its own entry (tests/CMakeLists.txt reads the names from the source). */
#ifndef TB_TEST_MAIN_H
#define TB_TEST_MAIN_H

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#define TB_TEST_MAIN(tests)                                        \
    int main(int argc, char **argv)                                \
    {                                                              \
        if (argc > 1)                                              \
            cmocka_set_test_filter(argv[1]);                       \
        return cmocka_run_group_tests(tests, NULL, NULL);          \
    }

/* |a - b| <= tol * |b|, with both numbers in the failure message. */
#define assert_rel(a, b, tol)                                                          \
    do {                                                                               \
        double a_ = (a), b_ = (b), t_ = (tol);                                         \
        if (!(fabs(a_ - b_) <= t_ * fabs(b_)))                                         \
            fail_msg("%s = %.17g, expected %.17g within %g relative (off by %.3g)", #a, \
                     a_, b_, t_, fabs(a_ - b_) / fabs(b_));                            \
    } while (0)

#define assert_below(a, bound)                                                   \
    do {                                                                         \
        double a_ = (a), b_ = (bound);                                           \
        if (!(a_ <= b_))                                                         \
            fail_msg("%s = %.17g, expected at most %.17g", #a, a_, b_);          \
    } while (0)

#endif
