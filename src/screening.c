/*
 * Screening, or direct mapping (book section 3.5, pp. 88-93, eqs. 3.26 and 3.32-3.37).
 *
 * Space is cut into cells of edge d >= the largest bounding diameter, so that two elements
 * can touch only if their cells are the same or neighbours (Figs. 3.16-3.17). Every cell has
 * a singly connected list of the elements mapped onto it: a head array C (one int per cell)
 * and a next array E (one int per element). Each detection
 *   step 1  pushes every element on the list of its cell (eqs. 3.34-3.35),
 *   step 2  checks every non-empty cell against itself and the cells of the contact mask,
 *           marking each cell the first time it is met so that it is checked once,
 *   removal resets the heads the elements touched (eqs. 3.36-3.37), never the whole array,
 * so the time is proportional to N, and the memory to the number of cells: nx*ny in 2D,
 * nx*ny*nz in 3D, "most often prohibitive" (p. 117) for a large or sparse domain. The head
 * array is therefore checked against the context's cell budget before anything is allocated.
 *
 * The padded grid. Cell coordinates ix, iy, iz run from 0 to n-1 on each axis (nbs__cell).
 * The mask reads (ix-1 .. ix+1) and (iy-1) in 2D, (ix-1 .. ix+1), (iy-1 .. iy+1) and (iz-1)
 * in 3D, so the head array is padded with cells that stay empty forever:
 *   2D: px = nx + 2, py = ny + 1                  (one empty column each side, one row below)
 *   3D: px = nx + 2, py = ny + 2, pz = nz + 1     (and one empty layer below)
 * and cell (ix, iy, iz) has the index c = ((iz + 1) * py + (iy + 1)) * px + (ix + 1) (iz
 * taken as -1 in 2D, so that c = (iy + 1) * px + ix + 1). Each neighbour of the mask is then
 * c plus a constant offset, and every such index lies inside the array.
 *
 * Work-block layout (work_kind NBS__WORK_SCREENING):
 *   C[work_cap[0]]  int32 heads; every head is NBS__EMPTY between detections,
 *   E[work_cap[1]]  int32 nexts; meaningless between detections.
 * A detection uses the first px*py*pz heads, in the shape of its own grid. Because all heads
 * are empty between detections, only the capacity must match, not the shape of the last
 * grid, and Step 0 (filling the heads) runs only when the layout is new or grows.
 *
 * Memory: 4 * (px*py*pz + N) bytes, plus up to 1/8 slack on the cells after a growth.
 */
#include "internal.h"

/* The padded grid of one detection. */
typedef struct nbs__screen_grid {
  int64_t px, pxy; /* padded cells in a row, in a layer */
  int64_t off[13]; /* index offsets of the half mask */
  int nmask;       /* 4 in 2D, 13 in 3D */
} nbs__screen_grid;

/* The book's integerisation (eq. 3.26, 0-based, shifted by the padding). */
static inline int64_t nbs__screen_index(const nbs__run *run, const nbs__screen_grid *sg,
                                        int32_t k) {
  const double *p = run->x + (size_t)k * (size_t)run->dim;
  int64_t c = (int64_t)nbs__cell(&run->grid, p, 0) + 1;
  c += ((int64_t)nbs__cell(&run->grid, p, 1) + 1) * sg->px;
  if (run->dim == 3) c += ((int64_t)nbs__cell(&run->grid, p, 2) + 1) * sg->pxy;
  return c;
}

/* Offers every pair (a, b), a on the list starting at ha, b on the list starting at hb. */
static nbs_status nbs__screen_lists(nbs__run *run, const int32_t *E, int32_t ha, int32_t hb) {
  for (int32_t a = ha; a != NBS__EMPTY; a = E[a]) {
    for (int32_t b = hb; b != NBS__EMPTY; b = E[b]) NBS__TRY(nbs__offer(run, a, b));
  }
  return NBS_OK;
}

/* Offers every unordered pair of the list starting at h once. */
static nbs_status nbs__screen_self(nbs__run *run, const int32_t *E, int32_t h) {
  for (int32_t a = h; a != NBS__EMPTY; a = E[a]) {
    for (int32_t b = E[a]; b != NBS__EMPTY; b = E[b]) NBS__TRY(nbs__offer(run, a, b));
  }
  return NBS_OK;
}

