/* Helpers shared by the tests: detection into a sorted list, a counting allocator that can
 * fail its k-th allocation. */
#ifndef NBS_TEST_UTIL_H
#define NBS_TEST_UTIL_H

#include "nbs/nbs.h"
#include "scenes.h"

#include <stdbool.h>

typedef struct pair_list {
  nbs_pair *p;
  size_t count;
} pair_list;

/* Runs one detection and copies its pairs in the algorithm's order (not sorted), in a
 * malloc'ed list. Returns the status. */
nbs_status detect_raw(nbs_context *ctx, const scene *s, nbs_algorithm algo, nbs_mode mode,
                      pair_list *out);
/* The same, the pairs sorted. */
nbs_status detect_sorted(nbs_context *ctx, const scene *s, nbs_algorithm algo, nbs_mode mode,
                         pair_list *out);
/* The same detection through a callback: its batches concatenated, in order (not sorted). */
nbs_status detect_callback(nbs_context *ctx, const scene *s, nbs_algorithm algo, nbs_mode mode,
                           pair_list *out);
/* Detects the contacts of s with algo (the default definition otherwise) and fills *st
 * with the detection's statistics. Returns the status. */
nbs_status detect_stats(nbs_context *ctx, const scene *s, nbs_algorithm algo, nbs_stats *st);
/* Copies count pairs into a new list (a buffer for pair_list_free). */
void pair_list_copy(pair_list *out, const nbs_pair *p, size_t count);
void pair_list_free(pair_list *l);
bool pair_lists_equal(const pair_list *a, const pair_list *b);
/* True when every pair of sub is in super (both sorted). */
bool pair_list_contains(const pair_list *super, const pair_list *sub);
nbs_input scene_input(const scene *s);
/* A scene of the caller's arrays (diameter 1), which it keeps: not for scene_free. */
scene scene_view(int dim, int64_t n, double *coords, double *radii);
/* The next of a reproducible sequence of numbers in [0, 1) (a 64-bit LCG's top 53 bits). */
double test_unit(uint64_t *state);
/* A scene of the shared library (seed 1, diameter 1); aborts if it cannot be made. */
scene test_scene(scene_kind kind, int dim, int64_t n, double fraction);

/* A test allocator: counts live allocations and bytes, and fails the allocation numbered
 * fail_at (0-based count since reset), or none when fail_at < 0. */
typedef struct test_alloc {
  long calls, live;
  size_t live_bytes;
  long fail_at;
  long failures;
  int with_realloc; /* 1: the allocator offers realloc (counted and failed like alloc) */
} test_alloc;
nbs_allocator test_allocator(test_alloc *ta);

#endif
