/* Names, messages, parsing and the pair sort. */
#include "internal.h"
#include "test.h"
#include "util.h"

static void test_status_names(void) {
  for (int s = 0; s <= NBS_ERR_ARGUMENT; s++) {
    CHECK_TRUE(strcmp(nbs_status_name((nbs_status)s), "unknown") != 0);
    CHECK_TRUE(nbs_status_message((nbs_status)s)[0] != '\0');
    for (int t = 0; t < s; t++) {
      CHECK_TRUE(strcmp(nbs_status_name((nbs_status)s), nbs_status_name((nbs_status)t)) != 0);
    }
  }
  CHECK_TRUE(strcmp(nbs_status_name((nbs_status)999), "unknown") == 0);
  CHECK_TRUE(strcmp(nbs_version(), NBS_VERSION_STRING) == 0);
}

static void test_algorithm_names(void) {
  for (int a = 0; a < NBS_ALGORITHM_COUNT; a++) {
    nbs_algorithm got;
    ASSERT_OK(nbs_algorithm_from_name(nbs_algorithm_name((nbs_algorithm)a), &got));
    CHECK_EQ(got, a);
  }
  nbs_algorithm got;
  CHECK_STATUS(nbs_algorithm_from_name("quadtree", &got), NBS_ERR_ALGORITHM);
  CHECK_STATUS(nbs_algorithm_from_name(NULL, &got), NBS_ERR_NULL);
  CHECK_TRUE(nbs_algorithm_name(NBS_ALGORITHM_COUNT) == NULL);
  CHECK_TRUE(nbs_algorithm_name((nbs_algorithm)-1) == NULL);
}

static int pair_cmp(const void *a, const void *b) {
  const nbs_pair *x = a, *y = b;
  if (x->i != y->i) return x->i < y->i ? -1 : 1;
  return (x->j > y->j) - (x->j < y->j);
}

static void test_sort_pairs(void) {
  uint64_t state = 12345;
  for (size_t count = 0; count < 5000; count = count * 3 + 1) {
    nbs_pair *a = malloc((count + 1) * sizeof *a), *b = malloc((count + 1) * sizeof *b);
    for (size_t k = 0; k < count; k++) {
      state = state * 6364136223846793005ull + 1442695040888963407ull;
      a[k].i = (int32_t)((state >> 33) % (count / 3 + 1));
      a[k].j = (int32_t)((state >> 20) % 2147483647u);
      if (k % 7 == 0 && k) a[k] = a[k - 1]; /* duplicates */
    }
    memcpy(b, a, count * sizeof *a);
    nbs_sort_pairs(a, count);
    if (count) qsort(b, count, sizeof *b, pair_cmp);
    CHECK_TRUE(count == 0 || memcmp(a, b, count * sizeof *a) == 0);
    free(a);
    free(b);
  }
  nbs_sort_pairs(NULL, 0);
}

int main(int argc, char **argv) {
  static const test_case tests[] = {
      {"status_names", test_status_names},
      {"algorithm_names", test_algorithm_names},
      {"sort_pairs", test_sort_pairs},
  };
  return test_main(argc, argv, tests, sizeof tests / sizeof *tests);
}
