/*
 * cellsort: nbs's fast path, beyond the book. The same cells and the same half mask as
 * screening and NBS, but the elements are first put in cell order so that every distance
 * test reads memory that is next to the last one read.
 *
 * Why it is fast. For a million elements in random order, the book's algorithms spend most
 * of their time waiting for memory: each candidate pair reads two coordinates that lie
 * anywhere in 24 MB, far beyond the caches (measured: NBS is 5x faster on the same scene in
 * spatially sorted order). cellsort pays for one sort instead:
 *   1. key = (iz, iy, x sub-cell) packed in 64 bits, one pass over the input; x counts
 *      sub-cells of edge / 8 (fewer when the key needs the bits);
 *   2. LSD radix sort of (key, element) by the key's significant bits only, in as few
 *      passes of at most 11 bits as they need; the scatter of each pass writes into at most
 *      2^11 sequential streams, which caches handle well;
 *   3. gather the coordinates (and radii) in cell order: the last random access;
 *   4. sweep the rows in key order. For each element, the half mask is a window of its own
 *      row (the elements before it within one edge in x) and a window of each neighbouring
 *      row (within one edge either side in x: one row in 2D, four in 3D). Each window's
 *      edges only move forwards as the sweep advances: no binary search (but once per
 *      thread), no cell array, no hash. The sub-cells make the windows hug |dx| <= edge,
 *      so about 9 cell volumes are searched per element instead of 13.5.
 * Memory: 8 (key) + 4 (element) + 8 * dim (coordinates) bytes per element, + 8 with radii:
 * 36 B per element in 3D, whatever the extent of the domain. The radix sort's scratch lives
 * in the coordinate array before the gather.
 * Time: O(N * passes) for the sort, with passes = ceil(bits of the cell count / 11), i.e.
 * linear in N for any domain whose cell count fits 64 bits, plus O(candidates).
 *
 * With OpenMP the key pass, the radix sort, the gather and the sweep run in parallel; the
 * sweep's threads take contiguous ranges of rows and their pairs are concatenated in range
 * order, so the output is identical for any number of threads.
 */
#include "internal.h"

#if defined(_OPENMP)
#include <omp.h>
#endif
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#define NBS__RADIX_BITS 11
/* Entries after the end of the key array, read by NBS__CS_ADVANCE. */
#define NBS__CS_PAD 4
/* Sub-cells per cell edge on the x axis: a power of two, so that scaling is exact; fewer
 * when the key would not fit 64 bits otherwise. */
#define NBS__CS_FINE_BITS 3

typedef struct nbs__cs {
  nbs__run *run;
  int dim;
  int32_t n;
  uint64_t *key;
  int32_t *idx;
  double *xs, *ys, *zs; /* coordinates in cell order, one array per axis */
  double *rs; /* radii in cell order, or NULL */
  double d2;
  int64_t nx, ny, nz;
  int bx, by;     /* bits of the key for the x sub-cell and for iy (iz takes the rest) */
  uint64_t fine;  /* sub-cells per cell edge on x */
} nbs__cs;

/* Number of bits needed for values < count (count >= 1). */
static int nbs__bits(uint64_t count) {
  int b = 0;
  while (b < 64 && (count - 1) >> b) b++;
  return b;
}

/* Where thread t's share of n elements starts, when `threads` share them evenly. */
static inline int32_t nbs__chunk(int32_t n, int t, int threads) {
  return (int32_t)((int64_t)n * t / threads);
}

/* LSD radix sort of (key, idx) on the low `bits` bits. tk / ti are scratch of n entries;
 * hist holds `threads` histograms. The result ends in key / idx. With several threads each
 * takes a contiguous part of the input and scatters it after the parts of the threads
 * before it, bucket by bucket: the sort stays stable, so its result is the same for any
 * number of threads. */
