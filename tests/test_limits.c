/*
 * Limits: the inputs at the edges of what nbs accepts, each checked against direct checking
 * (and direct against the contract evaluated here): the element count at the index limit,
 * spreads of more than 2^31 cells on an axis, coordinates near the largest finite double,
 * every element at one point, radius ratios of 1e6, 2D input on one line, denormal
 * diameters, radii so large that (ri + rj)^2 overflows, tight cell budgets, and pair limits
 * with both sinks.
 */
#include "internal.h"
#include "test.h"
#include "util.h"

#include <float.h>
#include <math.h>

/* The reference evaluation of the contract must not be contracted into a fused
 * multiply-add (the library is built with -ffp-contract=off); GCC in ISO C mode does not
 * contract, clang does unless told. */
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#endif

/* ---- helpers --------------------------------------------------------------------------- */

/* A scene made here (coordinates and radii malloc'ed, freed by scene_free). */
static scene new_scene(int dim, int64_t n, double diameter, bool radii) {
  scene s;
  memset(&s, 0, sizeof s);
  s.dim = dim;
  s.n = n;
  s.diameter = diameter;
  s.coords = calloc((size_t)(n > 0 ? n : 1) * (size_t)dim, sizeof(double));
  if (radii) s.radii = calloc((size_t)(n > 0 ? n : 1), sizeof(double));
  if (!s.coords || (radii && !s.radii)) abort();
  if (radii) {
    for (int64_t k = 0; k < n; k++) s.radii[k] = 0.5 * diameter;
  }
  return s;
}

/* The contract, evaluated here: |xi - xj|^2 <= (ri + rj)^2 in double, pairs in order. */
static void brute_force(const scene *s, pair_list *out) {
  size_t cap = 1024;
  out->p = malloc(cap * sizeof *out->p);
  out->count = 0;
  if (!out->p) abort();
  const int dim = s->dim;
  for (int64_t i = 0; i < s->n; i++) {
    for (int64_t j = i + 1; j < s->n; j++) {
      const double *a = s->coords + i * dim, *b = s->coords + j * dim;
      double dx = a[0] - b[0], dy = a[1] - b[1];
      double sum = dx * dx + dy * dy;
      if (dim == 3) {
        double dz = a[2] - b[2];
        sum += dz * dz;
      }
      double lim;
      if (s->radii) {
        double rr = s->radii[i] + s->radii[j];
        lim = rr * rr;
      } else {
        lim = s->diameter * s->diameter;
      }
      if (!(sum <= lim)) continue;
      if (out->count == cap) {
        cap *= 2;
        out->p = realloc(out->p, cap * sizeof *out->p);
        if (!out->p) abort();
      }
      out->p[out->count].i = (int32_t)i;
      out->p[out->count].j = (int32_t)j;
      out->count++;
    }
  }
}

/* Figures for docs/RELIABILITY.md: scenes and detections compared with direct checking. */
static long scenes_compared, detections_compared;

static bool well_formed(const pair_list *l, int64_t n) {
  for (size_t k = 0; k < l->count; k++) {
    if (l->p[k].i < 0 || l->p[k].i >= l->p[k].j || l->p[k].j >= n) return false;
    if (k > 0 && l->p[k - 1].i == l->p[k].i && l->p[k - 1].j == l->p[k].j) return false;
  }
  return true;
}

/* What a case expects: the status of each algorithm (NBS_OK unless set), sorting's axis
 * compression, and the number of contacts when it is known. */
typedef struct expect {
  nbs_status status[NBS_ALGORITHM_COUNT];
  int compressed;   /* sorting's axes compressed: 1, 0, or -1 for either */
  int64_t contacts; /* the number of contacts the contract gives, or -1 if not known */
} expect;

/* Direct against the contract, then auto and every other algorithm in both modes against
 * direct: contacts byte-identical after sorting, candidates well formed and containing the
 * contacts, the statuses those of `want`, list heads empty after every detection. */
static void against_direct_in(nbs_context *ctx, const char *label, const scene *s, expect want) {
  pair_list truth, ref;
  brute_force(s, &truth);
  ASSERT_OK(detect_sorted(ctx, s, NBS_DIRECT, NBS_MODE_CONTACTS, &ref));
  scenes_compared++;
  CHECK_MSG(pair_lists_equal(&truth, &ref), "%s: direct finds %zu contacts, the contract %zu",
            label, ref.count, truth.count);
  if (want.contacts >= 0) {
    CHECK_MSG((int64_t)truth.count == want.contacts, "%s: %zu contacts, expected %lld", label,
              truth.count, (long long)want.contacts);
  }
  for (int a = 0; a < NBS_ALGORITHM_COUNT; a++) {
    const nbs_algorithm algo = (nbs_algorithm)a;
    if (algo == NBS_DIRECT) continue;
    const char *name = nbs_algorithm_name(algo);
    const nbs_status expected = want.status[a];
    for (int mode = 0; mode < 2; mode++) {
      pair_list got;
      nbs_status st = detect_sorted(ctx, s, algo, (nbs_mode)mode, &got);
      CHECK_MSG(st == expected, "%s: %s %s: status %s, expected %s (%s)", label, name,
                mode ? "candidates" : "contacts", nbs_status_name(st), nbs_status_name(expected),
                nbs_context_error(ctx));
      CHECK_MSG(nbs__heads_empty(ctx), "%s: %s: list heads left dirty", label, name);
      if (st != NBS_OK) continue;
      detections_compared++;
      CHECK_MSG(well_formed(&got, s->n), "%s: %s: pairs not well formed", label, name);
      if (mode == NBS_MODE_CONTACTS) {
        CHECK_MSG(pair_lists_equal(&got, &ref), "%s: %s finds %zu contacts, direct %zu", label,
                  name, got.count, ref.count);
      } else {
        CHECK_MSG(pair_list_contains(&got, &ref), "%s: %s: the candidates miss a contact",
                  label, name);
      }
      nbs_stats stats;
      nbs_last_stats(ctx, &stats);
      if (algo == NBS_SORTING && want.compressed >= 0) {
        CHECK_MSG(stats.compressed == want.compressed, "%s: sorting compressed = %d, expected %d",
                  label, stats.compressed, want.compressed);
      }
      pair_list_free(&got);
    }
  }
  pair_list_free(&truth);
  pair_list_free(&ref);
}

