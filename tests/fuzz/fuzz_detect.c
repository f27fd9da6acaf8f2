/*
 * Fuzz target for the detection API: a scene is built from the fuzz bytes, every algorithm
 * runs on it in both modes, and everything is compared with a brute-force evaluation of the
 * contract done here, independently of the library:
 *   - contacts, sorted with nbs_sort_pairs, are byte-identical to the brute force's (and so
 *     to direct's) for every algorithm;
 *   - candidates are well formed (0 <= i < j < n, no pair twice) and contain the contacts;
 *   - the status is OK, or exactly one of the documented refusals, predicted here from the
 *     grid of src/input.c: screening NBS_ERR_EXTENT / NBS_ERR_BUDGET, nbs NBS_ERR_EXTENT /
 *     NBS_ERR_BUDGET, cellsort NBS_ERR_EXTENT, NBS_ERR_PAIRS when the context's max_pairs
 *     is passed; auto, sorting and direct never refuse finite input. Invalid input (a raw
 *     NaN or infinity, a radius that rounds to 0) must give NBS_ERR_COORD / NBS_ERR_RADIUS
 *     naming the first element;
 *   - statistics agree with the pairs; list heads are empty after every detection (or the
 *     layout is forgotten after an error); a repeated detection gives the same bytes in the
 *     same order; the context's byte count matches its allocator's; nothing leaks;
 *   - time steps: after cellsort's and auto's detections the elements move (by the bytes
 *     after the scene, or a fixed pattern) and the same context detects them, starting from
 *     its last cell order: the status and the pairs, in order, must be a fresh context's
 *     from scratch (nbs_detect_def.fresh); the detections after it start from the moved
 *     order and are checked against the contract as every other;
 *   - fault injection: one allocation (the k-th after the context's creation) may fail; the
 *     detection that meets it returns NBS_ERR_NOMEM, and every later one is correct.
 *
 * The doubles are adversarial on purpose: lattices whose step is exactly the contact
 * distance or the cell edge (ties and centres on cell faces), copies of other elements'
 * coordinates (identical points), neighbours placed at exactly ri + rj and one ulp either
 * side, offsets such as 1e15, 1e300 and +-1.7e308 (differences overflow), denormals, raw bit
 * patterns, diameters whose square underflows or overflows, radius ratios up to 1e6.
 *
 * Input layout (every read past the end yields 0, so any byte string is a scene):
 *   flags  bit 0 3D, bit 1 per-element radii, bit 2 callback sink, bit 3 max_pairs,
 *          bits 4-5 cell budget (1 MiB, 64 KiB, u16 bytes, 4 * u8 bytes), bit 6 reserve,
 *          bit 7 fail one allocation
 *   n      u8 % 65
 *   diam   u8: index into diameters[], else 8 raw bytes
 *   [budget u16 / u8] [max_pairs u16] [reserve u8] [failing allocation u8]
 *   origin u8 per axis (origins[], else 8 raw bytes); unit u8 (a step, see fz_unit)
 *   radii  u8 per element (radius ratios), when per-element
 *   coords u8 opcode (+ operands) per element and axis, see fz_coordinate
 *   moves  u8 per element and axis for the time step, see fz_step (what is left)
 *
 * N is at most 64, so one input runs in well under a millisecond of library time.
 */
#include "internal.h"
#include "fz_bytes.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The reference evaluation of the contract must not be contracted into a fused
 * multiply-add (the library is built with -ffp-contract=off); GCC in ISO C mode does not
 * contract, clang does unless told. */
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#endif

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define FZ_MAX_N 64
#define FZ_MAX_PAIRS (FZ_MAX_N * (FZ_MAX_N - 1) / 2)

/* ---- reading the bytes (fz_bytes.h) ------------------------------------------------------ */

static double fz_raw(fz_reader *r) {
  uint64_t b = 0;
  for (int i = 0; i < 8; i++) b |= (uint64_t)fz_u8(r) << (8 * i);
  double v;
  memcpy(&v, &b, sizeof v);
  return v;
}

/* ---- the scene -------------------------------------------------------------------------- */

static const double diameters[] = {
    1.0, 0.5, 2.0, 3.0, 0.1, 1.0 / 3.0, 1e-3, 1e-6, 1e6, 7.0,
    1e-160,                  /* D^2 denormal */
    1e-170,                  /* D^2 underflows to 0 */
    1e-300, 1e-310, 5e-324,  /* denormal diameters (5e-324 / 2 rounds to 0 as a radius) */
    0x1p-498, 0x1p-499, 0x1p-511, 0x1p-1022,
    1e150, 1e154,
    1.3407807929942596e154,  /* sqrt(DBL_MAX): D^2 just finite */
    1.35e154,                /* D^2 overflows: every pair touches */
    1e200, 1e300, DBL_MAX,
};
#define FZ_NDIAM (sizeof diameters / sizeof *diameters)

