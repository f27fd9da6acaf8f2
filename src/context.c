/*
 * The context (memory, errors, the pair sink) and nbs_detect, which validates the input,
 * picks an algorithm from the table and runs it.
 */
#if !defined(_POSIX_C_SOURCE)
#define _POSIX_C_SOURCE 199309L /* clock_gettime */
#endif
#include "internal.h"

#include <stdio.h>
#include <stdlib.h>
#include <time.h>

const char *nbs_version(void) { return NBS_VERSION_STRING; }

const char *nbs_status_name(nbs_status status) {
  switch (status) {
#define NBS_X_NAME(e, v, name, msg)                                                           \
  case e:                                                                                     \
    return name;
    NBS_STATUS_LIST(NBS_X_NAME)
#undef NBS_X_NAME
  }
  return "unknown";
}

const char *nbs_status_message(nbs_status status) {
  switch (status) {
#define NBS_X_MSG(e, v, name, msg)                                                            \
  case e:                                                                                     \
    return msg;
    NBS_STATUS_LIST(NBS_X_MSG)
#undef NBS_X_MSG
  }
  return "unknown status";
}

/* ---- algorithms ---------------------------------------------------------------------- */

typedef struct nbs__algorithm_entry {
  const char *name;
  nbs_status (*run)(nbs__run *run); /* NULL for auto, which picks one of the others */
} nbs__algorithm_entry;

static const nbs__algorithm_entry nbs__algorithms[NBS_ALGORITHM_COUNT] = {
    [NBS_AUTO] = {"auto", NULL},
    [NBS_DIRECT] = {"direct", nbs__direct},
    [NBS_SCREENING] = {"screening", nbs__screening},
    [NBS_SORTING] = {"sorting", nbs__sorting},
    [NBS_NBS] = {"nbs", nbs__nbs},
    [NBS_CELLSORT] = {"cellsort", nbs__cellsort},
};

const char *nbs_algorithm_name(nbs_algorithm algorithm) {
  if ((int)algorithm < 0 || algorithm >= NBS_ALGORITHM_COUNT) return NULL;
  return nbs__algorithms[algorithm].name;
}

nbs_status nbs_algorithm_from_name(const char *name, nbs_algorithm *out) {
  if (!name || !out) return NBS_ERR_NULL;
  for (int a = 0; a < NBS_ALGORITHM_COUNT; a++) {
    if (strcmp(name, nbs__algorithms[a].name) == 0) {
      *out = (nbs_algorithm)a;
      return NBS_OK;
    }
  }
  return NBS_ERR_ALGORITHM;
}

/* Below this many elements, checking every pair is cheaper than building any list. */
#define NBS__AUTO_DIRECT_MAX 32

/* auto: cellsort, nbs's fastest path (linear in N, about 36 bytes per element whatever
 * the domain's extent), wherever its 64-bit cell key can index the domain; otherwise
 * sorting, whose memory is 3N/4N integers whatever the spread and which compresses axes
 * too wide to index, so that every finite input succeeds. A handful of elements is
 * checked directly. */
static nbs_algorithm nbs__choose(const nbs__run *run) {
  if (run->n <= NBS__AUTO_DIRECT_MAX) return NBS_DIRECT;
  const nbs__grid *g = &run->grid;
  if (!g->fits) return NBS_SORTING;
  return nbs__cellsort_fits(g) ? NBS_CELLSORT : NBS_SORTING;
}

/* ---- memory -------------------------------------------------------------------------- */

static void *nbs__default_alloc(void *opaque, size_t size) {
  (void)opaque;
  return malloc(size);
}

static void nbs__default_free(void *opaque, void *p, size_t size) {
  (void)opaque;
  (void)size;
  free(p);
}

static void *nbs__default_realloc(void *opaque, void *p, size_t old_size, size_t new_size) {
  (void)opaque;
  (void)old_size;
  return realloc(p, new_size);
}

/* Threads of one detection may allocate at the same time (their pair lists): the user's
 * allocator and the byte count see one call at a time. */
void *nbs__alloc(nbs_context *ctx, size_t size) {
  if (size == 0) size = 1;
  void *p;
#if defined(_OPENMP)
#pragma omp critical(nbs__allocator)
#endif
  {
    p = ctx->allocator.alloc(ctx->allocator.opaque, size);
    if (p) {
      ctx->bytes += size;
      if (ctx->bytes > ctx->peak_bytes) ctx->peak_bytes = ctx->bytes;
    }
  }
  return p;
}

