/*
 * nbs_sort_pairs: the book's sort (section 3.7, eqs. 3.48-3.50) on pair keys
 * (i << 32 | j): find the minimum and the maximum, split at their midpoint, parse the array
 * from both ends swapping what lies on the wrong side, and repeat on both halves. It needs
 * no memory beyond the array and a constant stack (the smaller half is recursed into, the
 * larger one looped on), and every level halves the range of the keys, so it takes at most
 * 64 levels: T ~ N log2(range).
 */
#include "internal.h"

static inline uint64_t nbs__pair_key(nbs_pair p) {
  return (uint64_t)(uint32_t)p.i << 32 | (uint32_t)p.j;
}

static void nbs__midsort_pairs(nbs_pair *p, size_t count) {
  while (count > 1) {
    uint64_t lo = nbs__pair_key(p[0]), hi = lo;
    for (size_t i = 1; i < count; i++) {
      uint64_t k = nbs__pair_key(p[i]);
      if (k < lo) lo = k;
      if (k > hi) hi = k;
    }
    if (lo == hi) return;
    uint64_t mid = lo + (hi - lo) / 2; /* lo <= mid < hi: both sides are non-empty */
    size_t i = 0, j = count - 1;
    for (;;) {
      while (nbs__pair_key(p[i]) <= mid) i++;
      while (nbs__pair_key(p[j]) > mid) j--;
      if (i > j) break;
      nbs_pair t = p[i];
      p[i] = p[j];
      p[j] = t;
    }
    /* now [0, i) <= mid < [i, count) */
    if (i < count - i) {
      nbs__midsort_pairs(p, i);
      p += i;
      count -= i;
    } else {
      nbs__midsort_pairs(p + i, count - i);
      count = i;
    }
  }
}

void nbs_sort_pairs(nbs_pair *pairs, size_t count) {
  if (pairs && count > 1) nbs__midsort_pairs(pairs, count);
}