static const double origins[] = {
    0.0, 1.0, -1.0, 0.5, 1e9, -1e9, 1e15, -1e15, 0x1p52, 0x1p53, -0x1p53, 1e300, -1e300,
    1.7e308, -1.7e308, DBL_MAX, -DBL_MAX, 1e-300, 5e-324, -0.0, 0.1, 123456.789,
};
#define FZ_NORIGIN (sizeof origins / sizeof *origins)

static const double huge_values[] = {
    1e15, -1e15, 1e300, -1e300, 1.7e308, -1.7e308, DBL_MAX, -DBL_MAX,
    0x1p53, 0x1p1000, -0x1p1000, 1e16 + 2.0, 8.98846567431158e307 /* DBL_MAX / 2 */,
    -8.98846567431158e307, 1e308, -1e308,
};
#define FZ_NHUGE (sizeof huge_values / sizeof *huge_values)

static const double tiny_values[] = {
    5e-324, -5e-324, 1e-320, -1e-320, 2.2250738585072014e-308, -2.2250738585072014e-308,
    1e-310, 0.0, -0.0, 1e-300, 0x1p-1022, 0x1p-537, 0x1p-538, 1e-160, 1e-162, 1e-170,
};
#define FZ_NTINY (sizeof tiny_values / sizeof *tiny_values)

/* Radius = (D / 2) * ratio: ratios up to 1e6 between the largest and the smallest. */
static const double ratios[] = {1.0, 1.0, 0.5, 0.999999, 0.1, 1e-3, 1e-6, 1.0 / 3.0};

typedef struct fz_scene {
  int dim;
  int n;
  bool per_radius;
  bool callback;
  double diameter;
  size_t cell_budget;
  size_t max_pairs;
  int reserve; /* -1: none, else the pairs to reserve */
  long fail_at; /* -1: none, else the allocation (counted after the context's) that fails */
  double unit; /* the lattice step */
  double origin[3];
  double x[FZ_MAX_N * 3];
  double r[FZ_MAX_N];
} fz_scene;

/* A positive finite double from raw bytes, or fallback. */
static double fz_positive(double v, double fallback) {
  v = fabs(v);
  return v > 0 && v <= DBL_MAX ? v : fallback;
}

/* The contact distance of elements a and b. */
static double fz_reach(const fz_scene *s, int a, int b) {
  return s->per_radius ? s->r[a] + s->r[b] : s->diameter;
}

/* One coordinate of element k on axis a. Opcode: low 3 bits the kind, high 5 bits p.
 *   0  origin + (p - 16) * unit                    lattice: ties, cell faces
 *   1  copy of element p % k                       identical values
 *   2  element p % k  +- (rk + rj)                 exactly at the contact distance
 *   3  same, one ulp further or nearer             just out of / just in contact
 *   4  huge_values[p]                              overflowing differences
 *   5  tiny_values[p]                              denormals, signed zeros
 *   6  8 raw bytes (may be NaN or infinite: then the input is invalid)
 *   7  origin + unit * u16 / 4096                  uniform-ish over 16 steps */
static double fz_coordinate(fz_reader *rd, fz_scene *s, int k, int a) {
  unsigned op = fz_u8(rd);
  unsigned kind = op & 7, p = op >> 3;
  const int dim = s->dim;
  switch (kind) {
  case 0:
    return s->origin[a] + ((double)p - 16.0) * s->unit;
  case 1:
  case 2:
  case 3: {
    if (k == 0) return s->origin[a];
    int j = (int)(p % (unsigned)k);
    double base = s->x[j * dim + a];
    if (kind == 1) return base;
    double reach = fz_reach(s, k, j);
    double sign = (p & 16) ? -1.0 : 1.0;
    double v = base + sign * reach;
    if (kind == 3) v = nextafter(v, (p & 8) ? INFINITY : -INFINITY);
    return v;
  }
  case 4:
    return huge_values[p % FZ_NHUGE];
  case 5:
    return tiny_values[p % FZ_NTINY];
  case 6:
    return fz_raw(rd);
  default:
    return s->origin[a] + s->unit * ((double)fz_u16(rd) / 4096.0);
  }
}

/* The lattice step, relative to the diameter and the library's cell edge. */
static double fz_unit(unsigned sel, double dmax, double edge) {
  switch (sel % 12) {
  case 0: return dmax;
  case 1: return 0.5 * dmax;
  case 2: return edge;
  case 3: return 0.5 * edge;
  case 4: return 2.0 * dmax;
  case 5: return dmax / 3.0;
  case 6: return nextafter(dmax, INFINITY);
  case 7: return nextafter(dmax, 0.0);
  case 8: return nextafter(edge, 0.0);
  case 9: return 1.0;
  case 10: return 0.25 * dmax;
  default: return 1.5 * edge;
  }
}

