#include "test.h"

#include <stdbool.h>

int test_failures;

int test_main(int argc, char **argv, const test_case *tests, size_t count) {
  int passed = 0, failed = 0, named = 0, excluded = 0;
  bool *listed = calloc(count ? count : 1, sizeof *listed);
  if (!listed) abort();
  for (int a = 1; a < argc; a++) {
    const bool out = argv[a][0] == '-';
    size_t t = 0;
    while (t < count && strcmp(argv[a] + out, tests[t].name) != 0) t++;
    if (t == count) {
      fprintf(stderr, "%s: no test named %s\n", argv[0], argv[a] + out);
      free(listed);
      return 2;
    }
    listed[t] = true;
    excluded += out;
    named += !out;
  }
  if (named && excluded) {
    fprintf(stderr, "%s: name the tests to run or those to leave out, not both\n", argv[0]);
    free(listed);
    return 2;
  }
  for (size_t t = 0; t < count; t++) {
    if (named ? !listed[t] : listed[t]) continue;
    test_failures = 0;
    tests[t].fn();
    if (test_failures) {
      fprintf(stderr, "FAIL %s (%d failures)\n", tests[t].name, test_failures);
      failed++;
    } else {
      printf("ok   %s\n", tests[t].name);
      passed++;
    }
  }
  free(listed);
  printf("%d passed, %d failed\n", passed, failed);
  if (passed + failed == 0) {
    fprintf(stderr, "%s: no test ran\n", argv[0]);
    return 2;
  }
  return failed ? 1 : 0;
}
