/*
 * Fuzz target for cellsort's partitions (src/cellsort.c): nbs__cs_partition, the sort by the
 * keys' top digit with the coordinates carried along, and nbs__cs_core_part, the same for the
 * elements of a crowded core where a few far elements stretch the grid, with the outliers put
 * in their places apart. fuzz_detect's scenes (64 elements at most) never reach them: a
 * partition needs two digits or more and at least as many elements as the square of its
 * buckets (4096 for keys of 12 bits, 16384 for 21 bits). This target builds scenes of 1024
 * to 65536 elements from a few bytes: uniform in a box at a packing fraction, on a lattice of
 * 1/8 diameter or not (ties, centres on cell faces), with groups of outliers (an axis, a side,
 * a distance from half a diameter to 2^47 box edges past the box's face, the other
 * coordinates at random, on the box's lowest or highest face or at its corner; in chains that
 * touch, overlap, or just miss) at elements spread over the input or consecutive, and
 * checks:
 *   - a context created with NBS_PARTITION=always (the partitions wherever they can run; =wide,
 *     their top digit widened wherever the keys allow, where the seed is odd) and
 *     one with NBS_PARTITION=never (the sort and the gather) give cellsort's same status and,
 *     where it is NBS_OK, the same pairs in the same order, byte for byte, in the mode and
 *     with the threads (1 to 3) the bytes choose;
 *   - then every element moves (up to 0.2 diameters per axis) and each context detects again
 *     from its last order (a time step, nbs__cs_warm): the same again;
 *   - where N <= FZ_DIRECT_MAX, the contacts, sorted, are direct's.
 * A finding prints the scene's parameters and aborts.
 *
 * Input layout (every read past the end yields 0, so any byte string is a scene):
 *   flags    bit 0 3D, bit 1 per-element radii, bit 2 candidates, bits 3-4 threads (1 + v % 3),
 *            bit 5 on the lattice, bit 6 outliers at consecutive elements, bit 7 the time step
 *   n        u16: 1024 + n % 64513
 *   fraction u8: index into fractions[]
 *   seed     u32: the positions (a splitmix64 stream)
 *   groups   u8 % 9, then 5 bytes each: axis and side; distance; count (1 + c % 48); chain
 *            spacing and axis; where the other coordinates lie
 */
#define _POSIX_C_SOURCE 200809L /* setenv */
#include "internal.h"
#include "fz_bytes.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define FZ_MIN_N 1024
#define FZ_MAX_N 65536
#ifndef FZ_DIRECT_MAX
#define FZ_DIRECT_MAX 2048
#endif