/* ---- the grid of src/input.c, recomputed ------------------------------------------------ */

typedef struct fz_grid {
  double edge;
  int64_t n[3];
  bool fits;
} fz_grid;

static fz_grid fz_make_grid(const fz_scene *s) {
  fz_grid g;
  double rmax = 0.0;
  if (s->per_radius) {
    for (int k = 0; k < s->n; k++) rmax = s->r[k] > rmax ? s->r[k] : rmax;
  }
  double dmax = s->per_radius ? 2.0 * rmax : s->diameter;
  double inv;
  if (!(dmax * dmax <= DBL_MAX)) {
    g.edge = INFINITY;
    inv = 0.0;
  } else {
    g.edge = (dmax > 0x1p-498 ? dmax : 0x1p-498) * (1.0 + 0x1p-18);
    inv = 1.0 / g.edge;
  }
  g.fits = true;
  for (int a = 0; a < 3; a++) g.n[a] = 1;
  for (int a = 0; a < s->dim && s->n > 0; a++) {
    double lo = s->x[a], hi = s->x[a];
    for (int k = 1; k < s->n; k++) {
      double v = s->x[k * s->dim + a];
      lo = v < lo ? v : lo;
      hi = v > hi ? v : hi;
    }
    double top = (hi - lo) * inv;
    if (inv == 0.0) {
      g.n[a] = 1; /* an infinite edge: one cell, even when the extent overflows */
    } else if (top < 0x1p30) {
      g.n[a] = (int64_t)top + 1;
    } else {
      g.n[a] = -1;
      g.fits = false;
    }
  }
  return g;
}

/* ---- failure report --------------------------------------------------------------------- */

static void fz_dump(const fz_scene *s) {
  fprintf(stderr,
          "scene: dim %d, n %d, %s %a, budget %zu, max_pairs %zu, %s sink, reserve %d, "
          "failing allocation %ld\n",
          s->dim, s->n, s->per_radius ? "per-element radii, largest diameter about" : "diameter",
          s->diameter, s->cell_budget, s->max_pairs, s->callback ? "callback" : "buffer",
          s->reserve, s->fail_at);
  for (int k = 0; k < s->n; k++) {
    fprintf(stderr, "  %2d:", k);
    for (int a = 0; a < s->dim; a++) fprintf(stderr, " %a", s->x[k * s->dim + a]);
    if (s->per_radius) fprintf(stderr, "  r %a", s->r[k]);
    fputc('\n', stderr);
  }
}

#define FZ_FAIL(s, ...)                                                                       \
  do {                                                                                        \
    fprintf(stderr, "fuzz_detect: ");                                                         \
    fprintf(stderr, __VA_ARGS__);                                                             \
    fputc('\n', stderr);                                                                      \
    fz_dump(s);                                                                               \
    abort();                                                                                  \
  } while (0)

/* ---- pairs ------------------------------------------------------------------------------ */

typedef struct fz_pairs {
  nbs_pair p[FZ_MAX_PAIRS];
  size_t count;
  bool overflow;
  size_t batches;
} fz_pairs;

static int fz_collect(void *user, const nbs_pair *pairs, size_t count) {
  fz_pairs *out = user;
  out->batches++;
  if (count == 0 || count > FZ_MAX_PAIRS - out->count) {
    out->overflow = true;
    return 1;
  }
  memcpy(out->p + out->count, pairs, count * sizeof *pairs);
  out->count += count;
  return 0;
}

/* 0 <= i < j < n for every pair, and (once sorted) no pair twice. */
static bool fz_well_formed(const fz_pairs *l, int n) {
  for (size_t k = 0; k < l->count; k++) {
    if (l->p[k].i < 0 || l->p[k].i >= l->p[k].j || l->p[k].j >= n) return false;
    if (k > 0 && l->p[k - 1].i == l->p[k].i && l->p[k - 1].j == l->p[k].j) return false;
  }
  return true;
}

static bool fz_contains(const fz_pairs *super, const fz_pairs *sub) {
  size_t i = 0;
  for (size_t k = 0; k < sub->count; k++) {
    while (i < super->count && (super->p[i].i < sub->p[k].i ||
                                (super->p[i].i == sub->p[k].i && super->p[i].j < sub->p[k].j)))
      i++;
    if (i == super->count || super->p[i].i != sub->p[k].i || super->p[i].j != sub->p[k].j)
      return false;
  }
  return true;
}

static bool fz_equal(const fz_pairs *a, const fz_pairs *b) {
  return a->count == b->count &&
         (a->count == 0 || memcmp(a->p, b->p, a->count * sizeof *a->p) == 0);
}

