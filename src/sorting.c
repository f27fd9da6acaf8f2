/*
 * Sorting contact detection (book section 3.7, pp. 95-102, eqs. 3.41-3.50).
 *
 * Every element gets the integer coordinates of its cell (eq. 3.26); the arrays of cell
 * coordinates X, Y (Z) and the array D of element ids are sorted together,
 * lexicographically by cell (eq. 3.41: by z, then y, then x; in 2D by y, then x). Then the
 * elements of one cell are a run of consecutive entries, and the neighbour cells of the
 * contact mask are found by binary search. Memory: 3N integers in 2D, 4N in 3D (16 bytes
 * per element), whatever the spread of the elements (p. 99); time N log2 N (eq. 3.47).
 *
 * The sort is the book's (eqs. 3.48-3.50), not qsort: find the minimum and the maximum of
 * the key in the segment, split at their midpoint, parse the segment from both ends swapping
 * every entry that lies on the wrong side (all arrays together), and repeat on both halves.
 * It needs no memory beyond the arrays; the smaller half is recursed into and the larger one
 * looped on, so the stack stays below log2 N frames. When a segment has one value of the
 * key, it is sorted by the next key.
 *
 * Wide domains. The book's arrays do not depend on the spread, but integer cell coordinates
 * do: one escaped element can put 2^40 cells on an axis. Such an axis (grid.fits false) is
 * compressed: its cell coordinates are replaced by small integers that keep every property
 * the mask needs (see nbs__sort_compress_axis), so sorting succeeds for every finite input.
 *
 * Cell coordinates are stored as uint32: a regular axis has fewer than 2^30 cells, and a
 * compressed one fewer than 2N <= 2^32 - 2 (see below), which need not fit int32. Neighbour
 * coordinates (ix - 1, iy + 1, ...) are formed and compared in int64, so -1 and 2^32 simply
 * match nothing.
 *
 * Work-block layout (work_kind NBS__WORK_SORTING, work_cap[0] = N): int32 D[N], then uint32
 * X[N], Y[N] and, in 3D, Z[N]. Nothing needs initialising between detections.
 */
#include "internal.h"

/* The arrays sorted together. key[0] is the primary key: Z in 3D, Y in 2D. */
typedef struct nbs__sort_arrays {
  int32_t *d;
  uint32_t *key[3];
  int nkeys; /* dim */
} nbs__sort_arrays;

static inline void nbs__sort_swap(const nbs__sort_arrays *s, size_t i, size_t j) {
  int32_t t = s->d[i];
  s->d[i] = s->d[j];
  s->d[j] = t;
  for (int l = 0; l < s->nkeys; l++) {
    uint32_t u = s->key[l][i];
    s->key[l][i] = s->key[l][j];
    s->key[l][j] = u;
  }
}

/* Sorts entries [lo, hi) by keys level, level+1, ...; the keys before `level` are equal
 * within the segment. */
static void nbs__sort_cells(const nbs__sort_arrays *s, size_t lo, size_t hi, int level) {
  while (hi - lo > 1) {
    const uint32_t *k = s->key[level];
    /* Identify the minimum and the maximum (Fig. 3.29). */
    uint32_t kmin = k[lo], kmax = kmin;
    for (size_t i = lo + 1; i < hi; i++) {
      if (k[i] < kmin) kmin = k[i];
      if (k[i] > kmax) kmax = k[i];
    }
    if (kmin == kmax) {
      /* One value of this key: the segment is ordered by it; go on with the next key. */
      if (++level == s->nkeys) return;
      continue;
    }
    /* The middle point (eq. 3.49), without overflow; kmin <= mid < kmax, so neither side
     * is empty and every level at least halves the range of the key. */
    const uint32_t mid = kmin + (kmax - kmin) / 2;
    /* Parse from both ends (eq. 3.50). i stops on an entry > mid (the maximum is one), j on
     * an entry <= mid (the minimum is one), so neither runs off the segment. */
    size_t i = lo, j = hi - 1;
    for (;;) {
      while (k[i] <= mid) i++;
      while (k[j] > mid) j--;
      if (i > j) break;
      nbs__sort_swap(s, i, j);
    }
    /* Now [lo, i) <= mid < [i, hi). */
    if (i - lo < hi - i) {
      nbs__sort_cells(s, lo, i, level);
      lo = i;
    } else {
      nbs__sort_cells(s, i, hi, level);
      hi = i;
    }
  }
}

