/*
 * Determinism: the same input gives byte-identical pairs
 *   - across runs: repeated detections, fresh contexts, contexts that held another layout,
 *     and the callback sink, each in the algorithm's own order (not sorted);
 *   - across time steps: cellsort's start from the last detection's cell order gives the
 *     bytes of a detection from scratch, whatever the elements did since;
 *   - across thread counts: cellsort (and auto) with 1, 2, 3 and 8 threads, in order;
 *   - across sorts: cellsort's partition (NBS_PARTITION=always) and its sort and gather
 *     (NBS_PARTITION=never), in order, with 1 to 8 threads;
 *   - across kernels: cellsort's AVX-512 kernel (where the processor has it) and its generic
 *     one (NBS_SIMD=generic), in order, and so does the AVX2 one (NBS_SIMD=avx2); nbs's
 *     AVX-512 and AVX2 tests of the gathered candidates and its plain one the same;
 *   - across algorithms: after nbs_sort_pairs every algorithm gives the same bytes;
 *   - across orientations: the axis cellsort's rows and nbs's outer lists lie along is
 *     chosen by the cells per axis (nbs__axis_order), which fixes the order of the pairs and
 *     the speed: a slab, a strip and a rod, turned, take the axis the rule says, and give
 *     direct's pairs;
 *   - across builds and machines: golden hashes (FNV-1a 64 of the sorted pair list, each
 *     index as 4 little-endian bytes) of fixed scenes, committed below.
 *
 * The golden scenes use no transcendental function, so that their coordinates do not depend
 * on the C library: the lattice, faces and identical scenes of scenes/ (whose coordinates
 * are integers times the diameter, or one point; the library's pow() only picks the lattice
 * side there, an integer), and the generator below, which uses splitmix64 and only
 * +, -, *, sqrt and integer-to-double conversions, all exact or correctly rounded in
 * IEEE 754.
 *
 * Regenerating the golden table (only after a deliberate change of the contract or of a
 * scene): NBS_GOLDEN_PRINT=1 build/tests/test_determinism golden_hashes
 * prints the table in C; paste it over `goldens` below and say why in the commit.
 */
/* setenv, unsetenv */
#define _POSIX_C_SOURCE 200809L

#include "internal.h"
#include "test.h"
#include "util.h"

#include <float.h>
#include <math.h>
#include <stdint.h>

/* The scenes must be the same bytes with every compiler: no fused multiply-add may be
 * formed from their arithmetic (GCC in ISO C mode, as built here, does not contract; clang
 * does unless told). */
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#endif

/* ---- scenes without transcendental functions ------------------------------------------ */