static uint64_t fz_next(uint64_t *s) {
  uint64_t z = (*s += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

/* uniform in [0, 1) */
static double fz_uniform(uint64_t *s) { return (double)(fz_next(s) >> 11) * 0x1p-53; }

static const double fractions[] = {0.5, 0.3, 0.1, 0.02, 0.005, 0.0005, 0.6};
#define FZ_NFRAC (sizeof fractions / sizeof *fractions)

typedef struct fz_scene {
  int dim, threads;
  bool radii, candidates, lattice, consecutive, step;
  int32_t n, groups;
  double edge; /* the box's */
  unsigned frac;
  uint32_t seed;
  double x[FZ_MAX_N * 3], r[FZ_MAX_N];
} fz_scene;

static void fz_dump(const fz_scene *s) {
  fprintf(stderr, "  scene: %dD, n %d, fraction %g (box edge %g), seed %u, %d groups of outliers, "
          "radii %d, candidates %d, lattice %d, consecutive %d, time step %d, %d threads\n",
          s->dim, (int)s->n, fractions[s->frac], s->edge, (unsigned)s->seed, (int)s->groups,
          s->radii, s->candidates, s->lattice, s->consecutive, s->step, s->threads);
}

#define FZ_FAIL(s, ...)                                                                       \
  do {                                                                                        \
    fprintf(stderr, "fuzz_partition: ");                                                      \
    fprintf(stderr, __VA_ARGS__);                                                             \
    fputc('\n', stderr);                                                                      \
    fz_dump(s);                                                                               \
    abort();                                                                                  \
  } while (0)

/* A group of outliers: `count` elements in a chain along axis `chain`, `gap` apart, the
 * first `dist` past the box's face on axis `axis` (below it or above), the other
 * coordinates at random in the box, at its lowest face, its highest, or its corner. */
static void fz_group(fz_reader *rd, fz_scene *s, uint64_t *rng) {
  const int dim = s->dim;
  const unsigned a = fz_u8(rd), d = fz_u8(rd), c = fz_u8(rd), g = fz_u8(rd), o = fz_u8(rd);
  const int axis = (int)(a % (unsigned)dim);
  const bool below = (a >> 2) & 1;
  /* half a diameter to 63.5 past the face, or 2^0 to 2^47 box edges */
  const double dist = d & 0x80 ? s->edge * ldexp(1.0, (int)(d & 0x7f) % 48) : 0.5 * (d & 0x7f);
  const int count = 1 + (int)(c % 48);
  static const double gaps[] = {0.6, 0.95, 1.0, 3.0};
  const double gap = gaps[g % 4];
  const int chain = (int)((g >> 2) % (unsigned)dim);
  int32_t k = (int32_t)(fz_next(rng) % (uint64_t)s->n);
  double p[3];
  for (int b = 0; b < dim; b++) {
    switch (o % 4) {
    case 0: p[b] = fz_uniform(rng) * s->edge; break;
    case 1: p[b] = 0.0; break;
    case 2: p[b] = s->edge; break;
    default: p[b] = b == dim - 1 ? s->edge * fz_uniform(rng) : 0.0; break;
    }
  }
  p[axis] = below ? -dist : s->edge + dist;
  for (int m = 0; m < count; m++) {
    for (int b = 0; b < dim; b++) s->x[(size_t)k * dim + b] = p[b] + (b == chain ? gap * m : 0.0);
    k = s->consecutive ? (k + 1) % s->n : (int32_t)(fz_next(rng) % (uint64_t)s->n);
  }
}

static void fz_build(fz_reader *rd, fz_scene *s) {
  const unsigned flags = fz_u8(rd);
  s->dim = flags & 1 ? 3 : 2;
  s->radii = flags & 2;
  s->candidates = flags & 4;
  s->threads = 1 + (int)((flags >> 3) & 3) % 3;
  s->lattice = flags & 32;
  s->consecutive = flags & 64;
  s->step = flags & 128;
  s->n = FZ_MIN_N + (int32_t)(fz_u16(rd) % (FZ_MAX_N - FZ_MIN_N + 1));
  s->frac = fz_u8(rd) % FZ_NFRAC;
  s->seed = fz_u16(rd) | (uint32_t)fz_u16(rd) << 16;
  const double pi = 3.14159265358979323846;
  const double unit = s->dim == 3 ? pi / 6.0 : pi / 4.0; /* an element's volume, D = 1 */
  s->edge = pow((double)s->n * unit / fractions[s->frac], 1.0 / s->dim);
  uint64_t rng = s->seed;
  for (int32_t k = 0; k < s->n * s->dim; k++) {
    const double v = fz_uniform(&rng) * s->edge;
    s->x[k] = s->lattice ? floor(v * 8.0) * 0.125 : v;
  }
  for (int32_t k = 0; k < s->n; k++) s->r[k] = 0.05 + 0.45 * fz_uniform(&rng);
  s->groups = (int32_t)(fz_u8(rd) % 9);
  for (int32_t j = 0; j < s->groups; j++) fz_group(rd, s, &rng);
}

/* Partitioned detections (of the always context), those by the crowded core, and those
 * whose top digit was widened: replay prints them. */
static long fz_partitioned, fz_core_partitioned, fz_widened;

void fz_summary(void);
void fz_summary(void) {
  printf("%ld detections partitioned, %ld of them by the crowded core, %ld with the top digit "
         "widened\n", fz_partitioned, fz_core_partitioned, fz_widened);
}

typedef struct fz_result {
  nbs_status st;
  size_t count;
  nbs_pair *p; /* a copy of the pairs */
} fz_result;

static fz_result fz_detect(nbs_context *ctx, const fz_scene *s, nbs_algorithm algo, int fresh,
                           int sorted) {
  nbs_input in = {s->dim, s->n, s->x, s->radii ? s->r : NULL, 1.0};
  nbs_detect_def def = nbs_default_detect_def();
  def.algorithm = algo;
  def.mode = s->candidates ? NBS_MODE_CANDIDATES : NBS_MODE_CONTACTS;
  def.fresh = fresh;
  def.sorted = sorted;
  fz_result r = {nbs_detect(ctx, &in, &def), 0, NULL};
  if (r.st == NBS_OK) {
    const nbs_pair *p = nbs_pairs(ctx, &r.count);
    r.p = malloc((r.count ? r.count : 1) * sizeof *r.p);
    if (!r.p) abort();
    if (r.count) memcpy(r.p, p, r.count * sizeof *p);
  }
  return r;
}

static bool fz_same(const fz_result *a, const fz_result *b) {
  return a->st == b->st && a->count == b->count &&
         (a->count == 0 || memcmp(a->p, b->p, a->count * sizeof *a->p) == 0);
}

static nbs_context *fz_context(const fz_scene *s, const char *way) {
  nbs_context_def cdef = nbs_default_context_def();
  cdef.threads = s->threads;
  nbs_context *ctx = NULL;
  if (setenv("NBS_PARTITION", way, 1) != 0) abort();
  const nbs_status st = nbs_context_create(&cdef, &ctx);
  unsetenv("NBS_PARTITION");
  if (st != NBS_OK) FZ_FAIL(s, "nbs_context_create: %s", nbs_status_name(st));
  return ctx;
}

/* The always context's detection against the never context's. */
static void fz_compare(const fz_scene *s, nbs_context *part, nbs_context *sort, int fresh,
                       const char *what) {
  fz_result a = fz_detect(part, s, NBS_CELLSORT, fresh, 0);
  if (a.st == NBS_OK && part->cs_partitioned) { /* (a time step may sort from scratch) */
    fz_partitioned++;
    if (part->cs_outliers >= 0) fz_core_partitioned++;
    if (part->cs_part_widened) fz_widened++;
  }
  fz_result b = fz_detect(sort, s, NBS_CELLSORT, fresh, 0);
  if (!fz_same(&a, &b)) {
    FZ_FAIL(s, "%s: NBS_PARTITION=always gave %s and %zu pairs (partitioned %d), never %s and "
            "%zu pairs", what, nbs_status_name(a.st), a.count, (int)part->cs_partitioned,
            nbs_status_name(b.st), b.count);
  }
  if (a.st == NBS_OK && !s->candidates && s->n <= FZ_DIRECT_MAX) {
    fz_result d = fz_detect(sort, s, NBS_DIRECT, 1, 1);
    fz_result c = fz_detect(part, s, NBS_CELLSORT, fresh, 1);
    if (!fz_same(&c, &d)) {
      FZ_FAIL(s, "%s: cellsort gave %zu contacts, direct %zu", what, c.count, d.count);
    }
    free(c.p);
    free(d.p);
  }
  free(a.p);
  free(b.p);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  fz_reader rd = {data, size};
  static fz_scene s;
  fz_build(&rd, &s);
  /* an odd seed: the partition's top digit widened wherever the keys allow */
  nbs_context *part = fz_context(&s, s.seed & 1 ? "wide" : "always");
  nbs_context *sort = fz_context(&s, "never");
  fz_compare(&s, part, sort, 1, "from scratch");
  if (s.step) {
    uint64_t rng = s.seed ^ 0x5bd1e995u;
    for (int32_t k = 0; k < s.n * s.dim; k++) s.x[k] += 0.4 * (fz_uniform(&rng) - 0.5);
    fz_compare(&s, part, sort, 0, "a time step");
  }
  nbs_context_destroy(part);
  nbs_context_destroy(sort);
  return 0;
}