/* ---- axis compression ------------------------------------------------------------------
 *
 * An order-preserving 64-bit key of a double: for finite values, a < b implies
 * key(a) < key(b) (-0 and +0 get different keys, which only orders them).
 */
static inline uint64_t nbs__sort_order_key(double v) {
  uint64_t b;
  memcpy(&b, &v, sizeof b);
  return b ^ ((b >> 63) ? ~(uint64_t)0 : (uint64_t)1 << 63);
}

static inline uint64_t nbs__sort_coord_key(const nbs__run *run, int32_t e, int axis) {
  return nbs__sort_order_key(run->x[(size_t)e * (size_t)run->dim + (size_t)axis]);
}

/* Sorts the element ids d[0, count) by their coordinate on `axis`, with the same midpoint
 * sort on the 64-bit keys (read through d, no key array): each level halves the range of
 * the keys, so there are at most 64 levels, and the stack stays below log2 N frames. */
static void nbs__sort_by_coord(const nbs__run *run, int32_t *d, size_t count, int axis) {
  while (count > 1) {
    uint64_t kmin = nbs__sort_coord_key(run, d[0], axis), kmax = kmin;
    for (size_t i = 1; i < count; i++) {
      uint64_t k = nbs__sort_coord_key(run, d[i], axis);
      if (k < kmin) kmin = k;
      if (k > kmax) kmax = k;
    }
    if (kmin == kmax) return;
    const uint64_t mid = kmin + (kmax - kmin) / 2;
    size_t i = 0, j = count - 1;
    for (;;) {
      while (nbs__sort_coord_key(run, d[i], axis) <= mid) i++;
      while (nbs__sort_coord_key(run, d[j], axis) > mid) j--;
      if (i > j) break;
      int32_t t = d[i];
      d[i] = d[j];
      d[j] = t;
    }
    if (i < count - i) {
      nbs__sort_by_coord(run, d, i, axis);
      d += i;
      count -= i;
    } else {
      nbs__sort_by_coord(run, d + i, count - i, axis);
      count = i;
    }
  }
}

/* Replaces the cell coordinates of one axis by compressed ones, cell[e] for element e, and
 * returns the number of distinct compressed cells. d (N entries) is scratch.
 *
 * Walk the elements in increasing coordinate v. The first opens cell 0 with start s = v.
 * Each next one joins the current cell if fl(v - s) < edge; otherwise it opens a new cell
 * with start v, whose index is the previous one plus 1 if fl(v - s) < 2 edge, plus 2 (a gap:
 * no candidates across it) otherwise.
 *
 * Claim: elements p, q in compressed cells cp + 2 <= cq cannot pass the distance test, so
 * the mask (cells differing by at most 1 on each axis) still yields every contact.
 * Rounding is monotone and edge, 2 edge are doubles, so fl(x) < e implies x < e, and
 * fl(x) >= e implies x > e (1 - 2^-53) (or x is huge when fl(x) overflows to +inf).
 * Let cell cq open at s_q, and let the cell opened just before it start at s'. Every element
 * of a cell below that previous one comes before s' in sorted order, so v <= s'; every
 * element of the previous cell has fl(v - s') < edge, so v < s' + edge.
 *  - If cq jumped by 2 from the previous cell (index cq - 2 >= cp), p lies at or below that
 *    cell: v_p < s' + edge, and s_q - s' > 2 edge (1 - 2^-53), so v_q - v_p >= s_q - v_p >
 *    edge (1 - 2^-52).
 *  - If cq = (previous index) + 1, p lies at or below the cell before the previous one,
 *    starting at s'' with v_p < s'' + edge, and s_q > s' + edge(1 - 2^-53) > s'' +
 *    2 edge (1 - 2^-53): the same bound.
 * edge exceeds the largest diameter by the factor 1 + 2^-18 (nbs__prepare), far more than
 * the rounding of the distance test, so |dx| > edge (1 - 2^-52) fails it. (A finite edge
 * keeps dmax^2 finite, so 2 edge is finite too.)
 *
 * Indices grow by at most 2 per element, so they stay below 2N - 1 <= 2^32 - 3. When edge is
 * +inf every pair may touch and every element is in cell 0. */
