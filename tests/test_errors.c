/*
 * Every error of the API, provoked: each returns its status with a message (naming the
 * element where there is one), never crashes, and leaves the context usable. Allocation
 * failure is provoked at every allocation a detection reaches.
 */
#include "internal.h"
#include "test.h"
#include "util.h"

#include <math.h>

/* After an error: the next correct detection agrees with direct. */
static void check_usable(nbs_context *ctx) {
  scene s = test_scene(SCENE_UNIFORM, 3, 300, 0.5);
  pair_list ref, got;
  ASSERT_OK(detect_sorted(ctx, &s, NBS_DIRECT, NBS_MODE_CONTACTS, &ref));
  ASSERT_OK(detect_sorted(ctx, &s, NBS_NBS, NBS_MODE_CONTACTS, &got));
  CHECK_TRUE(pair_lists_equal(&ref, &got));
  CHECK_TRUE(nbs__heads_empty(ctx));
  CHECK_TRUE(nbs_context_error(ctx)[0] == '\0');
  pair_list_free(&ref);
  pair_list_free(&got);
  scene_free(&s);
}

static void test_null_and_ranges(void) {
  nbs_context *ctx;
  CHECK_STATUS(nbs_context_create(NULL, NULL), NBS_ERR_NULL);
  ASSERT_OK(nbs_context_create(NULL, &ctx));
  scene s = test_scene(SCENE_UNIFORM, 3, 100, 0.5);
  nbs_input in = scene_input(&s);
  CHECK_STATUS(nbs_detect(NULL, &in, NULL), NBS_ERR_NULL);
  CHECK_STATUS(nbs_detect(ctx, NULL, NULL), NBS_ERR_NULL);

  nbs_input bad = in;
  bad.coords = NULL;
  CHECK_STATUS(nbs_detect(ctx, &bad, NULL), NBS_ERR_NULL);
  bad = in;
  bad.n = -1;
  CHECK_STATUS(nbs_detect(ctx, &bad, NULL), NBS_ERR_COUNT);
  bad.n = (int64_t)1 << 31;
  CHECK_STATUS(nbs_detect(ctx, &bad, NULL), NBS_ERR_COUNT);
  CHECK_TRUE(strstr(nbs_context_error(ctx), "2147483648") != NULL);
  for (int dim = -1; dim <= 5; dim++) {
    if (dim == 2 || dim == 3) continue;
    bad = in;
    bad.dim = dim;
    CHECK_STATUS(nbs_detect(ctx, &bad, NULL), NBS_ERR_DIM);
  }
  nbs_detect_def def = nbs_default_detect_def();
  def.algorithm = (nbs_algorithm)99;
  CHECK_STATUS(nbs_detect(ctx, &in, &def), NBS_ERR_ALGORITHM);
  def = nbs_default_detect_def();
  def.mode = (nbs_mode)7;
  CHECK_STATUS(nbs_detect(ctx, &in, &def), NBS_ERR_MODE);
  size_t count = 123;
  CHECK_TRUE(nbs_pairs(ctx, &count) == NULL && count == 0);
  CHECK_STATUS(nbs_last_stats(ctx, NULL), NBS_ERR_NULL);
  check_usable(ctx);

  /* N = 0 needs no coordinates at all. */
  bad = in;
  bad.n = 0;
  bad.coords = NULL;
  CHECK_STATUS(nbs_detect(ctx, &bad, NULL), NBS_OK);
  CHECK_TRUE(nbs_pairs(ctx, &count) == NULL && count == 0);
  scene_free(&s);
  nbs_context_destroy(ctx);
  nbs_context_destroy(NULL);
}

