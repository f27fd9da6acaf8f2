/*
 * Input validation and the grid (the book's integerisation, eq. 3.26).
 *
 * One pass over the elements checks every number and measures the bounding box and the
 * largest radius; the grid follows from them.
 *
 * Why the cell edge is a hair larger than the largest diameter dmax. Every algorithm relies
 * on: two elements that pass the distance test of the contract lie in the same or in
 * neighbouring cells. Both the test and the integerisation round:
 *  - the test fl(dx^2 + ...) <= fl(R^2), R = ri + rj <= dmax, implies |dx| <= R(1 + 3u)
 *    (u = 2^-53) as long as R^2 is a normal number; when R is so small that R^2 underflows,
 *    it implies only |dx| <= 2^-499 or so, hence the floor on the edge below;
 *  - the cell coordinate fl(fl(x - lo) * fl(1/e)) is off by at most about 3u|x - lo|/e,
 *    i.e. 3u * (cells on the axis) <= 3u * 2^30 < 2^-21 cells for a grid of NBS__AXIS_MAX.
 *    Two coordinates whose computed cell positions differ by less than 1 have floors that
 *    differ by at most 1.
 * With e = max(dmax, 2^-498) * (1 + 2^-18), |dx|/e + the rounding of both positions stays
 * below 1, so the guarantee holds with any rounding, at a cost of 4e-6 in cell size.
 * When dmax^2 overflows, some pair may have (ri + rj)^2 = inf and then touches everything:
 * the edge is +inf and all elements share one cell.
 */
#include "internal.h"

#include <float.h>

#define NBS__EDGE_MARGIN 0x1p-18
#define NBS__EDGE_FLOOR 0x1p-498

static const char *const nbs__axis_name[3] = {"x", "y", "z"};

/* The coordinates' pass, written so that the compiler vectorises it: the flat array of
 * count = n * dim doubles is read in groups of NBS__SCAN_GROUP (a multiple of 2 and 3, so
 * that place j of every group holds axis j % dim), with a running minimum, maximum and
 * finiteness sum per place. The sum adds v * 0, which is 0 for a finite v and NaN for an
 * infinite or NaN one, and is looked at once per block of groups: the first block where it
 * is not 0 is read again one number at a time to name the first bad element. (The plain
 * loop, with a test and a branch per number, took 2.8 ns per element of the 36 of a whole
 * detection at N = 1e6; this one about 1.) The first group is read one number at a time,
 * so that a short array whose first number is bad is never read past it (test_limits
 * passes the largest count the API accepts with a NaN first, to see it refused without
 * 48 GB of coordinates). Returns the first bad element, or -1 with lo and hi set to the
 * bounding box. */
#define NBS__SCAN_GROUP 24
#define NBS__SCAN_BLOCK 256 /* groups per look at the sum */
static int32_t nbs__scan_coords(const double *x, size_t count, int dim, double lo[3],
                                double hi[3]) {
  double glo[NBS__SCAN_GROUP], ghi[NBS__SCAN_GROUP], sum[NBS__SCAN_GROUP];
  for (int j = 0; j < NBS__SCAN_GROUP; j++) {
    glo[j] = DBL_MAX;
    ghi[j] = -DBL_MAX;
    sum[j] = 0.0;
  }
  for (size_t k = 0; k < count && k < NBS__SCAN_GROUP; k++) {
    if (!(x[k] >= -DBL_MAX && x[k] <= DBL_MAX)) return (int32_t)(k / (size_t)dim);
  }
  const size_t groups = count / NBS__SCAN_GROUP;
  size_t at = 0; /* first number not yet known to be finite */
  for (size_t g0 = 0; g0 < groups; g0 += NBS__SCAN_BLOCK) {
    const size_t g1 = groups - g0 < NBS__SCAN_BLOCK ? groups : g0 + NBS__SCAN_BLOCK;
    for (size_t g = g0; g < g1; g++) {
      const double *v = x + g * NBS__SCAN_GROUP;
      for (int j = 0; j < NBS__SCAN_GROUP; j++) {
        glo[j] = v[j] < glo[j] ? v[j] : glo[j];
        ghi[j] = v[j] > ghi[j] ? v[j] : ghi[j];
        sum[j] += v[j] * 0.0;
      }
    }
    double total = 0.0;
    for (int j = 0; j < NBS__SCAN_GROUP; j++) total += sum[j];
    if (total != 0.0) break; /* NaN: a bad number in this block, found below */
    at = g1 * NBS__SCAN_GROUP;
  }
  for (int a = 0; a < dim; a++) {
    lo[a] = DBL_MAX;
    hi[a] = -DBL_MAX;
  }
  for (int j = 0; j < NBS__SCAN_GROUP; j++) {
    const int a = j % dim;
    if (glo[j] < lo[a]) lo[a] = glo[j];
    if (ghi[j] > hi[a]) hi[a] = ghi[j];
  }
  /* the rest, and a block that held a bad number: one number at a time; the comparisons
   * are written so that a NaN fails them */
  for (size_t k = at; k < count; k++) {
    const double v = x[k];
    if (!(v >= -DBL_MAX && v <= DBL_MAX)) return (int32_t)(k / (size_t)dim);
    const int a = (int)(k % (size_t)dim);
    if (v < lo[a]) lo[a] = v;
    if (v > hi[a]) hi[a] = v;
  }
  return -1;
}