static void nbs__radix(uint64_t *key, int32_t *idx, uint64_t *tk, int32_t *ti, int32_t n, int bits,
                       uint32_t *hist, int threads) {
  if (bits == 0) return;
  int passes = (bits + NBS__RADIX_BITS - 1) / NBS__RADIX_BITS;
  int digit = (bits + passes - 1) / passes;
  uint64_t mask = ((uint64_t)1 << digit) - 1;
  size_t buckets = (size_t)1 << digit;
  uint64_t *sk = key, *dk = tk;
  int32_t *si = idx, *di = ti;
  for (int p = 0; p < passes; p++) {
    int shift = p * digit;
#if defined(_OPENMP)
#pragma omp parallel num_threads(threads) if (threads > 1)
#endif
    {
      int t = 0;
#if defined(_OPENMP)
      t = omp_get_thread_num();
#endif
      int32_t from = nbs__chunk(n, t, threads), to = nbs__chunk(n, t + 1, threads);
      uint32_t *h = hist + (size_t)t * buckets;
      memset(h, 0, buckets * sizeof *h);
      for (int32_t k = from; k < to; k++) h[(sk[k] >> shift) & mask]++;
    }
    /* a digit shared by every key moves nothing: skip the pass */
    uint64_t d0 = (sk[0] >> shift) & mask, same = 0;
    for (int t = 0; t < threads; t++) same += hist[(size_t)t * buckets + d0];
    if (same == (uint64_t)n) continue;
    uint32_t sum = 0;
    for (size_t b = 0; b < buckets; b++) {
      for (int t = 0; t < threads; t++) {
        uint32_t c = hist[(size_t)t * buckets + b];
        hist[(size_t)t * buckets + b] = sum;
        sum += c;
      }
    }
#if defined(_OPENMP)
#pragma omp parallel num_threads(threads) if (threads > 1)
#endif
    {
      int t = 0;
#if defined(_OPENMP)
      t = omp_get_thread_num();
#endif
      int32_t from = nbs__chunk(n, t, threads), to = nbs__chunk(n, t + 1, threads);
      uint32_t *h = hist + (size_t)t * buckets;
      for (int32_t k = from; k < to; k++) {
        uint32_t at = h[(sk[k] >> shift) & mask]++;
        dk[at] = sk[k];
        di[at] = si[k];
      }
    }
    uint64_t *tswap = sk;
    sk = dk;
    dk = tswap;
    int32_t *u = si;
    si = di;
    di = u;
  }
  if (sk != key) {
    memcpy(key, sk, (size_t)n * sizeof *key);
    memcpy(idx, si, (size_t)n * sizeof *idx);
  }
}

/* Where a range of elements puts its pairs: the run's own sink (the first thread, or the
 * only one), or a thread's own list in the context, appended to the run's after the sweep
 * in thread order, so that the output does not depend on the number of threads. */
typedef struct nbs__sink {
  nbs_context *ctx;
  nbs__run *run; /* the run's sink (buf/count/cap mirror run->buf/count/cap), or NULL */
  int thread;    /* otherwise: the context's list of this thread (>= 1) */
  nbs_pair *buf;
  size_t count, cap;
  uint64_t candidates, emitted;
  nbs_status status;
} nbs__sink;

static nbs_status nbs__sink_room(nbs__sink *s, size_t need, bool *room) {
  *room = true;
  if (!s->run) {
    return nbs__thread_pairs_grow(s->ctx, s->thread, s->count + need, &s->buf, &s->cap);
  }
  nbs__run *run = s->run;
  run->count = s->count;
  nbs_status st = nbs__room(run, need, room);
  s->buf = run->buf;
  s->cap = run->cap;
  s->count = run->count;
  return st;
}

/* One pair, when a range found no room (only in the run's sink: callbacks and max_pairs
 * keep the sweep on one thread): at max_pairs, nbs__flush reports NBS_ERR_PAIRS. */