static void test_bad_numbers(void) {
  nbs_context *ctx;
  ASSERT_OK(nbs_context_create(NULL, &ctx));
  const double bads[] = {NAN, INFINITY, -INFINITY};
  for (int dim = 2; dim <= 3; dim++) {
    scene s = test_scene(SCENE_UNIFORM, dim, 100, 0.5);
    nbs_input in = scene_input(&s);
    for (int b = 0; b < 3; b++) {
      for (int axis = 0; axis < dim; axis++) {
        double keep = s.coords[17 * dim + axis];
        s.coords[17 * dim + axis] = bads[b];
        for (int a = 0; a < NBS_ALGORITHM_COUNT; a++) {
          nbs_detect_def def = nbs_default_detect_def();
          def.algorithm = (nbs_algorithm)a;
          CHECK_STATUS(nbs_detect(ctx, &in, &def), NBS_ERR_COORD);
          CHECK_EQ(nbs_context_error_element(ctx), 17);
          CHECK_MSG(strstr(nbs_context_error(ctx), "element 17") != NULL, "message: %s",
                    nbs_context_error(ctx));
        }
        s.coords[17 * dim + axis] = keep;
      }
    }
    /* the pass reads long arrays in blocks: a bad number anywhere, alone or after another,
     * names the first bad element, its axis and its kind */
    scene big = test_scene(SCENE_UNIFORM, dim, 20011, 0.5);
    nbs_input bin = scene_input(&big);
    const int64_t places[] = {0, 1, 7, 8, 255, 256, 2047, 2048, 2049, 6143, 6144, 10000, 20010};
    const char *const axis_names[3] = {"x coordinate", "y coordinate", "z coordinate"};
    for (size_t p = 0; p < sizeof places / sizeof *places; p++) {
      for (int axis = 0; axis < dim; axis++) {
        const int b = (int)((p + (size_t)axis) % 3);
        const size_t at = (size_t)places[p] * (size_t)dim + (size_t)axis;
        const double keep = big.coords[at];
        big.coords[at] = bads[b];
        /* a second bad number later on does not change which one is named */
        const size_t later = (size_t)big.n * (size_t)dim - 1;
        const double keep_later = big.coords[later];
        if (later > at) big.coords[later] = NAN;
        CHECK_STATUS(nbs_detect(ctx, &bin, NULL), NBS_ERR_COORD);
        CHECK_EQ(nbs_context_error_element(ctx), places[p]);
        CHECK_MSG(strstr(nbs_context_error(ctx), axis_names[axis]) != NULL &&
                      strstr(nbs_context_error(ctx), b == 0 ? "NaN" : "infinite") != NULL,
                  "element %lld axis %d: message: %s", (long long)places[p], axis,
                  nbs_context_error(ctx));
        big.coords[later] = keep_later;
        big.coords[at] = keep;
      }
    }
    CHECK_STATUS(nbs_detect(ctx, &bin, NULL), NBS_OK);
    /* the same for radii, read in blocks of their own */
    double *big_r = malloc((size_t)big.n * sizeof *big_r);
    for (int64_t k = 0; k < big.n; k++) big_r[k] = 0.5;
    bin.radii = big_r;
    for (size_t p = 0; p < sizeof places / sizeof *places; p++) {
      big_r[places[p]] = p % 2 ? NAN : -0.0;
      big_r[big.n - 1] = places[p] < big.n - 1 ? INFINITY : big_r[big.n - 1];
      CHECK_STATUS(nbs_detect(ctx, &bin, NULL), NBS_ERR_RADIUS);
      CHECK_EQ(nbs_context_error_element(ctx), places[p]);
      big_r[places[p]] = 0.5;
      big_r[big.n - 1] = 0.5;
    }
    big_r[12345] = 0.75; /* the largest radius sets the cell edge */
    CHECK_STATUS(nbs_detect(ctx, &bin, NULL), NBS_OK);
    nbs_stats st;
    ASSERT_OK(nbs_last_stats(ctx, &st));
    CHECK_TRUE(st.cell_size >= 1.5 && st.cell_size < 1.5 * (1 + 1e-5));
    free(big_r);
    scene_free(&big);

    /* radii: <= 0 or not finite, at element 5 */
    const double bad_r[] = {0.0, -1.0, NAN, INFINITY, -0.0};
    double *radii = malloc((size_t)s.n * sizeof *radii);
    for (int64_t k = 0; k < s.n; k++) radii[k] = 0.5;
    in.radii = radii;
    for (int b = 0; b < 5; b++) {
      radii[5] = bad_r[b];
      CHECK_STATUS(nbs_detect(ctx, &in, NULL), NBS_ERR_RADIUS);
      CHECK_EQ(nbs_context_error_element(ctx), 5);
      CHECK_MSG(strstr(nbs_context_error(ctx), "element 5") != NULL, "message: %s",
                nbs_context_error(ctx));
    }
    radii[5] = 0.5;
    CHECK_STATUS(nbs_detect(ctx, &in, NULL), NBS_OK);
    in.radii = NULL;
    for (int b = 0; b < 5; b++) {
      in.diameter = bad_r[b];
      CHECK_STATUS(nbs_detect(ctx, &in, NULL), NBS_ERR_RADIUS);
      CHECK_EQ(nbs_context_error_element(ctx), -1);
    }
    free(radii);
    scene_free(&s);
  }
  check_usable(ctx);
  nbs_context_destroy(ctx);
}

