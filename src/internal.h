/*
 * Internal interface shared by the core (context.c, input.c) and the algorithm files
 * (direct.c, screening.c, sorting.c, munjiza_nbs.c). Internal names use the `nbs__`
 * prefix; none of them is exported from the shared library.
 *
 * How a detection runs (context.c, nbs_detect):
 *   1. nbs__prepare validates the input in one pass and measures it: bounding box and
 *      largest radius, from which it derives the grid (cell edge and cells per axis).
 *   2. The algorithm chosen from the table runs on an nbs__run. It takes its arrays from
 *      the context's work block (nbs__work_reserve), walks its cells and hands each pair
 *      its mask yields to nbs__offer, which applies the distance test (contact mode) and
 *      stores the pair (nbs__emit).
 *   3. The core records the statistics.
 *
 * Adding an algorithm: write `nbs_status nbs__NAME(nbs__run *run)` in its own file, add it
 * to the table in context.c and a value to nbs_algorithm, and it is tested against direct by
 * tests/test_agreement.c as soon as it is in the list there.
 */
#ifndef NBS_INTERNAL_H
#define NBS_INTERNAL_H

#include "nbs/nbs.h"

#include <math.h>
#if defined(_OPENMP)
#include <omp.h>
#endif
#include <stdarg.h>
#include <stdbool.h>
#include <stdint.h>
#include <string.h>

/* The vector code (cellsort's kernels, NBS's tests of gathered candidates) needs a compiler
 * that can target AVX2 and AVX-512 (GCC and clang on x86-64); the processor is asked at run
 * time (ctx->simd). */
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define NBS__X86_SIMD 1
#include <immintrin.h>
#else
#define NBS__X86_SIMD 0
#endif

/* Every algorithm must evaluate the distance test as the same sequence of IEEE operations,
 * or a tie could be decided differently by two of them: no fused multiply-add. The build
 * passes -ffp-contract=off; clang also honours the standard pragma (gcc, in its ISO modes,
 * does not contract across statements anyway, and would warn about the pragma). */
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#endif

/* Largest number of cells on one axis of a regular grid. Cell coordinates, padded by one
 * cell on each side, then fit int32 with room to spare, and the rounding analysis of
 * nbs__prepare (cell edge margin 2^-18) holds for it. */
#define NBS__AXIS_MAX ((int64_t)1 << 30)

/* Head marking. The book marks a list as "old" by adding a large offset (2N) to its head;
 * with int32 heads and N up to 2^31 - 1 that overflows, so a marked head stores -2 - k
 * instead. Empty is -1, an unmarked list starts at k >= 0, a marked one at -2 - k <= -2. */
#define NBS__EMPTY (-1)
static inline int32_t nbs__mark(int32_t head) { return -2 - head; }
static inline int32_t nbs__unmark(int32_t head) { return head < NBS__EMPTY ? -2 - head : head; }
static inline bool nbs__is_marked(int32_t head) { return head < NBS__EMPTY; }

/* The regular grid of a scene (the book's integerisation, eq. 3.26):
 *   cell coordinate on axis a = Int((x_a - lo[a]) * inv_edge), 0-based.
 * edge is a hair (2^-18 relative) larger than the largest diameter, so that round-off in
 * this formula and in the distance test can never put a contacting pair in cells that are
 * not neighbours (see nbs__prepare for the argument). */
typedef struct nbs__grid {
  int dim;
  double lo[3], hi[3]; /* bounding box of the centres (lo is 0 when edge is +inf) */
  double edge;         /* cell edge; +inf when diameters are so large that every pair may touch */
  double inv_edge;     /* 1 / edge (0 when edge is +inf) */
  int64_t n[3];        /* cells per axis; -1 when the axis exceeds NBS__AXIS_MAX or overflows */
  bool fits;           /* every axis has 1 <= n <= NBS__AXIS_MAX */
  double rmax;         /* largest radius */
} nbs__grid;

/* The cell of coordinate v on `axis` of g; nbs__cell, that of the point x. */
static inline int32_t nbs__cell_of(const nbs__grid *g, double v, int axis) {
  return (int32_t)((v - g->lo[axis]) * g->inv_edge);
}