/* The contract, evaluated here with the same operations in the same order. */
static bool fz_touch(const fz_scene *s, int a, int b) {
  const double *pa = s->x + a * s->dim, *pb = s->x + b * s->dim;
  double dx = pa[0] - pb[0], dy = pa[1] - pb[1];
  double sum = dx * dx + dy * dy;
  if (s->dim == 3) {
    double dz = pa[2] - pb[2];
    sum += dz * dz;
  }
  double lim;
  if (s->per_radius) {
    double rr = s->r[a] + s->r[b];
    lim = rr * rr;
  } else {
    lim = s->diameter * s->diameter;
  }
  return sum <= lim;
}

/* ---- a counting allocator --------------------------------------------------------------- */

typedef struct fz_alloc {
  size_t live_bytes;
  long live;
  long calls, fail_at; /* the call numbered fail_at fails (none when < 0) */
  bool failed;         /* a call failed since the flag was last cleared */
} fz_alloc;

static void *fz_alloc_fn(void *opaque, size_t size) {
  fz_alloc *a = opaque;
  if (a->calls++ == a->fail_at) {
    a->failed = true;
    return NULL;
  }
  void *p = malloc(size);
  if (p) {
    a->live_bytes += size;
    a->live++;
  }
  return p;
}

static void fz_free_fn(void *opaque, void *ptr, size_t size) {
  fz_alloc *a = opaque;
  a->live_bytes -= size;
  a->live--;
  free(ptr);
}

/* ---- one detection, checked ------------------------------------------------------------- */

/* Detections that took cellsort's crowded-core path (nbs__cs_core): replay prints it. */
static long fz_core_detections;

void fz_summary(void);
void fz_summary(void) {
  printf("%ld detections took cellsort's crowded-core path\n", fz_core_detections);
}

typedef struct fz_run {
  const fz_scene *s;
  nbs_context *ctx;
  nbs_input in;
  fz_grid grid;
  nbs_status want_invalid; /* NBS_OK, or the validation error every detection must give */
  int64_t want_element;
  fz_alloc *alloc;
  fz_reader moves; /* the bytes after the scene */
} fz_run;

/* Bits needed for the values 0 .. count - 1 (cellsort's packed cell key). */
static int fz_bits(int64_t count) {
  int b = 0;
  while (b < 64 && ((uint64_t)count - 1) >> b) b++;
  return b;
}

/* NBS's lists per axis: the cells of each axis of the grid, or fewer where NBS folds the
 * axis. Which axes it folds is the library's choice (nbs__nbs_fold, asked here on the grid
 * the library derives); what a folded axis must be is checked: a power of two >= 4 (so
 * that the offsets -1, 0, +1 stay distinct), fewer than the axis's cells. Its pairs are
 * checked against direct checking like any other. */
static void fz_nbs_lists(const fz_run *R, int64_t l[3]) {
  nbs__run run;
  memset(&run, 0, sizeof run);
  run.ctx = R->ctx;
  if (nbs__prepare(&run, &R->in) != NBS_OK) {
    fprintf(stderr, "fuzz_detect: nbs__prepare refused an input the model calls valid\n");
    abort();
  }
  nbs__nbs_fold(&run, l);
  for (int a = 0; a < R->s->dim; a++) {
    const int64_t n = R->grid.n[a];
    if (l[a] != n && !(l[a] >= 4 && (l[a] & (l[a] - 1)) == 0 && l[a] < n)) {
      fprintf(stderr, "fuzz_detect: NBS folds %lld cells on axis %d onto %lld lists\n",
              (long long)n, a, (long long)l[a]);
      fz_dump(R->s);
      abort();
    }
  }
}

/* The status a detection must return, apart from NBS_ERR_PAIRS (checked by the caller): the
 * documented refusals of each algorithm, predicted from the grid. An algorithm not listed
 * here must succeed on every finite input; a new algorithm with refusals of its own must
 * add them here. */