/* The radii's pass, in the same way: the largest radius, and a count of the radii that are
 * not finite numbers > 0 per block of NBS__SCAN_GROUP * NBS__SCAN_BLOCK, the first block
 * that has one read again to name it. Returns that element, or -1 with *rmax set. */
static int32_t nbs__scan_radii(const double *r, int32_t n, double *rmax) {
  const int32_t block = NBS__SCAN_GROUP * NBS__SCAN_BLOCK;
  double top = 0.0;
  for (int32_t k0 = 0; k0 < n; k0 += block) {
    const int32_t k1 = n - k0 < block ? n : k0 + block;
    int32_t bad = 0;
    double m = top;
    for (int32_t k = k0; k < k1; k++) {
      bad += !(r[k] > 0 && r[k] <= DBL_MAX);
      m = r[k] > m ? r[k] : m;
    }
    if (bad) {
      for (int32_t k = k0; k < k1; k++) {
        if (!(r[k] > 0 && r[k] <= DBL_MAX)) return k;
      }
    }
    top = m;
  }
  *rmax = top;
  return -1;
}

/* The passes share the elements among the context's threads, each a range of whole groups
 * (so that place j of each group still holds axis j % dim) of at least this many elements.
 * With cellsort's phases halved by two threads, the pass's 1 ns per element was a twentieth
 * of a detection (3D, N = 1e6, two threads: 1.00 -> 0.52 ns per element). */
#define NBS__SCAN_MIN_PER_THREAD 32768

/* nbs__scan_coords over `threads` ranges: the same bounding box (min and max do not depend
 * on the order), and the first bad element, found in the lowest range that has one. The
 * first group is read alone first, as nbs__scan_coords does, so that a bad number there is
 * found before any thread reads further. */
static int32_t nbs__scan_coords_threads(const double *x, size_t count, int dim, int threads,
                                        double lo[3], double hi[3]) {
  if (threads <= 1 || count < (size_t)NBS__SCAN_GROUP * (size_t)threads) {
    return nbs__scan_coords(x, count, dim, lo, hi);
  }
  for (size_t k = 0; k < NBS__SCAN_GROUP; k++) {
    if (!(x[k] >= -DBL_MAX && x[k] <= DBL_MAX)) return (int32_t)(k / (size_t)dim);
  }
  const size_t groups = count / NBS__SCAN_GROUP;
  double tlo[NBS__THREADS_MAX][3], thi[NBS__THREADS_MAX][3];
  int32_t tbad[NBS__THREADS_MAX];
#if defined(_OPENMP)
#pragma omp parallel num_threads(threads)
#endif
  NBS__PARTS(t, threads) {
    const size_t from = groups * (size_t)t / (size_t)threads * NBS__SCAN_GROUP;
    const size_t end = groups * (size_t)(t + 1) / (size_t)threads * NBS__SCAN_GROUP;
    const size_t to = t + 1 == threads ? count : end;
    const int32_t bad = nbs__scan_coords(x + from, to - from, dim, tlo[t], thi[t]);
    tbad[t] = bad < 0 ? -1 : (int32_t)(from / (size_t)dim) + bad;
  }
  for (int t = 0; t < threads; t++) {
    if (tbad[t] >= 0) return tbad[t];
  }
  for (int a = 0; a < dim; a++) {
    lo[a] = tlo[0][a];
    hi[a] = thi[0][a];
    for (int t = 1; t < threads; t++) {
      if (tlo[t][a] < lo[a]) lo[a] = tlo[t][a];
      if (thi[t][a] > hi[a]) hi[a] = thi[t][a];
    }
  }
  return -1;
}