static inline int32_t nbs__cell(const nbs__grid *g, const double *x, int axis) {
  return nbs__cell_of(g, x[axis], axis);
}

#define NBS__THREADS_MAX 64

/* cellsort's keying of a cell order, as the context keeps it for the next detection (see
 * nbs_context.cs_kept and cellsort.c's nbs__cs_keying, which reads it): the grid with its
 * axes in the key's order and its origin anchored, the x sub-cells' scale, which coordinate
 * each of the key's axes reads, and where iy and iz start in the key. */
typedef struct nbs__cs_kept {
  nbs__grid g;
  double lo_x, inv_fine;
  int c[3];
  int dim, sy, sz;
} nbs__cs_kept;

/* A choice between two ways of doing a detection, timed (cellsort.c, nbs__tune_*): the
 * measurements are of inputs of class cls (dimension, threads and the power of two of the
 * input's bytes; another class starts them again, -1 none yet): tries[w] detections of way w
 * timed, the fastest of them best[w] seconds per element. Once each way has
 * NBS__CS_TUNE_TRIES, the faster is taken. */
typedef struct nbs__tune {
  int cls;
  int tries[2];
  double best[2];
} nbs__tune;

struct nbs_context {
  nbs_allocator allocator;
  size_t cell_budget;
  size_t max_pairs;

  size_t bytes, peak_bytes;