static nbs_status fz_expected(const fz_run *R, nbs_algorithm algo) {
  const fz_scene *s = R->s;
  if (R->want_invalid != NBS_OK) return R->want_invalid;
  if (s->n < 2) return NBS_OK;
  const fz_grid *g = &R->grid;
  switch (algo) {
  case NBS_SCREENING: {
    if (!g->fits) return NBS_ERR_EXTENT;
    /* padded cells: (nx+2)(ny+1) in 2D, (nx+2)(ny+2)(nz+1) in 3D; every axis <= 2^30 */
    long double cells =
        (long double)(g->n[0] + 2) * (long double)(g->n[1] + (s->dim == 3 ? 2 : 1));
    if (s->dim == 3) cells *= (long double)(g->n[2] + 1);
    return cells * 4.0L > (long double)s->cell_budget ? NBS_ERR_BUDGET : NBS_OK;
  }
  case NBS_NBS: {
    if (!g->fits) return NBS_ERR_EXTENT;
    int64_t l[3];
    fz_nbs_lists(R, l);
    /* heads (A: 2 (nx+2); 3D B: 2 (ny+2); and one per list of the elements, B: ny+2 in 2D,
     * C: nz+2 in 3D), the counts of the lists of the elements
     * (ny+2 or nz+2) and the records of started lists (2 (nx+1), those of the elements'
     * lists, ny+1 or nz+1, and 2 (ny+1) in 3D), all int32, with nx, ny, nz the lists per
     * axis */
    /* in NBS's order of the axes: the outer one (layers; 2D rows) is, of the others, the one
     * with the most lists (the later of equals) where it has at least twice as many as the
     * last axis; the rest keep their order */
    const int d = s->dim;
    int best = 0;
    for (int a = 1; a < d - 1; a++) best = l[a] >= l[best] ? a : best;
    const int top = l[best] >= 2 * l[d - 1] ? best : d - 1;
    int64_t m[3] = {1, 1, 1};
    for (int a = 0, j = 0; a < d; a++) {
      if (a != top) m[j++] = l[a];
    }
    m[d - 1] = l[top];
    const int64_t nl = m[d - 1];
    int64_t heads = 2 * (m[0] + 2) + (d == 3 ? 2 * (m[1] + 2) : 0) + nl + 2;
    int64_t counts = nl + 2;
    int64_t records = 2 * (m[0] + 1) + nl + 1 + (d == 3 ? 2 * (m[1] + 1) : 0);
    return (uint64_t)(heads + counts + records) * 4u > s->cell_budget ? NBS_ERR_BUDGET
                                                                     : NBS_OK;
  }
  case NBS_CELLSORT: {
    if (!g->fits) return NBS_ERR_EXTENT;
    int bits = fz_bits(g->n[0]) + fz_bits(g->n[1]) + (s->dim == 3 ? fz_bits(g->n[2]) : 0);
    return bits > 64 ? NBS_ERR_EXTENT : NBS_OK;
  }
  default:
    return NBS_OK;
  }
}

/* Runs algo in mode; fills *out (sorted) and returns the status. Checks everything that does
 * not need the reference. */