static nbs_status nbs__sink_one(nbs__sink *s, nbs_pair one) {
  bool room;
  NBS__TRY(nbs__sink_room(s, 1, &room));
  if (!room) {
    s->run->count = s->count;
    return nbs__flush(s->run);
  }
  s->buf[s->count++] = one;
  s->emitted++;
  return NBS_OK;
}

/* Tests element p against the elements [q0, q1) and writes the pairs that pass (all of them
 * in candidate mode) to out, without a branch on the test: the pair is always written and
 * the count moves on only if it passes. The caller has made room for q1 - q0 pairs.
 * The expression is the contract's, term for term as in nbs__touch, so that every
 * algorithm decides every tie the same way. */
static inline __attribute__((always_inline)) size_t
nbs__cs_kernel(const nbs__cs *c, int dim, bool radii, bool contacts, int32_t p, int32_t q0,
               int32_t q1, nbs_pair *out) {
  const double *X = c->xs, *Y = c->ys, *Z = c->zs;
  const int32_t *idx = c->idx;
  const double px = X[p], py = Y[p], pz = dim == 3 ? Z[p] : 0.0;
  const double rp = radii ? c->rs[p] : 0.0;
  const double d2 = c->d2;
  const int32_t ip = idx[p];
  size_t m = 0;
#if defined(__SSE2__)
  /* Two candidates per step with SSE2: the same IEEE operations as the scalar code, lane
   * by lane (no fused multiply-add), so every tie is decided the same way. Windows end
   * before p, so reading one element past a window's end stays inside the arrays; that
   * lane is masked off. */
  const __m128d PX = _mm_set1_pd(px), PY = _mm_set1_pd(py), PZ = _mm_set1_pd(pz);
  const __m128d RP = _mm_set1_pd(rp), LIM = _mm_set1_pd(d2);
  for (int32_t q = q0; q < q1; q += 2) {
    __m128d dx = _mm_sub_pd(PX, _mm_loadu_pd(X + q)), dy = _mm_sub_pd(PY, _mm_loadu_pd(Y + q));
    __m128d d = _mm_add_pd(_mm_mul_pd(dx, dx), _mm_mul_pd(dy, dy));
    if (dim == 3) {
      __m128d dz = _mm_sub_pd(PZ, _mm_loadu_pd(Z + q));
      d = _mm_add_pd(d, _mm_mul_pd(dz, dz));
    }
    __m128d lim = LIM;
    if (radii) {
      __m128d rr = _mm_add_pd(RP, _mm_loadu_pd(c->rs + q));
      lim = _mm_mul_pd(rr, rr);
    }
    int hit = contacts ? _mm_movemask_pd(_mm_cmple_pd(d, lim)) : 3;
    hit &= q + 1 < q1 ? 3 : 1;
    int32_t a0 = idx[q], a1 = idx[q + 1];
    nbs_pair pr;
    pr.i = ip < a0 ? ip : a0;
    pr.j = ip < a0 ? a0 : ip;
    out[m] = pr;
    m += (size_t)(hit & 1);
    pr.i = ip < a1 ? ip : a1;
    pr.j = ip < a1 ? a1 : ip;
    out[m] = pr;
    m += (size_t)(hit >> 1);
  }
#else
  for (int32_t q = q0; q < q1; q++) {
    double dx = px - X[q], dy = py - Y[q];
    double d = dx * dx + dy * dy;
    if (dim == 3) {
      double dz = pz - Z[q];
      d += dz * dz;
    }
    double lim = d2;
    if (radii) {
      double rr = rp + c->rs[q];
      lim = rr * rr;
    }
    int32_t iq = idx[q];
    nbs_pair pr;
    pr.i = ip < iq ? ip : iq;
    pr.j = ip < iq ? iq : ip;
    out[m] = pr;
    m += (size_t)(!contacts || d <= lim);
  }
#endif
  return m;
}