/* In a fresh context with the default settings. */
static void against_direct(const char *label, const scene *s, expect want) {
  nbs_context *ctx;
  ASSERT_OK(nbs_context_create(NULL, &ctx));
  against_direct_in(ctx, label, s, want);
  nbs_context_destroy(ctx);
}

/* Every algorithm succeeds on a regular grid. */
static const expect all_ok = {.compressed = 0, .contacts = -1};
/* More than 2^30 cells on an axis: the grid-indexed algorithms refuse, sorting compresses. */
static const expect too_wide = {
    .status = {[NBS_SCREENING] = NBS_ERR_EXTENT, [NBS_NBS] = NBS_ERR_EXTENT,
               [NBS_CELLSORT] = NBS_ERR_EXTENT},
    .compressed = 1,
    .contacts = -1};

/* An allocator that refuses any block over `limit` bytes, counting calls and recording the
 * largest request. */
typedef struct limit_alloc {
  size_t limit, largest;
  long calls, live;
} limit_alloc;

static void *limit_alloc_fn(void *opaque, size_t size) {
  limit_alloc *la = opaque;
  la->calls++;
  if (size > la->largest) la->largest = size;
  if (size > la->limit) return NULL;
  void *p = malloc(size);
  if (p) la->live++;
  return p;
}

static void limit_free_fn(void *opaque, void *p, size_t size) {
  limit_alloc *la = opaque;
  (void)size;
  la->live--;
  free(p);
}

/* ---- the element count ----------------------------------------------------------------- */

/* n = 2^31 and beyond is refused with NBS_ERR_COUNT before any allocation; n = 2^31 - 1 is
 * accepted (the first coordinate is then validated: a NaN there gives NBS_ERR_COORD, which
 * reads one element, not 2^31). Reservations that cannot be addressed fail cleanly. */
static void test_count_limit(void) {
  limit_alloc la = {(size_t)64 << 20, 0, 0, 0};
  nbs_context_def cdef = nbs_default_context_def();
  cdef.allocator.alloc = limit_alloc_fn;
  cdef.allocator.free = limit_free_fn;
  cdef.allocator.opaque = &la;
  nbs_context *ctx;
  ASSERT_OK(nbs_context_create(&cdef, &ctx));
  const long after_create = la.calls;

  double xyz[3] = {0.0, 0.0, 0.0};
  nbs_input in = {.dim = 3, .n = 0, .coords = xyz, .radii = NULL, .diameter = 1.0};
  const int64_t too_many[] = {(int64_t)1 << 31, ((int64_t)1 << 31) + 1, (int64_t)1 << 40,
                              INT64_MAX, -1, INT64_MIN};
  for (size_t k = 0; k < sizeof too_many / sizeof *too_many; k++) {
    in.n = too_many[k];
    for (int a = 0; a < NBS_ALGORITHM_COUNT; a++) {
      nbs_detect_def def = nbs_default_detect_def();
      def.algorithm = (nbs_algorithm)a;
      CHECK_STATUS(nbs_detect(ctx, &in, &def), NBS_ERR_COUNT);
    }
    char num[32];
    snprintf(num, sizeof num, "%lld", (long long)too_many[k]);
    CHECK_MSG(strstr(nbs_context_error(ctx), num) != NULL, "message \"%s\" lacks %s",
              nbs_context_error(ctx), num);
    CHECK_STATUS(nbs_context_reserve(ctx, too_many[k], 0), NBS_ERR_COUNT);
  }
  CHECK_EQ(la.calls, after_create); /* nothing was even asked of the allocator */

  /* The largest count accepted: validation starts, and stops at element 0's NaN. */
  xyz[0] = NAN;
  in.n = INT32_MAX;
  CHECK_STATUS(nbs_detect(ctx, &in, NULL), NBS_ERR_COORD);
  CHECK_EQ(nbs_context_error_element(ctx), 0);
  CHECK_EQ(la.calls, after_create);
  xyz[0] = 0.0;

  /* Reserving for 2^31 - 1 elements asks for the largest layout, cellsort's in 3D with
   * radii (44 bytes each, plus padding and histograms), in one block, without wrapping
   * (refused here, over the allocator's limit); then the context still works. */
  CHECK_STATUS(nbs_context_reserve(ctx, INT32_MAX, 0), NBS_ERR_NOMEM);
  CHECK_TRUE(la.largest >= (size_t)INT32_MAX * 44 &&
             la.largest <= (size_t)INT32_MAX * 44 + ((size_t)1 << 20));
  /* A pair reservation that cannot be addressed is refused before allocating; one that can
   * be addressed but not had is NBS_ERR_NOMEM. */
  long before = la.calls;
  nbs_status st = nbs_context_reserve(ctx, 0, SIZE_MAX);
  CHECK_MSG(st == NBS_ERR_PAIRS || st == NBS_ERR_NOMEM, "reserve(SIZE_MAX pairs): %s",
            nbs_status_name(st));
  CHECK_EQ(la.calls, before);
  CHECK_STATUS(nbs_context_reserve(ctx, 0, SIZE_MAX / sizeof(nbs_pair)), NBS_ERR_NOMEM);

  scene s = new_scene(3, 50, 1.0, false);
  for (int64_t k = 0; k < 50 * 3; k++) s.coords[k] = 0.3 * (double)(k % 7);
  against_direct_in(ctx, "after the refusals", &s, all_ok);
  scene_free(&s);
  nbs_context_destroy(ctx);
  CHECK_EQ(la.live, 0);
}