static nbs_status fz_detect(const fz_run *R, nbs_algorithm algo, nbs_mode mode, fz_pairs *out,
                            bool sort) {
  const fz_scene *s = R->s;
  const char *name = nbs_algorithm_name(algo);
  const char *mname = mode == NBS_MODE_CONTACTS ? "contacts" : "candidates";
  nbs_detect_def def = nbs_default_detect_def();
  def.algorithm = algo;
  def.mode = mode;
  out->count = 0;
  out->overflow = false;
  out->batches = 0;
  if (s->callback) {
    def.callback = fz_collect;
    def.user = out;
  }
  R->alloc->failed = false;
  nbs_status st = nbs_detect(R->ctx, &R->in, &def);
  if (out->overflow) FZ_FAIL(s, "%s %s: the callback received more pairs than exist", name, mname);

  nbs_status want = fz_expected(R, algo);
  /* A failed allocation ends the detection with NBS_ERR_NOMEM, whatever it would have
   * returned (the pair buffer is set up before an algorithm can refuse). */
  if (R->alloc->failed) want = NBS_ERR_NOMEM;
  bool pairs_limit = st == NBS_ERR_PAIRS && s->max_pairs && !s->callback && want == NBS_OK;
  if (st != want && !pairs_limit) {
    FZ_FAIL(s, "%s %s: status %s, expected %s (%s)", name, mname, nbs_status_name(st),
            nbs_status_name(want), nbs_context_error(R->ctx));
  }
  if (st == NBS_ERR_COORD || st == NBS_ERR_RADIUS) {
    if (nbs_context_error_element(R->ctx) != R->want_element) {
      FZ_FAIL(s, "%s: the error names element %lld, expected %lld", name,
              (long long)nbs_context_error_element(R->ctx), (long long)R->want_element);
    }
  }
  if (st != NBS_OK && nbs_context_error(R->ctx)[0] == '\0') {
    FZ_FAIL(s, "%s %s: status %s without a message", name, mname, nbs_status_name(st));
  }
  /* Between detections every list head is empty, or the layout was forgotten. */
  if (!nbs__heads_empty(R->ctx) && !(st != NBS_OK && R->ctx->work_kind == NBS__WORK_NONE)) {
    FZ_FAIL(s, "%s %s: list heads left dirty (status %s)", name, mname, nbs_status_name(st));
  }

  nbs_stats stats;
  if (nbs_last_stats(R->ctx, &stats) != NBS_OK) FZ_FAIL(s, "nbs_last_stats failed");
  size_t count;
  const nbs_pair *p = nbs_pairs(R->ctx, &count);
  if (st == NBS_ERR_PAIRS) {
    if (stats.pairs != s->max_pairs) {
      FZ_FAIL(s, "%s %s: NBS_ERR_PAIRS with %llu pairs counted, max_pairs %zu", name, mname,
              (unsigned long long)stats.pairs, s->max_pairs);
    }
  }
  if (st != NBS_OK) {
    if (p != NULL || count != 0) FZ_FAIL(s, "%s %s: pairs left after an error", name, mname);
    return st;
  }
  if (stats.algorithm == NBS_CELLSORT && s->n >= 2 && R->ctx->cs_outliers >= 0) {
    fz_core_detections++;
  }

  if (s->callback) {
    if (p != NULL || count != 0) {
      FZ_FAIL(s, "%s %s: buffer not empty in callback mode", name, mname);
    }
  } else {
    if (count > FZ_MAX_PAIRS) FZ_FAIL(s, "%s %s: %zu pairs, more than exist", name, mname, count);
    if (count) memcpy(out->p, p, count * sizeof *p);
    out->count = count;
    if (s->max_pairs && count > s->max_pairs) {
      FZ_FAIL(s, "%s %s: %zu pairs passed max_pairs %zu", name, mname, count, s->max_pairs);
    }
  }
  if (stats.pairs != out->count) {
    FZ_FAIL(s, "%s %s: stats count %llu pairs, %zu delivered", name, mname,
            (unsigned long long)stats.pairs, out->count);
  }
  if (mode == NBS_MODE_CANDIDATES ? stats.candidates != stats.pairs
                                  : stats.candidates < stats.pairs) {
    FZ_FAIL(s, "%s %s: %llu candidates for %llu pairs", name, mname,
            (unsigned long long)stats.candidates, (unsigned long long)stats.pairs);
  }
  if (algo == NBS_AUTO ? ((int)stats.algorithm <= (int)NBS_AUTO ||
                          (int)stats.algorithm >= (int)NBS_ALGORITHM_COUNT)
                       : stats.algorithm != algo) {
    FZ_FAIL(s, "%s %s: the statistics name algorithm %d", name, mname, (int)stats.algorithm);
  }
  if (stats.n != s->n || stats.dim != s->dim || stats.mode != mode) {
    FZ_FAIL(s, "%s %s: statistics of another detection", name, mname);
  }
  if (s->n >= 2 && stats.algorithm != NBS_DIRECT && R->want_invalid == NBS_OK &&
      memcmp(&stats.cell_size, &R->grid.edge, sizeof(double)) != 0) {
    FZ_FAIL(s, "%s %s: cell size %a, the grid of src/input.c gives %a", name, mname,
            stats.cell_size, R->grid.edge);
  }
  if (sort) nbs_sort_pairs(out->p, out->count);
  if (sort && !fz_well_formed(out, s->n)) {
    FZ_FAIL(s, "%s %s: a pair breaks 0 <= i < j < n or is reported twice", name, mname);
  }
  return NBS_OK;
}

/* A time step (see the file comment): each coordinate moves by (b % 16 - 8) / 16 units for
 * its byte b of R->moves when b < 128, else stays (past the end of the bytes, element k
 * moves on axis a when (3k + a) % 5 == 0, by (k % 7 - 3) / 16 units). The same context
 * detects the moved elements, and a fresh one, made alike, from scratch: the same status,
 * and in contact mode through the buffer the same bytes in the same order. The context
 * then holds the moved order; the caller's detections that follow start from it. */
static void fz_step(fz_run *R, nbs_algorithm algo) {
  const fz_scene *s = R->s;
  static double x[FZ_MAX_N * 3];
  fz_reader rd = R->moves;
  for (int k = 0; k < s->n; k++) {
    for (int a = 0; a < s->dim; a++) {
      const int i = k * s->dim + a;
      const unsigned b =
          rd.left ? fz_u8(&rd) : ((3 * k + a) % 5 == 0 ? (unsigned)(k % 7 + 5) : 128);
      x[i] = s->x[i] + (b < 128 ? (double)((int)(b % 16) - 8) / 16.0 * s->unit : 0.0);
    }
  }
  nbs_input in = R->in;
  in.coords = x;
  nbs_detect_def def = nbs_default_detect_def();
  def.algorithm = algo;
  R->alloc->failed = false;
  nbs_status st = nbs_detect(R->ctx, &in, &def);
  if (R->alloc->failed) return; /* fz_detect checks NBS_ERR_NOMEM; here only the result */
  nbs_context_def cdef = nbs_default_context_def();
  cdef.cell_budget = s->cell_budget;
  cdef.max_pairs = s->max_pairs;
  nbs_context *fresh;
  if (nbs_context_create(&cdef, &fresh) != NBS_OK) FZ_FAIL(s, "nbs_context_create failed");
  def.fresh = 1;
  nbs_status fst = nbs_detect(fresh, &in, &def);
  if (st != fst) {
    FZ_FAIL(s, "%s after a step: status %s, from scratch %s", nbs_algorithm_name(algo),
            nbs_status_name(st), nbs_status_name(fst));
  } else if (st == NBS_OK) {
    size_t c1, c2;
    const nbs_pair *p1 = nbs_pairs(R->ctx, &c1), *p2 = nbs_pairs(fresh, &c2);
    if (c1 != c2 || (c1 && memcmp(p1, p2, c1 * sizeof *p1) != 0)) {
      FZ_FAIL(s, "%s after a step: %zu pairs, from scratch %zu, or another order",
              nbs_algorithm_name(algo), c1, c2);
    }
  }
  nbs_context_destroy(fresh);
}