  /* The work block: one allocation reused by every algorithm. work_kind says which layout
   * it holds (0: none or unknown contents). Algorithms that keep list heads in it rely on
   * "all heads are empty between detections" and reset work_kind to 0 if they stop early
   * with heads dirty, so the next detection initialises them again. */
  void *work;
  size_t work_size;
  int work_kind;
  int64_t work_cap[4];
  /* The work block was allocated (nbs__work_reserve) and no cellsort detection has run in it
   * since: the next one's time is the first touch of its pages, and is no try of cs_ways or
   * cs_steps (nbs__detect). */
  bool work_new;
  /* NBS's layer block (3D): a copy of the elements of the central layer and of the layer
   * below it, in their own allocation because its size is known only once a detection has
   * counted the layers (munjiza_nbs.c). Nothing in it lives from one detection to the next. */
  void *nbs_block;
  size_t nbs_block_size;
  /* Whether NBS (3D) puts each central layer's rows together in its block: by the block's
   * size (0), always (1) or never (-1), from NBS_NBS_ROWS when the context was created
   * (nbs__nbs_rows_mode; munjiza_nbs.c, "Rows together"). */
  int8_t nbs_rows;
  /* NBS's elements in layer order (3D): each element's coordinates (and radius) copied by
   * step 1 to its place in its layer's run, n * (3 or 4) doubles, in their own allocation;
   * nothing in it lives from one detection to the next (munjiza_nbs.c, "The elements in
   * layer order"). Where the input is larger than NBS__NBS_ORDER_MIN (0), always (1) or never
   * (-1), from NBS_NBS_ORDER when the context was created (nbs__nbs_order_mode). */
  void *nbs_order;
  size_t nbs_order_size;
  int8_t nbs_order_mode;
  /* cellsort's cell order: when work_kind is NBS__WORK_CELLSORT and cs_order_n is n (> 0),
   * the work block's key array holds the packed words (key << eb | element) of the last
   * detection of n elements, sorted: the next detection may start from it (cellsort.c),
   * where its words have the same element bits, cs_order_eb (they depend on the cells as
   * well as on n). */
  int32_t cs_order_n;
  int cs_order_eb;
  /* With that order, and words whose low half is the element alone (cs_order_eb 32), the
   * work block's idx array may hold each element's key, idx[e] = word >> 32 for the word
   * of element e in the order: cs_keys says it does (nbs__cs_rekey). */
  bool cs_keys;
  /* After a start from it fails (too many elements changed place), the next cs_warm_wait
   * detections sort from scratch without trying: 2, 4, ... 64 after 1, 2, ... 6 failures in
   * a row (cs_warm_fails), so that steps that keep failing stop paying for the try. */
  int cs_warm_wait, cs_warm_fails;
  /* The keying of that order, where cs_keys may say its keys are there (cs_kept_ok): the
   * next detection's time-step pass (nbs__cellsort_step) computes every element's key with
   * it while it reads the input, in place of input.c's pass, and the keys stand if this
   * detection's own keying comes out the same. cs_stepped says whether the last detection
   * took that pass (read by the tests). */
  nbs__cs_kept cs_kept;
  bool cs_kept_ok, cs_stepped;
  /* Whether the last detection sorted from scratch with the keys of nbs__cellsort_fresh's
   * pass, or partitioned with its counts (its guessed keying was this detection's; read by
   * the tests). */
  bool cs_fresh_words;
  /* How the last cellsort detection sorted its keys: -1 by the whole key (and before any),
   * else by its crowded core, this many elements (the outliers) apart (nbs__cs_core). Read
   * by the tests, which cannot see it through the API. */
  int64_t cs_outliers;
  /* cellsort's partition (nbs__cs_partition) is tried where the input's coordinates (and
   * radii) take more bytes than this (nbs__cellsort_partition_min); cs_partitioned says
   * whether the last cellsort detection took it (one that started from the last order did
   * not; read by the tests). */
  size_t cs_part_min;
  bool cs_partitioned;
  /* the partition's top digit is widened wherever the keys allow (NBS_PARTITION=wide, for
   * the tests; else only where the even split's buckets would be too large for a cache,
   * nbs__cs_part_digits); cs_part_widened says whether the last partition widened it */
  bool cs_part_wide, cs_part_widened;
  /* Between NBS__CS_TUNE_MIN bytes and cs_part_min, which of the two ways a detection from
   * scratch takes is measured (nbs__cs_way): cs_tune says so (NBS_PARTITION unset); in
   * cs_ways, way 0 the sort and the gather, 1 the partition (+infinity where it could not
   * run). Likewise, where cs_tune and a detection from scratch would partition (by size, or
   * as cs_ways measured), whether a time step starts from the last order (way 0, with its
   * keys) or sorts from scratch (1), in cs_steps (nbs__cs_steps_way; at 3D N = 1e8 a
   * step's random gather of 2.4 GB costs more than a partition from scratch). Each time
   * from the detection's start to its search. */
  bool cs_tune;
  nbs__tune cs_ways, cs_steps;
  /* cellsort's threaded sweep (nbs__cs_sweep_parts): the chunks the last detection's threads
   * took from other threads' parts (read by the tests), and NBS_STEAL=first, which
   * makes every thread take one first (nbs__cellsort_steal_first). */
  int cs_stolen;
  bool cs_steal_first;
  /* The caller's coordinate of each axis of the last cellsort or nbs detection, in the
   * algorithm's order: cellsort's key x (the rows), y, z; nbs's x-, y- and z-lists (2D: x-
   * and y-lists). Which axis takes which place changes the speed, never the pairs' set
   * (nbs__axis_order); read by the tests. */
  int8_t axes[3];

  /* In a detection (nbs_detect): a pair callback that calls back into the context is
   * refused (NBS_ERR_BUSY) instead of freeing the arrays the detection is using. */
  bool busy;

  /* The pair buffer (buffer mode) and the batch used in callback mode. */
  nbs_pair *pairs;
  size_t pairs_cap, pairs_count;
  bool pairs_valid;

  /* Threads (cellsort): the number asked for (0: OpenMP's default), and each extra
   * thread's pair list, kept between detections. */
  int threads;
  /* cellsort's kernel: NBS__SIMD_GENERIC, _AVX512 or _AVX2 (nbs__cellsort_simd) */
  int simd;
  nbs_pair *tpairs[NBS__THREADS_MAX];
  size_t tcap[NBS__THREADS_MAX];

  nbs_stats stats;
  char error[256];
  int64_t error_element;
};