static int64_t nbs__sort_compress_axis(const nbs__run *run, int32_t *d, uint32_t *cell,
                                       int axis) {
  const int32_t n = run->n;
  const int dim = run->dim;
  const double edge = run->grid.edge;
  if (isinf(edge)) {
    for (int32_t e = 0; e < n; e++) cell[e] = 0;
    return 1;
  }
  for (int32_t e = 0; e < n; e++) d[e] = e;
  nbs__sort_by_coord(run, d, (size_t)n, axis);

  const double two_edge = 2.0 * edge;
  uint32_t index = 0;
  int64_t distinct = 1;
  double start = run->x[(size_t)d[0] * (size_t)dim + (size_t)axis];
  cell[d[0]] = 0;
  for (int32_t k = 1; k < n; k++) {
    const double v = run->x[(size_t)d[k] * (size_t)dim + (size_t)axis];
    const double gap = v - start;
    if (!(gap < edge)) {
      index += gap < two_edge ? 1u : 2u;
      start = v;
      distinct++;
    }
    cell[d[k]] = index;
  }
  return distinct;
}

/* ---- the search ------------------------------------------------------------------------ */

/* The cell of entry i as int64 coordinates (x, y, z); z = 0 in 2D. */
typedef struct nbs__sort_cell {
  int64_t x, y, z;
} nbs__sort_cell;

typedef struct nbs__sort_view {
  const int32_t *d;
  const uint32_t *x, *y, *z; /* z NULL in 2D */
} nbs__sort_view;

static inline nbs__sort_cell nbs__sort_cell_at(const nbs__sort_view *v, size_t i) {
  nbs__sort_cell c = {v->x[i], v->y[i], v->z ? v->z[i] : 0};
  return c;
}

static inline bool nbs__sort_same_cell(const nbs__sort_view *v, size_t i, size_t j) {
  return v->x[i] == v->x[j] && v->y[i] == v->y[j] && (!v->z || v->z[i] == v->z[j]);
}

/* Lexicographic comparison of entry i with a cell: negative, zero or positive. */
static inline int nbs__sort_compare(const nbs__sort_view *v, size_t i, nbs__sort_cell c) {
  if (v->z && (int64_t)v->z[i] != c.z) return (int64_t)v->z[i] < c.z ? -1 : 1;
  if ((int64_t)v->y[i] != c.y) return (int64_t)v->y[i] < c.y ? -1 : 1;
  if ((int64_t)v->x[i] != c.x) return (int64_t)v->x[i] < c.x ? -1 : 1;
  return 0;
}

/* The first entry of [lo, hi) not lexicographically below cell c (hi if none). */
static size_t nbs__sort_lower_bound(const nbs__sort_view *v, size_t lo, size_t hi,
                                    nbs__sort_cell c) {
  while (lo < hi) {
    size_t m = lo + (hi - lo) / 2;
    if (nbs__sort_compare(v, m, c) < 0) {
      lo = m + 1;
    } else {
      hi = m;
    }
  }
  return lo;
}

/* Offers every pair of an entry of [a0, a1) with an entry of [b0, b1). */
static nbs_status nbs__sort_offer_ranges(nbs__run *run, const int32_t *d, size_t a0, size_t a1,
                                         size_t b0, size_t b1) {
  for (size_t a = a0; a < a1; a++) {
    for (size_t b = b0; b < b1; b++) NBS__TRY(nbs__offer(run, d[a], d[b]));
  }
  return NBS_OK;
}