void nbs__free(nbs_context *ctx, void *p, size_t size) {
  if (!p) return;
  if (size == 0) size = 1;
#if defined(_OPENMP)
#pragma omp critical(nbs__allocator)
#endif
  {
    ctx->allocator.free(ctx->allocator.opaque, p, size);
    ctx->bytes -= size;
  }
}

/* Grows (or makes) a block to `size` bytes, keeping its first `keep` bytes: through the
 * allocator's realloc when it has one, else by allocating, copying and freeing. On failure
 * the old block is untouched and NULL is returned. */
static void *nbs__realloc(nbs_context *ctx, void *p, size_t old_size, size_t size, size_t keep) {
  if (!p) return nbs__alloc(ctx, size);
  if (!ctx->allocator.realloc) {
    void *q = nbs__alloc(ctx, size);
    if (!q) return NULL;
    if (keep) memcpy(q, p, keep);
    nbs__free(ctx, p, old_size);
    return q;
  }
  void *q;
#if defined(_OPENMP)
#pragma omp critical(nbs__allocator)
#endif
  {
    q = ctx->allocator.realloc(ctx->allocator.opaque, p, old_size, size);
    if (q) {
      ctx->bytes = ctx->bytes - old_size + size;
      if (ctx->bytes > ctx->peak_bytes) ctx->peak_bytes = ctx->bytes;
    }
  }
  return q;
}

nbs_status nbs__thread_pairs_grow(nbs_context *ctx, int t, size_t need, nbs_pair **buf,
                                  size_t *cap) {
  if (need <= ctx->tcap[t]) {
    *buf = ctx->tpairs[t];
    *cap = ctx->tcap[t];
    return NBS_OK;
  }
  size_t c = ctx->tcap[t] + ctx->tcap[t] / 2;
  if (c < need) c = need;
  if (c < 4096) c = 4096;
  if (c > SIZE_MAX / sizeof(nbs_pair)) return NBS_ERR_NOMEM;
  nbs_pair *p = nbs__realloc(ctx, ctx->tpairs[t], ctx->tcap[t] * sizeof(nbs_pair),
                             c * sizeof(nbs_pair), ctx->tcap[t] * sizeof(nbs_pair));
  if (!p) return NBS_ERR_NOMEM;
  ctx->tpairs[t] = p;
  ctx->tcap[t] = c;
  *buf = p;
  *cap = c;
  return NBS_OK;
}

int nbs__threads(const nbs_context *ctx, int64_t useful) {
#if defined(_OPENMP)
  int t = ctx->threads > 0 ? ctx->threads : omp_get_max_threads();
  /* called from inside parallel regions as deep as may be active (the caller's own, with
   * nesting off): a region of ours would get one thread, which would do every part */
  if (omp_get_active_level() >= omp_get_max_active_levels()) t = 1;
  if (t > NBS__THREADS_MAX) t = NBS__THREADS_MAX;
  if (t > useful) t = (int)useful;
  return t < 1 ? 1 : t;
#else
  (void)ctx;
  (void)useful;
  return 1;
#endif
}

/* Tried and left out: madvise(MADV_HUGEPAGE) on the new block (this machine's transparent
 * huge pages are given on request only): 3D cellsort, N = 1e6, 30.3 -> 29.6 ns per element,
 * N = 1e7 42.3 -> 58.5 (interleaved, min of 5). Again on 585a76a (Zen 5; the kernel then gave
 * the block's huge pages, /proc/vmstat's thp_fault_alloc): auto, N = 1e6, medians of 12
 * interleaved processes 25.10 -> 25.03, N = 1e7 25.66 -> 25.51, within the noise. And on
 * 72fa429 (Zen 3, AVX2 only; every default allocation of 4 MiB or more advised, the work
 * block, the pair buffer and the threads' lists; the same binary with the advice turned off
 * by an environment variable, 10 interleaved rounds, --fresh): auto 3D N = 1e6 min 49.68 ->
 * 49.33, medians 51.6 -> 50.6, preparation 18.7 -> 18.3; 2D 29.4 / 29.7; time steps 40.2 /
 * 40.4; N = 1e7 53.1 -> 57.7 (min of 3). The caller's coordinates on huge pages, in the
 * same run: 3D 49.6 -> 46.7 (preparation 18.9 -> 16.3: the gather's random reads, which
 * miss the TLB), 2D 28.3 -> 27.5 (README, "The C API"). */