/* Offers p against [q0, q1) into the sink: through the kernel when there is room, else
 * pair by pair (a callback's batch smaller than the range, or max_pairs in reach). */
static inline __attribute__((always_inline)) nbs_status
nbs__cs_range(const nbs__cs *c, nbs__sink *s, int dim, bool radii, bool contacts, int32_t p,
              int32_t q0, int32_t q1) {
  size_t need = (size_t)(q1 - q0) + 1; /* the kernel may write one pair more than it keeps */
  s->candidates += (size_t)(q1 - q0);
  if (s->cap - s->count < need) {
    /* The slow path works on a copy, so that the sweep's sink, whose address never
     * escapes, can live in registers. */
    nbs__sink t = *s;
    bool room;
    nbs_status st = nbs__sink_room(&t, need, &room);
    if (st == NBS_OK && !room) {
      for (int32_t q = q0; q < q1 && st == NBS_OK; q++) {
        nbs_pair one[2]; /* the kernel may write one more than it keeps */
        if (nbs__cs_kernel(c, dim, radii, contacts, p, q, q + 1, one)) st = nbs__sink_one(&t, one[0]);
      }
      *s = t;
      return st;
    }
    *s = t;
    NBS__TRY(st);
  }
  size_t m = nbs__cs_kernel(c, dim, radii, contacts, p, q0, q1, s->buf + s->count);
  s->count += m;
  s->emitted += m;
  return NBS_OK;
}

/* Moves a window's edge q forwards while key[q] OP bound. Edges mostly move by 0 to 3
 * places, in no pattern a branch predictor learns, and each step of a plain loop waits for
 * the load before it. So four keys are compared at once, without a branch (the keys are
 * sorted: the count of those that pass is the step), and only a step of four loops. The
 * key array has NBS__CS_PAD entries of UINT64_MAX after the end, never below a bound. */
#define NBS__CS_ADVANCE(key, q, OP, bound)                                                    \
  do {                                                                                        \
    int32_t nbs__step;                                                                        \
    do {                                                                                      \
      nbs__step = ((key)[(q)] OP(bound)) + ((key)[(q) + 1] OP(bound)) +                       \
                  ((key)[(q) + 2] OP(bound)) + ((key)[(q) + 3] OP(bound));                    \
      (q) += nbs__step;                                                                       \
    } while (nbs__step == 4);                                                                 \
  } while (0)

/* The lower bound of `k` in key[0, hi). */
static int32_t nbs__cs_lower(const uint64_t *key, int32_t hi, uint64_t k) {
  int32_t lo = 0;
  while (lo < hi) {
    int32_t m = lo + (hi - lo) / 2;
    if (key[m] < k) lo = m + 1;
    else hi = m;
  }
  return lo;
}

/* Sweeps the rows that start in [from, to) of the cell order (from and to on row
 * boundaries). Each element p of a central row is checked against the elements before it
 * in its own row within one cell edge in x, and against the elements of each neighbouring
 * row of the half mask within one cell edge either side in x. On the x axis the key counts
 * sub-cells of edge / fine (8 unless the key needs the bits), so these windows hug
 * |dx| <= edge: about 9 cell volumes are searched per element instead of 13.5. Every window only
 * moves forwards, so finding them costs O(1) per element and row. */