/* Steps 1 and 2 on a clean layout; returns with the lists still in place. */
static nbs_status nbs__screen_detect(nbs__run *run, const nbs__screen_grid *sg, int32_t *C,
                                     int32_t *E) {
  const int32_t n = run->n;

  /* Step 1: place each element on the singly connected list of its cell (eq. 3.35). */
  for (int32_t k = 0; k < n; k++) {
    int64_t c = nbs__screen_index(run, sg, k);
    E[k] = C[c];
    C[c] = k;
  }
  nbs__search_begins(run);

  /* Step 2: the first element met in a cell makes it the central cell: mark the cell (the
   * book adds N to its head; we store -2 - head, see nbs__mark) and check it against itself
   * and the half mask. The half mask holds one cell of every pair of neighbouring cells, so
   * each pair of cells is checked once:
   *   2D: (i-1,j-1) (i,j-1) (i+1,j-1) (i-1,j)
   *   3D: the 9 cells of layer iz-1, the 3 cells of row iy-1 in layer iz, and (ix-1,iy,iz).
   * A neighbour may have been central already, hence marked: read it through nbs__unmark. */
  for (int32_t k = 0; k < n; k++) {
    int64_t c = nbs__screen_index(run, sg, k);
    int32_t h = C[c];
    if (nbs__is_marked(h)) continue;
    C[c] = nbs__mark(h);
    NBS__TRY(nbs__screen_self(run, E, h));
    for (int m = 0; m < sg->nmask; m++) {
      int32_t hb = nbs__unmark(C[c + sg->off[m]]);
      if (hb != NBS__EMPTY) NBS__TRY(nbs__screen_lists(run, E, h, hb));
    }
  }
  return NBS_OK;
}

/* Records why the cell array cannot be made. */
static nbs_status nbs__screen_refuse_extent(nbs__run *run) {
  const nbs__grid *g = &run->grid;
  static const char axis[3] = {'x', 'y', 'z'};
  for (int a = 0; a < run->dim; a++) {
    if (g->n[a] < 1 || g->n[a] > NBS__AXIS_MAX) {
      return nbs__fail(run->ctx, NBS_ERR_EXTENT, -1,
                       "screening cannot index the domain: the %c axis spans %g with cells of "
                       "%g, more than 2^30 cells; use 'sorting' or 'auto'",
                       axis[a], g->hi[a] - g->lo[a], g->edge);
    }
  }
  return nbs__fail(run->ctx, NBS_ERR_EXTENT, -1, "screening cannot index the domain");
}