typedef struct nbs__run {
  nbs_context *ctx;
  int dim;
  int32_t n;
  const double *x; /* n * dim coordinates */
  const double *r; /* n radii or NULL */
  double d2;       /* diameter^2 when r is NULL */
  nbs_mode mode;
  nbs__grid grid;

  /* pair sink */
  nbs_pair *buf;
  size_t count, cap;
  nbs_pair_fn callback;
  void *user;
  uint64_t candidates, emitted;

  /* filled by the algorithm for the statistics */
  nbs_algorithm ran;
  size_t work_bytes;
  bool compressed;
  int64_t cells[3];
  bool fresh;         /* nbs_detect_def.fresh */
  /* The input was read by cellsort's time-step pass (nbs__cellsort_step) instead of
   * input.c's: the grid comes from the bounds it measured, and the work block holds the old
   * and new words of the step_moved elements whose key changed. */
  bool stepped;
  int64_t step_moved;
  /* That pass found more keys changed than a start from the order takes (it then counts as
   * the detection's failed start, and input.c's pass ran). */
  bool step_over;
  /* The input was read by cellsort's pass for a detection from scratch
   * (nbs__cellsort_fresh): the grid comes from the bounds it measured, and the work block
   * holds step 1's words made with the keying `pre`, of pre_bits bits, packed with pre_eb
   * element bits. */
  bool prewords;
  /* Or, where the partition is to run, the pass counted the keys' top digit into each
   * thread's histogram of the work block instead of making the words (precounts). */
  bool precounts;
  nbs__cs_kept pre;
  int pre_bits, pre_eb;
  /* That pass overwrote the last detection's order of this n, which this detection would
   * not have started from (its starts paused, or too many elements moved), whose words had
   * dropped_eb element bits: nbs__cellsort counts the pause or the failed start all the
   * same. */
  bool order_dropped;
  int dropped_eb;
  /* cellsort's way from scratch for this detection (nbs__cs_way): 0 not yet chosen, 1 the
   * sort and the gather, 2 the partition; cs_try says it is one of the context's timed
   * tries (cs_tune), and cs_tried what the try did (0: not taken, the detection having
   * started from the last order; 1 or 2: that way; 3: the partition could not run),
   * recorded after the detection (nbs__cellsort_tried). */
  int8_t cs_way;
  bool cs_try;
  int8_t cs_tried;
  /* This detection is one of the context's timed tries of its time steps (cs_steps):
   * 1 from the last order, 2 from scratch (run->fresh set by nbs__cs_steps_way); 0 not a
   * try. */
  int8_t cs_step_try;
  bool reused_order;  /* cellsort started from the last cell order */
  int64_t moved;      /* the elements it sorted again */
  /* When the algorithm began its search, every element in place (nbs__search_begins; 0:
   * not yet), for nbs_stats.seconds_search */
  double t_search;
} nbs__run;

/* A monotonic clock in seconds (context.c), for the statistics' split of the time. */
double nbs__now(void);
/* Each algorithm calls this where its search begins: every element is in its cells, lists
 * or order, and what follows tests candidates and hands out pairs. */
static inline void nbs__search_begins(nbs__run *run) { run->t_search = nbs__now(); }

/* ---- memory (context.c) ---- */
void *nbs__alloc(nbs_context *ctx, size_t size);
void nbs__free(nbs_context *ctx, void *p, size_t size);
/* Replaces the context's buffer *buf of *size bytes by a new one of `bytes`, its contents
 * not kept: false where the new one cannot be allocated (the old one is then kept). */
bool nbs__replace(nbs_context *ctx, void **buf, size_t *size, size_t bytes);
/* Makes ctx->work at least `bytes` long. When it has to reallocate, the old contents are
 * lost and work_kind becomes 0; on failure the old block is kept (NBS_ERR_NOMEM). */
nbs_status nbs__work_reserve(nbs_context *ctx, size_t bytes);

/* Grows thread t's pair list to at least `need` pairs (thread-safe); *buf and *cap follow. */
nbs_status nbs__thread_pairs_grow(nbs_context *ctx, int t, size_t need, nbs_pair **buf,
                                  size_t *cap);
/* How many threads to use for work that can use at most `useful` (>= 1 always): the
 * context's count (or OpenMP's default), 1 where no further parallel region may be active.
 * A region may still get fewer than this (OMP_THREAD_LIMIT, OMP_DYNAMIC): see NBS__PARTS. */
int nbs__threads(const nbs_context *ctx, int64_t useful);