/* The pass over the coordinates and radii is shared among the context's threads (input.c):
 * with 1 to 4 threads, a bad number at either side of where one thread's range ends and the
 * next begins is named, and a second one in a later range never is; nor does the box
 * depend on the threads (the same cells and pairs, with its ends outside the first range). */
static void test_bad_numbers_threads(void) {
  for (int dim = 2; dim <= 3; dim++) {
    scene s = test_scene(SCENE_UNIFORM, dim, 140011, 0.5);
    nbs_input in = scene_input(&s);
    const int64_t n = s.n;
    /* the box's ends in ranges after the first: an element above every other on each axis,
     * one below */
    for (int a = 0; a < dim; a++) {
      double lo = s.coords[a], hi = s.coords[a];
      for (int64_t k = 0; k < n; k++) {
        lo = fmin(lo, s.coords[k * dim + a]);
        hi = fmax(hi, s.coords[k * dim + a]);
      }
      s.coords[(n - 3) * dim + a] = hi + 3.0;
      s.coords[(n * 5 / 8) * dim + a] = lo - 3.0;
    }
    double *radii = malloc((size_t)n * sizeof *radii);
    for (int64_t k = 0; k < n; k++) radii[k] = 0.5;
    pair_list ref;
    nbs_context *one;
    nbs_context_def cdef = nbs_default_context_def();
    cdef.threads = 1;
    ASSERT_OK(nbs_context_create(&cdef, &one));
    ASSERT_OK(detect_sorted(one, &s, NBS_CELLSORT, NBS_MODE_CONTACTS, &ref));
    nbs_stats st1;
    ASSERT_OK(nbs_last_stats(one, &st1));
    nbs_context_destroy(one);
    for (int threads = 1; threads <= 4; threads++) {
      cdef.threads = threads;
      nbs_context *ctx;
      ASSERT_OK(nbs_context_create(&cdef, &ctx));
      for (int parts = 2; parts <= 4; parts++) {
        for (int t = 1; t < parts; t++) {
          const int64_t deltas[] = {-9, -5, -1, 0, 1, 5, 9};
          for (size_t d = 0; d < sizeof deltas / sizeof *deltas; d++) {
            const int64_t at = n * t / parts + deltas[d];
            const int axis = (int)(((size_t)t + d) % (size_t)dim);
            const size_t i = (size_t)at * (size_t)dim + (size_t)axis;
            const size_t last = (size_t)n * (size_t)dim - 1;
            const double keep = s.coords[i], keep_last = s.coords[last];
            s.coords[i] = d % 2 ? INFINITY : NAN;
            s.coords[last] = NAN;
            CHECK_STATUS(nbs_detect(ctx, &in, NULL), NBS_ERR_COORD);
            CHECK_MSG(nbs_context_error_element(ctx) == at, "%d threads: element %lld, not %lld",
                      threads, (long long)nbs_context_error_element(ctx), (long long)at);
            s.coords[last] = keep_last;
            s.coords[i] = keep;
            radii[at] = d % 2 ? -1.0 : NAN;
            radii[n - 1] = 0.0;
            in.radii = radii;
            CHECK_STATUS(nbs_detect(ctx, &in, NULL), NBS_ERR_RADIUS);
            CHECK_EQ(nbs_context_error_element(ctx), at);
            in.radii = NULL;
            radii[at] = 0.5;
            radii[n - 1] = 0.5;
          }
        }
      }
      /* no bad number: the same box, so the same pairs, whatever the threads; the largest
       * radius in the last range still sets the cell edge */
      pair_list got;
      ASSERT_OK(detect_sorted(ctx, &s, NBS_CELLSORT, NBS_MODE_CONTACTS, &got));
      CHECK_TRUE(pair_lists_equal(&ref, &got));
      pair_list_free(&got);
      nbs_stats st;
      ASSERT_OK(nbs_last_stats(ctx, &st));
      for (int a = 0; a < 3; a++) CHECK_EQ(st.cells[a], st1.cells[a]);
      radii[n - 2] = 0.75;
      in.radii = radii;
      CHECK_STATUS(nbs_detect(ctx, &in, NULL), NBS_OK);
      ASSERT_OK(nbs_last_stats(ctx, &st));
      CHECK_TRUE(st.cell_size >= 1.5 && st.cell_size < 1.5 * (1 + 1e-5));
      in.radii = NULL;
      radii[n - 2] = 0.5;
      nbs_context_destroy(ctx);
    }
    pair_list_free(&ref);
    free(radii);
    scene_free(&s);
  }
}