nbs_status nbs__screening(nbs__run *run) {
  nbs_context *ctx = run->ctx;
  const nbs__grid *g = &run->grid;
  const int dim = run->dim;
  const int32_t n = run->n;

  run->ran = NBS_SCREENING;
  run->compressed = false;
  run->work_bytes = 0;
  for (int a = 0; a < 3; a++) run->cells[a] = g->n[a];

  if (!g->fits) return nbs__screen_refuse_extent(run);

  /* The padded head array, counted without overflow: each axis is at most 2^30 + 2, so a
   * product of two fits 64 bits, but the product of three may not. */
  const uint64_t px = (uint64_t)g->n[0] + 2;
  const uint64_t py = (uint64_t)g->n[1] + (dim == 3 ? 2 : 1);
  const uint64_t pz = dim == 3 ? (uint64_t)g->n[2] + 1 : 1;
  const uint64_t pxy = px * py;
  const bool overflow = pxy > UINT64_MAX / pz;
  const uint64_t cells = overflow ? UINT64_MAX : pxy * pz;
  const size_t max_cells = ctx->cell_budget / sizeof(int32_t);
  if (overflow || cells > (uint64_t)max_cells) {
    if (overflow || cells > SIZE_MAX / sizeof(int32_t)) {
      return nbs__fail(ctx, NBS_ERR_BUDGET, -1,
                       "screening needs more than %zu bytes of cell heads (nx x ny x nz = "
                       "%llu x %llu x %llu padded cells), over the budget of %zu bytes",
                       (size_t)SIZE_MAX, (unsigned long long)px, (unsigned long long)py,
                       (unsigned long long)pz, ctx->cell_budget);
    }
    return nbs__fail(ctx, NBS_ERR_BUDGET, -1,
                     "screening needs %zu bytes of cell heads (nx x ny x nz = %llu x %llu x "
                     "%llu padded cells), over the budget of %zu bytes",
                     (size_t)cells * sizeof(int32_t), (unsigned long long)px,
                     (unsigned long long)py, (unsigned long long)pz, ctx->cell_budget);
  }
  const size_t need_cells = (size_t)cells;
  const size_t need_n = (size_t)n;

  /* Step 0 (eqs. 3.32-3.33), only when the layout is new: all heads empty. E needs no
   * initialisation: step 1 writes E[k] for every element before anything reads it. */
  if (ctx->work_kind != NBS__WORK_SCREENING || need_cells > (uint64_t)ctx->work_cap[0] ||
      need_n > (uint64_t)ctx->work_cap[1]) {
    size_t cap_cells = need_cells, cap_n = need_n;
    if (ctx->work_kind == NBS__WORK_SCREENING) {
      /* Growth: keep what we had, and give the cells 1/8 slack (within the budget) so that
       * a slowly expanding domain does not refill the heads every step. */
      size_t slack = need_cells / 8;
      cap_cells = need_cells + (slack < max_cells - need_cells ? slack : max_cells - need_cells);
      if ((uint64_t)ctx->work_cap[0] > cap_cells) cap_cells = (size_t)ctx->work_cap[0];
      if ((uint64_t)ctx->work_cap[1] > cap_n) cap_n = (size_t)ctx->work_cap[1];
    }
    if (cap_n > SIZE_MAX / sizeof(int32_t) - cap_cells) {
      return nbs__fail(ctx, NBS_ERR_NOMEM, -1, "screening's arrays cannot be addressed");
    }
    /* On failure the old block, and the old layout with its empty heads, are kept. */
    NBS__TRY(nbs__work_reserve(ctx, (cap_cells + cap_n) * sizeof(int32_t)));
    int32_t *C = ctx->work;
    for (size_t c = 0; c < cap_cells; c++) C[c] = NBS__EMPTY;
    ctx->work_kind = NBS__WORK_SCREENING;
    ctx->work_cap[0] = (int64_t)cap_cells;
    ctx->work_cap[1] = (int64_t)cap_n;
    ctx->work_cap[2] = ctx->work_cap[3] = 0;
  }
  int32_t *C = ctx->work;
  int32_t *E = C + ctx->work_cap[0];
  run->work_bytes = (need_cells + need_n) * sizeof(int32_t);

  nbs__screen_grid sg;
  sg.px = (int64_t)px;
  sg.pxy = (int64_t)pxy;
  if (dim == 2) {
    const int64_t m[4] = {-sg.px - 1, -sg.px, -sg.px + 1, -1};
    sg.nmask = 4;
    for (int i = 0; i < 4; i++) sg.off[i] = m[i];
  } else {
    sg.nmask = 0;
    for (int dy = -1; dy <= 1; dy++) {
      for (int dx = -1; dx <= 1; dx++) sg.off[sg.nmask++] = -sg.pxy + dy * sg.px + dx;
    }
    sg.off[sg.nmask++] = -sg.px - 1;
    sg.off[sg.nmask++] = -sg.px;
    sg.off[sg.nmask++] = -sg.px + 1;
    sg.off[sg.nmask++] = -1;
  }

  nbs_status s = nbs__screen_detect(run, &sg, C, E);
  if (s != NBS_OK) {
    /* Stopped with lists in place (callback stop, pair limit, no memory for pairs): the
     * heads are dirty, so the next detection must run Step 0 again. */
    ctx->work_kind = NBS__WORK_NONE;
    return s;
  }

  /* Removal (eqs. 3.36-3.37): reset only the heads of the cells the elements occupy. */
  for (int32_t k = 0; k < n; k++) C[nbs__screen_index(run, &sg, k)] = NBS__EMPTY;
  return NBS_OK;
}

bool nbs__screening_heads_empty(const nbs_context *ctx) {
  if (ctx->work_kind != NBS__WORK_SCREENING) return true;
  const int32_t *C = ctx->work;
  for (int64_t c = 0; c < ctx->work_cap[0]; c++) {
    if (C[c] != NBS__EMPTY) return false;
  }
  return true;
}