/* The calling thread's number in a parallel region (0 without OpenMP). */
static inline int nbs__thread_num(void) {
#if defined(_OPENMP)
  return omp_get_thread_num();
#else
  return 0;
#endif
}

/* The number of threads in the calling thread's team (1 without OpenMP). */
static inline int nbs__team_size(void) {
#if defined(_OPENMP)
  return omp_get_num_threads();
#else
  return 1;
#endif
}

/* The parts of the work that the calling thread of a parallel region does, where the work
 * is cut into `parts` (the threads asked for with num_threads): part t is its own number,
 * then every team-size-th after it. OpenMP may give a region fewer threads than it asks
 * for: one, when the detection is called from inside the caller's own parallel region and
 * nesting is off (the default); fewer under OMP_THREAD_LIMIT or OMP_DYNAMIC. Every part is
 * then still done, by a thread that does several. With the team asked for, each thread
 * does its own part, once. A region with barriers loops over its parts between each pair
 * of them, and keeps what a part carries across a barrier in arrays indexed by part. */
#define NBS__PARTS(t, parts)                                                                  \
  for (int t = nbs__thread_num(), nbs__team = nbs__team_size(); t < (parts); t += nbs__team)

/* Where thread t's share of n items starts, when `threads` share them evenly. */
static inline int32_t nbs__chunk(int32_t n, int t, int threads) {
  return (int32_t)((int64_t)n * t / threads);
}