static uint64_t det_next(uint64_t *state) {
  uint64_t z = (*state += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

/* Uniform in [0, 1), exactly (a 53-bit integer times 2^-53). */
static double det_uniform(uint64_t *state) { return (double)(det_next(state) >> 11) * 0x1p-53; }

typedef enum det_kind {
  DET_UNIFORM,   /* uniform in a box of edge `box` */
  DET_QUANTIZED, /* uniform on a grid of step 1/8: many pairs exactly at the contact distance */
  DET_RADII,     /* uniform, radii uniform in [0.05, 0.5] (ratio 10) */
  DET_CLUSTERS,  /* two dense boxes far apart, plus a few outliers at 1e12 */
  DET_NEAR_TIES, /* pairs at a distance of D up to rounding: (a, sqrt(1 - a^2)) apart */
  DET_STRIP,     /* DET_QUANTIZED along x in [0, box), the other axes in [0, 2): a strip
                  * (3D: a rod), whose few rows run its whole length */
} det_kind;

static scene det_scene(det_kind kind, int dim, int64_t n, double box, double offset,
                       uint64_t seed) {
  scene s;
  memset(&s, 0, sizeof s);
  s.dim = dim;
  s.n = n;
  s.diameter = 1.0;
  s.coords = malloc((size_t)n * (size_t)dim * sizeof(double));
  if (!s.coords) abort();
  if (kind == DET_RADII) {
    s.radii = malloc((size_t)n * sizeof(double));
    if (!s.radii) abort();
  }
  uint64_t rng = seed;
  if (kind == DET_NEAR_TIES) {
    /* Element 2m at a random point, element 2m + 1 at a unit offset whose squared length is
     * 1 only up to rounding (sqrt is correctly rounded, so this is portable): whether the
     * pair touches depends on the last bit of the distance test, which a fused multiply-add
     * or any other change of its evaluation would alter. */
    for (int64_t k = 0; k + 1 < n; k += 2) {
      double *p = s.coords + k * dim, *q = p + dim;
      double a = det_uniform(&rng), b = dim == 3 ? det_uniform(&rng) * (1.0 - a) : 0.0;
      double off[3] = {a, dim == 3 ? b : sqrt(1.0 - a * a), 0.0};
      if (dim == 3) off[2] = sqrt(1.0 - a * a - b * b);
      for (int d = 0; d < dim; d++) {
        p[d] = det_uniform(&rng) * box + offset;
        q[d] = p[d] + off[d];
      }
    }
    if (n % 2) {
      for (int d = 0; d < dim; d++) s.coords[(n - 1) * dim + d] = -10.0;
    }
    return s;
  }
  for (int64_t k = 0; k < n; k++) {
    for (int a = 0; a < dim; a++) {
      double v;
      switch (kind) {
      case DET_QUANTIZED:
        v = (double)(det_next(&rng) % (uint64_t)(box * 8.0)) * 0.125;
        break;
      case DET_STRIP:
        v = (double)(det_next(&rng) % (uint64_t)(a == 0 ? box * 8.0 : 16.0)) * 0.125;
        break;
      case DET_CLUSTERS:
        v = det_uniform(&rng) * box + (k % 2 ? 1000.0 : 0.0);
        if (k % 97 == 0) v += 1e12;
        break;
      default:
        v = det_uniform(&rng) * box;
        break;
      }
      s.coords[k * dim + a] = v + offset;
    }
    if (s.radii) s.radii[k] = 0.05 + 0.45 * det_uniform(&rng);
  }
  return s;
}

/* ---- the fixed scenes ---------------------------------------------------------------- */

typedef struct det_case {
  const char *name;
  int dim;
} det_case;

static const det_case cases[] = {
    {"lattice-2d", 2},   {"lattice-3d", 3},   {"faces-2d", 2},     {"faces-3d", 3},
    {"identical-3d", 3}, {"uniform-2d", 2},   {"uniform-3d", 3},   {"quantized-2d", 2},
    {"quantized-3d", 3}, {"radii-2d", 2},     {"radii-3d", 3},     {"offset1e9-3d", 3},
    {"clusters-3d", 3},  {"near-ties-2d", 2}, {"near-ties-3d", 3},
};
#define NCASES (sizeof cases / sizeof *cases)

static scene make_case(size_t c) {
  const int dim = cases[c].dim;
  switch (c) {
  case 0:
  case 1: return test_scene(SCENE_LATTICE, dim, 1000, 0.5);
  case 2:
  case 3: return test_scene(SCENE_FACES, dim, 1000, 0.5);
  case 4: return test_scene(SCENE_IDENTICAL, dim, 200, 0.5);
  case 5: return det_scene(DET_UNIFORM, dim, 3000, 50.0, 0.0, 11);
  case 6: return det_scene(DET_UNIFORM, dim, 4000, 14.0, 0.0, 12);
  case 7: return det_scene(DET_QUANTIZED, dim, 3000, 40.0, 0.0, 13);
  case 8: return det_scene(DET_QUANTIZED, dim, 4000, 12.0, 0.0, 14);
  case 9: return det_scene(DET_RADII, dim, 3000, 30.0, 0.0, 15);
  case 10: return det_scene(DET_RADII, dim, 4000, 9.0, 0.0, 16);
  case 11: return det_scene(DET_UNIFORM, dim, 3000, 12.0, 1e9, 17);
  case 12: return det_scene(DET_CLUSTERS, dim, 3000, 10.0, 0.0, 18);
  case 13: return det_scene(DET_NEAR_TIES, dim, 4000, 4000.0, 0.0, 19);
  default: return det_scene(DET_NEAR_TIES, dim, 4000, 400.0, 0.0, 20);
  }
}

/* ---- hashing ------------------------------------------------------------------------- */

/* FNV-1a 64 of the pairs, each index as 4 little-endian bytes (the same on every host). */
static uint64_t fnv1a_pairs(const nbs_pair *p, size_t count) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (size_t k = 0; k < count; k++) {
    const uint32_t v[2] = {(uint32_t)p[k].i, (uint32_t)p[k].j};
    for (int w = 0; w < 2; w++) {
      for (int b = 0; b < 4; b++) {
        h ^= (v[w] >> (8 * b)) & 0xffu;
        h *= 0x100000001b3ull;
      }
    }
  }
  return h;
}

/* The golden table: contacts of each case, sorted. */
typedef struct golden {
  const char *name;
  uint64_t count;
  uint64_t hash;
} golden;

static const golden goldens[] = {
    {"lattice-2d", 1936, 0xac4a4703b133f029ull},
    {"lattice-3d", 2700, 0x6a8143df562c2b4cull},
    {"faces-2d", 3811, 0xc2f77b61839d8e36ull},
    {"faces-3d", 10476, 0xdd22af248ceb5548ull},
    {"identical-3d", 19900, 0x57e37b98cb8c2be5ull},
    {"uniform-2d", 5605, 0x1c957d35e140f095ull},
    {"uniform-3d", 11294, 0x4dc71e1e1ac16919ull},
    {"quantized-2d", 8581, 0xb4c5bd01658aa26aull},
    {"quantized-3d", 17710, 0xdee6f9f3c70475c6ull},
    {"radii-2d", 5437, 0x284ae48d687c6115ull},
    {"radii-3d", 9510, 0xd1f8c81df8330f90ull},
    {"offset1e9-3d", 9829, 0x86b1da4745100d4bull},
    {"clusters-3d", 8343, 0x7bf4b74b2b211fdaull},
    {"near-ties-2d", 975, 0x61f38d1663531880ull},
    {"near-ties-3d", 992, 0xd255d08d7add9639ull},
};

/* Figures for docs/RELIABILITY.md: pair lists compared byte for byte. */
static long lists_compared;

static bool same_bytes(const pair_list *a, const pair_list *b) {
  lists_compared++;
  return pair_lists_equal(a, b);
}

/* ---- tests --------------------------------------------------------------------------- */

/* Every algorithm, both modes: the same bytes in the same order from a fresh context, from
 * the same context again, from a context that last held another algorithm's layout for a
 * larger scene, and through a callback. */
static void test_repeat_runs(void) {
  for (size_t c = 0; c < NCASES; c++) {
    scene s = make_case(c);
    scene other = det_scene(DET_UNIFORM, 3, 6000, 40.0, -5.0, 99);
    for (int a = 0; a < NBS_ALGORITHM_COUNT; a++) {
      const nbs_algorithm algo = (nbs_algorithm)a;
      for (int mode = 0; mode < 2; mode++) {
        nbs_context *fresh, *used;
        ASSERT_OK(nbs_context_create(NULL, &fresh));
        ASSERT_OK(nbs_context_create(NULL, &used));
        pair_list first, again, reused, viacb, scratch;
        nbs_status st = detect_raw(fresh, &s, algo, (nbs_mode)mode, &first);
        if (st != NBS_OK) {
          /* only the documented refusals, and the same refusal every time */
          CHECK_MSG(st == NBS_ERR_BUDGET || st == NBS_ERR_EXTENT, "%s %s: %s", cases[c].name,
                    nbs_algorithm_name(algo), nbs_status_name(st));
          CHECK_STATUS(detect_raw(used, &s, algo, (nbs_mode)mode, &again), st);
          nbs_context_destroy(fresh);
          nbs_context_destroy(used);
          continue;
        }
        ASSERT_OK(detect_raw(fresh, &s, algo, (nbs_mode)mode, &again));
        /* the other context: another scene with each algorithm first, then this one. direct
         * (no layout of its own, and never the last) only before itself: its O(N^2) on the
         * larger scene was a third of the test's time under AddressSanitizer */
        for (int b = 0; b < NBS_ALGORITHM_COUNT; b++) {
          if (b == NBS_DIRECT && algo != NBS_DIRECT) continue;
          if (detect_raw(used, &other, (nbs_algorithm)b, NBS_MODE_CONTACTS, &scratch) == NBS_OK) {
            pair_list_free(&scratch);
          }
        }
        ASSERT_OK(detect_raw(used, &s, algo, (nbs_mode)mode, &reused));
        ASSERT_OK(detect_callback(used, &s, algo, (nbs_mode)mode, &viacb));
        CHECK_MSG(same_bytes(&first, &again), "%s %s mode %d: a repeated run differs",
                  cases[c].name, nbs_algorithm_name(algo), mode);
        CHECK_MSG(same_bytes(&first, &reused), "%s %s mode %d: a used context differs",
                  cases[c].name, nbs_algorithm_name(algo), mode);
        CHECK_MSG(same_bytes(&first, &viacb), "%s %s mode %d: the callback order differs",
                  cases[c].name, nbs_algorithm_name(algo), mode);
        pair_list_free(&first);
        pair_list_free(&again);
        pair_list_free(&reused);
        pair_list_free(&viacb);
        nbs_context_destroy(fresh);
        nbs_context_destroy(used);
      }
    }
    scene_free(&other);
    scene_free(&s);
  }
}

/* Threads: cellsort and auto give the same bytes, in the same order, for every thread
 * count (and with a callback or max_pairs, which keep them on one thread). The scenes are
 * large enough (60000 elements) for cellsort to use threads: a square (cube) and a strip
 * (rod), whose threads start and end inside its few long rows. The threads' sweep takes
 * chunks from another's part where one falls behind, which a run may or may not see; with
 * NBS_STEAL=first (steal = 1) every thread first takes the last chunk of the next
 * one's part, whose pairs must still land in their place, and some must have been taken.
 * Without OpenMP the thread count is ignored and the comparison still holds. */
static void test_thread_shape(const int *counts, size_t ncounts, int shape, long *stolen) {
  const int dim = 2 + shape % 2;
  const bool strip = shape >= 2;
  scene s = strip ? det_scene(DET_STRIP, dim, 60000, dim == 2 ? 40000.0 : 15000.0, 0.0, 22)
                  : det_scene(DET_QUANTIZED, dim, 60000, dim == 2 ? 300.0 : 45.0, 0.0, 21);
  const char *what = strip ? "strip" : "square";
  const nbs_algorithm algos[] = {NBS_CELLSORT, NBS_AUTO};
  for (size_t a = 0; a < 2; a++) {
    for (int mode = 0; mode < 2; mode++) {
      pair_list ref = {NULL, 0};
      for (size_t t = 0; t < ncounts; t++) {
        nbs_context_def cdef = nbs_default_context_def();
        cdef.threads = counts[t];
        nbs_context *ctx;
        ASSERT_OK(nbs_context_create(&cdef, &ctx));
        pair_list got, again, viacb;
        ASSERT_OK(detect_raw(ctx, &s, algos[a], (nbs_mode)mode, &got));
        *stolen += ctx->cs_stolen;
        ASSERT_OK(detect_raw(ctx, &s, algos[a], (nbs_mode)mode, &again));
        ASSERT_OK(detect_callback(ctx, &s, algos[a], (nbs_mode)mode, &viacb));
        if (t == 0) {
          CHECK_MSG(got.count > (size_t)s.n / 2, "%dD %s: only %zu pairs", dim, what,
                    got.count);
          ref = got;
          got.p = NULL;
        } else {
          CHECK_MSG(same_bytes(&got, &ref), "%dD %s %s mode %d: %d threads differ from 1",
                    dim, what, nbs_algorithm_name(algos[a]), mode, counts[t]);
        }
        CHECK_MSG(same_bytes(&again, &ref), "%dD %s %s mode %d, %d threads: a repeat differs",
                  dim, what, nbs_algorithm_name(algos[a]), mode, counts[t]);
        CHECK_MSG(same_bytes(&viacb, &ref), "%dD %s %s mode %d, %d threads: the callback "
                  "differs", dim, what, nbs_algorithm_name(algos[a]), mode, counts[t]);
        pair_list_free(&got);
        pair_list_free(&again);
        pair_list_free(&viacb);
        nbs_context_destroy(ctx);
      }
      pair_list_free(&ref);
    }
  }
  scene_free(&s);
}

static void test_thread_counts(void) {
  /* cellsort takes a thread per 20000 elements (nbs__cs_threads), 3 of these scenes': 8 asks
   * more than it takes (4 and 7 were the same detections as 3 and 8) */
  const int counts[] = {1, 2, 3, 8};
  for (int steal = 0; steal < 2; steal++) {
    if (steal) ASSERT_TRUE(setenv("NBS_STEAL", "first", 1) == 0);
    long stolen = 0;
    for (int shape = 0; shape < 4; shape++) {
      test_thread_shape(counts, sizeof counts / sizeof *counts, shape, &stolen);
    }
    unsetenv("NBS_STEAL");
#if defined(_OPENMP)
    if (steal) CHECK_MSG(stolen > 0, "NBS_STEAL=first: no chunk taken from another part");
#endif
  }
}

/* Threads the runtime does not give as asked. A simulation code that threads its own loops
 * may call nbs_detect from inside its parallel region, a context per thread: with nesting
 * off (OpenMP's default) a region of the library then gets one thread, and with nesting on,
 * OMP_DYNAMIC or OMP_THREAD_LIMIT, whatever the runtime gives. cellsort cuts its work into
 * as many parts as the threads it asks for, and a thread of a smaller team does several
 * (NBS__PARTS): the bytes must be those of one thread, from scratch and in a time step
 * (the start from the last order, and its merge of the elements that moved). The settings:
 * two threads of the caller, each detecting with a context of 0 (OpenMP's default), 2 and 3
 * threads, nesting off and then on; and the same three contexts called from one thread
 * with OMP_DYNAMIC on. ctest also runs the thread tests under OMP_THREAD_LIMIT=2, where 3 to 8
 * threads asked get 2. Before NBS__PARTS, each of these crashed or gave a wrong error.
 * Without OpenMP the contexts of 0, 2 and 3 threads run from one thread, one thread each. */
static void test_caller_threads(void) {
#if defined(_OPENMP)
  const int save_levels = omp_get_max_active_levels();
  const int save_dynamic = omp_get_dynamic();
  const int settings = 3;
#else
  const int settings = 1; /* the contexts of 0, 2 and 3 threads from one thread */
#endif
  for (int dim = 2; dim <= 3; dim++) {
    scene s = det_scene(DET_QUANTIZED, dim, 60000, dim == 2 ? 300.0 : 45.0, 0.0, 31);
    /* a time step: every 50th element a quarter of a diameter further in x */
    scene t = s;
    t.coords = malloc((size_t)s.n * (size_t)dim * sizeof(double));
    if (!t.coords) abort();
    memcpy(t.coords, s.coords, (size_t)s.n * (size_t)dim * sizeof(double));
    for (int64_t k = 0; k < s.n; k += 50) t.coords[k * dim] += 0.25;
    pair_list ref[2];
    nbs_context_def one = nbs_default_context_def();
    one.threads = 1;
    nbs_context *ctx;
    ASSERT_OK(nbs_context_create(&one, &ctx));
    ASSERT_OK(detect_raw(ctx, &s, NBS_CELLSORT, NBS_MODE_CONTACTS, &ref[0]));
    ASSERT_OK(detect_raw(ctx, &t, NBS_CELLSORT, NBS_MODE_CONTACTS, &ref[1]));
    nbs_context_destroy(ctx);
    CHECK_MSG(ref[0].count > (size_t)s.n / 2 && ref[1].count > (size_t)s.n / 2,
              "%dD: only %zu and %zu pairs", dim, ref[0].count, ref[1].count);
    for (int setting = 0; setting < settings; setting++) {
#if defined(_OPENMP)
      const bool nested = setting < 2;
      omp_set_max_active_levels(setting == 1 ? 2 : 1);
      omp_set_dynamic(setting == 2);
#else
      const bool nested = false;
#endif
      int bad = 0, reused = 0, ran = 0;
#if defined(_OPENMP)
#pragma omp parallel num_threads(nested ? 2 : 1) reduction(+ : bad, reused, ran)
#endif
      {
        const int asked[] = {0, 2, 3};
        for (int a = 0; a < 3; a++) {
          nbs_context_def cdef = nbs_default_context_def();
          cdef.threads = asked[a];
          nbs_context *c;
          if (nbs_context_create(&cdef, &c) != NBS_OK) {
            bad++;
            continue;
          }
          for (int step = 0; step < 2; step++) {
            pair_list got;
            nbs_stats st;
            if (detect_raw(c, step ? &t : &s, NBS_CELLSORT, NBS_MODE_CONTACTS, &got) != NBS_OK ||
                nbs_last_stats(c, &st) != NBS_OK) {
              bad++;
              continue;
            }
            bad += !pair_lists_equal(&got, &ref[step]);
            reused += step == 1 && st.reused_order && st.moved > 0;
            ran++;
            pair_list_free(&got);
          }
          nbs_context_destroy(c);
        }
      }
      lists_compared += ran;
      const int want = (nested ? 2 : 1) * 3 * 2;
      CHECK_MSG(bad == 0 && ran == want, "%dD, setting %d: %d of %d detections differ from one "
                "thread's or failed", dim, setting, bad + (want - ran), want);
      CHECK_MSG(reused == want / 2, "%dD, setting %d: %d of %d time steps started from the "
                "last order", dim, setting, reused, want / 2);
    }
    pair_list_free(&ref[0]);
    pair_list_free(&ref[1]);
    free(t.coords);
    scene_free(&s);
  }
#if defined(_OPENMP)
  omp_set_max_active_levels(save_levels);
  omp_set_dynamic(save_dynamic);
#endif
}

/* A context of `threads` threads created with NBS_PARTITION=way in the environment; false
 * where it could not be. */
static bool partition_context(int threads, const char *way, nbs_context **ctx) {
  nbs_context_def cdef = nbs_default_context_def();
  cdef.threads = threads;
  CHECK_TRUE(setenv("NBS_PARTITION", way, 1) == 0);
  const nbs_status st = nbs_context_create(&cdef, ctx);
  unsetenv("NBS_PARTITION");
  CHECK_STATUS(st, NBS_OK);
  return st == NBS_OK;
}

/* Two contexts of `threads` threads: *part created with NBS_PARTITION=always in the
 * environment, *sort with NBS_PARTITION=never; false where either could not be. */
static bool partition_contexts(int threads, nbs_context **part, nbs_context **sort) {
  const bool a = partition_context(threads, "always", part);
  const bool b = partition_context(threads, "never", sort);
  return a && b;
}

/* The partition: cellsort's sort by the top digit with the coordinates carried along
 * (NBS_PARTITION=always, read when a context is created; by default only inputs larger than
 * 1 GiB take it) gives the bytes of the sort and the gather (NBS_PARTITION=never), in
 * order, in both modes, for 1, 2 and 3 threads (the most 60000 elements get), from scratch
 * and again from the order it left (the time-step start). The scenes: uniform (in 2D with
 * a sparse part, whose buckets hold an element or two) and quantized (exact ties, which the
 * partition must keep in element order), with radii, and a strip; 2D and 3D, each with
 * digits of at most 7 bits (the partition needs as many elements as the square of the
 * buckets); the partition must have run on each (ctx->cs_partitioned). And a sheet: 60000
 * of 70000 elements in one layer, whose top digit they share, so that the partition, having
 * counted the digits, must give way to the sort (a bucket too large for a cache). Each is
 * also detected with the partition's top digit widened as far as the keys allow
 * (NBS_PARTITION=wide; by default only where the even split's buckets would be too large
 * for a cache, 3D N > 1.7e7 or so), whose bytes must be the sort's too. */
static void test_partition(void) {
  const int counts[] = {1, 2, 3};
  bool widened[11] = {false};
  for (int sc = 0; sc < 11; sc++) {
    const int dim = sc == 8 || sc == 9 ? 3 : sc == 10 ? 2 : 2 + sc % 2;
    scene s;
    switch (sc / 2) {
    case 0:
      s = det_scene(DET_UNIFORM, dim, 60000, dim == 2 ? 250.0 : 40.0, 0.0, 31);
      /* 2D: every 500th element moved up into [250, 500): buckets of an element or two,
       * whose places begin and end inside one line */
      for (int64_t k = 0; dim == 2 && k < s.n; k += 500) s.coords[k * 2 + 1] += 250.0;
      break;
    case 1: s = det_scene(DET_QUANTIZED, dim, 60000, dim == 2 ? 300.0 : 45.0, 0.0, 32); break;
    case 2: s = det_scene(DET_RADII, dim, 60000, dim == 2 ? 200.0 : 35.0, 0.0, 33); break;
    case 3:
      s = det_scene(DET_STRIP, dim, 60000, dim == 2 ? 40000.0 : 15000.0, 0.0, 34);
      break;
    default:
      /* the sheet: z in [0, 1) for all but every seventh element */
      s = det_scene(DET_UNIFORM, 3, 70000, 300.0, 0.0, 35);
      for (int64_t k = 0; k < s.n; k++) {
        if (k % 7 != 0) s.coords[k * 3 + 2] /= 300.0;
      }
      break;
    }
    const bool expect = sc < 8;
    for (size_t t = 0; t < sizeof counts / sizeof *counts; t++) {
      for (int mode = 0; mode < 2; mode++) {
        nbs_context *part, *sort, *wide;
        ASSERT_TRUE(partition_contexts(counts[t], &part, &sort));
        pair_list a, b, again, w;
        ASSERT_OK(detect_raw(part, &s, NBS_CELLSORT, (nbs_mode)mode, &a));
        const bool took = part->cs_partitioned;
        CHECK_MSG(!part->cs_part_widened, "scene %d: the partition's top digit widened for "
                  "%d elements", sc, (int)s.n);
        ASSERT_OK(detect_raw(sort, &s, NBS_CELLSORT, (nbs_mode)mode, &b));
        /* the top digit widened (NBS_PARTITION=wide): the same bytes */
        ASSERT_TRUE(partition_context(counts[t], "wide", &wide));
        ASSERT_OK(detect_raw(wide, &s, NBS_CELLSORT, (nbs_mode)mode, &w));
        CHECK_MSG(wide->cs_partitioned == expect, "scene %d (%dD), %d threads, NBS_PARTITION="
                  "wide: the partition %s", sc, dim, counts[t],
                  wide->cs_partitioned ? "ran" : "did not run");
        if (wide->cs_part_widened) widened[sc] = true;
        CHECK_MSG(same_bytes(&w, &b), "scene %d (%dD) mode %d, %d threads: the partition with "
                  "its top digit widened differs from the sort", sc, dim, mode, counts[t]);
        pair_list_free(&w);
        nbs_context_destroy(wide);
        CHECK_MSG(!sort->cs_partitioned, "scene %d: NBS_PARTITION=never partitioned", sc);
        ASSERT_OK(detect_raw(part, &s, NBS_CELLSORT, (nbs_mode)mode, &again));
        CHECK_MSG(took == expect, "scene %d (%dD), %d threads: the partition %s", sc, dim,
                  counts[t], took ? "ran" : "did not run");
        CHECK_MSG(a.count > (size_t)s.n / 4, "scene %d: only %zu pairs", sc, a.count);
        CHECK_MSG(same_bytes(&a, &b), "scene %d (%dD) mode %d, %d threads: the partition "
                  "differs from the sort", sc, dim, mode, counts[t]);
        CHECK_MSG(same_bytes(&again, &b), "scene %d (%dD) mode %d, %d threads: the start from "
                  "the partition's order differs", sc, dim, mode, counts[t]);
        pair_list_free(&a);
        pair_list_free(&b);
        pair_list_free(&again);
        nbs_context_destroy(part);
        nbs_context_destroy(sort);
      }
    }
    scene_free(&s);
  }
  /* the widened top digit ran in both dimensions (it does on scenes 0, 4 and 6, 2D, and 7,
   * 3D: the others' even split already gives the top digit the bits its keys allow) */
  bool in2 = false, in3 = false;
  for (int sc = 0; sc < 8; sc++) {
    if (widened[sc] && sc % 2 == 0) in2 = true;
    if (widened[sc] && sc % 2 == 1) in3 = true;
  }
  CHECK_MSG(in2 && in3, "NBS_PARTITION=wide widened the top digit in 2D %d, in 3D %d", in2, in3);
}

/* The partition by the crowded core (nbs__cs_core_part): where a few elements far out
 * stretch the grid, so that cellsort sorts by the keys of the crowded core's box and puts the
 * outliers in their places apart, NBS_PARTITION=always partitions the core's elements by
 * their keys relative to the box and must give the bytes of NBS_PARTITION=never (the sort by
 * the core, then the gather), in both modes, for 1, 2 and 3 threads. The scenes: 60000
 * elements uniform in a box (3D, whose whole keys then take 64 bits, unpacked; 2D, whose 43
 * bits share a word with the element), with and without radii, and outliers of each kind:
 * below the box's lowest key (a million diameters down the key's last axis), above its
 * highest, between (within the box's range on the last axis, a million diameters out on
 * another: they fall among the core's elements of one bucket, and are merged into it), in
 * small groups that touch each other, and a halo touching the box's side (its elements in or
 * out of the box as the sample puts it); and four scenes whose outliers are placed at random
 * (an axis, a side, 10^3 to 10^6 diameters out, some in touching pairs); and a 3D scene whose
 * whole keys are packed (35 bits), with outliers between whose keys lie a little above the
 * lowest of a bucket (of the test's scenes, only there can an outlier's key come within the
 * box's side of a bucket's lowest: the others' grids are too coarse for the sample to leave
 * such outliers out of the box); and a 3D scene of 40000 whose core box passes the top of
 * the whole key's y field, with an outlier between in the box's top layer. It fails when an
 * outlier of any kind is put in the wrong place or with the wrong coordinates, when a
 * bucket's range is off by one place, when the bucket search puts outliers up to 1000 above a
 * bucket's lowest key in the bucket before, when the box's highest key is taken past the
 * whole key's fields, or when the partition does not run (ctx->cs_partitioned) or finds no
 * outliers. */
static void test_core_partition(void) {
  const int counts[] = {1, 2, 3};
  int widened[2] = {0, 0};
  for (int sc = 0; sc < 12; sc++) {
    const int dim = sc == 8 || sc == 9 || sc == 11 ? 3 : sc == 10 ? 2 : 2 + sc % 2;
    const double box = sc == 11 ? 31.5 : dim == 3 ? 40.0 : 250.0, far = 1e6;
    scene s = det_scene(sc % 4 < 2 ? DET_UNIFORM : DET_RADII, dim, sc == 11 ? 40000 : 60000, box,
                        0.0, 41 + sc);
    int64_t outliers = 0;
    uint64_t rng = 71 + (uint64_t)sc;
    if (sc == 11) {
      /* a core box whose rows pass the top of the whole key's y field (bug 2 of e9600c4's
       * fuzz target, fixed in 8b54712): the core stretched to 1.2 box edges on x, whose 38
       * rows take a field of 64 and a box of rows 1 to 64 (past the field's 63); moved up 0.6
       * on y, whose box is then layers 2 to 33 (32 of them, the last odd: where the box's
       * highest key was taken past the fields, y's 64 spilled into z's lowest bit, which the
       * odd layer already had, and the key came out as that layer's row 0, below its core
       * elements); 42 outliers in a chain at z = 513 box edges (the rows then lie along z);
       * and a chain of 430 at x = 0, z just past the core's top, 0.3 apart up y to 129 (y's
       * field then 256 layers), most of them outliers, one an outlier between in the box's
       * top layer, whose key was taken for above the box's highest: it was put after every
       * element (the three detections in candidate mode differ) */
      for (int64_t k = 0; k < s.n; k++) {
        s.coords[k * 3] *= 1.2;
        s.coords[k * 3 + 1] += 0.6;
      }
      for (int m = 0; m < 42; m++) {
        double *p = s.coords + (1000 + m) * 3;
        p[0] = 0.0, p[1] = 0.95 * m, p[2] = 513.0 * box;
      }
      for (int m = 0; m < 430; m++) {
        double *p = s.coords + (5000 + m) * 3;
        p[0] = 0.0, p[1] = 0.3 * m, p[2] = box + 1.5;
      }
      outliers = 42;
    }
    /* the other scenes' outliers, placed element by element (scene 11's are above) */
    for (int64_t k = 0; sc < 11 && k < s.n; k++) {
      double *p = s.coords + k * dim;
      if (sc >= 9) {
        /* turned: outliers 4e7 diameters below on the last axis only, which then has the
         * most cells, so that the keys' rows lie along it (the key's x is the caller's last
         * coordinate, its y the first) and the partition must store each coordinate in the
         * caller's order; and a sparse skirt below the box on the first axis, which the
         * sample leaves out of the core box, whose elements (outliers between) touch the
         * core's: a pair of a core element and an outlier, whose coordinates came by two
         * ways, is found only if both keep the caller's order */
        if (k % 997 == 0) {
          p[dim - 1] = -4e7 - (double)(k % 5) * 0.6;
          outliers++;
        } else if (k % 67 == 0) {
          p[0] = -0.3 * (double)(k % 20);
        }
        continue;
      }
      if (sc == 8) {
        /* 3D, the whole keys packed (35 bits): a few outliers 5000 diameters out along x
         * (the rows' axis, whose grid is then fine enough for the sample to leave out what
         * lies just past the core), 3000 below and above along z; and 1 in 157 just past the
         * box's side on x (66 to 120 diameters, within 1000 sub-cells of its corner), in
         * its first rows (y = 0 to 2) and at any z: each one's key a little above the
         * lowest of the bucket that holds its layer's first rows, and merged into that
         * bucket, not the one before */
        if (k % 997 == 0) {
          p[0] = 5000.0 + (double)(k % 3) * 0.6;
        } else if (k % 1009 == 0) {
          p[2] = (k % 2 ? 3000.0 : -3000.0) + (double)(k % 3) * 0.6;
        } else if (k % 157 == 0) {
          p[0] = 66.0 + (double)(k % 55);
          p[1] = 0.5 * (double)(k % 5);
        } else {
          continue;
        }
        outliers++;
        continue;
      }
      if (sc >= 4) {
        /* at random: 1 in 120 out on a random axis, up or down, 10^3 to 10^6 diameters,
         * some of them in pairs */
        if (det_uniform(&rng) < 1.0 / 120.0) {
          const int a = (int)(det_uniform(&rng) * dim) % dim;
          const double d = pow(10.0, 3.0 + 3.0 * det_uniform(&rng));
          p[a] = det_uniform(&rng) < 0.5 ? -d : box + d;
          if (k + 1 < s.n && det_uniform(&rng) < 0.3) {
            double *q = p + dim; /* the next one touching it */
            for (int b = 0; b < dim; b++) q[b] = p[b] + (b == 0 ? 0.7 : 0.0);
            k++;
            outliers++;
          }
          outliers++;
        }
        continue;
      }
      const double g = (double)(k % 5) * 0.6; /* five to a group, touching */
      const int last = dim - 1;               /* the key's last axis (the longest first) */
      if (k % 193 == 0) {
        p[last] = -far + g; /* below */
      } else if (k % 197 == 0) {
        p[last] = far + g; /* above */
      } else if (k % 211 == 0) {
        p[0] = far + g; /* between: the last axis within the box */
      } else if (k % 223 == 0) {
        p[0] = -far - g;
      } else if (dim == 3 && k % 227 == 0) {
        p[1] = far + g;
      } else if (k % 53 == 0) {
        p[0] = box + 0.45 * (double)(k % 7); /* the halo */
        continue;
      } else {
        continue;
      }
      outliers++;
    }
    for (size_t t = 0; t < sizeof counts / sizeof *counts; t++) {
      for (int mode = 0; mode < 2; mode++) {
        nbs_context *part, *sort;
        ASSERT_TRUE(partition_contexts(counts[t], &part, &sort));
        pair_list a, b;
        ASSERT_OK(detect_raw(part, &s, NBS_CELLSORT, (nbs_mode)mode, &a));
        CHECK_MSG(part->cs_partitioned, "scene %d (%dD), %d threads: the partition did not run",
                  sc, dim, counts[t]);
        CHECK_MSG(part->cs_outliers >= outliers, "scene %d: %lld outliers, %lld far out", sc,
                  (long long)part->cs_outliers, (long long)outliers);
        ASSERT_OK(detect_raw(sort, &s, NBS_CELLSORT, (nbs_mode)mode, &b));
        CHECK_MSG(!sort->cs_partitioned, "scene %d: NBS_PARTITION=never partitioned", sc);
        /* (scenes 8's and 11's sorts take the whole keys, packed words made with the keys'
         * pass) */
        CHECK_MSG(sort->cs_outliers == (sc == 8 || sc == 11 ? -1 : part->cs_outliers),
                  "scene %d: %lld outliers, the sort %lld", sc, (long long)part->cs_outliers,
                  (long long)sort->cs_outliers);
        CHECK_MSG(a.count > (size_t)s.n / 4, "scene %d: only %zu pairs", sc, a.count);
        CHECK_MSG(same_bytes(&a, &b), "scene %d (%dD) mode %d, %d threads: the core's "
                  "partition differs from the sort", sc, dim, mode, counts[t]);
        /* and with the top digit widened wherever the keys allow (NBS_PARTITION=wide) */
        nbs_context *wide;
        pair_list w;
        ASSERT_TRUE(partition_context(counts[t], "wide", &wide));
        ASSERT_OK(detect_raw(wide, &s, NBS_CELLSORT, (nbs_mode)mode, &w));
        CHECK_MSG(wide->cs_partitioned, "scene %d (%dD), %d threads, NBS_PARTITION=wide: the "
                  "partition did not run", sc, dim, counts[t]);
        if (wide->cs_part_widened && wide->cs_outliers >= 0) widened[dim - 2]++;
        CHECK_MSG(same_bytes(&w, &b), "scene %d (%dD) mode %d, %d threads: the core's partition "
                  "with its top digit widened differs from the sort", sc, dim, mode, counts[t]);
        pair_list_free(&w);
        nbs_context_destroy(wide);
        pair_list_free(&a);
        pair_list_free(&b);
        nbs_context_destroy(part);
        nbs_context_destroy(sort);
      }
    }
    scene_free(&s);
  }
  /* the widened digits taken by the core's partition, in both dimensions */
  CHECK_MSG(widened[0] > 0 && widened[1] > 0,
            "the core's partition widened its top digit in %d 2D and %d 3D detections",
            widened[0], widened[1]);
}

/* ctx detects s with cellsort from scratch (fresh) or from the last order, into *out. */
static void tuned_detect(nbs_context *ctx, const scene *s, bool fresh, pair_list *out) {
  nbs_input in = scene_input(s);
  nbs_detect_def def = nbs_default_detect_def();
  def.algorithm = NBS_CELLSORT;
  def.fresh = fresh;
  out->p = NULL;
  out->count = 0;
  ASSERT_OK(nbs_detect(ctx, &in, &def));
  size_t count;
  const nbs_pair *p = nbs_pairs(ctx, &count);
  out->p = malloc((count ? count : 1) * sizeof *out->p);
  if (!out->p) abort();
  if (count) memcpy(out->p, p, count * sizeof *p);
  out->count = count;
}

/* The way a detection from scratch takes between 8 MiB of input and 1 GiB (nbs__cs_way), and
 * the partition's counts made by the pass over the input (nbs__cellsort_fresh): by
 * default the context times its first such detections, the sort and the gather, then the
 * partition, twice each, alternating, and takes the faster way from then on; a detection
 * that starts from the last order is not a try, nor is the first in a work block just
 * allocated (the context's first here, and the 2D scene's, which needs a larger block); an
 * input of another class (2D, or 3D of another power of two of bytes) is measured again, and
 * one below 8 MiB never partitions;
 * NBS_PARTITION=never and =always keep to their way and measure nothing. A sheet (most
 * elements in one layer, under one top digit) that the partition cannot take counts as its
 * tries, and is never partitioned after. Every detection gives the bytes of the sort and the
 * gather (NBS_PARTITION=never), with one thread and two. */
static void test_tuned_way(void) {
  scene s3 = det_scene(DET_UNIFORM, 3, 400000, 75.0, 0.0, 61);  /* 9.6 MB */
  scene s2 = det_scene(DET_UNIFORM, 2, 600000, 970.0, 0.0, 62); /* 9.6 MB */
  scene sheet = det_scene(DET_UNIFORM, 3, 420000, 550.0, 0.0, 63);
  for (int64_t k = 0; k < sheet.n; k++) {
    if (k % 7 != 0) sheet.coords[k * 3 + 2] /= 550.0;
  }
  scene small = det_scene(DET_UNIFORM, 3, 300000, 68.0, 0.0, 64); /* 7.2 MB */
  const scene *scenes[] = {&s3, &s2, &sheet, &small};
  const char *names[] = {"3D", "2D", "sheet", "3D below 8 MiB"};
  for (int threads = 1; threads <= 2; threads++) {
    nbs_context_def cdef = nbs_default_context_def();
    cdef.threads = threads;
    nbs_context *never, *always, *tuned;
    ASSERT_TRUE(setenv("NBS_PARTITION", "never", 1) == 0);
    ASSERT_OK(nbs_context_create(&cdef, &never));
    ASSERT_TRUE(setenv("NBS_PARTITION", "always", 1) == 0);
    ASSERT_OK(nbs_context_create(&cdef, &always));
    unsetenv("NBS_PARTITION");
    ASSERT_OK(nbs_context_create(&cdef, &tuned));
    CHECK_TRUE(tuned->cs_tune && !never->cs_tune && !always->cs_tune);
    for (int sc = 0; sc < 4; sc++) {
      const scene *s = scenes[sc];
      pair_list ref, got;
      tuned_detect(never, s, true, &ref);
      CHECK_MSG(!never->cs_partitioned, "%s: NBS_PARTITION=never partitioned", names[sc]);
      tuned_detect(always, s, true, &got);
      CHECK_MSG(always->cs_partitioned == (sc != 2), "%s: NBS_PARTITION=always: partitioned %d",
                names[sc], (int)always->cs_partitioned);
      CHECK_MSG(same_bytes(&got, &ref), "%s, %d threads: NBS_PARTITION=always differs",
                names[sc], threads);
      pair_list_free(&got);
      /* the tries, then the way chosen: 1 the sort and the gather, 2 the partition */
      const int expect[4] = {1, 2, 1, 2};
      int took[8] = {0}, tries = 0, skipped = 0;
      for (int k = 0; k < 8 && !test_failures; k++) {
        /* detection 5 starts from the last order: no try, no change */
        const bool fresh = k != 5;
        /* a detection in a work block just allocated is no try either (its pages' first
         * touch): the context's first, or one that makes the block larger */
        const bool was_new = tuned->work_new;
        const size_t block = tuned->work_size;
        tuned_detect(tuned, s, fresh, &got);
        const bool first_use = was_new || tuned->work_size != block;
        const int now = tuned->cs_ways.tries[0] + tuned->cs_ways.tries[1];
        took[k] = tuned->cs_partitioned ? 2 : 1;
        /* a partition from scratch counts its top digits in the pass over the input that
         * validates it (nbs__cellsort_fresh: in a context that holds its work block), where
         * the guessed keying holds, as it does here */
        CHECK_MSG(took[k] == 1 || k == 5 || tuned->cs_fresh_words,
                  "%s, %d threads, detection %d: the partition counted again", names[sc],
                  threads, k);
        CHECK_MSG(same_bytes(&got, &ref), "%s, %d threads, detection %d: the bytes differ",
                  names[sc], threads, k);
        pair_list_free(&got);
        CHECK_MSG(!tuned->work_new, "%s, %d threads, detection %d: the block still new",
                  names[sc], threads, k);
        if (sc == 3) {
          CHECK_MSG(took[k] == 1, "%s: detection %d partitioned", names[sc], k);
        } else if (sc == 2) {
          CHECK_MSG(took[k] == 1, "%s: detection %d partitioned", names[sc], k);
        } else if (!fresh || first_use || tries == 4) {
          /* no try: from the last order, in a new block, or after the four (tries counts
           * this scene's class alone, which its first detection measures afresh) */
          CHECK_MSG(now == tries, "%s, %d threads, detection %d: %d tries, %d before",
                    names[sc], threads, k, now, tries);
          if (fresh && first_use) {
            CHECK_MSG(took[k] == 1, "%s, %d threads, detection %d (the block's first) took "
                      "way %d", names[sc], threads, k, took[k]);
            skipped++;
          }
        } else {
          CHECK_MSG(now == tries + 1 && took[k] == expect[tries],
                    "%s, %d threads, detection %d: try %d took way %d (%d tries)", names[sc],
                    threads, k, tries, took[k], now);
          tries = now;
        }
      }
      if (sc < 2) {
        CHECK_MSG(tries == 4, "%s, %d threads: %d tries", names[sc], threads, tries);
        /* the context's first detection, and the 2D scene's larger block */
        CHECK_MSG(skipped == 1, "%s, %d threads: %d detections skipped", names[sc], threads,
                  skipped);
        /* after the tries, the faster way */
        const int faster = tuned->cs_ways.best[1] < tuned->cs_ways.best[0] ? 2 : 1;
        for (int k = 6; k < 8; k++) {
          CHECK_MSG(took[k] == faster, "%s, %d threads: detection %d took way %d, %d was "
                    "faster", names[sc], threads, k, took[k], faster);
        }
      }
      if (sc < 3) {
        CHECK_MSG(tuned->cs_ways.tries[0] == 2 && tuned->cs_ways.tries[1] == 2,
                  "%s, %d threads: %d and %d tries", names[sc], threads,
                  tuned->cs_ways.tries[0], tuned->cs_ways.tries[1]);
      }
      if (sc == 2) {
        CHECK_MSG(tuned->cs_ways.best[1] == DBL_MAX, "sheet: the partition's time %g",
                  tuned->cs_ways.best[1]);
      }
      pair_list_free(&ref);
    }
    nbs_context_destroy(never);
    nbs_context_destroy(always);
    nbs_context_destroy(tuned);
  }
  for (int k = 0; k < 4; k++) scene_free((scene *)scenes[k]);
}

/* Moves elements k = first, first + every, ... by up to amp per axis (amp < 0: by -amp
 * or 0 or amp, exactly: quantized scenes stay on their grid). */
static void det_move(scene *s, int64_t first, int64_t every, double amp, uint64_t *rng) {
  for (int64_t k = first; k < s->n; k += every) {
    for (int a = 0; a < s->dim; a++) {
      const double u = det_uniform(rng);
      s->coords[k * s->dim + a] += amp >= 0 ? amp * (2.0 * u - 1.0)
                                            : -amp * (double)((int)(u * 3.0) - 1);
    }
  }
}

/* One step: ctx detects s (its pairs in order, through the buffer or a callback) and the
 * context ref detects it from scratch (def.fresh: ref itself only ever does); the bytes
 * must be the same. Returns the stepping context's statistics in *st. */
static void det_step(nbs_context *ctx, nbs_context *ref_ctx, const scene *s,
                     nbs_algorithm algo, nbs_mode mode, bool callback, nbs_stats *st,
                     const char *what) {
  pair_list got, ref;
  nbs_status sg = callback ? detect_callback(ctx, s, algo, mode, &got)
                           : detect_raw(ctx, s, algo, mode, &got);
  ASSERT_OK(sg);
  ASSERT_OK(nbs_last_stats(ctx, st));
  nbs_context *fresh = ref_ctx;
  nbs_input in = scene_input(s);
  nbs_detect_def def = nbs_default_detect_def();
  def.algorithm = algo;
  def.mode = mode;
  def.fresh = 1;
  ASSERT_OK(nbs_detect(fresh, &in, &def));
  nbs_stats fs;
  ASSERT_OK(nbs_last_stats(fresh, &fs));
  CHECK_EQ(fs.reused_order, 0);
  size_t count;
  const nbs_pair *p = nbs_pairs(fresh, &count);
  pair_list_copy(&ref, p, count);
  CHECK_MSG(same_bytes(&got, &ref), "%s: %zu pairs, %zu from scratch (reused %d, moved %lld)",
            what, got.count, ref.count, st->reused_order, (long long)st->moved);
  pair_list_free(&got);
  pair_list_free(&ref);
}

/* Puts element n - 1 of s (when far) 64 boxes (2D: 1024) beyond the others on every axis:
 * the cell keys then take more than 31 bits, and cellsort's packed words give the element
 * fewer than 32 (the start from the last order is then nbs__cs_warm, else
 * nbs__cs_rekey). */
static void det_far(scene *s, bool far, double box) {
  if (!far) return;
  for (int a = 0; a < s->dim; a++) {
    s->coords[(s->n - 1) * s->dim + a] = (s->dim == 2 ? 1024.0 : 64.0) * box;
  }
}

/* Time steps: cellsort (and auto) start a detection from the last one's cell order
 * (nbs.h). Through steps that move the elements a little (and sometimes not at all), move
 * them far, replace them, change n, the dimension or the radii, or follow another
 * algorithm in the same context, every detection gives the bytes of a detection from
 * scratch, in order, in both modes, through the buffer and a callback, with 1 to 3
 * threads (on enough elements for cellsort to use them). The statistics must show the order
 * reused with elements re-sorted on small steps, and not reused on an input of other
 * elements, so that both paths are taken; and each of the two ways of starting from the
 * order (cellsort.c) must have been taken: with an element far out (keys of more than 31
 * bits: nbs__cs_warm) and without (nbs__cs_rekey, which leaves ctx->cs_keys set). */
static void test_time_steps(void) {
  const det_kind kinds[] = {DET_UNIFORM, DET_QUANTIZED, DET_RADII, DET_UNIFORM};
  for (int dim = 2; dim <= 3; dim++) {
    for (size_t kd = 0; kd < sizeof kinds / sizeof *kinds; kd++) {
      const det_kind kind = kinds[kd];
      const bool far = kd == 3; /* the last: uniform with an element far out */
      for (int threads = 1; threads <= 3; threads++) {
        /* cellsort takes a thread per 20000 elements: 70000 let 3 threads work (3: parts
         * of unequal merges); the box keeps the fraction near 0.5 */
        const int64_t n = threads == 1 ? 20000 : 70000;
        const double box = (dim == 2 ? 140.0 : 26.0) * pow((double)n / 20000.0, 1.0 / dim);
        for (int variant = 0; variant < 3; variant++) {
          /* 0: contacts through the buffer, 1: candidates, 2: contacts through a callback */
          const nbs_mode mode = variant == 1 ? NBS_MODE_CANDIDATES : NBS_MODE_CONTACTS;
          const bool cb = variant == 2;
          const nbs_algorithm algo = variant == 1 ? NBS_CELLSORT : NBS_AUTO;
          char what[160];
          nbs_context_def cdef = nbs_default_context_def();
          cdef.threads = threads;
          nbs_context *ctx, *ref;
          ASSERT_OK(nbs_context_create(&cdef, &ctx));
          ASSERT_OK(nbs_context_create(&cdef, &ref));
          /* the lowest coordinate 1.18, 0.8 above a point of the lattice (k + 0.381966) e of
           * cellsort's origin, which moves when the lowest coordinate crosses one, and every
           * key with it: six small steps (quantized: at most 6 x 0.125) do not reach one */
          scene s = det_scene(kind, dim, n, box, 1.18, 30 + kd);
          det_far(&s, far, box);
          uint64_t rng = 77;
          const double small = kind == DET_QUANTIZED ? -0.125 : 0.01;
          nbs_stats st;
          int64_t moved = 0;
#define STEP(label)                                                                           \
  do {                                                                                        \
    snprintf(what, sizeof what, "%dD kind %d, %d threads, variant %d: %s", dim, (int)kind,    \
             threads, variant, label);                                                        \
    det_step(ctx, ref, &s, algo, mode, cb, &st, what);                                        \
    if (test_failures) break;                                                                 \
  } while (0)
          do {
            STEP("first");
            CHECK_EQ(st.reused_order, 0);
            STEP("unmoved");
            CHECK_EQ(st.reused_order, 1);
            CHECK_EQ(st.moved, 0);
            for (int k = 0; k < 6; k++) {
              /* one element in 7 by a hundredth, one in 61 by a sub-cell (quantized): either
               * way fewer than n / 16 change place */
              det_move(&s, k, kind == DET_QUANTIZED ? 61 : 7, small, &rng);
              /* and at the fourth, element 0 to the lowest corner, whose key is the lowest:
               * it goes before the first element of the last order (the merge's first part
               * takes the words below the last order's first) */
              if (k == 3) {
                for (int a = 0; a < dim; a++) s.coords[a] = 1.18;
              }
              STEP("small step");
              CHECK_EQ(st.reused_order, 1);
              CHECK_MSG(ctx->cs_keys == !far, "%s: cs_keys %d", what, (int)ctx->cs_keys);
              /* and with keys the step read the input once */
              CHECK_MSG(ctx->cs_stepped == !far, "%s: stepped %d", what, (int)ctx->cs_stepped);
              moved += st.moved;
            }
            CHECK_MSG(moved > 0, "%s: no element changed place in six steps", what);
            det_move(&s, 0, 1, 5.0, &rng); /* every element, up to 5 diameters */
            STEP("far step");
            CHECK_EQ(st.reused_order, 0);
            for (int k = 0; k < 4; k++) STEP("after a far step"); /* waits, then reuses */
            CHECK_EQ(st.reused_order, 1);
            scene other = det_scene(kind, dim, n, box, 3.0, 90 + kd);
            det_far(&other, far, box);
            scene keep = s;
            s = other;
            STEP("other elements");
            CHECK_EQ(st.reused_order, 0);
            s = keep;
            scene_free(&other);
            for (int k = 0; k < 8; k++) STEP("the first elements again");
            if (threads == 1 && !cb && mode == NBS_MODE_CONTACTS) {
              pair_list scratch;
              ASSERT_OK(detect_raw(ctx, &s, NBS_NBS, NBS_MODE_CONTACTS, &scratch));
              pair_list_free(&scratch);
              STEP("after nbs");
              CHECK_EQ(st.reused_order, 0);
              scene fewer = s;
              fewer.n = s.n - 1;
              scene keep2 = s;
              s = fewer;
              STEP("one element fewer");
              CHECK_EQ(st.reused_order, 0);
              STEP("one element fewer, again");
              CHECK_EQ(st.reused_order, 1);
              s = keep2;
              STEP("all elements");
              CHECK_EQ(st.reused_order, 0);
            }
          } while (0);
#undef STEP
          scene_free(&s);
          nbs_context_destroy(ctx);
          nbs_context_destroy(ref);
          if (test_failures) return;
        }
      }
    }
  }
  /* the dimension and the radii change, with the same n */
  nbs_context *ctx, *ref;
  ASSERT_OK(nbs_context_create(NULL, &ctx));
  ASSERT_OK(nbs_context_create(NULL, &ref));
  scene s3 = det_scene(DET_UNIFORM, 3, 12000, 23.0, 0.0, 41);
  scene s2 = det_scene(DET_UNIFORM, 2, 12000, 110.0, 0.0, 42);
  scene sr = det_scene(DET_RADII, 3, 12000, 23.0, 0.0, 43);
  nbs_stats st;
  const scene *seq[] = {&s3, &s3, &s2, &s2, &s3, &sr, &sr, &s3};
  for (size_t k = 0; k < sizeof seq / sizeof *seq && !test_failures; k++) {
    char what[64];
    snprintf(what, sizeof what, "dimension and radii, step %zu", k);
    det_step(ctx, ref, seq[k], NBS_CELLSORT, NBS_MODE_CONTACTS, false, &st, what);
  }
  /* The element bits of the packed words change with the same n: 32 where the key fits 31
   * bits (s3: 23 diameters a side), the bits of n - 1 where it does not (wide: 64 times
   * wider, 33 bits of cells). A start from the last order read its words with this
   * detection's element bits, and crashed on the change (element numbers of 2^32 - 1 and
   * more): the order must not be reused across it, and is reused again after it. */
  scene wide = det_scene(DET_UNIFORM, 3, 12000, 23.0 * 64, 0.0, 44);
  const scene *bits[] = {&s3, &wide, &wide, &s3, &s3, &wide};
  const int reused[] = {0, 0, 1, 0, 1, 0};
  nbs_context *bctx; /* a context of its own: no wait from failed starts before */
  ASSERT_OK(nbs_context_create(NULL, &bctx));
  for (size_t k = 0; k < sizeof bits / sizeof *bits && !test_failures; k++) {
    char what[64];
    snprintf(what, sizeof what, "element bits, step %zu", k);
    det_step(bctx, ref, bits[k], NBS_CELLSORT, NBS_MODE_CONTACTS, false, &st, what);
    CHECK_MSG(st.reused_order == reused[k], "%s: reused %d", what, st.reused_order);
  }
  nbs_context_destroy(bctx);
  /* The cells grow and shrink back, with few keys changed. 500 elements in a box whose keys
   * take 13 bits (3D: 14 x 6 x 6 diameters, 4 + 3 bits of x with its sub-cells, 3 of y, 3
   * of z; 2D: 26 x 26, 5 + 3 and 5): with the element's 32, 45 bits, which the radix sort
   * takes in exactly 5 passes of 9. Element 0 goes to 10 (2D: 40) above the others' lowest
   * z (y), so that z takes a bit more, and back, with elements 1-3 moved a sub-cell there and
   * back too. The step back sorts the changed elements' old words, whose keys took 14 bits,
   * with the new ones: sorted by this detection's 45 bits only, element 0's old word came
   * first and the merge kept elements 1-3 twice (found by the fuzzer, n = 50). The rows stay
   * along x (z, y stays under twice its cells). */
  for (int dim = 2; dim <= 3 && !test_failures; dim++) {
    nbs_context *gctx;
    ASSERT_OK(nbs_context_create(NULL, &gctx));
    const double side[3] = {dim == 3 ? 14.0 : 26.0, dim == 3 ? 6.0 : 26.0, 6.0};
    scene gs = det_scene(DET_UNIFORM, dim, 500, 1.0, 1.18, 46);
    for (int64_t e = 0; e < gs.n; e++) {
      for (int a = 0; a < dim; a++) {
        double *v = &gs.coords[e * dim + a];
        *v = 1.18 + (*v - 1.18) * side[a];
      }
    }
    const double keep0 = gs.coords[dim - 1];
    for (int k = 0; k < 4 && !test_failures; k++) {
      if (k == 2 || k == 3) {
        gs.coords[dim - 1] = k == 2 ? 1.18 + (dim == 3 ? 10.0 : 40.0) : keep0;
        for (int e = 1; e <= 3; e++) gs.coords[e * dim] += k == 2 ? 0.2 : -0.2;
      }
      char what[64];
      snprintf(what, sizeof what, "cells growing and shrinking, %dD, step %d", dim, k);
      det_step(gctx, ref, &gs, NBS_CELLSORT, NBS_MODE_CONTACTS, false, &st, what);
      CHECK_MSG(st.reused_order == (k > 0) && (k < 2 || st.moved >= 2),
                "%s: reused %d, moved %lld", what, st.reused_order, (long long)st.moved);
    }
    scene_free(&gs);
    nbs_context_destroy(gctx);
  }
  /* An input over 8 MiB (cellsort's NBS__CS_PREFETCH_MIN), where the gathers prefetch:
   * the gather from scratch and that of nbs__cs_rekey, with one thread and two, and two
   * with NBS_STEAL=first (each thread first gathers, sorts buckets of and sweeps the end
   * of the other's part: ranges taken from another's part, in all three). */
  for (int threads = 1; threads <= 3 && !test_failures; threads++) {
    nbs_context_def cdef = nbs_default_context_def();
    cdef.threads = threads == 3 ? 2 : threads;
    if (threads == 3) ASSERT_TRUE(setenv("NBS_STEAL", "first", 1) == 0);
    nbs_context *lctx;
    ASSERT_OK(nbs_context_create(&cdef, &lctx));
    unsetenv("NBS_STEAL");
    scene big = det_scene(DET_UNIFORM, 3, 380000, 70.0, 1.18, 45);
    uint64_t rng = 78;
    for (int k = 0; k < 5 && !test_failures; k++) {
      if (k >= 2) det_move(&big, k, 7, 0.01, &rng);
      char what[64];
      snprintf(what, sizeof what, "large input, %d threads, step %d", threads, k);
      det_step(lctx, ref, &big, NBS_AUTO, NBS_MODE_CONTACTS, false, &st, what);
      CHECK_MSG(st.reused_order == (k > 0) && (k < 2 || st.moved > 0) && lctx->cs_keys == (k > 0),
                "%s: reused %d, moved %lld, keys %d", what, st.reused_order,
                (long long)st.moved, (int)lctx->cs_keys);
    }
    scene_free(&big);
    nbs_context_destroy(lctx);
  }
  scene_free(&wide);
  scene_free(&s3);
  scene_free(&s2);
  scene_free(&sr);
  nbs_context_destroy(ctx);
  nbs_context_destroy(ref);
}

/* Time steps where a detection from scratch would partition (nbs__cs_steps_way): by
 * default the context times its first steps of a class from the last order and from
 * scratch, two of each, alternating, and takes the faster from then on. A start from the
 * order just after a detection from scratch writes the order's keys first, and is not timed
 * (words with fewer than 32 element bits have no keys, and every start from the order is
 * timed); nor is a start from the order that did not take place. Each branch of the choice
 * is then forced (the measurements set by hand) and followed; an input of another class
 * measures again. The inputs here are of 9.6 MB, and the contexts' cs_part_min is set to 8 MiB
 * (as if they were over 1 GiB); with the default 1 GiB, steps are timed only once the context
 * has measured the partition faster from scratch for the class; below 8 MiB and under
 * NBS_PARTITION=never never. Every step gives the bytes of a detection from scratch, with
 * one thread and two. */
static void tuned_steps_run(nbs_context *ctx, nbs_context *ref, scene *s, int threads,
                            bool eb32, const char *name) {
  uint64_t rng = 91;
  nbs_stats st;
  char what[96];
  /* the tries: the first detection (no order), then for words with keys: an untimed start
   * (keys written), a timed one, one from scratch, again; without keys every start is timed */
  const int order_32[7] = {0, 1, 1, 0, 1, 1, 0};
  const int tried_32[7][2] = {{0, 0}, {0, 0}, {1, 0}, {1, 1}, {1, 1}, {2, 1}, {2, 2}};
  const int order_far[5] = {0, 1, 0, 1, 0};
  const int tried_far[5][2] = {{0, 0}, {1, 0}, {1, 1}, {2, 1}, {2, 2}};
  const int steps = eb32 ? 7 : 5;
  for (int k = 0; k < steps && !test_failures; k++) {
    if (k > 0) det_move(s, k, 7, 0.01, &rng);
    snprintf(what, sizeof what, "%s, %d threads, step %d", name, threads, k);
    det_step(ctx, ref, s, NBS_AUTO, NBS_MODE_CONTACTS, false, &st, what);
    const int reused = eb32 ? order_32[k] : order_far[k];
    const int *tried = eb32 ? tried_32[k] : tried_far[k];
    CHECK_MSG(st.algorithm == NBS_CELLSORT && st.reused_order == reused,
              "%s: ran %d, reused %d, expected %d", what, (int)st.algorithm, st.reused_order,
              reused);
    /* (the first detection has no order of this n: a class measured before stays as it was
     * until the next) */
    CHECK_MSG(k == 0 ||
                  (ctx->cs_steps.tries[0] == tried[0] && ctx->cs_steps.tries[1] == tried[1]),
              "%s: tries %d and %d, expected %d and %d", what, ctx->cs_steps.tries[0],
              ctx->cs_steps.tries[1], tried[0], tried[1]);
  }
  /* the choice, as measured: the faster way from then on (a start from the order after one
   * from scratch writes its keys first, so the second is the plain step) */
  const bool fresh = ctx->cs_steps.best[1] < ctx->cs_steps.best[0];
  for (int k = 0; k < 3 && !test_failures; k++) {
    det_move(s, k, 5, 0.01, &rng);
    snprintf(what, sizeof what, "%s, %d threads, chosen %s, step %d", name, threads,
             fresh ? "from scratch" : "from the order", k);
    det_step(ctx, ref, s, NBS_AUTO, NBS_MODE_CONTACTS, false, &st, what);
    CHECK_MSG(st.reused_order == !fresh, "%s: reused %d", what, st.reused_order);
    CHECK_MSG(!eb32 || fresh || k == 0 || ctx->cs_stepped, "%s: not the step's pass", what);
  }
  /* either choice, forced */
  for (int way = 0; way < 2 && !test_failures; way++) {
    ctx->cs_steps.best[way] = 1.0;
    ctx->cs_steps.best[1 - way] = 2.0;
    for (int k = 0; k < 3 && !test_failures; k++) {
      det_move(s, k, 5, 0.01, &rng);
      snprintf(what, sizeof what, "%s, %d threads, %s forced, step %d", name, threads,
               way ? "from scratch" : "from the order", k);
      det_step(ctx, ref, s, NBS_AUTO, NBS_MODE_CONTACTS, false, &st, what);
      CHECK_MSG(st.reused_order == (way == 0), "%s: reused %d", what, st.reused_order);
      CHECK_MSG(ctx->cs_steps.tries[0] == 2 && ctx->cs_steps.tries[1] == 2,
                "%s: tries %d and %d", what, ctx->cs_steps.tries[0], ctx->cs_steps.tries[1]);
    }
  }
}

static void test_tuned_steps(void) {
  scene s3 = det_scene(DET_UNIFORM, 3, 400000, 75.0, 1.18, 65);  /* 9.6 MB */
  scene s2 = det_scene(DET_UNIFORM, 2, 600000, 970.0, 1.18, 66); /* 9.6 MB */
  scene far = det_scene(DET_UNIFORM, 3, 400000, 75.0, 1.18, 67);
  det_far(&far, true, 75.0); /* keys of more than 31 bits: nbs__cs_warm */
  scene small = det_scene(DET_UNIFORM, 3, 300000, 68.0, 1.18, 68); /* 7.2 MB */
  for (int threads = 1; threads <= 2 && !test_failures; threads++) {
    nbs_context_def cdef = nbs_default_context_def();
    cdef.threads = threads;
    nbs_context *ctx, *ref, *never;
    ASSERT_OK(nbs_context_create(&cdef, &ref));
    ASSERT_OK(nbs_context_create(&cdef, &ctx));
    CHECK_TRUE(ctx->cs_tune && ctx->cs_steps.cls == -1);
    const size_t over = (size_t)8 << 20; /* the inputs' 9.6 MB pass it */
    ctx->cs_part_min = over;
    tuned_steps_run(ctx, ref, &s3, threads, true, "3D");
    const int cls = ctx->cs_steps.cls;
    /* another class (2D) measures again, in the same context */
    tuned_steps_run(ctx, ref, &s2, threads, true, "2D");
    CHECK_MSG(ctx->cs_steps.cls != cls, "2D: the class of 3D's (%d)", cls);
    nbs_context_destroy(ctx);
    ASSERT_OK(nbs_context_create(&cdef, &ctx));
    ctx->cs_part_min = over;
    tuned_steps_run(ctx, ref, &far, threads, false, "far");
    nbs_context_destroy(ctx);
    /* 1 GiB: the way from scratch is measured first (four detections from scratch); until
     * the partition is found the faster, no step is timed; then they are */
    ASSERT_OK(nbs_context_create(&cdef, &ctx));
    {
      uint64_t rng = 95;
      nbs_stats st;
      char what[96];
      /* (the first, in the context's new work block, is no try) */
      for (int k = 0; k < 5 && !test_failures; k++) {
        pair_list got;
        tuned_detect(ctx, &s3, true, &got);
        pair_list_free(&got);
      }
      CHECK_MSG(ctx->cs_ways.tries[0] == 2 && ctx->cs_ways.tries[1] == 2,
                "1 GiB, %d threads: the ways' tries %d and %d", threads, ctx->cs_ways.tries[0],
                ctx->cs_ways.tries[1]);
      for (int pass = 0; pass < 2 && !test_failures; pass++) {
        /* pass 0: the sort and the gather measured the faster; 1: the partition */
        ctx->cs_ways.best[0] = pass == 0 ? 1.0 : 2.0;
        ctx->cs_ways.best[1] = pass == 0 ? 2.0 : 1.0;
        /* (pass 1 starts after pass 0's steps from the order, with the keys: timed at once,
         * then one from scratch, one untimed, one timed) */
        const int reused[4] = {1, pass == 0, 1, 1};
        const int tried[4][2] = {{pass, 0}, {pass, pass}, {pass, pass}, {2 * pass, pass}};
        for (int k = 0; k < 4 && !test_failures; k++) {
          det_move(&s3, k, 7, 0.01, &rng);
          snprintf(what, sizeof what, "1 GiB, %d threads, %s faster, step %d", threads,
                   pass ? "the partition" : "the gather", k);
          det_step(ctx, ref, &s3, NBS_AUTO, NBS_MODE_CONTACTS, false, &st, what);
          CHECK_MSG(st.reused_order == reused[k], "%s: reused %d", what, st.reused_order);
          CHECK_MSG(ctx->cs_steps.tries[0] == tried[k][0] && ctx->cs_steps.tries[1] == tried[k][1],
                    "%s: tries %d and %d, expected %d and %d", what, ctx->cs_steps.tries[0],
                    ctx->cs_steps.tries[1], tried[k][0], tried[k][1]);
        }
      }
    }
    nbs_context_destroy(ctx);
    /* below 8 MiB, and under NBS_PARTITION=never: every step from the order, none timed */
    ASSERT_OK(nbs_context_create(&cdef, &ctx));
    ASSERT_TRUE(setenv("NBS_PARTITION", "never", 1) == 0);
    ASSERT_OK(nbs_context_create(&cdef, &never));
    unsetenv("NBS_PARTITION");
    const struct {
      nbs_context *c;
      scene *s;
      const char *name;
    } plain[2] = {{ctx, &small, "below 8 MiB"}, {never, &s3, "NBS_PARTITION=never"}};
    for (int p = 0; p < 2 && !test_failures; p++) {
      uint64_t rng = 93;
      for (int k = 0; k < 6 && !test_failures; k++) {
        if (k > 0) det_move(plain[p].s, k, 7, 0.01, &rng);
        char what[96];
        snprintf(what, sizeof what, "%s, %d threads, step %d", plain[p].name, threads, k);
        nbs_stats st;
        det_step(plain[p].c, ref, plain[p].s, NBS_AUTO, NBS_MODE_CONTACTS, false, &st, what);
        CHECK_MSG(st.reused_order == (k > 0), "%s: reused %d", what, st.reused_order);
        CHECK_MSG(plain[p].c->cs_steps.tries[0] == 0 && plain[p].c->cs_steps.tries[1] == 0,
                  "%s: tries %d and %d", what, plain[p].c->cs_steps.tries[0],
                  plain[p].c->cs_steps.tries[1]);
      }
    }
    nbs_context_destroy(ctx);
    nbs_context_destroy(never);
    nbs_context_destroy(ref);
  }
  scene_free(&s3);
  scene_free(&s2);
  scene_free(&far);
  scene_free(&small);
}

/* The time step's pass over the input (nbs__cellsort_step), which replaces input.c's
 * where the context has an order and its keys: it computes the keys with the last
 * detection's keying and measures the box, and the keys stand only if this detection's
 * keying is the same. Every step gives the bytes of a detection from scratch, or its error:
 *  - a coordinate that is not finite, at the start, in the middle and among the last
 *    elements (the AVX-512 pass takes 8 at a time, the rest one by one), on each axis: the
 *    same status, element and message as input.c's pass gives a fresh context; the steps
 *    after it take up the order again;
 *  - an element below the grid's origin, or past the bits of a key's field, where the pass
 *    stops (stepped 0), and the box growing or shrinking within them, where it does not;
 *  - the diameter changed (the keying is not the same: from scratch);
 *  - another algorithm between steps, and auto choosing another after the pass;
 *  - with radii, a bad radius (the same error), and a radius above the largest;
 * with the default kernel and the generic one (whose pass is the scalar loop), one thread
 * and two. */
static void test_step_pass(void) {
  for (int dim = 2; dim <= 3; dim++) {
    for (int kr = 0; kr < 4; kr++) {
      const int kernel = kr % 2, radii = kr / 2;
      for (int threads = 1; threads <= 2; threads++) {
        nbs_context_def cdef = nbs_default_context_def();
        cdef.threads = threads;
        nbs_context *ctx, *ref;
        if (kernel) ASSERT_TRUE(setenv("NBS_SIMD", "generic", 1) == 0);
        nbs_status cs = nbs_context_create(&cdef, &ctx);
        unsetenv("NBS_SIMD");
        ASSERT_OK(cs);
        ASSERT_OK(nbs_context_create(&cdef, &ref));
        /* 45,003 elements: two threads' parts, and 3 past the last 8 */
        const int64_t n = 45003;
        const double box = (dim == 2 ? 140.0 : 26.0) * pow((double)n / 20000.0, 1.0 / dim);
        scene s = det_scene(radii ? DET_RADII : DET_UNIFORM, dim, n, box, 1.18, 60 + dim);
        uint64_t rng = 79;
        nbs_stats st;
        char what[160];
#define PSTEP(label, stepped)                                                                 \
  do {                                                                                        \
    snprintf(what, sizeof what, "%dD, kernel %d, radii %d, %d threads: %s", dim, kernel,     \
             radii, threads, label);                                                          \
    det_step(ctx, ref, &s, NBS_AUTO, NBS_MODE_CONTACTS, false, &st, what);                   \
    if (stepped >= 0) {                                                                       \
      CHECK_MSG((int)ctx->cs_stepped == (stepped), "%s: stepped %d", what,                  \
                (int)ctx->cs_stepped);                                                        \
    }                                                                                         \
  } while (0)
        PSTEP("first", 0);
        PSTEP("second (writes the keys)", 0);
        det_move(&s, 0, 5, 0.01, &rng);
        PSTEP("small step", 1);
        CHECK_MSG(st.moved > 0, "%s: moved %lld", what, (long long)st.moved);
        /* a bad number: the same error as from scratch, then the steps go on */
        const int64_t at[] = {0, n / 2 + 3, n - 2};
        const double bad[] = {NAN, INFINITY, -INFINITY};
        for (size_t b = 0; b < 3 && !test_failures; b++) {
          for (int a = 0; a < dim && !test_failures; a++) {
            double *v = &s.coords[at[b] * dim + a];
            const double keep = *v;
            *v = bad[(b + (size_t)a) % 3];
            nbs_input in = scene_input(&s);
            nbs_detect_def def = nbs_default_detect_def();
            const nbs_status got = nbs_detect(ctx, &in, &def);
            def.fresh = 1;
            const nbs_status want = nbs_detect(ref, &in, &def);
            snprintf(what, sizeof what, "%dD, kernel %d, radii %d, %d threads: element %lld "
                     "axis %d", dim, kernel, radii, threads, (long long)at[b], a);
            CHECK_MSG(got == NBS_ERR_COORD && want == NBS_ERR_COORD, "%s: %s, %s", what,
                      nbs_status_name(got), nbs_status_name(want));
            CHECK_MSG(nbs_context_error_element(ctx) == at[b] &&
                          strcmp(nbs_context_error(ctx), nbs_context_error(ref)) == 0,
                      "%s: element %lld (%s), from scratch %lld (%s)", what,
                      (long long)nbs_context_error_element(ctx), nbs_context_error(ctx),
                      (long long)nbs_context_error_element(ref), nbs_context_error(ref));
            *v = keep;
            PSTEP("after the bad number", -1);
            CHECK_EQ(st.reused_order, 1);
            det_move(&s, b, 7, 0.01, &rng);
            PSTEP("the step after that", 1);
          }
        }
        /* a bad radius (read after the coordinates): the same error as from scratch */
        for (size_t b = 0; radii && b < 3 && !test_failures; b++) {
          double *v = &s.radii[at[b]];
          const double keep = *v;
          /* with elements moved: the keys the pass rewrote must not be taken for the order's */
          det_move(&s, (int64_t)b + 1, 5, 0.01, &rng);
          *v = b == 0 ? 0.0 : b == 1 ? -0.25 : NAN;
          nbs_input in = scene_input(&s);
          nbs_detect_def def = nbs_default_detect_def();
          const nbs_status got = nbs_detect(ctx, &in, &def);
          def.fresh = 1;
          const nbs_status want = nbs_detect(ref, &in, &def);
          snprintf(what, sizeof what, "%dD, kernel %d, %d threads: radius of element %lld",
                   dim, kernel, threads, (long long)at[b]);
          CHECK_MSG(got == NBS_ERR_RADIUS && want == NBS_ERR_RADIUS, "%s: %s, %s", what,
                    nbs_status_name(got), nbs_status_name(want));
          CHECK_MSG(nbs_context_error_element(ctx) == at[b] &&
                        strcmp(nbs_context_error(ctx), nbs_context_error(ref)) == 0,
                    "%s: element %lld (%s), from scratch %lld (%s)", what,
                    (long long)nbs_context_error_element(ctx), nbs_context_error(ctx),
                    (long long)nbs_context_error_element(ref), nbs_context_error(ref));
          *v = keep;
          PSTEP("after the bad radius", -1);
          CHECK_EQ(st.reused_order, 1);
          det_move(&s, b, 7, 0.01, &rng);
          PSTEP("the step after that", 1);
        }
        /* below the origin (a lattice point under the lowest coordinate): the pass stops */
        double *lowest = &s.coords[5 * dim];
        const double keep_low = *lowest;
        *lowest = 1.18 - 2.0;
        PSTEP("an element below the origin", 0);
        *lowest = keep_low;
        PSTEP("and back", -1);
        PSTEP("and again", -1);
        det_move(&s, 1, 9, 0.01, &rng);
        PSTEP("a small step after those", -1);
        /* past the bits of x's field (the rows' axis: the key's x), then back */
        double *far = &s.coords[7 * dim];
        const double keep_far = *far;
        *far = 1.18 + 4.0 * box;
        PSTEP("an element past the key's bits", -1);
        *far = keep_far;
        for (int k = 0; k < 4; k++) PSTEP("back", -1);
        det_move(&s, 2, 9, 0.01, &rng);
        PSTEP("small step", 1);
        for (int k = 0; k < 2; k++) {
          det_move(&s, 3, 11, 0.01, &rng);
          PSTEP("small step", 1);
        }
        /* the diameter (with radii: a radius above the largest): another keying, from
         * scratch, then steps again */
        if (radii) s.radii[3] = 0.5 + 0x1p-20;
        else s.diameter = 1.0 + 0x1p-20;
        PSTEP("another diameter", 0);
        CHECK_EQ(st.reused_order, 0);
        PSTEP("the same diameter", 0);
        det_move(&s, 4, 7, 0.01, &rng);
        PSTEP("small step", 1);
        /* another algorithm between */
        pair_list scratch;
        ASSERT_OK(detect_raw(ctx, &s, NBS_SORTING, NBS_MODE_CONTACTS, &scratch));
        pair_list_free(&scratch);
        PSTEP("after sorting", 0);
        PSTEP("and again", 0);
        det_move(&s, 5, 7, 0.01, &rng);
        PSTEP("small step", 1);
#undef PSTEP
        scene_free(&s);
        nbs_context_destroy(ctx);
        nbs_context_destroy(ref);
        if (test_failures) return;
      }
    }
    /* The pass reads the input where auto may yet choose another algorithm: 32 elements,
     * which auto checks directly (NBS__AUTO_DIRECT_MAX), after cellsort asked for by name.
     * Two elements change places (two keys: n / 16), auto runs, and cellsort again with
     * nothing moved: the keys the pass rewrote are not the order's, and taken for them,
     * the two would keep their old places in the order, with their new coordinates. */
    nbs_context *ctx, *ref;
    ASSERT_OK(nbs_context_create(NULL, &ctx));
    ASSERT_OK(nbs_context_create(NULL, &ref));
    scene s = det_scene(DET_UNIFORM, dim, 32, 4.0, 1.18, 70 + dim);
    nbs_stats st;
    const nbs_algorithm seq[] = {NBS_CELLSORT, NBS_CELLSORT, NBS_AUTO, NBS_CELLSORT,
                                 NBS_CELLSORT};
    for (size_t k = 0; k < sizeof seq / sizeof *seq && !test_failures; k++) {
      if (k == 2) {
        for (int a = 0; a < dim; a++) {
          const double t = s.coords[5 * dim + a];
          s.coords[5 * dim + a] = s.coords[9 * dim + a];
          s.coords[9 * dim + a] = t;
        }
      }
      char what[96];
      snprintf(what, sizeof what, "%dD, 32 elements, step %zu (%s)", dim, k,
               nbs_algorithm_name(seq[k]));
      det_step(ctx, ref, &s, seq[k], NBS_MODE_CONTACTS, false, &st, what);
      CHECK_MSG(st.algorithm == (k == 2 ? NBS_DIRECT : NBS_CELLSORT), "%s: ran %s", what,
                nbs_algorithm_name(st.algorithm));
    }
    scene_free(&s);
    nbs_context_destroy(ctx);
    nbs_context_destroy(ref);
  }
}

/* A detection from scratch in a context that holds cellsort's work arrays reads the input
 * once: cellsort computes every element's key with a keying guessed from a sample while it
 * validates the input and measures its box (nbs__cellsort_fresh), and the keys stand only
 * if the detection's own keying is the guess. Every such detection must give the bytes of
 * a first detection in a new context (which has no arrays: input.c's pass, then the keys),
 * or its error (status, element, message):
 *  - the scene as it is (the guess holds: ctx->cs_fresh_words);
 *  - a coordinate that is not finite, on an element of the sample and on others, on each
 *    axis, at the start, in the middle (the AVX-512 pass takes 8 at a time) and at the end;
 *  - an element a little below the others (the lattice point below the lowest coordinate
 *    may change: the guess fails, the keys are computed again), far below and far above
 *    (the pass stops: input.c's pass runs), and one of the sample far below (the guess
 *    holds);
 *  - a bad radius; a scene of two clusters with outliers at 1e12 (keys too wide to share a
 *    word with the element: no guess);
 *  - a scene spread thin, whose keys of more than 31 bits share their word with the element
 *    all the same (fewer than 32 bits for the element): in 3D the guess holds; in 2D, whose
 *    axes then have more cells than the sample has elements, no guess;
 * with auto and cellsort, the default kernel and the generic one, one thread and two. */
typedef struct fp_ctx {
  nbs_context_def cdef;
  int kernel; /* 1: NBS_SIMD=generic */
} fp_ctx;

static void fp_create(const fp_ctx *f, nbs_context **ctx) {
  if (f->kernel) ASSERT_TRUE(setenv("NBS_SIMD", "generic", 1) == 0);
  nbs_status cs = nbs_context_create(&f->cdef, ctx);
  unsetenv("NBS_SIMD");
  ASSERT_OK(cs);
}

/* ctx detects s from scratch, and so does a new context; the same bytes or the same error.
 * words >= 0: whether ctx must have taken the guessed keys. */
static void fp_check(const fp_ctx *f, nbs_context *ctx, const scene *s, nbs_algorithm algo,
                     int words, const char *what) {
  nbs_context *ref;
  fp_create(f, &ref);
  nbs_input in = scene_input(s);
  nbs_detect_def def = nbs_default_detect_def();
  def.algorithm = algo;
  def.fresh = 1;
  const nbs_status got = nbs_detect(ctx, &in, &def);
  const bool took = ctx->cs_fresh_words;
  pair_list a = {0}, b = {0};
  if (got == NBS_OK) {
    size_t count;
    const nbs_pair *p = nbs_pairs(ctx, &count);
    pair_list_copy(&a, p, count);
  }
  const nbs_status want = nbs_detect(ref, &in, &def);
  CHECK_MSG(!ref->cs_fresh_words, "%s: a new context took guessed keys", what);
  CHECK_MSG(got == want, "%s: %s, a new context %s", what, nbs_status_name(got),
            nbs_status_name(want));
  if (got == want && got == NBS_OK) {
    size_t count;
    const nbs_pair *p = nbs_pairs(ref, &count);
    pair_list_copy(&b, p, count);
    CHECK_MSG(same_bytes(&a, &b), "%s: %zu pairs, a new context %zu", what, a.count, b.count);
  } else if (got == want) {
    CHECK_MSG(nbs_context_error_element(ctx) == nbs_context_error_element(ref) &&
                  strcmp(nbs_context_error(ctx), nbs_context_error(ref)) == 0,
              "%s: element %lld (%s), a new context %lld (%s)", what,
              (long long)nbs_context_error_element(ctx), nbs_context_error(ctx),
              (long long)nbs_context_error_element(ref), nbs_context_error(ref));
  }
  if (words >= 0) CHECK_MSG((int)took == words, "%s: guessed keys %d", what, (int)took);
  pair_list_free(&a);
  pair_list_free(&b);
  nbs_context_destroy(ref);
}

/* Whether ctx's last detection started from the order before it. */
static int st_reused(nbs_context *ctx) {
  nbs_stats st;
  return nbs_last_stats(ctx, &st) == NBS_OK ? st.reused_order : -1;
}

static void test_fresh_pass(void) {
  long took = 0;
  for (int dim = 2; dim <= 3; dim++) {
    for (int kr = 0; kr < 4; kr++) {
      for (int threads = 1; threads <= 2; threads++) {
        fp_ctx f;
        f.cdef = nbs_default_context_def();
        f.cdef.threads = threads;
        f.kernel = kr % 2;
        const int radii = kr / 2;
        const nbs_algorithm algo = threads == 1 ? NBS_AUTO : NBS_CELLSORT;
        nbs_context *ctx;
        fp_create(&f, &ctx);
        /* 45,003 elements: two threads' parts, and 3 past the last 8 */
        const int64_t n = 45003;
        const double box = (dim == 2 ? 140.0 : 26.0) * pow((double)n / 20000.0, 1.0 / dim);
        scene s = det_scene(radii ? DET_RADII : DET_UNIFORM, dim, n, box, 1.18, 70 + dim);
        /* element 0, in every sample, at the lowest corner: the guess's lattice point is
         * the box's (a random sample's lowest element lies a few hundredths of a cell above
         * the lowest one, and now and then on the other side of a lattice point) */
        for (int a = 0; a < dim; a++) s.coords[a] = 1.18;
        char what[200];
#define FPCHECK(label, words)                                                                 \
  do {                                                                                        \
    snprintf(what, sizeof what, "%dD, kernel %d, radii %d, %d threads: %s", dim, f.kernel,    \
             radii, threads, label);                                                          \
    fp_check(&f, ctx, &s, algo, words, what);                                                 \
    took += ctx->cs_fresh_words;                                                              \
  } while (0)
        FPCHECK("first (no arrays yet)", 0);
        FPCHECK("second", 1);
        /* not finite: elements 0 and n - 8 are in every sample, 1, n / 2 + 3 and n - 2 in
         * none of these scenes' */
        const int64_t at[] = {0, 1, n / 2 + 3, n - 8, n - 2};
        const double bad[] = {NAN, INFINITY, -INFINITY};
        for (size_t b = 0; b < sizeof at / sizeof *at && !test_failures; b++) {
          for (int a = 0; a < dim && !test_failures; a++) {
            double *v = &s.coords[at[b] * dim + a];
            const double keep = *v;
            *v = bad[(b + (size_t)a) % 3];
            char label[64];
            snprintf(label, sizeof label, "element %lld axis %d not finite", (long long)at[b], a);
            FPCHECK(label, 0);
            *v = keep;
          }
        }
        FPCHECK("all finite again", 1);
        /* below and above the others, on each axis in turn */
        const double shifts[] = {-0.3, -0.9, -40.0, 3.0 * box, 1e9};
        for (size_t k = 0; k < sizeof shifts / sizeof *shifts && !test_failures; k++) {
          for (int a = 0; a < dim && !test_failures; a++) {
            const int64_t e = 5 + 2 * a; /* in no sample */
            double *v = &s.coords[e * dim + a];
            const double keep = *v;
            *v = 1.18 + shifts[k];
            char label[64];
            snprintf(label, sizeof label, "element %lld at %g on axis %d", (long long)e, *v, a);
            FPCHECK(label, -1);
            *v = keep;
          }
        }
        /* one of the sample far below: in the guess */
        const double keep0 = s.coords[0];
        s.coords[0] = 1.18 - 40.0;
        FPCHECK("element 0 far below", 1);
        s.coords[0] = keep0;
        if (radii) {
          for (size_t b = 0; b < 3 && !test_failures; b++) {
            double *v = &s.radii[at[b + 1]];
            const double keep = *v;
            *v = b == 0 ? 0.0 : b == 1 ? -0.25 : NAN;
            FPCHECK("a bad radius", 0);
            *v = keep;
          }
        }
        FPCHECK("as at first", 1);
#undef FPCHECK
        /* time steps that move every element far (another scene of the same n, with element
         * 0 at the lowest corner again): the time-step pass finds too many keys changed,
         * the starts from the order pause for 2 detections, then 4 (cs_warm_wait); the
         * detections that do not start from the order take this pass, and count the failed
         * start or the pause as before */
        if (threads == 1 && !test_failures) {
          nbs_detect_def step = nbs_default_detect_def();
          step.algorithm = algo;
          scene t = det_scene(radii ? DET_RADII : DET_UNIFORM, dim, n, box, 1.18, 90 + dim);
          for (int a = 0; a < dim; a++) t.coords[a] = 1.18;
          const nbs_input in = scene_input(&s), tin = scene_input(&t);
          ASSERT_OK(nbs_detect(ctx, &in, &step));
          ASSERT_OK(nbs_detect(ctx, &in, &step)); /* the second writes the keys */
          const int fails = ctx->cs_warm_fails;
          /* the expected waits: 2 after the failed start, counted down by the pauses, then
           * the order's start tried again on the same scene, which succeeds */
          const int waits[] = {2, 1, 0};
          for (int k = 0; k < 4 && !test_failures; k++) {
            const nbs_input *which = &tin;
            ASSERT_OK(nbs_detect(ctx, which, &step));
            snprintf(what, sizeof what, "%dD, kernel %d, radii %d: far step %d", dim, f.kernel,
                     radii, k);
            if (k < 3) {
              CHECK_MSG(ctx->cs_fresh_words && !ctx->cs_stepped && ctx->cs_warm_wait == waits[k] &&
                            ctx->cs_warm_fails == fails + 1,
                        "%s: guessed keys %d, stepped %d, wait %d, fails %d (before %d)", what,
                        (int)ctx->cs_fresh_words, (int)ctx->cs_stepped, ctx->cs_warm_wait,
                        ctx->cs_warm_fails, fails);
            } else {
              CHECK_MSG(!ctx->cs_fresh_words && ctx->cs_warm_wait == 0 && st_reused(ctx),
                        "%s: guessed keys %d, wait %d, reused %d", what,
                        (int)ctx->cs_fresh_words, ctx->cs_warm_wait, st_reused(ctx));
            }
            /* the same bytes as a new context */
            pair_list a = {0}, b = {0};
            size_t count;
            const nbs_pair *p = nbs_pairs(ctx, &count);
            pair_list_copy(&a, p, count);
            nbs_context *ref;
            fp_create(&f, &ref);
            ASSERT_OK(nbs_detect(ref, which, &step));
            p = nbs_pairs(ref, &b.count);
            CHECK_MSG(a.count == b.count && (a.count == 0 || memcmp(a.p, p, a.count * sizeof *p) == 0),
                      "%s: %zu pairs, a new context %zu", what, a.count, b.count);
            lists_compared++;
            pair_list_free(&a);
            nbs_context_destroy(ref);
          }
          scene_free(&t);
        }
        scene_free(&s);
        /* two clusters and outliers at 1e12 (auto: another algorithm, or keys too wide for
         * a guess) */
        scene c = det_scene(DET_CLUSTERS, dim, n, box, 1.18, 80 + dim);
        snprintf(what, sizeof what, "%dD, kernel %d, %d threads: clusters", dim, f.kernel,
                 threads);
        fp_check(&f, ctx, &c, algo, 0, what);
        fp_check(&f, ctx, &c, algo, 0, what);
        scene_free(&c);
        /* spread thin: 3D 70 times the box, 2,300 cells a side (keys of 39 bits, fewer than
         * the sample's 2,812 elements per axis), 2D 400 times, 84,000 (37 bits: more); 16
         * bits for the element. Elements 0 and n - 8, in every sample, at the lowest and
         * highest corners, so that the sample's box gives the keying (the first: another
         * algorithm's arrays, with auto, or cellsort's, whose guess is taken) */
        const double wide = (dim == 3 ? 70.0 : 400.0) * box;
        scene t = det_scene(radii ? DET_RADII : DET_UNIFORM, dim, n, wide, 1.18, 60 + dim);
        for (int a = 0; a < dim; a++) {
          t.coords[a] = 1.18;
          t.coords[(n - 8) * dim + a] = 1.18 + wide;
        }
        snprintf(what, sizeof what, "%dD, kernel %d, radii %d, %d threads: spread thin", dim,
                 f.kernel, radii, threads);
        fp_check(&f, ctx, &t, algo, -1, what);
        took += ctx->cs_fresh_words;
        fp_check(&f, ctx, &t, algo, dim == 3, what);
        took += ctx->cs_fresh_words;
        scene_free(&t);
        nbs_context_destroy(ctx);
      }
    }
  }
  CHECK_MSG(took > 0, "no detection took the guessed keys");
}

/* The kernels' cases: the fixed ones, then two whose keys are wider than 31 bits, so that
 * the SIMD kernels read each element's number in their two other forms: from a packed word
 * under its key (3D, 3000 diameters a side: keys of 39 bits and 12 for the element), and
 * from the array of elements of unpacked keys (3D, 2^19 diameters a side: 60 bits). Pairs
 * at a distance of D up to rounding, so that both find contacts. */
#define NKERNEL_CASES (NCASES + 2)
static scene kernel_case(size_t c, const char **name) {
  if (c < NCASES) {
    *name = cases[c].name;
    return make_case(c);
  }
  *name = c == NCASES ? "near-ties-3d-masked" : "near-ties-3d-unpacked";
  return det_scene(DET_NEAR_TIES, 3, 4000, c == NCASES ? 3000.0 : 0x1p19, 0.0, 21 + c);
}

/* Kernels: cellsort's generic kernel (asked for with NBS_SIMD=generic, read when a context
 * is created) gives the same bytes in the same order as the one the processor gets by
 * default and as the AVX2 one (NBS_SIMD=avx2), on every case and both modes. Where the
 * processor lacks AVX-512 or AVX2, the contexts fall back to a lesser kernel and the
 * comparison still holds. */
static void test_kernels(void) {
  const char *const kernels[] = {NULL, "avx2"};
  for (size_t c = 0; c < NKERNEL_CASES; c++) {
    const char *name;
    scene s = kernel_case(c, &name);
    for (size_t kn = 0; kn < sizeof kernels / sizeof *kernels; kn++) {
      for (int mode = 0; mode < 2; mode++) {
        nbs_context *other, *generic;
        if (kernels[kn]) ASSERT_TRUE(setenv("NBS_SIMD", kernels[kn], 1) == 0);
        nbs_status st = nbs_context_create(NULL, &other);
        ASSERT_TRUE(setenv("NBS_SIMD", "generic", 1) == 0);
        nbs_status st2 = nbs_context_create(NULL, &generic);
        unsetenv("NBS_SIMD");
        ASSERT_OK(st);
        ASSERT_OK(st2);
        pair_list a, b;
        /* auto where cellsort refuses the extent */
        st = detect_raw(other, &s, NBS_CELLSORT, (nbs_mode)mode, &a);
        const nbs_algorithm algo = st == NBS_ERR_EXTENT ? NBS_AUTO : NBS_CELLSORT;
        if (st == NBS_ERR_EXTENT) ASSERT_OK(detect_raw(other, &s, algo, (nbs_mode)mode, &a));
        ASSERT_OK(st == NBS_ERR_EXTENT ? NBS_OK : st);
        ASSERT_OK(detect_raw(generic, &s, algo, (nbs_mode)mode, &b));
        CHECK_MSG(same_bytes(&a, &b), "%s %s mode %d: the %s kernel differs from the generic one",
                  name, nbs_algorithm_name(algo), mode,
                  kernels[kn] ? kernels[kn] : "default");
        pair_list_free(&a);
        pair_list_free(&b);
        /* nbs's test of the gathered candidates (AVX-512 where the processor has it, AVX2
         * with NBS_SIMD=avx2) */
        st = detect_raw(other, &s, NBS_NBS, (nbs_mode)mode, &a);
        if (st == NBS_OK) {
          ASSERT_OK(detect_raw(generic, &s, NBS_NBS, (nbs_mode)mode, &b));
          CHECK_MSG(same_bytes(&a, &b), "%s nbs mode %d: the %s test differs from the plain one",
                    name, mode, kernels[kn] ? kernels[kn] : "default");
          pair_list_free(&a);
          pair_list_free(&b);
        } else {
          CHECK_MSG(st == NBS_ERR_BUDGET || st == NBS_ERR_EXTENT, "%s nbs: %s", name,
                    nbs_status_name(st));
        }
        nbs_context_destroy(other);
        nbs_context_destroy(generic);
      }
    }
    scene_free(&s);
  }
}

/* After nbs_sort_pairs, every algorithm's contacts are the same bytes, and their hash is
 * the committed golden one. */
static void test_golden_hashes(void) {
  const bool print = getenv("NBS_GOLDEN_PRINT") != NULL;
  if (print) printf("static const golden goldens[] = {\n");
  for (size_t c = 0; c < NCASES; c++) {
    scene s = make_case(c);
    nbs_context *ctx;
    ASSERT_OK(nbs_context_create(NULL, &ctx));
    pair_list ref;
    ASSERT_OK(detect_sorted(ctx, &s, NBS_DIRECT, NBS_MODE_CONTACTS, &ref));
    const uint64_t hash = fnv1a_pairs(ref.p, ref.count);
    if (print) {
      printf("    {\"%s\", %zu, 0x%016llxull},\n", cases[c].name, ref.count,
             (unsigned long long)hash);
    }
    for (int a = 0; a < NBS_ALGORITHM_COUNT; a++) {
      pair_list got;
      nbs_status st = detect_sorted(ctx, &s, (nbs_algorithm)a, NBS_MODE_CONTACTS, &got);
      if (st != NBS_OK) {
        CHECK_MSG(st == NBS_ERR_BUDGET || st == NBS_ERR_EXTENT, "%s %s: %s", cases[c].name,
                  nbs_algorithm_name((nbs_algorithm)a), nbs_status_name(st));
        continue;
      }
      CHECK_MSG(same_bytes(&got, &ref) && fnv1a_pairs(got.p, got.count) == hash,
                "%s: %s's sorted contacts differ from direct's", cases[c].name,
                nbs_algorithm_name((nbs_algorithm)a));
      pair_list_free(&got);
    }
    const golden *g = NULL;
    for (size_t k = 0; k < sizeof goldens / sizeof *goldens; k++) {
      if (strcmp(goldens[k].name, cases[c].name) == 0) g = &goldens[k];
    }
    if (!print) {
      CHECK_MSG(g != NULL, "%s: no golden hash (see the top of this file)", cases[c].name);
      if (g) {
        CHECK_MSG(g->count == ref.count && g->hash == hash,
                  "%s: %zu contacts with hash 0x%016llx; golden: %llu with 0x%016llx",
                  cases[c].name, ref.count, (unsigned long long)hash,
                  (unsigned long long)g->count, (unsigned long long)g->hash);
      }
    }
    pair_list_free(&ref);
    nbs_context_destroy(ctx);
    scene_free(&s);
  }
  if (print) printf("};\n");
}

/* The scene s with its coordinates turned: coordinate a of the result is coordinate
 * from[a] of s. */
static scene turned(const scene *s, const int from[3]) {
  scene t = *s;
  t.coords = malloc((size_t)s->n * (size_t)s->dim * sizeof *t.coords);
  t.radii = NULL;
  if (!t.coords) abort();
  for (int64_t k = 0; k < s->n; k++) {
    for (int a = 0; a < s->dim; a++) t.coords[k * s->dim + a] = s->coords[k * s->dim + from[a]];
  }
  return t;
}

/* Detects the contacts of s with cellsort and nbs, checks them against direct's, and gives
 * the axes each took (ctx->axes: axes[0] cellsort's, axes[1] nbs's). */
static void took_axes(const scene *s, const char *what, int8_t axes[2][3]) {
  nbs_context *ctx;
  ASSERT_OK(nbs_context_create(NULL, &ctx));
  pair_list ref, got;
  ASSERT_OK(detect_sorted(ctx, s, NBS_DIRECT, NBS_MODE_CONTACTS, &ref));
  for (int a = 0; a < 2; a++) {
    const nbs_algorithm algo = a == 0 ? NBS_CELLSORT : NBS_NBS;
    ASSERT_OK(detect_sorted(ctx, s, algo, NBS_MODE_CONTACTS, &got));
    CHECK_MSG(same_bytes(&got, &ref), "%s: %s's contacts differ from direct's", what,
              nbs_algorithm_name(algo));
    memcpy(axes[a], ctx->axes, sizeof ctx->axes);
    pair_list_free(&got);
  }
  pair_list_free(&ref);
  nbs_context_destroy(ctx);
}

/* The rule (nbs__axis_order): the slot's axis is the one with the most cells where it has
 * at least twice as many as the slot's own axis (the later axis on a tie), and the other
 * axes keep their order; then the axes detections choose on turned scenes, with the pairs
 * checked against direct's. cellsort's slot is the key's x (its rows), nbs's the outer
 * lists' (z in 3D, y in 2D). */
static void test_axis_order(void) {
  static const struct {
    int dim, slot;
    int64_t count[3];
    int at[3];
  } rules[] = {
      {3, 0, {10, 15, 12}, {0, 1, 2}}, {3, 0, {10, 20, 5}, {1, 0, 2}},
      {3, 0, {10, 5, 30}, {2, 0, 1}},  {3, 0, {10, 30, 30}, {2, 0, 1}},
      {3, 0, {10, 19, 19}, {0, 1, 2}}, {3, 2, {100, 10, 10}, {1, 2, 0}},
      {3, 2, {10, 10, 10}, {0, 1, 2}}, {3, 2, {10, 40, 10}, {0, 2, 1}},
      {2, 1, {100, 10, 0}, {1, 0, 2}}, {2, 1, {10, 100, 0}, {0, 1, 2}},
      {2, 0, {10, 100, 0}, {1, 0, 2}}, {2, 0, {100, 10, 0}, {0, 1, 2}},
  };
  for (size_t r = 0; r < sizeof rules / sizeof *rules; r++) {
    int at[3] = {-1, -1, -1};
    nbs__axis_order(rules[r].dim, rules[r].count, rules[r].slot, at);
    CHECK_MSG(at[0] == rules[r].at[0] && at[1] == rules[r].at[1] && at[2] == rules[r].at[2],
              "rule %zu: axes %d %d %d, expected %d %d %d", r, at[0], at[1], at[2],
              rules[r].at[0], rules[r].at[1], rules[r].at[2]);
  }

  /* A slab (a strip in 2D) is thin on its last axis; turned, on each axis in turn. The
   * long axes have about as many cells each, so a thin axis never takes a slot, and a wide
   * one takes the slot of a thin one. */
  for (int dim = 2; dim <= 3; dim++) {
    scene slab = test_scene(SCENE_SLAB, dim, 6000, 0.5);
    for (int thin = 0; thin < dim; thin++) {
      int from[3] = {0, 1, 2};
      from[thin] = dim - 1; /* the slab's thin axis becomes `thin` */
      from[dim - 1] = thin;
      scene s = turned(&slab, from);
      char what[64];
      snprintf(what, sizeof what, "%dD slab thin on %d", dim, thin);
      int8_t axes[2][3];
      took_axes(&s, what, axes);
      for (int a = 0; a < 2; a++) {
        const char *name = nbs_algorithm_name(a == 0 ? NBS_CELLSORT : NBS_NBS);
        const int slot = a == 0 ? 0 : dim - 1;
        /* the slot keeps its axis unless that is the thin one */
        if (thin != slot) {
          CHECK_MSG(axes[a][slot] == slot, "%s: %s's slot %d took axis %d", what, name, slot,
                    axes[a][slot]);
        } else {
          CHECK_MSG(axes[a][slot] != thin, "%s: %s's slot kept it", what, name);
        }
        /* the other axes keep their order */
        for (int i = 0, prev = -1; i < dim; i++) {
          if (i == slot) continue;
          CHECK_MSG(axes[a][i] > prev, "%s: %s's axes out of order", what, name);
          prev = axes[a][i];
        }
      }
      free(s.coords);
    }
    scene_free(&slab);
  }

  /* A rod along each axis of 3D (the strip's coordinates, its thin one on two axes): both
   * slots take the rod's axis. */
  scene strip = test_scene(SCENE_SLAB, 2, 6000, 0.5);
  for (int along = 0; along < 3; along++) {
    scene rod = strip;
    rod.dim = 3;
    rod.coords = malloc((size_t)strip.n * 3 * sizeof *rod.coords);
    if (!rod.coords) abort();
    for (int64_t k = 0; k < strip.n; k++) {
      for (int a = 0; a < 3; a++) {
        rod.coords[k * 3 + a] = a == along ? strip.coords[k * 2] : strip.coords[k * 2 + 1];
      }
    }
    char what[64];
    snprintf(what, sizeof what, "rod along %d", along);
    int8_t axes[2][3];
    took_axes(&rod, what, axes);
    CHECK_MSG(axes[0][0] == along, "%s: cellsort's rows along axis %d", what, axes[0][0]);
    CHECK_MSG(axes[1][2] == along, "%s: nbs's z-lists along axis %d", what, axes[1][2]);
    free(rod.coords);
  }
  scene_free(&strip);
}

/* The hash itself, on known bytes, so that a broken hash cannot pass for a stable one. */
static void test_hash_function(void) {
  CHECK_TRUE(fnv1a_pairs(NULL, 0) == 0xcbf29ce484222325ull);
  /* FNV-1a 64 of the 8 bytes 01 00 00 00 02 00 00 00 */
  const nbs_pair p = {1, 2};
  uint64_t h = 0xcbf29ce484222325ull;
  const unsigned char bytes[8] = {1, 0, 0, 0, 2, 0, 0, 0};
  for (int b = 0; b < 8; b++) {
    h ^= bytes[b];
    h *= 0x100000001b3ull;
  }
  CHECK_TRUE(fnv1a_pairs(&p, 1) == h);
  const nbs_pair q = {2, 1};
  CHECK_TRUE(fnv1a_pairs(&q, 1) != h);
}

int main(int argc, char **argv) {
  static const test_case tests[] = {
      {"hash_function", test_hash_function},
      {"repeat_runs", test_repeat_runs},
      {"thread_counts", test_thread_counts},
      {"caller_threads", test_caller_threads},
      {"partition", test_partition},
      {"core_partition", test_core_partition},
      {"tuned_way", test_tuned_way},
      {"kernels", test_kernels},
      {"time_steps", test_time_steps},
      {"tuned_steps", test_tuned_steps},
      {"step_pass", test_step_pass},
      {"fresh_pass", test_fresh_pass},
      {"golden_hashes", test_golden_hashes},
      {"axis_order", test_axis_order},
  };
  int rc = test_main(argc, argv, tests, sizeof tests / sizeof *tests);
  printf("%ld pair lists compared byte for byte\n", lists_compared);
  return rc;
}