static void fz_check(fz_run *R) {
  const fz_scene *s = R->s;
  static fz_pairs ref, got, again;

  /* The reference: the contract evaluated here, pairs in (i, j) order. */
  ref.count = 0;
  if (R->want_invalid == NBS_OK) {
    for (int i = 0; i < s->n; i++) {
      for (int j = i + 1; j < s->n; j++) {
        if (fz_touch(s, i, j)) ref.p[ref.count++] = (nbs_pair){i, j};
      }
    }
  }
  const size_t all = s->n > 1 ? (size_t)s->n * (size_t)(s->n - 1) / 2 : 0;

  /* direct first (checked against the contract), then auto and every other algorithm */
  for (int a = 0; a < NBS_ALGORITHM_COUNT; a++) {
    const nbs_algorithm algo = a == 0 ? NBS_DIRECT : a == 1 ? NBS_AUTO : (nbs_algorithm)a;
    const char *name = nbs_algorithm_name(algo);

    nbs_status st = fz_detect(R, algo, NBS_MODE_CONTACTS, &got, false);
    if (st == NBS_OK) {
      /* The same input again, in the same context: the same bytes in the same order (unless
       * this detection met the failing allocation, which fz_detect has checked). */
      if (fz_detect(R, algo, NBS_MODE_CONTACTS, &again, false) == NBS_OK &&
          !fz_equal(&got, &again)) {
        FZ_FAIL(s, "%s: a repeated detection differs", name);
      }
      if (algo == NBS_CELLSORT || algo == NBS_AUTO) fz_step(R, algo);
      nbs_sort_pairs(got.p, got.count);
      if (!fz_well_formed(&got, s->n)) FZ_FAIL(s, "%s: contacts not well formed", name);
      if (!fz_equal(&got, &ref)) {
        FZ_FAIL(s, "%s: %zu contacts, the contract gives %zu", name, got.count, ref.count);
      }
    } else if (st == NBS_ERR_PAIRS) {
      if (ref.count <= s->max_pairs) {
        FZ_FAIL(s, "%s: NBS_ERR_PAIRS for %zu contacts, max_pairs %zu", name, ref.count,
                s->max_pairs);
      }
    }
    if (st == NBS_OK && s->max_pairs && !s->callback && ref.count > s->max_pairs) {
      FZ_FAIL(s, "%s: %zu contacts delivered past max_pairs %zu", name, ref.count, s->max_pairs);
    }

    st = fz_detect(R, algo, NBS_MODE_CANDIDATES, &got, true);
    if (st == NBS_OK) {
      if (!fz_contains(&got, &ref)) FZ_FAIL(s, "%s: the candidates miss a contact", name);
      if (algo == NBS_DIRECT && got.count != all) {
        FZ_FAIL(s, "direct: %zu candidates, %zu pairs exist", got.count, all);
      }
    }
  }

  /* After every refusal above, the context still detects correctly. */
  if (fz_detect(R, NBS_SORTING, NBS_MODE_CONTACTS, &got, true) == NBS_OK && !fz_equal(&got, &ref)) {
    FZ_FAIL(s, "sorting: wrong contacts at the end of the run");
  }
}

/* ---- the entry point -------------------------------------------------------------------- */

