/*
 * Fuzz target for nbs_sort_pairs, the sort every comparison of pair lists relies on: any
 * list of pairs with non-negative indices (as the library produces them; duplicates, runs of
 * equal keys and extreme values included) must come out as the same multiset in (i, j)
 * order, identical to qsort's result, and sorting it again must change nothing.
 */
#include "nbs/nbs.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define FZ_MAX_PAIRS 4096

static int fz_compare(const void *a, const void *b) {
  const nbs_pair *x = a, *y = b;
  if (x->i != y->i) return x->i < y->i ? -1 : 1;
  if (x->j != y->j) return x->j < y->j ? -1 : 1;
  return 0;
}

/* Reads one index: 1 byte selects a small value, a value near INT32_MAX, or 4 raw bytes
 * (sign bit cleared), so that both dense and extreme key ranges occur. */
static int32_t fz_index(const uint8_t **p, const uint8_t *end) {
  if (*p == end) return 0;
  unsigned sel = *(*p)++;
  if (sel < 128) return (int32_t)(sel & 31);
  if (sel < 192) return INT32_MAX - (int32_t)(sel & 15);
  uint32_t v = 0;
  for (int b = 0; b < 4 && *p < end; b++) v |= (uint32_t)*(*p)++ << (8 * b);
  return (int32_t)(v & 0x7fffffffu);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  static nbs_pair got[FZ_MAX_PAIRS], want[FZ_MAX_PAIRS];
  const uint8_t *p = data, *end = data + size;
  size_t count = 0;
  while (p < end && count < FZ_MAX_PAIRS) {
    got[count].i = fz_index(&p, end);
    got[count].j = fz_index(&p, end);
    count++;
  }
  memcpy(want, got, count * sizeof *got);
  qsort(want, count, sizeof *want, fz_compare);
  nbs_sort_pairs(count ? got : NULL, count);
  if (count && memcmp(got, want, count * sizeof *got) != 0) {
    for (size_t k = 0; k < count; k++) {
      fprintf(stderr, "%zu: got (%d, %d) want (%d, %d)\n", k, (int)got[k].i, (int)got[k].j,
              (int)want[k].i, (int)want[k].j);
    }
    fprintf(stderr, "fuzz_sort_pairs: nbs_sort_pairs differs from qsort on %zu pairs\n", count);
    abort();
  }
  nbs_sort_pairs(got, count);
  if (count && memcmp(got, want, count * sizeof *got) != 0) {
    fprintf(stderr, "fuzz_sort_pairs: sorting a sorted list changed it\n");
    abort();
  }
  return 0;
}