bool nbs__replace(nbs_context *ctx, void **buf, size_t *size, size_t bytes) {
  void *p = nbs__alloc(ctx, bytes);
  if (!p) return false;
  nbs__free(ctx, *buf, *size);
  *buf = p;
  *size = bytes;
  return true;
}

nbs_status nbs__work_reserve(nbs_context *ctx, size_t bytes) {
  if (bytes <= ctx->work_size) return NBS_OK;
  if (!nbs__replace(ctx, &ctx->work, &ctx->work_size, bytes)) {
    return nbs__fail(ctx, NBS_ERR_NOMEM, -1, "cannot allocate %zu bytes of work arrays", bytes);
  }
  ctx->work_kind = NBS__WORK_NONE;
  ctx->work_new = true;
  return NBS_OK;
}

/* Grows the pair buffer to hold at least `need` pairs, by half again its size at least,
 * but to no more than `limit` pairs (0: no limit; need <= limit). With `whole`, need is a
 * detection's whole list, known before it is written (cellsort's threads append their pairs
 * at the end): the buffer is grown to it and a sixteenth more instead, so that the next
 * detections, time steps whose count moves a little, fit it. Half again was for a list
 * growing pair by pair; here it had left the buffer at 1.5 times the pairs after the first
 * time step that found a few more. Measured (N = 1e6, two threads, nbs_bench --move 1e-3
 * against --fresh, 3 rounds interleaved, the context's peak bytes): 3D time steps 74.1-74.4
 * -> 62.9-67.7 MB (the buffer 23.7 -> 16.8 MB for 15.8 MB of pairs); from scratch, where the
 * count does not move and the buffer had been the pairs exactly, 61.8-66.2 -> 62.7-67.7;
 * 2D 42.5-42.8 -> 42.9-43.3 both ways (the staged lists vary with what the threads take
 * from each other). One thread grows its list pair by pair as before. */
static nbs_status nbs__pairs_grow(nbs_context *ctx, size_t need, size_t limit, bool whole) {
  if (need <= ctx->pairs_cap) return NBS_OK;
  size_t cap = whole ? need + need / 16 : ctx->pairs_cap + ctx->pairs_cap / 2;
  if (cap < need) cap = need; /* either sum wrapped around */
  if (cap < 1024) cap = 1024;
  if (limit && cap > limit) cap = limit;
  if (cap > SIZE_MAX / sizeof(nbs_pair)) {
    return nbs__fail(ctx, NBS_ERR_PAIRS, -1, "a buffer of %zu pairs cannot be addressed", need);
  }
  nbs_pair *p = nbs__realloc(ctx, ctx->pairs, ctx->pairs_cap * sizeof(nbs_pair),
                             cap * sizeof(nbs_pair), ctx->pairs_count * sizeof(nbs_pair));
  if (!p) {
    return nbs__fail(ctx, NBS_ERR_NOMEM, -1, "cannot grow the pair buffer to %zu pairs (%zu bytes)",
                     cap, cap * sizeof(nbs_pair));
  }
  ctx->pairs = p;
  ctx->pairs_cap = cap;
  return NBS_OK;
}

/* ---- errors -------------------------------------------------------------------------- */

nbs_status nbs__fail(nbs_context *ctx, nbs_status status, int64_t element, const char *fmt, ...) {
  if (!ctx) return status;
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(ctx->error, sizeof ctx->error, fmt, ap);
  va_end(ap);
  ctx->error_element = element;
  return status;
}

const char *nbs_context_error(const nbs_context *ctx) { return ctx ? ctx->error : ""; }

int64_t nbs_context_error_element(const nbs_context *ctx) { return ctx ? ctx->error_element : -1; }

/* ---- context ------------------------------------------------------------------------- */

nbs_context_def nbs_default_context_def(void) {
  nbs_context_def def;
  memset(&def, 0, sizeof def);
  def.cell_budget = NBS_DEFAULT_CELL_BUDGET;
  return def;
}