static void test_budget_extent(void) {
  nbs_context_def cdef = nbs_default_context_def();
  /* under what NBS's heads need even with its axes folded (about 1.4 kB here) */
  cdef.cell_budget = 256;
  nbs_context *ctx;
  ASSERT_OK(nbs_context_create(&cdef, &ctx));
  scene s = test_scene(SCENE_SPARSE, 3, 2000, 0.5);
  nbs_input in = scene_input(&s);
  nbs_detect_def def = nbs_default_detect_def();
  def.algorithm = NBS_SCREENING;
  CHECK_STATUS(nbs_detect(ctx, &in, &def), NBS_ERR_BUDGET);
  CHECK_MSG(strstr(nbs_context_error(ctx), "budget") != NULL, "message: %s",
            nbs_context_error(ctx));
  def.algorithm = NBS_NBS;
  CHECK_STATUS(nbs_detect(ctx, &in, &def), NBS_ERR_BUDGET);
  def.algorithm = NBS_AUTO; /* auto never refuses: it takes an algorithm without cell arrays */
  CHECK_STATUS(nbs_detect(ctx, &in, &def), NBS_OK);
  nbs_stats st;
  nbs_last_stats(ctx, &st);
  CHECK_TRUE(st.algorithm == NBS_CELLSORT || st.algorithm == NBS_SORTING);
  scene_free(&s);
  nbs_context_destroy(ctx);

  /* A domain wider than any grid: screening and NBS say so; sorting and auto succeed. */
  ASSERT_OK(nbs_context_create(NULL, &ctx));
  s = test_scene(SCENE_FAR, 3, 500, 0.5);
  in = scene_input(&s);
  def.algorithm = NBS_SCREENING;
  CHECK_STATUS(nbs_detect(ctx, &in, &def), NBS_ERR_EXTENT);
  def.algorithm = NBS_NBS;
  CHECK_STATUS(nbs_detect(ctx, &in, &def), NBS_ERR_EXTENT);
  def.algorithm = NBS_CELLSORT;
  CHECK_STATUS(nbs_detect(ctx, &in, &def), NBS_ERR_EXTENT);
  def.algorithm = NBS_SORTING;
  CHECK_STATUS(nbs_detect(ctx, &in, &def), NBS_OK);
  nbs_last_stats(ctx, &st);
  CHECK_TRUE(st.compressed);
  def.algorithm = NBS_AUTO;
  CHECK_STATUS(nbs_detect(ctx, &in, &def), NBS_OK);
  nbs_last_stats(ctx, &st);
  CHECK_EQ(st.algorithm, NBS_SORTING);
  check_usable(ctx);
  scene_free(&s);
  nbs_context_destroy(ctx);
}

static int stop_after_two(void *user, const nbs_pair *pairs, size_t count) {
  (void)pairs;
  int *calls = user;
  (void)count;
  return ++*calls >= 2;
}

static void test_pair_limits(void) {
  scene s = test_scene(SCENE_IDENTICAL, 3, 300, 0.5); /* 44850 pairs */
  nbs_input in = scene_input(&s);
  for (int a = 0; a < NBS_ALGORITHM_COUNT; a++) {
    nbs_context_def cdef = nbs_default_context_def();
    cdef.max_pairs = 10000;
    nbs_context *ctx;
    ASSERT_OK(nbs_context_create(&cdef, &ctx));
    nbs_detect_def def = nbs_default_detect_def();
    def.algorithm = (nbs_algorithm)a;
    CHECK_STATUS(nbs_detect(ctx, &in, &def), NBS_ERR_PAIRS);
    nbs_stats st;
    nbs_last_stats(ctx, &st);
    CHECK_EQ(st.pairs, 10000);
    CHECK_TRUE(nbs__heads_empty(ctx) || ctx->work_kind == NBS__WORK_NONE);
    int calls = 0;
    def.callback = stop_after_two;
    def.user = &calls;
    CHECK_STATUS(nbs_detect(ctx, &in, &def), NBS_ERR_STOPPED);
    CHECK_EQ(calls, 2);
    check_usable(ctx);
    nbs_context_destroy(ctx);
  }
  scene_free(&s);
}

