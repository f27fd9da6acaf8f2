/*
 * A small test harness: typed asserts that print both values, tests registered in a table,
 * a closing line "N passed, N failed". Each test file is its own executable run by ctest.
 */
#ifndef NBS_TEST_H
#define NBS_TEST_H

#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

extern int test_failures; /* failures in the current test */

#define TEST_FAIL_AT(...)                                                                     \
  do {                                                                                        \
    fprintf(stderr, "%s:%d: ", __FILE__, __LINE__);                                           \
    fprintf(stderr, __VA_ARGS__);                                                             \
    fputc('\n', stderr);                                                                      \
    test_failures++;                                                                          \
  } while (0)

/* Each ASSERT returns from the test function on failure; CHECK carries on. */
#define CHECK_MSG(cond, ...)                                                                  \
  do {                                                                                        \
    if (!(cond)) TEST_FAIL_AT(__VA_ARGS__);                                                   \
  } while (0)
#define ASSERT_MSG(cond, ...)                                                                 \
  do {                                                                                        \
    if (!(cond)) {                                                                            \
      TEST_FAIL_AT(__VA_ARGS__);                                                              \
      return;                                                                                 \
    }                                                                                         \
  } while (0)
#define ASSERT_TRUE(c) ASSERT_MSG((c), "expected true: %s", #c)
#define CHECK_TRUE(c) CHECK_MSG((c), "expected true: %s", #c)
#define ASSERT_EQ(a, b)                                                                       \
  do {                                                                                        \
    long long test_a = (long long)(a), test_b = (long long)(b);                               \
    ASSERT_MSG(test_a == test_b, "%s == %s: %lld != %lld", #a, #b, test_a, test_b);           \
  } while (0)
#define CHECK_EQ(a, b)                                                                        \
  do {                                                                                        \
    long long test_a = (long long)(a), test_b = (long long)(b);                               \
    CHECK_MSG(test_a == test_b, "%s == %s: %lld != %lld", #a, #b, test_a, test_b);            \
  } while (0)
#define ASSERT_STATUS(expr, want)                                                             \
  do {                                                                                        \
    nbs_status test_s = (expr), test_w = (want);                                              \
    ASSERT_MSG(test_s == test_w, "%s: status %s, expected %s", #expr, nbs_status_name(test_s), \
               nbs_status_name(test_w));                                                      \
  } while (0)
#define CHECK_STATUS(expr, want)                                                              \
  do {                                                                                        \
    nbs_status test_s = (expr), test_w = (want);                                              \
    CHECK_MSG(test_s == test_w, "%s: status %s, expected %s", #expr, nbs_status_name(test_s),  \
              nbs_status_name(test_w));                                                       \
  } while (0)
#define ASSERT_OK(expr) ASSERT_STATUS((expr), NBS_OK)

typedef struct test_case {
  const char *name;
  void (*fn)(void);
} test_case;

/* Runs the tests named on the command line, or all but those named with a leading '-' (ctest
 * splits a long program into parts that way, one part taking whatever the others do not
 * name), or all without arguments. A name that is no test's, or no test run, is an
 * error (exit 2). */
int test_main(int argc, char **argv, const test_case *tests, size_t count);

#endif