nbs_status nbs_context_create(const nbs_context_def *def, nbs_context **out) {
  if (!out) return NBS_ERR_NULL;
  *out = NULL;
  nbs_context_def d = def ? *def : nbs_default_context_def();
  if ((d.allocator.alloc == NULL) != (d.allocator.free == NULL)) return NBS_ERR_ARGUMENT;
  if (d.allocator.realloc && !d.allocator.alloc) return NBS_ERR_ARGUMENT;
  if (d.threads < 0) return NBS_ERR_ARGUMENT;
  if (!d.allocator.alloc) {
    d.allocator.alloc = nbs__default_alloc;
    d.allocator.free = nbs__default_free;
    d.allocator.realloc = nbs__default_realloc;
    d.allocator.opaque = NULL;
  }
  nbs_context *ctx = d.allocator.alloc(d.allocator.opaque, sizeof *ctx);
  if (!ctx) return NBS_ERR_NOMEM;
  memset(ctx, 0, sizeof *ctx);
  ctx->allocator = d.allocator;
  ctx->cell_budget = d.cell_budget;
  ctx->max_pairs = d.max_pairs;
  ctx->threads = d.threads;
  ctx->simd = nbs__cellsort_simd();
  ctx->cs_part_min = nbs__cellsort_partition_min();
  ctx->cs_part_wide = nbs__cellsort_partition_wide();
  ctx->nbs_rows = nbs__nbs_rows_mode();
  ctx->nbs_order_mode = nbs__nbs_order_mode();
  ctx->cs_tune = nbs__cellsort_tune();
  ctx->cs_ways.cls = ctx->cs_steps.cls = -1;
  ctx->cs_steal_first = nbs__cellsort_steal_first();
  ctx->bytes = ctx->peak_bytes = sizeof *ctx;
  ctx->error_element = -1;
  ctx->cs_outliers = -1;
  *out = ctx;
  return NBS_OK;
}

void nbs_context_destroy(nbs_context *ctx) {
  if (!ctx) return;
  nbs__free(ctx, ctx->work, ctx->work_size);
  nbs__free(ctx, ctx->nbs_block, ctx->nbs_block_size);
  nbs__free(ctx, ctx->nbs_order, ctx->nbs_order_size);
  nbs__free(ctx, ctx->pairs, ctx->pairs_cap * sizeof(nbs_pair));
  for (int t = 0; t < NBS__THREADS_MAX; t++) {
    nbs__free(ctx, ctx->tpairs[t], ctx->tcap[t] * sizeof(nbs_pair));
  }
  nbs_allocator a = ctx->allocator;
  a.free(a.opaque, ctx, sizeof *ctx);
}

size_t nbs_context_bytes(const nbs_context *ctx) { return ctx ? ctx->bytes : 0; }

size_t nbs_context_peak_bytes(const nbs_context *ctx) { return ctx ? ctx->peak_bytes : 0; }

nbs_status nbs_context_reserve(nbs_context *ctx, int64_t n, size_t pairs) {
  if (!ctx) return NBS_ERR_NULL;
  if (ctx->busy) return NBS_ERR_BUSY; /* its detection's error and figures stay as they are */
  ctx->error[0] = '\0';
  ctx->error_element = -1;
  if (n < 0 || n > INT32_MAX) {
    return nbs__fail(ctx, NBS_ERR_COUNT, -1, "cannot reserve for %lld elements",
                     (long long)n);
  }
  /* The largest per-element layout of the algorithms: cellsort's in 3D with radii (44 bytes
   * per element, for as many threads as a detection may use), above sorting's 4 int32 and
   * NBS's 3 int32 plus the per-axis heads. */
  const int threads = nbs__threads(ctx, NBS__THREADS_MAX);
  if (n > 0) {
    NBS__TRY(nbs__work_reserve(ctx, nbs__cellsort_bytes(3, (int32_t)n, true, threads)));
  }
  NBS__TRY(nbs__pairs_grow(ctx, pairs, 0, false));
  /* With threads, cellsort's threads stage their pairs in lists of their own (thread 0's
   * the chunks it takes from others' parts), appended to the buffer after the sweep. How
   * the chunks fall to the threads changes from detection to detection with the cores'
   * speeds, and a thread may take all but the first: each list is made to hold them all. */
  for (int t = 0; threads > 1 && pairs > 0 && t < threads; t++) {
    nbs_pair *buf;
    size_t cap;
    if (nbs__thread_pairs_grow(ctx, t, pairs, &buf, &cap) != NBS_OK) {
      return nbs__fail(ctx, NBS_ERR_NOMEM, -1,
                       "cannot allocate thread %d's pair list of %zu pairs", t, pairs);
    }
  }
  return NBS_OK;
}

/* ---- the pair sink ------------------------------------------------------------------- */

/* Grows the pair buffer under run to hold `more` pairs beyond its count (nbs__pairs_grow),
 * and points the run at it; NBS_ERR_PAIRS where they would pass the context's max_pairs. */