/* nbs__scan_radii over `threads` ranges of whole blocks, in the same way. */
static int32_t nbs__scan_radii_threads(const double *r, int32_t n, int threads, double *rmax) {
  const int32_t block = NBS__SCAN_GROUP * NBS__SCAN_BLOCK;
  const int32_t blocks = (n + block - 1) / block;
  if (threads > blocks) threads = blocks;
  if (threads <= 1) return nbs__scan_radii(r, n, rmax);
  double tmax[NBS__THREADS_MAX];
  int32_t tbad[NBS__THREADS_MAX];
#if defined(_OPENMP)
#pragma omp parallel num_threads(threads)
#endif
  NBS__PARTS(t, threads) {
    const int32_t from = nbs__chunk(blocks, t, threads) * block;
    const int32_t to = t + 1 == threads ? n : nbs__chunk(blocks, t + 1, threads) * block;
    const int32_t bad = nbs__scan_radii(r + from, to - from, &tmax[t]);
    tbad[t] = bad < 0 ? -1 : from + bad;
  }
  double top = 0.0;
  for (int t = 0; t < threads; t++) {
    if (tbad[t] >= 0) return tbad[t];
    if (tmax[t] > top) top = tmax[t];
  }
  *rmax = top;
  return -1;
}

bool nbs__radii_max(const nbs__run *run, double *rmax) {
  const int threads = nbs__threads(run->ctx, run->n / NBS__SCAN_MIN_PER_THREAD);
  return nbs__scan_radii_threads(run->r, run->n, threads, rmax) < 0;
}

nbs_status nbs__prepare(nbs__run *run, const nbs_input *in) {
  NBS__TRY(nbs__prepare_args(run, in));
  return nbs__prepare_scan(run, in);
}

nbs_status nbs__prepare_args(nbs__run *run, const nbs_input *in) {
  nbs_context *ctx = run->ctx;
  if (in->dim != 2 && in->dim != 3) {
    return nbs__fail(ctx, NBS_ERR_DIM, -1, "dimension %d: it must be 2 or 3", in->dim);
  }
  if (in->n < 0 || in->n > INT32_MAX) {
    return nbs__fail(ctx, NBS_ERR_COUNT, -1, "%lld elements: the count must be 0 <= n < 2^31",
                     (long long)in->n);
  }
  if (in->n > 0 && !in->coords) {
    return nbs__fail(ctx, NBS_ERR_NULL, -1, "the coordinates are NULL for %lld elements",
                     (long long)in->n);
  }
  if (!in->radii && !(isfinite(in->diameter) && in->diameter > 0)) {
    return nbs__fail(ctx, NBS_ERR_RADIUS, -1,
                     "the diameter %g is not a finite number > 0 (give radii or a diameter)",
                     in->diameter);
  }

  const int dim = in->dim;
  const int32_t n = (int32_t)in->n;
  run->dim = dim;
  run->n = n;
  run->x = in->coords;
  run->r = in->radii;
  run->d2 = in->radii ? 0.0 : in->diameter * in->diameter;

  nbs__grid *g = &run->grid;
  memset(g, 0, sizeof *g);
  g->dim = dim;
  for (int a = 0; a < 3; a++) {
    g->lo[a] = 0.0;
    g->hi[a] = 0.0;
    g->n[a] = 1;
  }
  g->fits = true;
  if (n == 0) {
    g->edge = in->radii ? 1.0 : in->diameter;
    g->inv_edge = 1.0 / g->edge;
  }
  return NBS_OK;
}