/* A pair callback that calls back into the detecting context: a detection of another,
 * larger scene and a reserve (each would have freed the arrays the outer detection is
 * using: a use after free under ASan before NBS_ERR_BUSY), then nbs_pairs; and a detection
 * on another context, which works. The outer detection must go on as if nothing happened. */
typedef struct reentry {
  nbs_context *ctx, *other;
  const nbs_input *big;
  nbs_status inner, reserve, elsewhere;
  size_t pairs_seen, count_inside;
  long calls;
} reentry;

static int call_back_in(void *user, const nbs_pair *pairs, size_t count) {
  (void)pairs;
  reentry *r = user;
  if (r->calls++ == 0) {
    r->inner = nbs_detect(r->ctx, r->big, NULL);
    r->reserve = nbs_context_reserve(r->ctx, 10 * r->big->n, 1000000);
    nbs_pairs(r->ctx, &r->count_inside);
    r->elsewhere = nbs_detect(r->other, r->big, NULL);
  }
  r->pairs_seen += count;
  return 0;
}

static void test_reentry(void) {
  scene s = test_scene(SCENE_UNIFORM, 3, 20000, 0.5);
  scene b = test_scene(SCENE_UNIFORM, 3, 80000, 0.3);
  nbs_input in = scene_input(&s), big = scene_input(&b);
  for (int a = 0; a < NBS_ALGORITHM_COUNT; a++) {
    if (a == NBS_DIRECT) continue; /* O(N^2) on 20000 elements: the others cover the sink */
    nbs_context *ctx, *other;
    ASSERT_OK(nbs_context_create(NULL, &ctx));
    ASSERT_OK(nbs_context_create(NULL, &other));
    pair_list ref;
    ASSERT_OK(detect_sorted(ctx, &s, (nbs_algorithm)a, NBS_MODE_CONTACTS, &ref));
    const size_t held = nbs_context_bytes(ctx);
    reentry r = {ctx, other, &big, NBS_OK, NBS_OK, NBS_ERR_NULL, 0, 99, 0};
    nbs_detect_def def = nbs_default_detect_def();
    def.algorithm = (nbs_algorithm)a;
    def.callback = call_back_in;
    def.user = &r;
    CHECK_STATUS(nbs_detect(ctx, &in, &def), NBS_OK);
    CHECK_STATUS(r.inner, NBS_ERR_BUSY);
    CHECK_STATUS(r.reserve, NBS_ERR_BUSY);
    CHECK_STATUS(r.elsewhere, NBS_OK);
    CHECK_EQ(r.count_inside, 0);
    CHECK_MSG(r.calls >= 2 && r.pairs_seen == ref.count, "%s: %ld batches, %zu pairs of %zu",
              nbs_algorithm_name((nbs_algorithm)a), r.calls, r.pairs_seen, ref.count);
    CHECK_TRUE(nbs_context_bytes(ctx) == held); /* the reserve changed nothing */
    CHECK_TRUE(nbs_context_error(ctx)[0] == '\0');
    nbs_stats st;
    ASSERT_OK(nbs_last_stats(ctx, &st));
    CHECK_EQ(st.n, s.n);
    /* and the context is whole after it */
    pair_list again;
    ASSERT_OK(detect_sorted(ctx, &s, (nbs_algorithm)a, NBS_MODE_CONTACTS, &again));
    CHECK_TRUE(pair_lists_equal(&ref, &again));
    pair_list_free(&again);
    pair_list_free(&ref);
    nbs_context_destroy(other);
    nbs_context_destroy(ctx);
  }
  scene_free(&b);
  scene_free(&s);
}

static void test_allocator_def(void) {
  nbs_context_def cdef = nbs_default_context_def();
  test_alloc ta = {0, 0, 0, -1, 0, 0};
  cdef.allocator = test_allocator(&ta);
  cdef.allocator.free = NULL;
  nbs_context *ctx = (nbs_context *)&cdef;
  CHECK_STATUS(nbs_context_create(&cdef, &ctx), NBS_ERR_ARGUMENT);
  CHECK_TRUE(ctx == NULL);
  /* realloc without alloc and free */
  ta.with_realloc = 1;
  cdef.allocator = test_allocator(&ta);
  cdef.allocator.alloc = NULL;
  cdef.allocator.free = NULL;
  CHECK_STATUS(nbs_context_create(&cdef, &ctx), NBS_ERR_ARGUMENT);
  /* negative thread counts */
  cdef = nbs_default_context_def();
  cdef.threads = -1;
  CHECK_STATUS(nbs_context_create(&cdef, &ctx), NBS_ERR_ARGUMENT);
}