static inline __attribute__((always_inline)) nbs_status
nbs__cs_sweep_rows(const nbs__cs *c, nbs__sink *s, int dim, bool radii, int32_t from, int32_t to) {
  const bool contacts = c->run->mode == NBS_MODE_CONTACTS;
  const uint64_t *key = c->key;
  const int bx = c->bx, by = c->by;
  const uint64_t mx = ((uint64_t)1 << bx) - 1, my = ((uint64_t)1 << by) - 1;
  const uint64_t fine = c->fine;
  const int64_t ny = c->ny;
  /* the rows of the half mask, (dy, dz): (-1, 0) in 2D; (-1, 0) (-1, -1) (0, -1) (1, -1) in 3D */
  const int rows = dim == 3 ? 4 : 1;
  static const int row_dy[4] = {-1, -1, 0, 1}, row_dz[4] = {0, -1, -1, -1};
  int32_t cur[4] = {-1, -1, -1, -1};
  int32_t a = from;
  while (a < to) {
    const uint64_t row = key[a] >> bx;
    int32_t b = a + 1;
    while (b < to && key[b] >> bx == row) b++;
    const int64_t iy = (int64_t)(row & my), iz = (int64_t)(row >> by);

    /* own row: the elements before p, from fx - fine on */
    int32_t w = a;
    for (int32_t p = a; p < b; p++) {
      const uint64_t k = key[p], fx = k & mx;
      const uint64_t lo = k - (fx < fine ? fx : fine);
      NBS__CS_ADVANCE(key, w, <, lo);
      NBS__TRY(nbs__cs_range(c, s, dim, radii, contacts, p, w, p));
    }
    /* each neighbouring row: a window of fx - fine .. fx + fine */
    for (int r = 0; r < rows; r++) {
      const int64_t y = iy + row_dy[r], z = iz + row_dz[r];
      if (y < 0 || y >= ny || z < 0) continue;
      const uint64_t trow = (uint64_t)z << by | (uint64_t)y, base = trow << bx;
      int32_t q = cur[r];
      if (q < 0) q = nbs__cs_lower(key, a, base); /* first use: search, then forwards */
      NBS__CS_ADVANCE(key, q, <, base); /* stops at a at the latest: key[a] >> bx > trow */
      cur[r] = q;
      if (key[q] >> bx != trow) continue; /* the row is empty */
      int32_t q0 = q, q1 = q;
      for (int32_t p = a; p < b; p++) {
        const uint64_t fx = key[p] & mx;
        const uint64_t lo = base + (fx > fine ? fx - fine : 0);
        const uint64_t hi = base + (mx - fx > fine ? fx + fine : mx);
        /* both stop at a at the latest: key[a] > base + mx */
        NBS__CS_ADVANCE(key, q0, <, lo);
        if (q1 < q0) q1 = q0;
        NBS__CS_ADVANCE(key, q1, <=, hi);
        if (q1 > q0) NBS__TRY(nbs__cs_range(c, s, dim, radii, contacts, p, q0, q1));
      }
    }
    a = b;
  }
  return NBS_OK;
}

/* The sweep on a local copy of the sink (kept in registers), written back at the end. */
static inline __attribute__((always_inline)) nbs_status
nbs__cs_sweep(const nbs__cs *c, nbs__sink *s, int dim, bool radii, int32_t from, int32_t to) {
  nbs__sink local = *s;
  nbs_status st = nbs__cs_sweep_rows(c, &local, dim, radii, from, to);
  *s = local;
  return st;
}

static nbs_status nbs__cs_sweep_any(const nbs__cs *c, nbs__sink *s, int32_t from, int32_t to) {
  if (c->dim == 3) {
    return c->rs ? nbs__cs_sweep(c, s, 3, true, from, to) : nbs__cs_sweep(c, s, 3, false, from, to);
  }
  return c->rs ? nbs__cs_sweep(c, s, 2, true, from, to) : nbs__cs_sweep(c, s, 2, false, from, to);
}

#if defined(_OPENMP)
/* The first position at or after p where a row starts (n at the end). */
static int32_t nbs__cs_row_start(const nbs__cs *c, int32_t p) {
  while (p > 0 && p < c->n && c->key[p] >> c->bx == c->key[p - 1] >> c->bx) p++;
  return p;
}
#endif

bool nbs__cellsort_fits(const nbs__grid *g) {
  if (!g->fits) return false;
  int bits = 0;
  for (int a = 0; a < g->dim; a++) bits += nbs__bits((uint64_t)g->n[a]);
  return bits <= 64;
}