static nbs_status nbs__run_grow(nbs__run *run, size_t more, bool whole) {
  nbs_context *ctx = run->ctx;
  if (ctx->max_pairs && run->count + more > ctx->max_pairs) {
    return nbs__fail(ctx, NBS_ERR_PAIRS, -1,
                     "more than %zu pairs (the context's max_pairs); use a callback or raise it",
                     ctx->max_pairs);
  }
  ctx->pairs_count = run->count;
  NBS__TRY(nbs__pairs_grow(ctx, run->count + more, ctx->max_pairs, whole));
  run->buf = ctx->pairs;
  run->cap = ctx->pairs_cap;
  return NBS_OK;
}

nbs_status nbs__flush(nbs__run *run) {
  nbs_context *ctx = run->ctx;
  if (run->callback) {
    if (run->callback(run->user, run->buf, run->count) != 0) {
      run->count = 0;
      return nbs__fail(ctx, NBS_ERR_STOPPED, -1, "the pair callback asked to stop");
    }
    run->count = 0;
    return NBS_OK;
  }
  return nbs__run_grow(run, 1, false);
}

nbs_status nbs__room_whole(nbs__run *run, size_t need) {
  if (run->cap - run->count >= need) return NBS_OK;
  return nbs__run_grow(run, need, true);
}

nbs_status nbs__room(nbs__run *run, size_t need, bool *room) {
  *room = true;
  if (run->cap - run->count >= need) return NBS_OK;
  if (run->callback) {
    if (run->count > 0) NBS__TRY(nbs__flush(run));
    *room = run->cap >= need;
    return NBS_OK;
  }
  nbs_context *ctx = run->ctx;
  if (ctx->max_pairs && run->count + need > ctx->max_pairs) {
    *room = false; /* the pair-by-pair path will stop at the limit with NBS_ERR_PAIRS */
    return NBS_OK;
  }
  return nbs__run_grow(run, need, false);
}

/* ---- detection ----------------------------------------------------------------------- */

