#include "test.h"

int test_failures;

int test_main(int argc, char **argv, const test_case *tests, size_t count) {
  int passed = 0, failed = 0;
  for (size_t t = 0; t < count; t++) {
    if (argc > 1) {
      int wanted = 0;
      for (int a = 1; a < argc; a++) wanted |= strcmp(argv[a], tests[t].name) == 0;
      if (!wanted) continue;
    }
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
  printf("%d passed, %d failed\n", passed, failed);
  return failed ? 1 : 0;
}
