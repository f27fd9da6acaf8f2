/*
 * A simulation's use of nbs: create a context once, detect every time step.
 * Build against an installed nbs:
 *   cc step.c $(pkg-config --cflags --libs nbs)      or CMake: find_package(nbs) + nbs::nbs
 */
#include <nbs/nbs.h>

#include <stdio.h>
#include <stdlib.h>

int main(void) {
  enum { N = 1000 };
  static double xyz[3 * N];
  for (int k = 0; k < N; k++) { /* a 10 x 10 x 10 lattice, spacing 1 */
    xyz[3 * k + 0] = k % 10;
    xyz[3 * k + 1] = (k / 10) % 10;
    xyz[3 * k + 2] = k / 100;
  }
  nbs_context *ctx;
  if (nbs_context_create(NULL, &ctx) != NBS_OK) return 1;
  nbs_input in = {.dim = 3, .n = N, .coords = xyz, .diameter = 1.0};
  for (int step = 0; step < 3; step++) {
    nbs_status s = nbs_detect(ctx, &in, NULL);
    if (s != NBS_OK) {
      fprintf(stderr, "nbs: %s: %s\n", nbs_status_name(s), nbs_context_error(ctx));
      nbs_context_destroy(ctx);
      return 1;
    }
    size_t count;
    const nbs_pair *pairs = nbs_pairs(ctx, &count);
    nbs_stats st;
    nbs_last_stats(ctx, &st);
    printf("step %d: %zu contacts (%s), first (%d, %d)\n", step, count,
           nbs_algorithm_name(st.algorithm), count ? pairs[0].i : -1, count ? pairs[0].j : -1);
    for (int k = 0; k < 3 * N; k++) xyz[k] *= 1.0001; /* the elements move apart a little */
  }
  nbs_context_destroy(ctx);
  return 0;
}