/* ---- spreads ---------------------------------------------------------------------------- */

/* A touching cluster of m elements at `at` on axis `axis`: m/2 identical points, and a row
 * at exactly the contact distance (ties). */
static void put_cluster(scene *s, int64_t first, int64_t m, int axis, double at, double step) {
  for (int64_t k = 0; k < m; k++) {
    double *p = s->coords + (first + k) * s->dim;
    for (int a = 0; a < s->dim; a++) p[a] = 0.0;
    p[axis] = at + (k < m / 2 ? 0.0 : (double)(k - m / 2) * step);
  }
}

/* More than 2^31 (and 2^32, 2^53, 1e300/D) cells on an axis: screening and NBS refuse with
 * NBS_ERR_EXTENT, sorting compresses the axis, auto picks sorting, all agree with direct.
 * Just under NBS__AXIS_MAX cells the grid is regular again. */
static void test_wide_spread(void) {
  const double far[] = {0x1p31 + 5, 0x1p32 + 1, 3e9, 5e9, 1e12, 1e15, 0x1p53, 1e18, 1e300};
  for (int dim = 2; dim <= 3; dim++) {
    for (int axis = 0; axis < dim; axis++) {
      for (size_t f = 0; f < sizeof far / sizeof *far; f++) {
        /* a central cluster, clusters at +far and -far/2 on the axis, spread elements */
        scene s = new_scene(dim, 400, 1.0, false);
        put_cluster(&s, 0, 100, axis, 0.0, 1.0);
        put_cluster(&s, 100, 60, axis, far[f], 1.0);
        put_cluster(&s, 160, 60, axis, -0.5 * far[f], 1.0);
        for (int64_t k = 220; k < 400; k++) {
          for (int a = 0; a < dim; a++) s.coords[k * dim + a] = (double)((k * (a + 3)) % 41) * 0.7;
        }
        char label[96];
        snprintf(label, sizeof label, "%dD spread %g on axis %d", dim, far[f], axis);
        against_direct(label, &s, too_wide);
        scene_free(&s);
      }
    }
    /* 2^30 - 64 cells: still a regular grid (sorting does not compress), and 2^30 + 64
     * cells: compressed. */
    for (int side = 0; side < 2; side++) {
      scene s = new_scene(dim, 200, 1.0, false);
      double edge = 1.0 * (1.0 + 0x1p-18);
      double span = (side ? 0x1p30 + 64 : 0x1p30 - 64) * edge; /* the row adds 49 */
      put_cluster(&s, 0, 100, 0, 0.0, 1.0);
      put_cluster(&s, 100, 100, 0, span, 1.0);
      char label[96];
      snprintf(label, sizeof label, "%dD 2^30 %s 64 cells", dim, side ? "+" : "-");
      /* under the limit, screening's cells (8 GiB and more) pass the default budget;
       * NBS folds the axis (two crowded clusters and nothing between: its heads would
       * outweigh the elements) and cellsort's memory does not depend on the extent */
      expect under = {.status = {[NBS_SCREENING] = NBS_ERR_BUDGET}, .compressed = 0,
                      .contacts = -1};
      expect e = side ? too_wide : under;
      against_direct(label, &s, e);
      scene_free(&s);
    }
  }
}

/* Coordinates near the largest finite double, where differences overflow to infinity. Out
 * there doubles are 2^971 (2e292) apart, far more than any diameter whose square is finite,
 * so with D = 1 or 1e154 only equal coordinates touch; with D = 1e300, D^2 overflows, every
 * pair touches and the grid is one cell of infinite edge. */
