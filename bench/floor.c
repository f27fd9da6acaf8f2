/*
 * nbs_floor: what this machine's memory alone costs a detection's preparation, per element,
 * measured by the same kind of loops without any contact detection around them. It prints
 * one key=value line per measurement (as nbs_bench does), for bench/suite.py's summary of
 * the linear target: how much of the growth in ns per element from N = 1e4 to 1e7 no
 * preparation can avoid on this machine.
 *
 *   tool=floor-gather  the input (N elements of dim doubles, side by side, as a caller
 *                      gives them) copied to dim arrays in a random order: one random read
 *                      of each element, which any algorithm that puts random-order elements
 *                      in cell order by gathering them pays (cellsort's gather; nbs's list
 *                      walks read each element at random too). The best of two loops: no
 *                      prefetches, and the library's two stages (256 places ahead into L2,
 *                      32 ahead into L1, both ends of an element; nbs__cs_prefetch).
 *   tool=floor-copy    the same copy in the input's order: one streaming pass that reads
 *                      the input and writes it once, which even an input already in cell
 *                      order pays.
 *
 * The order is a random permutation (xorshift64, Fisher-Yates, --seed): a scene in random
 * order is that, seen from its cell order. Each figure is the minimum over the repeats (at
 * least --repeats, and more until --min-time seconds have passed), as nbs_bench's are.
 *
 *   nbs_floor --n N [--dim 3|2] [--repeats R] [--min-time S] [--seed K]
 */
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now_seconds(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* The library's prefetch distances (src/cellsort.c, NBS__CS_AHEAD and NBS__CS_NEAR). */
enum { FLOOR_AHEAD = 256, FLOOR_NEAR = 32 };

/* out[a][p] = x[order[p] * dim + a] for every place p; with prefetches or without. */
static void gather(const double *x, const uint32_t *order, size_t n, int dim, double **out,
                   int ask) {
  for (size_t p = 0; p < n; p++) {
    if (ask) {
      const double *far = x + (size_t)order[p + FLOOR_AHEAD < n ? p + FLOOR_AHEAD : p] * dim;
      const double *near = x + (size_t)order[p + FLOOR_NEAR < n ? p + FLOOR_NEAR : p] * dim;
      __builtin_prefetch(far, 0, 1);
      __builtin_prefetch(far + dim - 1, 0, 1);
      __builtin_prefetch(near);
      __builtin_prefetch(near + dim - 1);
    }
    const double *e = x + (size_t)order[p] * dim;
    for (int a = 0; a < dim; a++) out[a][p] = e[a];
  }
}

/* out[a][p] = x[p * dim + a]: the same copy in the input's order. */
static void copy(const double *x, size_t n, int dim, double **out) {
  for (size_t p = 0; p < n; p++) {
    for (int a = 0; a < dim; a++) out[a][p] = x[p * dim + a];
  }
}

static int usage(const char *why) {
  fprintf(stderr,
          "nbs_floor: %s\n"
          "usage: nbs_floor --n N [--dim 3|2] [--repeats R] [--min-time S] [--seed K]\n",
          why);
  return 2;
}

/* A number argument, whole and in [lo, hi], or -1. */
static double number(const char *s, double lo, double hi) {
  char *end;
  errno = 0;
  const double v = strtod(s, &end);
  if (errno || end == s || *end || !(v >= lo && v <= hi)) return -1;
  return v;
}

int main(int argc, char **argv) {
  double nd = -1, min_time = 0.2;
  int dim = 3, repeats = 5;
  uint64_t seed = 1;
  for (int i = 1; i < argc; i++) {
    const char *o = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
    if (!v) return usage("every option takes a value");
    double got;
    if (strcmp(o, "--n") == 0) {
      if ((nd = number(v, 1, 2e9)) < 0 || nd != (double)(uint32_t)nd) {
        return usage("--n: a whole number from 1 to 2e9");
      }
    } else if (strcmp(o, "--dim") == 0) {
      if ((got = number(v, 2, 3)) < 0 || (got != 2 && got != 3)) return usage("--dim: 2 or 3");
      dim = (int)got;
    } else if (strcmp(o, "--repeats") == 0) {
      if ((got = number(v, 1, 1e6)) < 0 || got != (int)got) return usage("--repeats: 1 to 1e6");
      repeats = (int)got;
    } else if (strcmp(o, "--min-time") == 0) {
      if ((min_time = number(v, 0, 3600)) < 0) return usage("--min-time: 0 to 3600 seconds");
    } else if (strcmp(o, "--seed") == 0) {
      if ((got = number(v, 0, 1e18)) < 0 || got != (double)(uint64_t)got) {
        return usage("--seed: a whole number");
      }
      seed = (uint64_t)got;
    } else {
      return usage("unknown option");
    }
    i++;
  }
  if (nd < 0) return usage("--n is required");
  const size_t n = (size_t)nd;
  double *x = malloc(n * (size_t)dim * sizeof *x);
  uint32_t *order = malloc(n * sizeof *order);
  double *out[3] = {NULL, NULL, NULL};
  int ok = x && order;
  for (int a = 0; a < dim && ok; a++) ok = (out[a] = malloc(n * sizeof *out[a])) != NULL;
  if (!ok) {
    fprintf(stderr, "nbs_floor: out of memory for N = %zu\n", n);
    return 1;
  }
  /* every page written before the clock runs, as a caller's coordinates and the library's
   * arrays are after a first detection */
  for (size_t i = 0; i < n * (size_t)dim; i++) x[i] = (double)i;
  for (int a = 0; a < dim; a++) memset(out[a], 0, n * sizeof *out[a]);
  uint64_t s = seed * 0x9E3779B97F4A7C15ull + 0x2545F4914F6CDD1Dull;
  for (size_t i = 0; i < n; i++) order[i] = (uint32_t)i;
  for (size_t i = n - 1; i > 0; i--) {
    s ^= s << 13;
    s ^= s >> 7;
    s ^= s << 17;
    const size_t j = (size_t)(s % (i + 1));
    const uint32_t t = order[i];
    order[i] = order[j];
    order[j] = t;
  }
  const char *names[2] = {"floor-gather", "floor-copy"};
  double sum = 0;
  for (int k = 0; k < 2; k++) {
    double best = 1e300;
    int done = 0;
    const double start = now_seconds();
    while (done < repeats || now_seconds() - start < min_time) {
      for (int ask = 0; ask < (k == 0 ? 2 : 1); ask++) {
        const double t0 = now_seconds();
        if (k == 0) gather(x, order, n, dim, out, ask);
        else copy(x, n, dim, out);
        const double t = now_seconds() - t0;
        if (t < best) best = t;
      }
      done++;
      sum += out[dim - 1][n / 2]; /* read, so the copies are not dropped */
    }
    printf("tool=%s status=ok n=%zu dim=%d seconds=%.9g ns_per_element=%.4f repeats=%d\n",
           names[k], n, dim, best, best / (double)n * 1e9, done);
  }
  if (sum < 0) puts("");
  for (int a = 0; a < dim; a++) free(out[a]);
  free(order);
  free(x);
  return 0;
}