static int count_pairs(void *user, const nbs_pair *pairs, size_t count) {
  (void)pairs;
  *(size_t *)user += count;
  return 0;
}

/* Fails the k-th allocation for every k a detection reaches, in every algorithm, mode and
 * sink: NBS_ERR_NOMEM each time, nothing leaked, and the context then correct. */
static void test_allocation_failure(void) {
  for (int dim = 2; dim <= 3; dim++) {
    scene s = test_scene(SCENE_IDENTICAL, dim, 120, 0.5); /* 7140 pairs: the buffer grows */
    scene u = test_scene(SCENE_UNIFORM, dim, 800, 0.5);
    for (int a = 0; a < NBS_ALGORITHM_COUNT; a++) {
      for (int sink = 0; sink < 4; sink++) { /* bit 0: callback; bit 1: allocator's realloc */
        for (int scn = 0; scn < 2; scn++) {
          const scene *sc = scn ? &u : &s;
          nbs_input in = scene_input(sc);
          pair_list ref;
          {
            nbs_context *rc;
            ASSERT_OK(nbs_context_create(NULL, &rc));
            ASSERT_OK(detect_sorted(rc, sc, NBS_DIRECT, NBS_MODE_CONTACTS, &ref));
            nbs_context_destroy(rc);
          }
          long reached = 0;
          for (long k = 0;; k++) {
            test_alloc ta = {0, 0, 0, k, 0, sink >> 1};
            nbs_context_def cdef = nbs_default_context_def();
            cdef.allocator = test_allocator(&ta);
            nbs_context *ctx;
            nbs_status st = nbs_context_create(&cdef, &ctx);
            if (st != NBS_OK) {
              CHECK_STATUS(st, NBS_ERR_NOMEM);
              CHECK_EQ(ta.live, 0);
              continue;
            }
            nbs_detect_def def = nbs_default_detect_def();
            def.algorithm = (nbs_algorithm)a;
            size_t counted = 0;
            if (sink & 1) {
              def.callback = count_pairs;
              def.user = &counted;
            }
            st = nbs_detect(ctx, &in, &def);
            if (ta.failures == 0) {
              CHECK_STATUS(st, NBS_OK);
              if (sink & 1) CHECK_EQ(counted, ref.count);
              nbs_context_destroy(ctx);
              CHECK_EQ(ta.live, 0);
              reached = k;
              break;
            }
            CHECK_MSG(st == NBS_ERR_NOMEM, "%dD %s sink %d: allocation %ld failed, status %s",
                      dim, nbs_algorithm_name((nbs_algorithm)a), sink, k, nbs_status_name(st));
            /* the context stays usable */
            ta.fail_at = -1;
            pair_list got;
            CHECK_STATUS(detect_sorted(ctx, sc, (nbs_algorithm)a, NBS_MODE_CONTACTS, &got),
                         NBS_OK);
            CHECK_MSG(pair_lists_equal(&got, &ref), "%dD %s: wrong pairs after failure %ld",
                      dim, nbs_algorithm_name((nbs_algorithm)a), k);
            CHECK_TRUE(nbs__heads_empty(ctx));
            pair_list_free(&got);
            nbs_context_destroy(ctx);
            CHECK_EQ(ta.live, 0);
            CHECK_EQ(ta.live_bytes, 0);
            if (k > 100) {
              TEST_FAIL_AT("more than 100 allocations in one detection");
              break;
            }
          }
          CHECK_MSG(reached >= 2, "%dD %s: only %ld allocations were reached", dim,
                    nbs_algorithm_name((nbs_algorithm)a), reached);
          pair_list_free(&ref);
        }
      }
    }
    scene_free(&s);
    scene_free(&u);
  }
}

/* A random sequence of contexts and detections under every limit at once, as a simulation
 * code that sets them might meet them: contexts with 0 to 3 threads, a counting allocator
 * (with or without realloc), max_pairs of none, a few, or some thousands, and cell budgets
 * of the default or a few kB; scenes of 2D and 3D, 0 to 3000 elements or 10000 to 20000,
 * with or without radii, sometimes 1000 times wider, with 1 element in 300 a hundred million
 * diameters out; time steps; any algorithm, from scratch or not, into the buffer or a
 * callback that sometimes stops; and, a third of the time, the allocator failing one of the
 * next few allocations. Each status must be one the API documents for what happened and
 * mean what it says: NBS_OK with exactly the contacts of a fresh context's direct (or
 * NBS beyond 4000 elements); NBS_ERR_PAIRS only with a max_pairs below the contacts
 * and no callback; NBS_ERR_NOMEM only when an allocation failed; NBS_ERR_STOPPED only when
 * the callback asked; NBS_ERR_BUDGET and NBS_ERR_EXTENT never from auto. Any failure has an
 * error text and leaves no pairs in the buffer; the context's byte count is the allocator's
 * live bytes after every detection, its lists are empty, and destroying it frees all. (A
 * probe like it ran 2256 detections on three other seeds under ASan and found nothing.) */