static void test_near_max_double(void) {
  const double at[] = {1.7e308, -1.7e308, DBL_MAX, -DBL_MAX, 0.0, 1e308, -8.98846567431158e307};
  for (int dim = 2; dim <= 3; dim++) {
    const double diameters[] = {1.0, 1e154, 1e300};
    for (int d = 0; d < 3; d++) {
      for (int radii = 0; radii < 2; radii++) {
        const int64_t per = 24, n = per * 7;
        scene s = new_scene(dim, n, diameters[d], radii);
        for (int c = 0; c < 7; c++) {
          for (int64_t k = 0; k < per; k++) {
            double *p = s.coords + (c * per + k) * dim;
            for (int a = 0; a < dim; a++) {
              double v = at[c];
              /* step by ulps, towards zero so that nothing overflows */
              for (int64_t u = 0; u < (k * (a + 1)) % 5; u++) v = nextafter(v, 0.0);
              p[a] = v;
            }
            if (radii) s.radii[c * per + k] = 0.5 * diameters[d] * (1.0 - 0.1 * (double)(k % 3));
          }
        }
        char label[96];
        snprintf(label, sizeof label, "%dD near +-DBL_MAX, D %g%s", dim, diameters[d],
                 radii ? ", radii" : "");
        /* D = 1e300: the edge is infinite and the grid one cell, whatever the extent */
        expect e = too_wide;
        if (d == 2) {
          e = all_ok;
          e.contacts = n * (n - 1) / 2;
        }
        against_direct(label, &s, e);
        scene_free(&s);
      }
    }
    /* Everything within a few ulps of +1.7e308 with D = 2 ulps: D^2 overflows, so the cell
     * edge is infinite, the grid is one cell, every algorithm runs and every pair touches. */
    const double ulp = 0x1p971;
    scene s = new_scene(dim, 120, 2.0 * ulp, false);
    for (int64_t k = 0; k < 120; k++) {
      for (int a = 0; a < dim; a++) {
        s.coords[k * dim + a] = 1.7e308 - (double)((k * (a + 2)) % 23) * ulp;
      }
    }
    char label[64];
    snprintf(label, sizeof label, "%dD within a few ulps of 1.7e308", dim);
    expect e = all_ok;
    e.contacts = 120 * 119 / 2;
    against_direct(label, &s, e);
    scene_free(&s);
  }
}

/* ---- one point, pair limits ----------------------------------------------------------- */

static int count_pairs(void *user, const nbs_pair *pairs, size_t count) {
  (void)pairs;
  *(uint64_t *)user += count;
  return 0;
}

/* All elements at one point: N(N-1)/2 pairs, delivered by every algorithm; with max_pairs
 * set, a clear NBS_ERR_PAIRS naming the limit, the count found in nbs_last_stats, no pairs
 * left in the buffer, and the context usable; with a callback, every pair is counted. */
static void test_one_point(void) {
  for (int dim = 2; dim <= 3; dim++) {
    for (int radii = 0; radii < 2; radii++) {
      const int64_t n = 2000;
      scene s = new_scene(dim, n, 1.0, radii);
      for (int64_t k = 0; k < n * dim; k++) s.coords[k] = -7.25;
      char label[64];
      snprintf(label, sizeof label, "%dD %lld at one point%s", dim, (long long)n,
               radii ? ", radii" : "");
      expect e = all_ok;
      e.contacts = n * (n - 1) / 2;
      against_direct(label, &s, e);

      nbs_context_def cdef = nbs_default_context_def();
      cdef.max_pairs = 100000;
      nbs_context *ctx;
      ASSERT_OK(nbs_context_create(&cdef, &ctx));
      nbs_input in = scene_input(&s);
      for (int a = 0; a < NBS_ALGORITHM_COUNT; a++) {
        nbs_detect_def def = nbs_default_detect_def();
        def.algorithm = (nbs_algorithm)a;
        CHECK_STATUS(nbs_detect(ctx, &in, &def), NBS_ERR_PAIRS);
        CHECK_MSG(strstr(nbs_context_error(ctx), "100000") != NULL, "message: %s",
                  nbs_context_error(ctx));
        nbs_stats st;
        nbs_last_stats(ctx, &st);
        CHECK_EQ(st.pairs, 100000);
        size_t count = 1;
        CHECK_TRUE(nbs_pairs(ctx, &count) == NULL && count == 0);
        CHECK_TRUE(nbs__heads_empty(ctx) || ctx->work_kind == NBS__WORK_NONE);
        CHECK_TRUE(nbs_context_bytes(ctx) < (size_t)3 << 20); /* the buffer stopped at 800 KB */
        /* The whole count, through a callback (the buffer's limit does not apply). */
        uint64_t counted = 0;
        def.callback = count_pairs;
        def.user = &counted;
        CHECK_STATUS(nbs_detect(ctx, &in, &def), NBS_OK);
        CHECK_EQ(counted, n * (n - 1) / 2);
      }
      scene small = new_scene(dim, 40, 1.0, false);
      for (int64_t k = 0; k < 40 * dim; k++) small.coords[k] = 0.4 * (double)(k % 5);
      against_direct_in(ctx, "after NBS_ERR_PAIRS", &small, all_ok);
      scene_free(&small);
      nbs_context_destroy(ctx);
      scene_free(&s);
    }
  }
}

/* An allocator with a 64 KiB guard zone after every block, checked when the block is freed:
 * a write past the end of a block is caught even without a sanitizer. */
typedef struct guard_alloc {
  long live, overruns;
  size_t worst; /* bytes written past the end of a block, at most */
} guard_alloc;

#define GUARD_BYTES ((size_t)64 << 10)