static void fz_build(fz_reader *rd, fz_scene *s) {
  memset(s, 0, sizeof *s);
  unsigned flags = fz_u8(rd);
  s->dim = (flags & 1) ? 3 : 2;
  s->per_radius = (flags & 2) != 0;
  s->callback = (flags & 4) != 0;
  s->n = (int)(fz_u8(rd) % (FZ_MAX_N + 1));
  unsigned dsel = fz_u8(rd);
  s->diameter = dsel < FZ_NDIAM ? diameters[dsel] : fz_positive(fz_raw(rd), 1.0);
  switch ((flags >> 4) & 3) {
  case 0: s->cell_budget = (size_t)1 << 20; break;
  case 1: s->cell_budget = (size_t)1 << 16; break;
  case 2: s->cell_budget = fz_u16(rd); break;
  default: s->cell_budget = 4 * (size_t)fz_u8(rd); break;
  }
  s->max_pairs = (flags & 8) ? 1 + fz_u16(rd) % 2500 : 0;
  s->reserve = (flags & 64) ? (int)fz_u8(rd) * 8 : -1;
  s->fail_at = (flags & 128) ? (long)fz_u8(rd) : -1;
  for (int a = 0; a < s->dim; a++) {
    unsigned o = fz_u8(rd);
    s->origin[a] = o < FZ_NORIGIN ? origins[o] : fz_raw(rd);
    if (!isfinite(s->origin[a])) s->origin[a] = 0.0;
  }
  unsigned usel = fz_u8(rd);

  /* Radii first, so that coordinates can be placed at exactly ri + rj. */
  double rmax = 0.0;
  if (s->per_radius) {
    for (int k = 0; k < s->n; k++) {
      unsigned q = fz_u8(rd);
      s->r[k] = q == 255 ? fabs(fz_raw(rd)) : 0.5 * s->diameter * ratios[q % 8];
      if (s->r[k] > rmax && s->r[k] <= DBL_MAX) rmax = s->r[k];
    }
  }
  double dmax = s->per_radius ? 2.0 * rmax : s->diameter;
  double edge = (dmax > 0x1p-498 ? dmax : 0x1p-498) * (1.0 + 0x1p-18);
  s->unit = fz_unit(usel, dmax > 0 ? dmax : 1.0, isfinite(edge) ? edge : dmax);
  if (!(s->unit > 0 && s->unit <= DBL_MAX)) s->unit = 1.0;
  for (int k = 0; k < s->n; k++) {
    for (int a = 0; a < s->dim; a++) s->x[k * s->dim + a] = fz_coordinate(rd, s, k, a);
  }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  fz_reader rd = {data, size};
  static fz_scene s;
  fz_build(&rd, &s);

  fz_run R;
  memset(&R, 0, sizeof R);
  R.s = &s;
  R.moves = rd;
  R.in.dim = s.dim;
  R.in.n = s.n;
  R.in.coords = s.x;
  R.in.radii = s.per_radius ? s.r : NULL;
  R.in.diameter = s.diameter;

  /* The validation the library must do, in its order: every coordinate, then every radius. */
  R.want_invalid = NBS_OK;
  R.want_element = -1;
  for (int k = 0; k < s.n * s.dim && R.want_invalid == NBS_OK; k++) {
    if (!isfinite(s.x[k])) {
      R.want_invalid = NBS_ERR_COORD;
      R.want_element = k / s.dim;
    }
  }
  for (int k = 0; k < s.n && s.per_radius && R.want_invalid == NBS_OK; k++) {
    if (!(s.r[k] > 0 && s.r[k] <= DBL_MAX)) {
      R.want_invalid = NBS_ERR_RADIUS;
      R.want_element = k;
    }
  }
  if (R.want_invalid == NBS_OK) R.grid = fz_make_grid(&s);

  fz_alloc counter = {0, 0, 0, -1, false};
  nbs_context_def cdef = nbs_default_context_def();
  cdef.allocator.alloc = fz_alloc_fn;
  cdef.allocator.free = fz_free_fn;
  cdef.allocator.opaque = &counter;
  cdef.cell_budget = s.cell_budget;
  cdef.max_pairs = s.max_pairs;
  if (nbs_context_create(&cdef, &R.ctx) != NBS_OK) FZ_FAIL(&s, "nbs_context_create failed");
  R.alloc = &counter;
  if (s.fail_at >= 0) counter.fail_at = counter.calls + s.fail_at;
  if (s.reserve >= 0) {
    counter.failed = false;
    nbs_status st = nbs_context_reserve(R.ctx, s.n, (size_t)s.reserve);
    if (st != (counter.failed ? NBS_ERR_NOMEM : NBS_OK)) {
      FZ_FAIL(&s, "nbs_context_reserve(%d, %d): %s", s.n, s.reserve, nbs_status_name(st));
    }
  }

  fz_check(&R);

  if (nbs_context_bytes(R.ctx) != counter.live_bytes) {
    FZ_FAIL(&s, "the context counts %zu bytes, its allocator holds %zu",
            nbs_context_bytes(R.ctx), counter.live_bytes);
  }
  nbs_context_destroy(R.ctx);
  if (counter.live != 0 || counter.live_bytes != 0) {
    FZ_FAIL(&s, "%ld blocks (%zu bytes) not freed", counter.live, counter.live_bytes);
  }
  return 0;
}