/* ---- errors (context.c) ---- */
/* Records status with a formatted detail (element -1 when none) and returns status. */
nbs_status nbs__fail(nbs_context *ctx, nbs_status status, int64_t element, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;
#define NBS__TRY(expr)                                                                        \
  do {                                                                                        \
    nbs_status nbs__s = (expr);                                                               \
    if (nbs__s != NBS_OK) return nbs__s;                                                      \
  } while (0)

/* ---- input (input.c) ---- */
/* Validates `in` and fills run->grid. Names the first offending element. In two parts:
 * nbs__prepare_args checks what needs no pass over the elements (dimension, count,
 * pointers, diameter), sets run's dim, n, x, r, d2 and, for n = 0, the grid;
 * nbs__prepare_scan is the pass over the elements (every number finite, radii > 0) and the
 * grid from the bounds it measured (nbs__grid_measured). */
nbs_status nbs__prepare(nbs__run *run, const nbs_input *in);
nbs_status nbs__prepare_args(nbs__run *run, const nbs_input *in);
nbs_status nbs__prepare_scan(nbs__run *run, const nbs_input *in);
/* run->grid from the bounding box [lo, hi] of the n > 0 elements, all finite, and their
 * largest radius rmax (half the diameter without radii). */
void nbs__grid_measured(nbs__run *run, const double lo[3], const double hi[3], double rmax);
/* input.c's pass over run's n > 0 radii alone: whether every one is a finite number > 0,
 * and then the largest in *rmax. */
bool nbs__radii_max(const nbs__run *run, double *rmax);
/* An order of the axes for an algorithm whose structure nests them (NBS's lists, cellsort's
 * key), with count[a] cells or lists on coordinate axis a: its axis i is coordinate at[i].
 * Coordinate i at each place i, except at `slot`, where the axis that nests worst when
 * short goes (NBS's layers: slot dim - 1; cellsort's rows: slot 0): of the other axes, the
 * one with the most (the later of equals), where it has at least twice as many as axis
 * `slot`; the others then keep their order. A cube keeps every axis in its place. */
void nbs__axis_order(int dim, const int64_t count[3], int slot, int at[3]);
/* g with its axes in the order at[] (axis a of the result is axis at[a] of g). */
nbs__grid nbs__grid_reorder(const nbs__grid *g, const int at[3]);

/* ---- pair sink (context.c) ---- */
/* Called when the batch is full: delivers it to the callback, or grows the buffer. */
nbs_status nbs__flush(nbs__run *run);

/* Makes room for `need` more pairs (flushing a callback's batch or growing the buffer), so
 * that a fast loop can write them without checks. *room is false when that cannot be (a
 * batch smaller than need, or max_pairs in reach): then emit pair by pair. */
nbs_status nbs__room(nbs__run *run, size_t need, bool *room);

/* Makes room for `need` more pairs where the run's count and need are the detection's whole
 * list (cellsort's threads, appending theirs at the end; no callback): the buffer grows to
 * that and a sixteenth more, not by half again (context.c, nbs__pairs_grow). NBS_ERR_PAIRS
 * where the list would pass the context's max_pairs (cellsort runs one thread then). */
nbs_status nbs__room_whole(nbs__run *run, size_t need);

/* The pair of elements a and b as reported: (i, j) with i < j. */
static inline nbs_pair nbs__pair_of(int32_t a, int32_t b) {
  nbs_pair p;
  p.i = a < b ? a : b;
  p.j = a < b ? b : a;
  return p;
}

static inline nbs_status nbs__emit(nbs__run *run, int32_t a, int32_t b) {
  if (run->count == run->cap) {
    nbs_status s = nbs__flush(run);
    if (s != NBS_OK) return s;
  }
  run->buf[run->count++] = nbs__pair_of(a, b);
  run->emitted++;
  return NBS_OK;
}

/* The contact test of the contract on two points pa, pb of dim coordinates and the radii
 * ra, rb (r: whether there are radii; else lim2 is the diameter squared):
 * |xa - xb|^2 <= (ra + rb)^2 in double, always as this sequence of operations. */
static inline bool nbs__touch_at(const double *pa, const double *pb, int dim, bool r, double ra,
                                 double rb, double lim2) {
  double dx = pa[0] - pb[0], dy = pa[1] - pb[1];
  double s = dx * dx + dy * dy;
  if (dim == 3) {
    double dz = pa[2] - pb[2];
    s += dz * dz;
  }
  if (r) {
    double rr = ra + rb;
    lim2 = rr * rr;
  }
  return s <= lim2;
}

/* The contact test of elements a and b (nbs__touch_at on the caller's coordinates). */
static inline bool nbs__touch(const nbs__run *run, int32_t a, int32_t b) {
  const bool r = run->r != NULL;
  return nbs__touch_at(run->x + (size_t)a * (size_t)run->dim,
                       run->x + (size_t)b * (size_t)run->dim, run->dim, r, r ? run->r[a] : 0,
                       r ? run->r[b] : 0, run->d2);
}

/* A pair yielded by an algorithm's cell mask: counted as a candidate, tested in contact
 * mode, emitted if it passes (or always in candidate mode). */
static inline nbs_status nbs__offer(nbs__run *run, int32_t a, int32_t b) {
  run->candidates++;
  if (run->mode == NBS_MODE_CONTACTS && !nbs__touch(run, a, b)) return NBS_OK;
  return nbs__emit(run, a, b);
}

/* ---- algorithms (one file each) ---- */
nbs_status nbs__direct(nbs__run *run);
nbs_status nbs__screening(nbs__run *run);
nbs_status nbs__sorting(nbs__run *run);
nbs_status nbs__nbs(nbs__run *run);
/* NBS's lists per axis for the run's grid and elements: the cells of each axis, or, where
 * the heads would outweigh the elements, fewer lists onto which the axis is folded
 * (munjiza_nbs.c, "Folded axes"). Fills lists[] (1 past dim) and returns true when an axis
 * is folded. */
bool nbs__nbs_fold(const nbs__run *run, int64_t lists[3]);
nbs_status nbs__cellsort(nbs__run *run);
/* A time step's pass over the input (see cellsort.c), in place of nbs__prepare_scan where
 * the context holds a cell order it can start from and `asked` may run cellsort; returns
 * whether it took it (run->stepped, run->grid set). Else nothing was read, or what was is
 * discarded, and the caller runs nbs__prepare_scan. run: as nbs__prepare_args left it. */
bool nbs__cellsort_step(nbs__run *run, const nbs_input *in, nbs_algorithm asked);
/* A detection from scratch's pass over the input (see cellsort.c), in place of
 * nbs__prepare_scan where the context holds a free work block for cellsort and `asked` may
 * run it; returns whether it took it (run->prewords, run->grid set). Else the caller runs
 * nbs__prepare_scan. run: as nbs__prepare_args left it. */
bool nbs__cellsort_fresh(nbs__run *run, const nbs_input *in, nbs_algorithm asked);
/* True when cellsort's 64-bit cell key can index the grid (auto's test). */
bool nbs__cellsort_fits(const nbs__grid *g);
/* Bytes of cellsort's work block for n elements (with radii or not) and `threads` threads:
 * 36 per element in 3D, 28 in 2D, 8 more with radii, whatever the extent. */
size_t nbs__cellsort_bytes(int dim, int32_t n, bool radii, int threads);
/* Which kernel cellsort uses in this process (NBS__SIMD_...); the environment variable
 * NBS_SIMD=generic or NBS_SIMD=avx2 asks for a lesser one. */
enum { NBS__SIMD_GENERIC = 0, NBS__SIMD_AVX512 = 1, NBS__SIMD_AVX2 = 2 };
int nbs__cellsort_simd(void);
#if NBS__X86_SIMD
/* The permutations of 8 int32 (4 pairs) that pack the pairs of a 4-bit mask to the front,
 * for AVX2, which has no compress: row m moves the pairs of m's set bits, in order. Used by
 * cellsort's and NBS's AVX2 tests; defined in cellsort.c. */
extern const int32_t nbs__pack4[16][8];
/* Four int32 from p, each twice: {p0, p0, p1, p1, ...}. Against an element's number twice,
 * a pair {min, max} is then one min and one max blended, already in nbs_pair's layout. */
static inline __attribute__((always_inline, target("avx2"))) __m256i
nbs__twice4(const int32_t *p) {
  const __m256i v = _mm256_castsi128_si256(_mm_loadu_si128((const __m128i *)(const void *)p));
  return _mm256_permutevar8x32_epi32(v, _mm256_set_epi32(3, 3, 2, 2, 1, 1, 0, 0));
}
#endif
size_t nbs__cellsort_partition_min(void);
bool nbs__cellsort_partition_wide(void);
/* NBS (3D) puts each layer's rows together where its layer block is larger than this
 * (munjiza_nbs.c, "Rows together"). Below it, in a core's L2 with room to spare, the entries'
 * order costs little and putting them in order only costs (N = 1e4, a block of 33 kB: 75.0 ->
 * 79.5 ns per element; 1e5, 170 kB, even). */
#define NBS__NBS_ROWS_MIN ((size_t)512 << 10)
int8_t nbs__nbs_rows_mode(void);
/* NBS (3D) copies every element's coordinates (and radius) into its layer's place in step 1
 * where the input's coordinates and radii are larger than this (munjiza_nbs.c, "The elements
 * in layer order"): about the last-level cache of the machines measured, below which the
 * walks' random reads of the input are answered from it and the copy only costs (N = 1e6,
 * 24 MB: 88.3 -> 89.1 ns per element, a prototype; 3e6, 72 MB, 88.6 -> 86.4; 1e7 101.0 ->
 * 87.6). */
#define NBS__NBS_ORDER_MIN ((size_t)32 << 20)
int8_t nbs__nbs_order_mode(void);
bool nbs__cellsort_tune(void);
/* After a detection that succeeded: where it was one of cellsort's timed tries (run->cs_try),
 * its time from its start to its search, `seconds`, is recorded (nbs_context.cs_tune). */
void nbs__cellsort_tried(nbs_context *ctx, const nbs__run *run, double seconds);
bool nbs__cellsort_steal_first(void);

/* Work-block layouts, for work_kind. */
enum { NBS__WORK_NONE = 0, NBS__WORK_SCREENING = 1, NBS__WORK_SORTING = 2, NBS__WORK_NBS = 3,
       NBS__WORK_CELLSORT = 4 };

/* ---- test hooks (not part of the API; used by tests/ against the static library) ---- */
/* True when every list head in the context's NBS / screening layout is empty (or when the
 * work block holds no such layout). nbs__heads_empty dispatches on work_kind to the
 * algorithm file that owns the layout. */
bool nbs__heads_empty(const nbs_context *ctx);
bool nbs__screening_heads_empty(const nbs_context *ctx);
bool nbs__nbs_heads_empty(const nbs_context *ctx);

#endif /* NBS_INTERNAL_H */