static void *guard_alloc_fn(void *opaque, size_t size) {
  (void)opaque;
  unsigned char *p = malloc(size + GUARD_BYTES);
  if (!p) return NULL;
  memset(p + size, 0xA5, GUARD_BYTES);
  ((guard_alloc *)opaque)->live++;
  return p;
}

static void guard_free_fn(void *opaque, void *ptr, size_t size) {
  guard_alloc *g = opaque;
  unsigned char *p = ptr;
  size_t last = 0;
  for (size_t k = 0; k < GUARD_BYTES; k++) {
    if (p[size + k] != 0xA5) last = k + 1;
  }
  if (last) {
    g->overruns++;
    if (last > g->worst) g->worst = last;
  }
  g->live--;
  free(p);
}

/* The context's max_pairs limits the buffer; a callback receives every pair whatever it is.
 * With a max_pairs below the callback batch (4096 pairs), the batch must still stay inside
 * the memory the library allocated for it. */
static void test_callback_small_max_pairs(void) {
  const size_t limits[] = {1, 10, 100, 1000, 4095, 4096, 5000};
  scene s = new_scene(3, 100, 1.0, false); /* one point: 4950 pairs, more than one batch */
  nbs_input in = scene_input(&s);
  for (size_t l = 0; l < sizeof limits / sizeof *limits; l++) {
    for (int a = 0; a < NBS_ALGORITHM_COUNT; a++) {
      guard_alloc g = {0, 0, 0};
      nbs_context_def cdef = nbs_default_context_def();
      cdef.max_pairs = limits[l];
      cdef.allocator.alloc = guard_alloc_fn;
      cdef.allocator.free = guard_free_fn;
      cdef.allocator.opaque = &g;
      nbs_context *ctx;
      ASSERT_OK(nbs_context_create(&cdef, &ctx));
      nbs_detect_def def = nbs_default_detect_def();
      def.algorithm = (nbs_algorithm)a;
      uint64_t counted = 0;
      def.callback = count_pairs;
      def.user = &counted;
      CHECK_STATUS(nbs_detect(ctx, &in, &def), NBS_OK);
      CHECK_EQ(counted, 4950);
      nbs_context_destroy(ctx);
      CHECK_EQ(g.live, 0);
      CHECK_MSG(g.overruns == 0,
                "%s, max_pairs %zu, callback: %zu bytes written past the end of a block",
                nbs_algorithm_name((nbs_algorithm)a), limits[l], g.worst);
    }
  }
  scene_free(&s);
}

/* A max_pairs of exactly the scene's contacts is enough: every algorithm delivers them all,
 * whatever candidates come after the buffer is full (it may be flushed, or found at the
 * limit, only for a pair that touches). One fewer is NBS_ERR_PAIRS. 2D and 3D, crowded, and
 * a scene of one contact followed by a candidate that does not touch (max_pairs 1). */
static void test_max_pairs_exact(void) {
  for (int c = 0; c < 4; c++) {
    const int dim = 2 + c % 2;
    scene s;
    if (c < 2) {
      s = test_scene(SCENE_UNIFORM, dim, 3000, 0.5);
    } else {
      /* a pair that touches in one cell, and in the cells on either side of it one
       * element each that touches neither: whichever cell is checked first, the pair
       * that touches is followed by candidates that do not */
      s = new_scene(dim, 4, 1.0, false);
      const double at[4] = {0.0, 0.9, -1.05, 1.95};
      for (int k = 0; k < 4; k++) s.coords[k * dim] = at[k];
    }
    nbs_input in = scene_input(&s);
    nbs_context *ref;
    ASSERT_OK(nbs_context_create(NULL, &ref));
    nbs_detect_def def = nbs_default_detect_def();
    def.algorithm = NBS_DIRECT;
    ASSERT_OK(nbs_detect(ref, &in, &def));
    size_t contacts = 0;
    nbs_pairs(ref, &contacts);
    CHECK_TRUE(c < 2 ? contacts > 100 : contacts == 1);
    for (size_t extra = 0; extra < (contacts > 1 ? 2 : 1); extra++) { /* max_pairs 0: none */
      nbs_context_def cdef = nbs_default_context_def();
      cdef.max_pairs = contacts - extra;
      for (int a = 0; a < NBS_ALGORITHM_COUNT; a++) {
        nbs_context *ctx;
        ASSERT_OK(nbs_context_create(&cdef, &ctx));
        def.algorithm = (nbs_algorithm)a;
        const nbs_status st = nbs_detect(ctx, &in, &def);
        CHECK_MSG(st == (extra ? NBS_ERR_PAIRS : NBS_OK), "%dD %s, max_pairs %zu of %zu: %s",
                  dim, nbs_algorithm_name((nbs_algorithm)a), cdef.max_pairs, contacts,
                  nbs_status_name(st));
        size_t count = 0;
        nbs_pairs(ctx, &count);
        CHECK_EQ(count, extra ? 0 : contacts);
        nbs_context_destroy(ctx);
      }
    }
    nbs_context_destroy(ref);
    scene_free(&s);
  }
}

/* ---- sizes ------------------------------------------------------------------------------ */

/* Radii from 0.5 down to 5e-7 (ratio 1e6): small elements in touching rows, some touching
 * the large ones at exactly rl + rs, large ones touching each other at exactly 1. */