nbs_status nbs__prepare_scan(nbs__run *run, const nbs_input *in) {
  nbs_context *ctx = run->ctx;
  const int dim = run->dim;
  const int32_t n = run->n;
  if (n == 0) return NBS_OK;
  /* The pass: every coordinate finite, every radius finite and > 0; box and rmax. */
  double lo[3], hi[3];
  const int threads = nbs__threads(ctx, n / NBS__SCAN_MIN_PER_THREAD);
  int32_t bad =
      nbs__scan_coords_threads(in->coords, (size_t)n * (size_t)dim, dim, threads, lo, hi);
  if (bad >= 0) {
    const double *xb = in->coords + (size_t)bad * (size_t)dim;
    int a = 0;
    while (a < dim - 1 && isfinite(xb[a])) a++;
    return nbs__fail(ctx, NBS_ERR_COORD, bad, "element %d: %s coordinate is %s", (int)bad,
                     nbs__axis_name[a], isnan(xb[a]) ? "NaN" : "infinite");
  }
  double rmax;
  if (in->radii) {
    bad = nbs__scan_radii_threads(in->radii, n, threads, &rmax);
    if (bad >= 0) {
      return nbs__fail(ctx, NBS_ERR_RADIUS, bad,
                       "element %d: radius %g is not a finite number > 0", (int)bad,
                       in->radii[bad]);
    }
  } else {
    rmax = 0.5 * in->diameter;
  }
  nbs__grid_measured(run, lo, hi, rmax);
  return NBS_OK;
}

void nbs__grid_measured(nbs__run *run, const double lo[3], const double hi[3], double rmax) {
  nbs__grid *g = &run->grid;
  const int dim = run->dim;
  g->rmax = rmax;

  /* without radii rmax is half the diameter, and twice it the diameter again exactly
   * wherever it decides the edge (above NBS__EDGE_FLOOR) */
  const double dmax = 2.0 * rmax;
  if (!(dmax * dmax <= DBL_MAX)) {
    g->edge = INFINITY;
    g->inv_edge = 0.0;
  } else {
    g->edge = (dmax > NBS__EDGE_FLOOR ? dmax : NBS__EDGE_FLOOR) * (1.0 + NBS__EDGE_MARGIN);
    g->inv_edge = 1.0 / g->edge;
  }

  for (int a = 0; a < dim; a++) {
    g->lo[a] = lo[a];
    g->hi[a] = hi[a];
    /* The same formula as nbs__cell, applied to the largest coordinate: rounding is
     * monotone, so every element's cell is <= this one. */
    double top = (hi[a] - lo[a]) * g->inv_edge;
    if (g->inv_edge == 0.0) {
      /* One cell holds everything, even an extent that overflows; with lo = 0, x - lo is
       * finite for every element and the cell formula gives 0, never inf * 0. */
      g->lo[a] = 0.0;
      g->n[a] = 1;
    } else if (top < (double)NBS__AXIS_MAX) {
      g->n[a] = (int64_t)top + 1;
    } else {
      g->n[a] = -1; /* too many cells, or an extent that overflows to infinity */
      g->fits = false;
    }
  }
}

void nbs__axis_order(int dim, const int64_t count[3], int slot, int at[3]) {
  int best = slot;
  for (int a = 0; a < dim; a++) {
    if (a != slot && (best == slot || count[a] >= count[best])) best = a;
  }
  if (best == slot || count[best] < 2 * count[slot]) best = slot;
  for (int a = 0, j = 0; a < 3; a++) {
    if (j == slot) j++; /* the slot's place is best's */
    if (a != best) at[j++] = a;
  }
  at[slot] = best;
}

nbs__grid nbs__grid_reorder(const nbs__grid *g, const int at[3]) {
  nbs__grid r = *g;
  for (int a = 0; a < g->dim; a++) {
    r.lo[a] = g->lo[at[a]];
    r.hi[a] = g->hi[at[a]];
    r.n[a] = g->n[at[a]];
  }
  return r;
}