typedef struct collected {
  pair_list l;
  size_t cap;
  int batches, stop_at;
} collected;

static int collect_pairs(void *user, const nbs_pair *pairs, size_t count) {
  collected *c = user;
  if (c->l.count + count > c->cap) {
    c->cap = 2 * (c->l.count + count) + 64;
    nbs_pair *p = realloc(c->l.p, c->cap * sizeof *p);
    if (!p) abort();
    c->l.p = p;
  }
  memcpy(c->l.p + c->l.count, pairs, count * sizeof *pairs);
  c->l.count += count;
  c->batches++;
  return c->stop_at > 0 && c->batches >= c->stop_at;
}

static void test_limit_sequence(void) {
  const int64_t most = 20000;
  double *x = malloc((size_t)most * 3 * sizeof *x), *r = malloc((size_t)most * sizeof *r);
  ASSERT_TRUE(x && r);
  uint64_t state = 2718;
  int tally[NBS_ERR_BUSY + 1] = {0};
  collected col = {{NULL, 0}, 0, 0, 0};
  for (int it = 0; it < 60 && !test_failures; it++) {
    test_alloc ta = {0, 0, 0, -1, 0, test_unit(&state) < 0.5};
    nbs_context_def cdef = nbs_default_context_def();
    cdef.allocator = test_allocator(&ta);
    cdef.threads = (int)(test_unit(&state) * 4);
    const double u = test_unit(&state);
    cdef.max_pairs = u < 0.25 ? 0 : u < 0.5 ? (size_t)(test_unit(&state) * 50)
                                            : (size_t)(test_unit(&state) * 20000);
    if (test_unit(&state) < 0.3) cdef.cell_budget = (size_t)(test_unit(&state) * 100000);
    nbs_context *ctx;
    ASSERT_OK(nbs_context_create(&cdef, &ctx));
    const int dim = test_unit(&state) < 0.5 ? 2 : 3;
    const int64_t n = test_unit(&state) < 0.15 ? 10000 + (int64_t)(test_unit(&state) * 10000)
                                                : (int64_t)(test_unit(&state) * 3000);
    const bool radii = test_unit(&state) < 0.3;
    const double box = pow((double)(n + 1) / (0.2 + test_unit(&state)), 1.0 / dim) *
                       (test_unit(&state) < 0.2 ? 1000.0 : 1.0);
    for (int64_t k = 0; k < n * dim; k++) {
      x[k] = test_unit(&state) * box + (test_unit(&state) < 1.0 / 300 ? 1e8 : 0.0);
    }
    for (int64_t k = 0; k < n; k++) r[k] = 0.1 + 0.4 * test_unit(&state);
    scene s = scene_view(dim, n, x, radii ? r : NULL);
    nbs_input in = scene_input(&s);
    for (int step = 0; step < 5 && !test_failures; step++) {
      if (step > 0 && test_unit(&state) < 0.5) {
        for (int64_t k = 0; k < n * dim; k++) x[k] += 1e-3 * (test_unit(&state) - 0.5);
      }
      pair_list ref;
      {
        nbs_context *rc;
        ASSERT_OK(nbs_context_create(NULL, &rc));
        ASSERT_OK(detect_sorted(rc, &s, n > 4000 ? NBS_NBS : NBS_DIRECT,
                                NBS_MODE_CONTACTS, &ref));
        nbs_context_destroy(rc);
      }
      nbs_detect_def def = nbs_default_detect_def();
      def.algorithm = (nbs_algorithm)(test_unit(&state) * NBS_ALGORITHM_COUNT);
      if (def.algorithm == NBS_DIRECT && n > 4000) def.algorithm = NBS_AUTO;
      const bool callback = test_unit(&state) < 0.3;
      col.l.count = 0;
      col.batches = 0;
      col.stop_at = test_unit(&state) < 0.3 ? 1 + (int)(test_unit(&state) * 3) : 0;
      if (callback) {
        def.callback = collect_pairs;
        def.user = &col;
      }
      def.sorted = !callback;
      def.fresh = test_unit(&state) < 0.25;
      const bool fail = test_unit(&state) < 0.3;
      ta.fail_at = fail ? ta.calls + (long)(test_unit(&state) * 6) : -1;
      ta.failures = 0;
      const nbs_status st = nbs_detect(ctx, &in, &def);
      ta.fail_at = -1;
      if ((size_t)st < sizeof tally / sizeof *tally) tally[st]++; /* others fail below */
      pair_list got;
      got.p = (nbs_pair *)nbs_pairs(ctx, &got.count);
      /* the buffer holds no pairs after an error, nor after a detection with a callback */
      CHECK_MSG((st == NBS_OK && !callback) || got.count == 0,
                "context %d detection %d: %s, %zu pairs in the buffer", it, step,
                nbs_status_name(st), got.count);
      if (callback) {
        nbs_sort_pairs(col.l.p, col.l.count);
        got = col.l;
      }
      const char *name = nbs_algorithm_name(def.algorithm);
      char what[96];
      snprintf(what, sizeof what, "context %d detection %d: %s, %dD, n = %lld%s%s", it, step,
               name, dim, (long long)n, radii ? ", radii" : "", callback ? ", callback" : "");
      switch (st) {
      case NBS_OK:
        CHECK_MSG(pair_lists_equal(&got, &ref), "%s: %zu pairs of %zu", what, got.count,
                  ref.count);
        CHECK_MSG(!callback || !col.stop_at || col.batches < col.stop_at,
                  "%s: the callback asked to stop", what);
        break;
      case NBS_ERR_PAIRS:
        CHECK_MSG(!callback && cdef.max_pairs && ref.count > cdef.max_pairs,
                  "%s: NBS_ERR_PAIRS with max_pairs %zu, %zu contacts", what, cdef.max_pairs,
                  ref.count);
        break;
      case NBS_ERR_NOMEM:
        CHECK_MSG(ta.failures > 0, "%s: NBS_ERR_NOMEM with no allocation failed", what);
        break;
      case NBS_ERR_STOPPED:
        CHECK_MSG(callback && col.stop_at, "%s: NBS_ERR_STOPPED unasked", what);
        break;
      case NBS_ERR_BUDGET:
      case NBS_ERR_EXTENT:
        CHECK_MSG(def.algorithm != NBS_AUTO, "%s: auto refused (%s)", what,
                  nbs_context_error(ctx));
        break;
      default:
        CHECK_MSG(false, "%s: status %s (%s)", what, nbs_status_name(st),
                  nbs_context_error(ctx));
      }
      CHECK_MSG(st == NBS_OK || nbs_context_error(ctx)[0] != '\0', "%s: %s without a text", what,
                nbs_status_name(st));
      CHECK_MSG(nbs_context_bytes(ctx) == ta.live_bytes, "%s: %zu bytes held, %zu live", what,
                nbs_context_bytes(ctx), ta.live_bytes);
      CHECK_TRUE(nbs__heads_empty(ctx));
      pair_list_free(&ref);
    }
    nbs_context_destroy(ctx);
    CHECK_EQ(ta.live, 0);
    CHECK_EQ(ta.live_bytes, 0);
  }
  /* the sequence reaches every status it checks */
  const nbs_status reached[] = {NBS_OK,          NBS_ERR_PAIRS,  NBS_ERR_NOMEM,
                                NBS_ERR_STOPPED, NBS_ERR_BUDGET, NBS_ERR_EXTENT};
  for (size_t k = 0; k < sizeof reached / sizeof *reached; k++) {
    CHECK_MSG(tally[reached[k]] > 0, "no detection of the sequence gave %s",
              nbs_status_name(reached[k]));
  }
  free(col.l.p);
  free(x);
  free(r);
}

int main(int argc, char **argv) {
  static const test_case tests[] = {
      {"null_and_ranges", test_null_and_ranges},
      {"bad_numbers", test_bad_numbers},
      {"bad_numbers_threads", test_bad_numbers_threads},
      {"budget_extent", test_budget_extent},
      {"pair_limits", test_pair_limits},
      {"reentry", test_reentry},
      {"allocator_def", test_allocator_def},
      {"allocation_failure", test_allocation_failure},
      {"limit_sequence", test_limit_sequence},
  };
  return test_main(argc, argv, tests, sizeof tests / sizeof *tests);
}