static void test_radius_ratio(void) {
  for (int dim = 2; dim <= 3; dim++) {
    const int64_t big = 12, small = 1500, n = big + small;
    scene s = new_scene(dim, n, 1.0, true);
    const double rs = 5e-7;
    for (int64_t k = 0; k < big; k++) {
      s.radii[k] = 0.5;
      s.coords[k * dim] = (double)k; /* a row of large elements, each touching the next */
    }
    for (int64_t k = 0; k < small; k++) {
      double *p = s.coords + (big + k) * dim;
      s.radii[big + k] = rs;
      int64_t host = k % big, slot = k / big;
      /* on the far side of large element `host`, at exactly rl + rs, then a row of small
       * ones 1.5 rs apart: each touches the next, not the one after */
      p[0] = (double)host;
      p[1] = (0.5 + rs) + (double)slot * (1.5 * rs);
      if (dim == 3) p[2] = (double)(slot % 2) * 1e-7; /* 7.6e-7 from the next: touching */
    }
    char label[64];
    snprintf(label, sizeof label, "%dD radius ratio 1e6", dim);
    pair_list truth;
    brute_force(&s, &truth);
    size_t small_small = 0, small_big = 0;
    for (size_t k = 0; k < truth.count; k++) {
      if (truth.p[k].i >= big) small_small++;
      else if (truth.p[k].j >= big) small_big++;
    }
    CHECK_MSG(small_small >= (size_t)(small - big) && small_big >= (size_t)big,
              "%s: the scene has %zu small-small and %zu small-large contacts", label,
              small_small, small_big);
    pair_list_free(&truth);
    against_direct(label, &s, all_ok);
    scene_free(&s);
  }
}

/* Diameters whose square is denormal or underflows to 0. The contract then counts as
 * touching every pair whose squared distance underflows too: elements a few denormals apart
 * touch, elements 1e-150 apart do not. */
static void test_denormal_diameters(void) {
  const double diameters[] = {5e-324, 1e-320, 1e-310, 2.2250738585072014e-308, 1e-170, 1e-160,
                              0x1p-498, 0x1p-499};
  for (int dim = 2; dim <= 3; dim++) {
    for (size_t d = 0; d < sizeof diameters / sizeof *diameters; d++) {
      for (int radii = 0; radii < 2; radii++) {
        const int64_t n = 300;
        scene s = new_scene(dim, n, diameters[d], radii);
        if (radii && !(s.radii[0] > 0)) {
          /* half of the smallest denormal rounds to 0: use it whole as the radius */
          for (int64_t k = 0; k < n; k++) s.radii[k] = diameters[d];
        }
        for (int64_t k = 0; k < n; k++) {
          double *p = s.coords + k * dim;
          for (int a = 0; a < dim; a++) {
            switch (k % 5) {
            case 0: p[a] = (double)((k + a) % 9) * 5e-324; break;            /* denormals */
            case 1: p[a] = (k + a) % 2 ? 0.0 : -0.0; break;                   /* zeros */
            case 2: p[a] = (double)((k * 3 + a) % 7) * diameters[d]; break;   /* a lattice */
            case 3: p[a] = 1e-150 * (double)((k + a) % 4); break;             /* apart */
            default: p[a] = 1.0 + (double)(k % 3) * 0x1p-52; break;           /* far, ulps */
            }
          }
        }
        char label[96];
        snprintf(label, sizeof label, "%dD diameter %g%s", dim, diameters[d],
                 radii ? ", radii" : "");
        /* The grid spans 1 / 2^-498 cells: screening and NBS cannot index it. */
        against_direct(label, &s, too_wide);
        scene_free(&s);
      }
    }
  }
}

/* Radii so large that (ri + rj)^2 overflows to infinity: every pair touches, by the
 * contract, even pairs at -DBL_MAX and +DBL_MAX (whose squared distance is infinite too);
 * the cell edge is infinite and one cell holds everything. */
static void test_huge_radii(void) {
  for (int dim = 2; dim <= 3; dim++) {
    const double sizes[] = {1e200, 1.35e154, DBL_MAX};
    for (size_t z = 0; z < 3; z++) {
      for (int radii = 0; radii < 2; radii++) {
        for (int extremes = 0; extremes < 2; extremes++) {
          const int64_t n = 500;
          scene s = new_scene(dim, n, sizes[z], radii);
          for (int64_t k = 0; k < n * dim; k++) s.coords[k] = (double)(k % 13) * 1e150 - 3e9;
          if (extremes) {
            for (int a = 0; a < dim; a++) {
              s.coords[0 * dim + a] = DBL_MAX;
              s.coords[1 * dim + a] = -DBL_MAX;
              s.coords[2 * dim + a] = 1.7e308;
            }
          }
          if (radii) {
            for (int64_t k = 0; k < n; k++) s.radii[k] = sizes[z] * (k % 2 ? 0.5 : 0.25);
          }
          char label[96];
          snprintf(label, sizeof label, "%dD size %g%s%s", dim, sizes[z], radii ? ", radii" : "",
                   extremes ? ", at +-DBL_MAX" : "");
          /* the cell edge is infinite: one cell holds everything, even when the extent
           * overflows, so every algorithm runs */
          expect e = all_ok;
          /* (ri + rj)^2 overflows for every pair, except for radii of 1.35e154 / 4 */
          e.contacts = radii && z == 1 && extremes ? -1 : n * (n - 1) / 2;
          against_direct(label, &s, e);
          scene_free(&s);
        }
      }
    }
    /* sqrt(DBL_MAX): D^2 is finite, so elements at +-DBL_MAX do not touch each other. */
    scene s = new_scene(dim, 4, 1.3407807929942596e154, false);
    for (int a = 0; a < dim; a++) {
      s.coords[0 * dim + a] = DBL_MAX;
      s.coords[1 * dim + a] = -DBL_MAX;
      s.coords[2 * dim + a] = 0.0;
      s.coords[3 * dim + a] = 1e153;
    }
    expect e = too_wide;
    e.compressed = -1;
    e.contacts = 1; /* only (2, 3) */
    against_direct(dim == 2 ? "2D D = sqrt(DBL_MAX)" : "3D D = sqrt(DBL_MAX)", &s, e);
    scene_free(&s);
  }
}