double nbs__now(void) {
  struct timespec t;
#if defined(CLOCK_MONOTONIC)
  if (clock_gettime(CLOCK_MONOTONIC, &t) != 0) return 0.0;
#else
  if (timespec_get(&t, TIME_UTC) != TIME_UTC) return 0.0;
#endif
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

nbs_detect_def nbs_default_detect_def(void) {
  nbs_detect_def def;
  memset(&def, 0, sizeof def);
  def.algorithm = NBS_AUTO;
  def.mode = NBS_MODE_CONTACTS;
  return def;
}

/* In callback mode pairs are batched in the context's pair buffer, this many at a time. */
#define NBS__BATCH 4096

static nbs_status nbs__detect(nbs_context *ctx, const nbs_input *in, const nbs_detect_def *def);

nbs_status nbs_detect(nbs_context *ctx, const nbs_input *in, const nbs_detect_def *def) {
  if (!ctx) return NBS_ERR_NULL;
  if (ctx->busy) return NBS_ERR_BUSY; /* the detection's error and figures stay as they are */
  ctx->busy = true;
  const nbs_status s = nbs__detect(ctx, in, def);
  ctx->busy = false;
  return s;
}

static nbs_status nbs__detect(nbs_context *ctx, const nbs_input *in, const nbs_detect_def *def) {
  const double t_start = nbs__now();
  ctx->error[0] = '\0';
  ctx->error_element = -1;
  ctx->pairs_count = 0;
  ctx->pairs_valid = false;
  if (!in) return nbs__fail(ctx, NBS_ERR_NULL, -1, "the input is NULL");
  nbs_detect_def d = def ? *def : nbs_default_detect_def();
  if ((int)d.algorithm < 0 || d.algorithm >= NBS_ALGORITHM_COUNT) {
    return nbs__fail(ctx, NBS_ERR_ALGORITHM, -1, "unknown algorithm %d", (int)d.algorithm);
  }
  if (d.mode != NBS_MODE_CONTACTS && d.mode != NBS_MODE_CANDIDATES) {
    return nbs__fail(ctx, NBS_ERR_MODE, -1, "unknown mode %d", (int)d.mode);
  }

  nbs__run run;
  memset(&run, 0, sizeof run);
  run.ctx = ctx;
  run.mode = d.mode;
  run.callback = d.callback;
  run.user = d.user;
  run.fresh = d.fresh != 0;
  ctx->cs_stepped = false;
  ctx->cs_fresh_words = false;
  NBS__TRY(nbs__prepare_args(&run, in));
  /* A time step of cellsort reads the input once, validating it and measuring its bounds
   * as it computes each element's key (nbs__cellsort_step); else input.c's pass. (A large
   * input's step may be made one from scratch there, where that is faster.) */
  if (!nbs__cellsort_step(&run, in, d.algorithm) && !nbs__cellsort_fresh(&run, in, d.algorithm)) {
    NBS__TRY(nbs__prepare_scan(&run, in));
  }
  const double t_input = nbs__now();

  nbs_algorithm algo = d.algorithm == NBS_AUTO ? nbs__choose(&run) : d.algorithm;
  run.ran = algo;

  /* The sink: the pair buffer itself (holding at most max_pairs), or a batch of it in
   * callback mode (where max_pairs does not apply: the context holds no pairs). */
  size_t first = run.callback ? NBS__BATCH : 1024;
  size_t limit = run.callback ? 0 : ctx->max_pairs;
  if (limit && first > limit) first = limit;
  if (ctx->pairs_cap < first) {
    ctx->pairs_count = 0;
    NBS__TRY(nbs__pairs_grow(ctx, first, limit, false));
  }
  run.buf = ctx->pairs;
  run.cap = run.callback ? NBS__BATCH : ctx->pairs_cap;
  if (limit && run.cap > limit) run.cap = limit;

  nbs_status s = NBS_OK;
  if (run.n >= 2) s = nbs__algorithms[algo].run(&run);
  if (s == NBS_OK && run.callback && run.count > 0) {
    s = nbs__flush(&run);
  }

  nbs_stats *st = &ctx->stats;
  memset(st, 0, sizeof *st);
  st->algorithm = run.ran;
  st->mode = run.mode;
  st->dim = run.dim;
  st->n = run.n;
  st->pairs = run.emitted;
  st->candidates = run.candidates;
  st->cell_size = algo == NBS_DIRECT ? 0.0 : run.grid.edge;
  for (int a = 0; a < 3; a++) st->cells[a] = run.cells[a];
  st->compressed = run.compressed;
  st->work_bytes = run.work_bytes;
  st->pair_bytes = ctx->pairs_cap * sizeof(nbs_pair);
  st->reused_order = run.reused_order;
  st->moved = run.moved;
  st->seconds_input = t_input - t_start;
  const double t_found = nbs__now();
  if (run.t_search > 0.0) st->seconds_search = t_found - run.t_search;
  st->seconds = t_found - t_start;
  if (s != NBS_OK) return s;
  /* A try of cellsort's ways (nbs__cellsort_tried) counts only in a work block that an earlier
   * cellsort detection has used. The first detection in a block just allocated (the context's
   * first, or one after nbs_context_reserve or a larger input) faults in every page of it as it
   * writes its arrays, and takes about twice as long to its search as the next ones (3D, N =
   * 1e6, Zen 3: 50-71 against 27-38 ns per element). Counted, it was the first try of the sort
   * and the gather, which the context tries first: that way had one real try against the
   * partition's two, and contexts took the partition where it was the slower way (bench/README,
   * "An eighth machine", 2026-12-03 evening). The try not counted is made at the next
   * detection. */
  const bool first_use = ctx->work_new;
  if (run.ran == NBS_CELLSORT) ctx->work_new = false;
  if ((run.cs_try || run.cs_step_try) && run.t_search > 0.0 && !first_use) {
    nbs__cellsort_tried(ctx, &run, run.t_search - t_start);
  }

  ctx->pairs_count = run.callback ? 0 : run.count;
  ctx->pairs_valid = true;
  if (d.sorted && !run.callback) {
    nbs_sort_pairs(ctx->pairs, ctx->pairs_count);
    st->seconds = nbs__now() - t_start;
  }
  return NBS_OK;
}

const nbs_pair *nbs_pairs(const nbs_context *ctx, size_t *count) {
  if (!ctx || !ctx->pairs_valid || ctx->pairs_count == 0) {
    if (count) *count = 0;
    return NULL;
  }
  if (count) *count = ctx->pairs_count;
  return ctx->pairs;
}

nbs_status nbs_last_stats(const nbs_context *ctx, nbs_stats *out) {
  if (!ctx || !out) return NBS_ERR_NULL;
  *out = ctx->stats;
  return NBS_OK;
}

bool nbs__heads_empty(const nbs_context *ctx) {
  switch (ctx->work_kind) {
  case NBS__WORK_SCREENING:
    return nbs__screening_heads_empty(ctx);
  case NBS__WORK_NBS:
    return nbs__nbs_heads_empty(ctx);
  default:
    return true;
  }
}