/* Below this many elements per thread, one thread is faster. */
#define NBS__CS_MIN_PER_THREAD 20000

nbs_status nbs__cellsort(nbs__run *run) {
  nbs_context *ctx = run->ctx;
  const nbs__grid *g = &run->grid;
  const int dim = run->dim;
  const int32_t n = run->n;
  run->ran = NBS_CELLSORT;
  run->compressed = false;
  if (!g->fits) {
    return nbs__fail(ctx, NBS_ERR_EXTENT, -1,
                     "cellsort: the domain spans more than %lld cells on an axis; use 'auto'",
                     (long long)NBS__AXIS_MAX);
  }
  int64_t nx = g->n[0], ny = g->n[1], nz = dim == 3 ? g->n[2] : 1;
  int by = nbs__bits((uint64_t)ny), bz = nbs__bits((uint64_t)nz);
  int bx = nbs__bits((uint64_t)nx), fine_bits = NBS__CS_FINE_BITS;
  /* the packed cell key (iz, iy, x sub-cell) must fit 64 bits */
  if (!nbs__cellsort_fits(g)) {
    return nbs__fail(ctx, NBS_ERR_EXTENT, -1,
                     "cellsort: %lld x %lld x %lld cells need a %d-bit key; use 'auto'",
                     (long long)nx, (long long)ny, (long long)nz, bx + by + bz);
  }
  if (bx + by + bz + fine_bits > 64) fine_bits = 64 - (bx + by + bz);
  bx += fine_bits;
  run->cells[0] = nx;
  run->cells[1] = ny;
  run->cells[2] = dim == 3 ? nz : 1;

  /* layout: key[n] | idx[n, padded to 8 bytes] | xs[n * dim] | rs[n] | hist[2^11] */
  size_t nn = (size_t)n;
  size_t key_b = (nn + NBS__CS_PAD) * sizeof(uint64_t);
  size_t idx_b = (nn * sizeof(int32_t) + 7) & ~(size_t)7;
  size_t xs_b = nn * (size_t)dim * sizeof(double);
  size_t rs_b = run->r ? nn * sizeof(double) : 0;
  int threads = nbs__threads(ctx, n / NBS__CS_MIN_PER_THREAD);
  /* callbacks and max_pairs need the pairs in one stream */
  if (run->callback || ctx->max_pairs) threads = 1;
  size_t hist_b = (size_t)threads * ((size_t)1 << NBS__RADIX_BITS) * sizeof(uint32_t);
  size_t bytes = key_b + idx_b + xs_b + rs_b + hist_b;
  NBS__TRY(nbs__work_reserve(ctx, bytes));
  ctx->work_kind = NBS__WORK_CELLSORT;
  char *w = ctx->work;
  nbs__cs c;
  c.run = run;
  c.dim = dim;
  c.n = n;
  c.key = (uint64_t *)(void *)w;
  c.idx = (int32_t *)(void *)(w + key_b);
  c.xs = (double *)(void *)(w + key_b + idx_b);
  c.ys = c.xs + nn;
  c.zs = dim == 3 ? c.ys + nn : NULL;
  c.rs = run->r ? (double *)(void *)(w + key_b + idx_b + xs_b) : NULL;
  uint32_t *hist = (uint32_t *)(void *)(w + key_b + idx_b + xs_b + rs_b);
  c.d2 = run->d2;
  c.nx = nx;
  c.ny = ny;
  c.nz = nz;
  c.bx = bx;
  c.by = by;
  c.fine = (uint64_t)1 << fine_bits;
  run->work_bytes = bytes;

  /* 1. keys */
  const double *x = run->x;
  const int sy = bx, sz = bx + by;
  /* x in sub-cells: (x - lo) * (NBS__CS_FINE / edge), the same roundings as nbs__cell's
   * (the scaling by a power of two is exact), so the argument of input.c holds with
   * windows of `fine` sub-cells: |dx| <= edge(1 - margin) stays within them */
  const double inv_fine = g->inv_edge * (double)((uint64_t)1 << fine_bits);
  const double lo_x = g->lo[0];
#if defined(_OPENMP)
#pragma omp parallel for num_threads(threads) schedule(static) if (threads > 1)
#endif
  for (int32_t k = 0; k < n; k++) {
    const double *xk = x + (size_t)k * (size_t)dim;
    uint64_t ix = (uint64_t)((xk[0] - lo_x) * inv_fine), iy = (uint64_t)nbs__cell(g, xk, 1);
    uint64_t iz = dim == 3 ? (uint64_t)nbs__cell(g, xk, 2) : 0;
    c.key[k] = iz << sz | iy << sy | ix;
    c.idx[k] = k;
  }
  /* 2. sort; the scratch is the coordinate array, not yet filled (12 of its >= 16 bytes
   * per element) */
  uint64_t *tk = (uint64_t *)(void *)c.xs;
  int32_t *ti = (int32_t *)(void *)(c.xs + nn);
  nbs__radix(c.key, c.idx, tk, ti, n, bx + by + bz, hist, threads);
  for (size_t t = nn; t < nn + NBS__CS_PAD; t++) c.key[t] = UINT64_MAX;
  /* 3. gather */
#if defined(_OPENMP)
#pragma omp parallel for num_threads(threads) schedule(static) if (threads > 1)
#endif
  for (int32_t p = 0; p < n; p++) {
    const double *xk = x + (size_t)c.idx[p] * (size_t)dim;
    c.xs[p] = xk[0];
    c.ys[p] = xk[1];
    if (dim == 3) c.zs[p] = xk[2];
    if (c.rs) c.rs[p] = run->r[c.idx[p]];
  }

  /* 4. sweep: thread t takes the elements [n t / T, n (t + 1) / T) of the cell order */
  nbs__sink sinks[NBS__THREADS_MAX];
  for (int t = 0; t < threads; t++) {
    memset(&sinks[t], 0, sizeof sinks[t]);
    sinks[t].ctx = ctx;
    sinks[t].thread = t;
    if (t == 0) {
      sinks[t].run = run;
      sinks[t].buf = run->buf;
      sinks[t].count = run->count;
      sinks[t].cap = run->cap;
    } else {
      sinks[t].buf = ctx->tpairs[t];
      sinks[t].cap = ctx->tcap[t];
    }
  }
  if (threads == 1) {
    sinks[0].status = nbs__cs_sweep_any(&c, &sinks[0], 0, n);
  } else {
#if defined(_OPENMP)
#pragma omp parallel num_threads(threads)
    {
      int t = omp_get_thread_num();
      int32_t from = nbs__cs_row_start(&c, nbs__chunk(n, t, threads));
      int32_t to = nbs__cs_row_start(&c, nbs__chunk(n, t + 1, threads));
      sinks[t].status = nbs__cs_sweep_any(&c, &sinks[t], from, to);
    }
#endif
  }
  /* the run's sink first, then each thread's pairs in order */
  run->count = sinks[0].count;
  nbs_status st = sinks[0].status;
  for (int t = 0; t < threads; t++) {
    run->candidates += sinks[t].candidates;
    run->emitted += sinks[t].emitted;
    if (st == NBS_OK) st = sinks[t].status;
  }
  if (st == NBS_ERR_NOMEM && !ctx->error[0]) {
    st = nbs__fail(ctx, NBS_ERR_NOMEM, -1, "cannot grow a thread's pair list");
  }
  for (int t = 1; t < threads && st == NBS_OK; t++) {
    bool room;
    st = nbs__room(run, sinks[t].count, &room);
    if (st == NBS_OK) {
      memcpy(run->buf + run->count, sinks[t].buf, sinks[t].count * sizeof(nbs_pair));
      run->count += sinks[t].count;
    }
  }
  return st;
}