/* ---- shapes ----------------------------------------------------------------------------- */

/* 2D input with every element on one line: horizontal, vertical, diagonal, and along the
 * z axis in 3D; at exactly the contact distance (n - 1 contacts), at half of it, and spread
 * over 3e9 cells. */
static void test_one_line(void) {
  const int64_t n = 3000;
  const double steps[] = {1.0, 0.5, 1e6};
  for (int shape = 0; shape < 4; shape++) {
    for (size_t st = 0; st < 3; st++) {
      int dim = shape == 3 ? 3 : 2;
      scene s = new_scene(dim, n, 1.0, false);
      for (int64_t k = 0; k < n; k++) {
        double *p = s.coords + k * dim;
        double t = (double)k * steps[st] + 12.5;
        switch (shape) {
        case 0: p[0] = t; p[1] = -3.0; break;          /* y = -3 */
        case 1: p[0] = 1e9; p[1] = t; break;           /* x = 1e9 */
        case 2: p[0] = t; p[1] = t; break;             /* y = x: spacing sqrt(2) steps */
        default: p[0] = 0.5; p[1] = 0.5; p[2] = t;     /* along z */
        }
      }
      static const char *const shapes[] = {"2D horizontal", "2D vertical", "2D diagonal",
                                           "3D along z"};
      char label[96];
      snprintf(label, sizeof label, "%s line, step %g", shapes[shape], steps[st]);
      expect e = st == 2 ? too_wide : all_ok;
      if (st == 2) e.compressed = 1;
      if (st == 0) e.contacts = shape == 2 ? 0 : n - 1;
      if (st == 1) e.contacts = shape == 2 ? n - 1 : 2 * n - 3;
      if (st == 2) e.contacts = 0;
      against_direct(label, &s, e);
      scene_free(&s);
    }
  }
}

/* NBS folds the axes of a domain whose heads would outweigh its elements (a crowded cluster
 * and two elements 3e5 cells away): cell c of an axis goes on list c mod m, and the
 * neighbour of list m - 1 is list 0. The cluster (a jittered lattice at spacing 0.9, so that
 * every element touches its neighbours) is moved through two periods of the fold in steps of
 * 1.7 cells, so that its contacts meet the wrap-around at every place of the cluster. */
static void test_folded_axes(void) {
  for (int dim = 2; dim <= 3; dim++) {
    const int side = dim == 2 ? 12 : 6, cluster = dim == 2 ? side * side : side * side * side;
    const int64_t n = cluster + 3;
    for (int step = 0; step < 20; step++) {
      const double at = 0.3 + 1.7 * step;
      scene s = new_scene(dim, n, 1.0, false);
      for (int64_t k = 0; k < cluster; k++) {
        int64_t q = k;
        for (int a = 0; a < dim; a++) {
          const double jitter = 0.05 * (double)((k * 7 + a * 3) % 5) - 0.1;
          s.coords[k * dim + a] = at + 0.9 * (double)(q % side) + jitter;
          q /= side;
        }
      }
      /* one element at the origin (the grid's corner), two 3e5 cells out: fewer than the 2%
       * at either end that NBS leaves out of an axis's core */
      for (int64_t k = cluster + 1; k < n; k++) {
        for (int a = 0; a < dim; a++) {
          s.coords[k * dim + a] = 3e5 + 977.3 * (double)((k + a) % 2) + 0.25 * (double)a;
        }
      }
      char label[96];
      snprintf(label, sizeof label, "%dD cluster at %g cells, folded axes", dim, at);
      const expect folded = {.status = {[NBS_SCREENING] = NBS_ERR_BUDGET}, .compressed = 0,
                             .contacts = -1};
      nbs_context *ctx;
      ASSERT_OK(nbs_context_create(NULL, &ctx));
      against_direct_in(ctx, label, &s, folded);
      /* NBS did fold: a power of two of lists per axis, far fewer than the cells */
      nbs_stats st;
      ASSERT_OK(detect_stats(ctx, &s, NBS_NBS, &st));
      CHECK_MSG(st.compressed == 1, "%s: NBS did not fold", label);
      for (int a = 0; a < dim; a++) {
        CHECK_MSG(st.cells[a] >= 4 && st.cells[a] <= 64 && (st.cells[a] & (st.cells[a] - 1)) == 0,
                  "%s: %lld lists on axis %d", label, (long long)st.cells[a], a);
      }
      nbs_context_destroy(ctx);
      scene_free(&s);
    }
  }
}

