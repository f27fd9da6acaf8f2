/* Names, messages, parsing and the pair sort. */
#include "internal.h"
#include "test.h"
#include "util.h"

static void test_status_names(void) {
  for (int s = 0; s <= NBS_ERR_BUSY; s++) {
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

/* def.sorted: the context's own buffer comes back sorted, equal to a sorted copy. */
static void test_sorted_option(void) {
  scene_def sd = scene_default_def();
  sd.n = 3000;
  scene s;
  char err[200];
  ASSERT_MSG(scene_generate(&sd, &s, err, sizeof err) == 0, "%s", err);
  nbs_context *ctx;
  ASSERT_OK(nbs_context_create(NULL, &ctx));
  for (int a = 1; a < NBS_ALGORITHM_COUNT; a++) {
    pair_list ref;
    ASSERT_OK(detect_sorted(ctx, &s, (nbs_algorithm)a, NBS_MODE_CONTACTS, &ref));
    nbs_input in = scene_input(&s);
    nbs_detect_def def = nbs_default_detect_def();
    def.algorithm = (nbs_algorithm)a;
    def.sorted = 1;
    ASSERT_OK(nbs_detect(ctx, &in, &def));
    size_t count;
    const nbs_pair *p = nbs_pairs(ctx, &count);
    CHECK_EQ(count, ref.count);
    CHECK_TRUE(count == ref.count && memcmp(p, ref.p, count * sizeof *p) == 0);
    pair_list_free(&ref);
  }
  nbs_context_destroy(ctx);
  scene_free(&s);
}

int main(int argc, char **argv) {
  static const test_case tests[] = {
      {"status_names", test_status_names},
      {"algorithm_names", test_algorithm_names},
      {"sort_pairs", test_sort_pairs},
      {"sorted_option", test_sorted_option},
  };
  return test_main(argc, argv, tests, sizeof tests / sizeof *tests);
}