/* Walks the sorted arrays cell by cell and offers the pairs of the mask. */
static nbs_status nbs__sort_search(nbs__run *run, const nbs__sort_view *v) {
  const size_t n = (size_t)run->n;
  const int32_t *d = v->d;
  /* Neighbour rows of the half mask, as (dy, dz), in increasing lexicographic order; each
   * covers cells ix-1 .. ix+1 of its row. 2D: row iy-1. 3D: rows iy-1, iy, iy+1 of layer
   * iz-1 and row iy-1 of layer iz. With (ix-1, iy, iz) these are the book's 4 and 13 cells. */
  static const int rows2[1][2] = {{-1, 0}};
  static const int rows3[4][2] = {{-1, -1}, {0, -1}, {1, -1}, {-1, 0}};
  const int(*rows)[2] = v->z ? rows3 : rows2;
  const int nrows = v->z ? 4 : 1;

  size_t prev = 0; /* start of the previous cell's run */
  for (size_t s = 0; s < n;) {
    size_t e = s + 1;
    while (e < n && nbs__sort_same_cell(v, e, s)) e++;
    const nbs__sort_cell c = nbs__sort_cell_at(v, s);

    /* The cell itself: every pair once. */
    for (size_t a = s; a < e; a++) {
      for (size_t b = a + 1; b < e; b++) NBS__TRY(nbs__offer(run, d[a], d[b]));
    }

    /* (ix-1, iy, iz) is the cell just before this one in sorted order, if it exists. */
    if (s > 0) {
      nbs__sort_cell left = c;
      left.x -= 1;
      if (nbs__sort_compare(v, prev, left) == 0) {
        NBS__TRY(nbs__sort_offer_ranges(run, d, s, e, prev, s));
      }
    }

    /* The neighbouring rows. Cells (iz', iy', ix-1), (iz', iy', ix), (iz', iy', ix+1) are
     * consecutive in lexicographic order, so one binary search per row (for ix-1) finds
     * all three: they are the entries from there on whose cell is at most (iz', iy', ix+1).
     * The rows come in increasing order and all lie before this cell, so each search runs
     * on [end of the previous row's range, s). */
    size_t from = 0;
    for (int r = 0; r < nrows; r++) {
      nbs__sort_cell lo = {c.x - 1, c.y + rows[r][0], c.z + rows[r][1]};
      nbs__sort_cell hi = {c.x + 1, lo.y, lo.z};
      size_t b0 = nbs__sort_lower_bound(v, from, s, lo);
      size_t b1 = b0;
      while (b1 < s && nbs__sort_compare(v, b1, hi) <= 0) b1++;
      if (b1 > b0) NBS__TRY(nbs__sort_offer_ranges(run, d, s, e, b0, b1));
      from = b1;
    }

    prev = s;
    s = e;
  }
  return NBS_OK;
}

nbs_status nbs__sorting(nbs__run *run) {
  nbs_context *ctx = run->ctx;
  const nbs__grid *g = &run->grid;
  const int dim = run->dim;
  const int32_t n = run->n;

  run->ran = NBS_SORTING;
  run->compressed = false;
  run->work_bytes = 0;
  for (int a = 0; a < 3; a++) run->cells[a] = g->n[a];
  if (n < 2) return NBS_OK;

  /* D, X, Y (, Z): (dim + 1) N int32, at most 4 * (2^31 - 1) * 4 bytes. */
  const size_t count = (size_t)n;
  if (count > SIZE_MAX / sizeof(int32_t) / (size_t)(dim + 1)) {
    return nbs__fail(ctx, NBS_ERR_NOMEM, -1, "sorting's arrays cannot be addressed");
  }
  const size_t bytes = count * (size_t)(dim + 1) * sizeof(int32_t);
  NBS__TRY(nbs__work_reserve(ctx, bytes));
  /* The block may have held another layout (screening's heads): it is ours now. */
  ctx->work_kind = NBS__WORK_SORTING;
  ctx->work_cap[0] = n;
  ctx->work_cap[1] = ctx->work_cap[2] = ctx->work_cap[3] = 0;
  run->work_bytes = bytes;

  int32_t *D = ctx->work;
  uint32_t *cell[3] = {NULL, NULL, NULL}; /* by axis: X, Y, Z */
  for (int a = 0; a < dim; a++) cell[a] = (uint32_t *)(D + count * (size_t)(a + 1));

  /* Integerise (eq. 3.26); an axis with too many cells is compressed instead. */
  for (int a = 0; a < dim; a++) {
    if (g->n[a] >= 1 && g->n[a] <= NBS__AXIS_MAX) {
      for (int32_t e = 0; e < n; e++) {
        cell[a][e] = (uint32_t)nbs__cell(g, run->x + (size_t)e * (size_t)dim, a);
      }
    } else {
      run->cells[a] = nbs__sort_compress_axis(run, D, cell[a], a);
      run->compressed = true;
    }
  }
  for (int32_t e = 0; e < n; e++) D[e] = e;

  /* Sort lexicographically: z, then y, then x (eq. 3.41). */
  nbs__sort_arrays arrays;
  arrays.d = D;
  arrays.nkeys = dim;
  for (int l = 0; l < dim; l++) arrays.key[l] = cell[dim - 1 - l];
  nbs__sort_cells(&arrays, 0, count, 0);

  nbs__sort_view view = {D, cell[0], cell[1], dim == 3 ? cell[2] : NULL};
  nbs__search_begins(run);
  return nbs__sort_search(run, &view);
}