/* Where NBS scales sparse axes down, cells far apart share lists; elements on a lattice
 * whose period is a multiple of 8 cells would fall on a few lists per axis (lattice
 * coordinate i at cell 1000 i is on list 40 i mod 64 of 64, one of 8) and make every element
 * a candidate of dozens. The fold measures that on its sample and folds less: the
 * candidates stay those of a spread scene. With the check removed from nbs__nbs_fold:
 * 129,025 candidates in 2D and 63,489 in 3D, for 4096 elements. */
static void test_folded_lattice(void) {
  for (int dim = 2; dim <= 3; dim++) {
    const int side = dim == 2 ? 64 : 16;
    const int64_t n = dim == 2 ? side * side : side * side * side;
    const double edge = 1.0 + 0x1p-18; /* the cell edge for diameter 1 */
    scene s = new_scene(dim, n, 1.0, false);
    for (int64_t k = 0; k < n; k++) {
      int64_t q = k;
      for (int a = 0; a < dim; a++) {
        s.coords[k * dim + a] = (1000.0 * (double)(q % side) + 0.5) * edge;
        q /= side;
      }
    }
    /* and a pair in contact, so the count is not trivially 0 */
    s.coords[dim] = s.coords[0] + 0.5;
    char label[64];
    snprintf(label, sizeof label, "%dD lattice of period 1000 cells", dim);
    const expect want = {.status = {[NBS_SCREENING] = NBS_ERR_BUDGET}, .compressed = -1,
                         .contacts = 1};
    nbs_context *ctx;
    ASSERT_OK(nbs_context_create(NULL, &ctx));
    against_direct_in(ctx, label, &s, want);
    nbs_stats st;
    ASSERT_OK(detect_stats(ctx, &s, NBS_NBS, &st));
    CHECK_MSG(st.candidates <= (uint64_t)n, "%s: %llu candidates for %lld elements", label,
              (unsigned long long)st.candidates, (long long)n);
    nbs_context_destroy(ctx);
    scene_free(&s);
  }
}

/* ---- budgets ---------------------------------------------------------------------------- */

/* auto succeeds for every finite input, whatever the cell budget: it falls back to sorting
 * when NBS's head arrays would pass the budget. Scanned over budgets of 0 to 400 bytes,
 * around the head arrays of grids of 1, 2 and 3 cells per axis. */
static void test_auto_tight_budget(void) {
  for (int dim = 2; dim <= 3; dim++) {
    for (int cells = 1; cells <= 3; cells++) {
      scene s = new_scene(dim, 40, 1.0, false);
      for (int64_t k = 0; k < 40; k++) {
        for (int a = 0; a < dim; a++) {
          s.coords[k * dim + a] = (double)((k + a * 7) % (cells * 2)) * 0.5;
        }
      }
      pair_list ref;
      brute_force(&s, &ref);
      nbs_input in = scene_input(&s);
      for (size_t budget = 0; budget <= 400; budget += 4) {
        nbs_context_def cdef = nbs_default_context_def();
        cdef.cell_budget = budget;
        nbs_context *ctx;
        ASSERT_OK(nbs_context_create(&cdef, &ctx));
        nbs_status st = nbs_detect(ctx, &in, NULL);
        nbs_stats stats;
        nbs_last_stats(ctx, &stats);
        CHECK_MSG(st == NBS_OK, "%dD, %d cells per axis, cell budget %zu bytes: auto ran %s "
                  "and returned %s (%s)", dim, cells, budget,
                  nbs_algorithm_name(stats.algorithm), nbs_status_name(st),
                  nbs_context_error(ctx));
        if (st == NBS_OK) {
          size_t count;
          const nbs_pair *p = nbs_pairs(ctx, &count);
          pair_list got = {malloc((count ? count : 1) * sizeof(nbs_pair)), count};
          if (!got.p) abort();
          if (count) memcpy(got.p, p, count * sizeof *p);
          nbs_sort_pairs(got.p, got.count);
          CHECK_TRUE(pair_lists_equal(&got, &ref));
          pair_list_free(&got);
        }
        nbs_context_destroy(ctx);
      }
      pair_list_free(&ref);
      scene_free(&s);
    }
  }
}

int main(int argc, char **argv) {
  static const test_case tests[] = {
      {"count_limit", test_count_limit},
      {"wide_spread", test_wide_spread},
      {"near_max_double", test_near_max_double},
      {"one_point", test_one_point},
      {"callback_small_max_pairs", test_callback_small_max_pairs},
      {"max_pairs_exact", test_max_pairs_exact},
      {"radius_ratio", test_radius_ratio},
      {"denormal_diameters", test_denormal_diameters},
      {"huge_radii", test_huge_radii},
      {"one_line", test_one_line},
      {"folded_axes", test_folded_axes},
      {"folded_lattice", test_folded_lattice},
      {"auto_tight_budget", test_auto_tight_budget},
  };
  int rc = test_main(argc, argv, tests, sizeof tests / sizeof *tests);
  printf("%ld scenes, %ld detections compared with direct checking\n", scenes_compared,
         detections_compared);
  return rc;
}
