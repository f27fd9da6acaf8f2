/*
 * Munjiza-NBS contact detection ("No Binary Search"; book section 3.8 for 2D, section 3.10
 * for 3D and its generalisation, pp. 103-128).
 *
 * Elements are mapped onto cells of edge d >= the largest diameter (the book's
 * integerisation, eq. 3.26; grid.edge here), so that only elements in the same or in
 * neighbouring cells can touch. Instead of an array of cells (screening, whose memory grows
 * with the number of cells) NBS keeps one level of singly connected lists per axis, built and
 * torn down per detection:
 *
 *   2D:  y-lists B[ny] + Y[N]            one list per row of cells
 *        x-lists A[2][nx] + X[N]         one list per cell of the central row (set 0) and of
 *                                        the row below it (set 1)
 *   3D:  z-lists C[nz] + Z[N]            one list per layer
 *        y-lists B[2][ny] + Y[N]         rows of the central layer (set 0), of the layer
 *                                        below it (set 1)
 *        x-lists A[2][nx] + X[N]         cells of the central row (set 0), of its neighbour
 *                                        rows (set 1, eqs. 3.78-3.79)
 *
 * A list is found non-empty by looping over the elements of the list one level up, never by
 * looping over cells, and each list is removed by resetting only the heads the elements that
 * built it touched. Time is therefore proportional to N whatever the packing density and the
 * extent of the domain (eqs. 3.63-3.64), and memory is ny + 2nx + 2N integers in 2D
 * (eq. 3.65), 3N + nz + 2ny + 2nx in 3D (eq. 3.80), plus the records described below (2nx in
 * 2D, 2nx + 2ny in 3D).
 *
 * Deviations from the book's text, all of them representation only:
 *  - 0-based element indices, and the end of a list is NBS__EMPTY (-1);
 *  - each head array is padded by one cell on each side, so that a cell coordinate i is
 *    stored at index i + 1 and i - 1, i + 1 are always valid indices;
 *  - a list is marked "old" by storing -2 - head (nbs__mark) instead of adding 2N, which
 *    would overflow int32 for large N; a marked head read as a neighbour goes through
 *    nbs__unmark. Lists of set 1 are never marked;
 *  - records of started heads (RB0, RB1 of at most ny entries, RA0, RA1 of at most nx): a
 *    push that starts a list (its head was empty) also notes the head's index. The removal
 *    of a set of lists (3D steps 9, 10, 11; the 2D removal of x-lists) resets the heads its
 *    record names instead of walking the lists a second time to recompute them (the same
 *    heads: exactly those the elements touched). In 3D, step 5's loop over the central
 *    layer, which finds each row "new" at its first element in layer order, runs over RB0:
 *    step 3 walks the same layer in the same order and notes each row at the same first
 *    element, so the central rows come in the book's order without a second walk of the
 *    layer (the rows are still found by the loop over the elements of the layer, step 3's);
 *  - walks of independent lists go side by side (2D: the central row and the row below it;
 *    3D: steps 3 and 4, and steps 6 and the first row of step 7), and in 3D the five rows of
 *    a central row's steps 6-10 are first walked once side by side, prefetching the
 *    elements' coordinates. In random element order every step of a list is a cache miss;
 *    walked side by side the misses overlap. Each list still receives its elements in the
 *    book's order, so the pairs come out in the same order as from the plain rendering.
 *
 * Measured on the 2-core AMD EPYC of bench/README.md, N = 1e6, fraction 0.5, random order,
 * one thread, before and after these last two deviations, back to back (minimum of 15):
 * 3D 548 -> 297 ns per element (side by side: 548 -> 395, then step 11 side by side 433 ->
 * 326, then the records 382 -> 297), 2D 229 -> 115 ns. What did not help, tried and left out:
 * caching each element's cell coordinates next to its links (an array of {Y, X, ix, iy}
 * structs, or one of {Z, Y, X, iy}: 3D 10-30% slower, 2D up to 60% slower; the coordinates
 * must be read for the contact test anyway, and reading them during the list walks is what
 * brings them into the cache), and walking the next central layer ahead during steps 3-4 to
 * prefetch it (2%, within the noise).
 *
 * The work block (ctx->work, work_kind NBS__WORK_NBS) holds, as int32:
 *   [ C: nz+2 ] [ B0: ny+2 ] [ B1: ny+2 ] [ A0: nx+2 ] [ A1: nx+2 ]
 *   [ RB0: ny+1 ] [ RB1: ny+1 ] [ RA0: nx+1 ] [ RA1: nx+1 ] [ Z: N ] [ Y: N ] [ X: N ]
 * in 3D, and in 2D
 *   [ B: ny+2 ] [ A0: nx+2 ] [ A1: nx+2 ] [ RA0: nx+1 ] [ RA1: nx+1 ] [ Y: N ] [ X: N ]
 * that is 4 (3N + nz + 4ny + 4nx + 14) bytes in 3D and 4 (2N + ny + 4nx + 8) in 2D: eqs. 3.80
 * and 3.65, the records, and the padding (a record has one spare entry, written and not
 * counted by a push that starts no list). nx, ny, nz, N here are the capacities
 * ctx->work_cap[0], [1], [2], [3]: exactly the grid and N of the first detection, grown later
 * only when a detection needs more (axes then get 1/8 slack, within the cell budget).
 * work_cap[2] is 0 for the 2D layout (a 3D grid always has nz >= 1), which is how the
 * dimension is encoded.
 * All heads are contiguous at the start, and between detections every head is NBS__EMPTY
 * (the book's step 0, done once when the layout is created); the next arrays and the
 * records need no initialisation because an entry is always written before it is read. A detection
 * that stops early (pair buffer failure, callback stop) leaves heads dirty, so it resets
 * work_kind to NBS__WORK_NONE and the next detection initialises the layout again.
 */
#include "internal.h"

/* ---- the work-block layout ----------------------------------------------------------- */

typedef struct nbs__nbs_layout {
  size_t bytes;       /* heads and next arrays */
  int32_t *C;         /* z-list heads (3D only) */
  int32_t *B0;        /* y-list heads; in 2D the only set */
  int32_t *B1;        /* y-list heads of the layer below the central one (3D only) */
  int32_t *A0;        /* x-list heads of the central row */
  int32_t *A1;        /* x-list heads of the neighbouring rows */
  int32_t *Z, *Y, *X; /* next arrays (Z in 3D only) */
  /* The heads each set's lists were started at, in the order they were started: at most
   * ny (RB0, RB1; 3D only) and nx (RA0, RA1) entries. */
  int32_t *RB0, *RB1, *RA0, *RA1;
} nbs__nbs_layout;

/* Number of heads for capacities cap[] = {nx, ny, nz (0 in 2D), N}, padding included. */
static int64_t nbs__nbs_head_count(int dim, const int64_t cap[4]) {
  int64_t h = 2 * (cap[0] + 2); /* A[2][nx] */
  if (dim == 3) {
    h += 2 * (cap[1] + 2); /* B[2][ny] */
    h += cap[2] + 2;       /* C[nz] */
  } else {
    h += cap[1] + 2; /* B[ny] */
  }
  return h;
}

/* Number of entries of the started-heads records: 2 (nx + 1), and 2 (ny + 1) in 3D (each
 * record has room for one entry more than the heads it can name, written and not counted by
 * a push that starts no list). */
static int64_t nbs__nbs_record_count(int dim, const int64_t cap[4]) {
  return 2 * (cap[0] + 1) + (dim == 3 ? 2 * (cap[1] + 1) : 0);
}

/* Bytes of the arrays that follow the cells per axis, heads and records: what the cell
 * budget bounds. */
static uint64_t nbs__nbs_axis_bytes(int dim, const int64_t cap[4]) {
  return (uint64_t)(nbs__nbs_head_count(dim, cap) + nbs__nbs_record_count(dim, cap)) *
         sizeof(int32_t);
}

/* Bytes of the whole layout: heads, records of started heads and (dim) next arrays of N
 * int32 each (eqs. 3.65, 3.80, plus 2nx (2D) or 2nx + 2ny (3D) for the records). */
static uint64_t nbs__nbs_layout_bytes(int dim, const int64_t cap[4]) {
  uint64_t ints = (uint64_t)nbs__nbs_head_count(dim, cap) +
                  (uint64_t)nbs__nbs_record_count(dim, cap) + (uint64_t)dim * (uint64_t)cap[3];
  return ints * sizeof(int32_t);
}

/* Points the arrays of *L into `work`, laid out for dimension dim and capacities cap[]. */
static void nbs__nbs_layout_at(nbs__nbs_layout *L, void *work, int dim, const int64_t cap[4]) {
  int32_t *w = work;
  L->bytes = (size_t)nbs__nbs_layout_bytes(dim, cap);
  if (dim == 3) {
    L->C = w;
    w += cap[2] + 2;
    L->B0 = w;
    w += cap[1] + 2;
    L->B1 = w;
    w += cap[1] + 2;
  } else {
    L->C = NULL;
    L->B0 = w;
    w += cap[1] + 2;
    L->B1 = NULL;
  }
  L->A0 = w;
  w += cap[0] + 2;
  L->A1 = w;
  w += cap[0] + 2;
  if (dim == 3) {
    L->RB0 = w;
    w += cap[1] + 1;
    L->RB1 = w;
    w += cap[1] + 1;
  } else {
    L->RB0 = L->RB1 = NULL;
  }
  L->RA0 = w;
  w += cap[0] + 1;
  L->RA1 = w;
  w += cap[0] + 1;
  if (dim == 3) {
    L->Z = w;
    w += cap[3];
  } else {
    L->Z = NULL;
  }
  L->Y = w;
  w += cap[3];
  L->X = w;
}

/* The dimension of the NBS layout that ctx->work holds (see the file comment). */
static int nbs__nbs_layout_dim(const nbs_context *ctx) { return ctx->work_cap[2] > 0 ? 3 : 2; }

bool nbs__nbs_heads_empty(const nbs_context *ctx) {
  if (ctx->work_kind != NBS__WORK_NBS) return true;
  const int32_t *h = ctx->work;
  int64_t count = nbs__nbs_head_count(nbs__nbs_layout_dim(ctx), ctx->work_cap);
  for (int64_t i = 0; i < count; i++) {
    if (h[i] != NBS__EMPTY) return false;
  }
  return true;
}

/* ---- helpers of the detection -------------------------------------------------------- */

/* Padded cell coordinate of element k on `axis`: 1 + Int((x - xmin) / d) (eq. 3.26, whose
 * book form is 1-based as well). dim is a constant at every call, so this folds away. */
static inline int32_t nbs__nbs_cell(const nbs__grid *g, const double *x, int dim, int32_t k,
                                    int axis) {
  return 1 + nbs__cell(g, x + (size_t)k * (size_t)dim, axis);
}

/* A hint to fetch the cache line at p; nothing on compilers without the builtin. */
#if defined(__GNUC__) || defined(__clang__)
#define NBS__NBS_PREFETCH(p) __builtin_prefetch(p)
#else
#define NBS__NBS_PREFETCH(p) ((void)(p))
#endif

/* Walks the y-lists starting at r[0..4] side by side, touching each element's link and
 * prefetching its coordinates, so that the cache misses of the five walks overlap. */
static inline void nbs__nbs_touch_rows(const int32_t *Y, const double *x, int dim,
                                       const int32_t r[5]) {
  int32_t e[5] = {r[0], r[1], r[2], r[3], r[4]};
  for (;;) {
    int live = 0;
    for (int l = 0; l < 5; l++) {
      if (e[l] == NBS__EMPTY) continue;
      NBS__NBS_PREFETCH(x + (size_t)e[l] * (size_t)dim);
      e[l] = Y[e[l]];
      live = 1;
    }
    if (!live) break;
  }
}

/* Heads are dirty when a detection stops in the middle: forget the layout, so that the next
 * detection sets every head to empty again (step 0). */
static nbs_status nbs__nbs_abort(nbs__run *run, nbs_status s) {
  run->ctx->work_kind = NBS__WORK_NONE;
  return s;
}

/* Checks the central cell, whose x-list (set 0, linked by X) starts at element c, with the
 * contact mask (2D: the mask of section 3.8, cells (ix-1,iy-1) (ix,iy-1) (ix+1,iy-1)
 * (ix-1,iy); 3D: the 13 cells of eq. 3.73):
 *   - the cell itself: every element against those after it in the list (each pair once);
 *   - the cell (ix-1) of the central row, nb[0]: A0[ix-1], unmarked by the caller;
 *   - the cells ix-1, ix, ix+1 of the neighbouring rows, nb[1..3]: A1[ix-1], A1[ix],
 *     A1[ix+1]. In 2D they are row iy-1; in 3D set 1 merges rows (iy-1,iz), (iy-1,iz-1),
 *     (iy,iz-1), (iy+1,iz-1), so these three lists cover the 3 cells of row iy-1 in layer
 *     iz and the 9 cells of layer iz-1.
 * Together 4 (2D) or 13 (3D) neighbour cells: each pair of neighbouring cells is visited
 * from exactly one of the two. */
static inline nbs_status nbs__nbs_check_cell(nbs__run *run, const int32_t *X, int32_t c,
                                             const int32_t nb[4]) {
  for (int32_t a = c; a != NBS__EMPTY; a = X[a]) {
    for (int32_t b = X[a]; b != NBS__EMPTY; b = X[b]) NBS__TRY(nbs__offer(run, a, b));
  }
  for (int l = 0; l < 4; l++) {
    if (nb[l] == NBS__EMPTY) continue;
    for (int32_t a = c; a != NBS__EMPTY; a = X[a]) {
      for (int32_t b = nb[l]; b != NBS__EMPTY; b = X[b]) NBS__TRY(nbs__offer(run, a, b));
    }
  }
  return NBS_OK;
}

/* Propagates an error of the pair sink, forgetting the (now dirty) layout. */
#define NBS__NBS_TRY(expr)                                                                    \
  do {                                                                                        \
    nbs_status nbs__s = (expr);                                                               \
    if (nbs__s != NBS_OK) return nbs__nbs_abort(run, nbs__s);                                 \
  } while (0)

/* Pushes element e onto the list of head H[i] (its link: next), and records i in R[top++]
 * when the list was empty, i.e. when e starts it. */
#define NBS__NBS_PUSH(e, next, H, i, R, top)                                                  \
  do {                                                                                        \
    const int32_t nbs__h = (H)[i];                                                            \
    (next) = nbs__h;                                                                          \
    (H)[i] = (e);                                                                             \
    (R)[top] = (i);                                                                           \
    (top) += nbs__h == NBS__EMPTY;                                                            \
  } while (0)

/* Pushes element e onto the x-list of its cell in the set A (record R, top). */
#define NBS__NBS_PUSH_X(e, A, R, top, dim)                                                    \
  do {                                                                                        \
    const int32_t nbs__ix = nbs__nbs_cell(g, x, dim, (e), 0);                                 \
    NBS__NBS_PUSH((e), X[e], A, nbs__ix, R, top);                                             \
  } while (0)

/* Pushes the elements of the y-lists starting at first0 and first1 onto the x-lists of the sets A0
 * and A1, walking the two lists side by side so that their cache misses overlap; each
 * x-list still gets its elements in the book's order. */
#define NBS__NBS_PUSH_ROWS(first0, first1, dim)                                               \
  do {                                                                                        \
    int32_t f0 = (first0), f1 = (first1);                                                     \
    while (f0 != NBS__EMPTY && f1 != NBS__EMPTY) {                                            \
      const int32_t m0 = Y[f0], m1 = Y[f1];                                                   \
      NBS__NBS_PUSH_X(f0, A0, RA0, na0, dim);                                                 \
      NBS__NBS_PUSH_X(f1, A1, RA1, na1, dim);                                                 \
      f0 = m0;                                                                                \
      f1 = m1;                                                                                \
    }                                                                                         \
    for (; f0 != NBS__EMPTY; f0 = Y[f0]) NBS__NBS_PUSH_X(f0, A0, RA0, na0, dim);              \
    for (; f1 != NBS__EMPTY; f1 = Y[f1]) NBS__NBS_PUSH_X(f1, A1, RA1, na1, dim);              \
  } while (0)

/* Empties the heads H[R[0..top-1]] that a set's lists were started at. */
static inline void nbs__nbs_clear(int32_t *H, const int32_t *R, int32_t top) {
  for (int32_t i = 0; i < top; i++) H[R[i]] = NBS__EMPTY;
}

/* ---- 2D (section 3.8) ---------------------------------------------------------------- */

static nbs_status nbs__nbs_2d(nbs__run *run, const nbs__nbs_layout *L) {
  const nbs__grid *g = &run->grid;
  const double *x = run->x;
  const int32_t n = run->n;
  int32_t *restrict B = L->B0;
  int32_t *restrict A0 = L->A0;
  int32_t *restrict A1 = L->A1;
  int32_t *restrict Y = L->Y;
  int32_t *restrict X = L->X;
  int32_t *restrict RA0 = L->RA0;
  int32_t *restrict RA1 = L->RA1;

  /* Mapping onto rows: integerise y and push each element on its y-list (the book's
   * eqs. 3.34-3.35 with one coordinate): Y[k] = B[iy]; B[iy] = k. */
  for (int32_t k = 0; k < n; k++) {
    int32_t iy = nbs__nbs_cell(g, x, 2, k, 1);
    Y[k] = B[iy];
    B[iy] = k;
  }

  /* Loop over the elements: the first element found in a "new" row makes it the central
   * row. */
  for (int32_t k = 0; k < n; k++) {
    int32_t iy = nbs__nbs_cell(g, x, 2, k, 1);
    if (nbs__is_marked(B[iy])) continue;
    const int32_t row = B[iy];
    B[iy] = nbs__mark(row); /* mark the row "old" */
    /* Row iy-1 may have been central already: read its head unmarked. */
    const int32_t below = nbs__unmark(B[iy - 1]);

    /* x-lists of set 0: the elements of the central row iy; x-lists of set 1: the elements
     * of the neighbouring row iy-1. */
    int32_t na0 = 0, na1 = 0;
    NBS__NBS_PUSH_ROWS(row, below, 2);

    /* Loop over the central row: the first element in a "new" cell makes it the central
     * cell; mark it and check it with the contact mask. */
    for (int32_t e = row; e != NBS__EMPTY; e = Y[e]) {
      int32_t ix = nbs__nbs_cell(g, x, 2, e, 0);
      if (nbs__is_marked(A0[ix])) continue;
      const int32_t c = A0[ix];
      A0[ix] = nbs__mark(c);
      const int32_t nb[4] = {nbs__unmark(A0[ix - 1]), A1[ix - 1], A1[ix], A1[ix + 1]};
      NBS__NBS_TRY(nbs__nbs_check_cell(run, X, c, nb));
    }

    /* Removal of the x-lists: reset the heads the two rows started. */
    nbs__nbs_clear(A0, RA0, na0);
    nbs__nbs_clear(A1, RA1, na1);
  }

  /* Removal of the y-lists, by a loop over the elements (eqs. 3.36-3.37 for rows). */
  for (int32_t k = 0; k < n; k++) B[nbs__nbs_cell(g, x, 2, k, 1)] = NBS__EMPTY;
  return NBS_OK;
}

/* ---- 3D (section 3.10; the numbered steps are those of the pseudocode on p. 127) ----- */

/* Pushes element e onto the y-list of its row in the set B (record R, top). */
#define NBS__NBS_PUSH_Y(e, B, R, top)                                                         \
  do {                                                                                        \
    const int32_t nbs__iy = nbs__nbs_cell(g, x, 3, (e), 1);                                   \
    NBS__NBS_PUSH((e), Y[e], B, nbs__iy, R, top);                                             \
  } while (0)

static nbs_status nbs__nbs_3d(nbs__run *run, const nbs__nbs_layout *L) {
  const nbs__grid *g = &run->grid;
  const double *x = run->x;
  const int32_t n = run->n;
  int32_t *restrict C = L->C;
  int32_t *restrict B0 = L->B0;
  int32_t *restrict B1 = L->B1;
  int32_t *restrict A0 = L->A0;
  int32_t *restrict A1 = L->A1;
  int32_t *restrict Z = L->Z;
  int32_t *restrict Y = L->Y;
  int32_t *restrict X = L->X;
  int32_t *restrict RB0 = L->RB0;
  int32_t *restrict RB1 = L->RB1;
  int32_t *restrict RA0 = L->RA0;
  int32_t *restrict RA1 = L->RA1;

  /* Step 1: map every element onto its z-list (layer): Z[k] = C[iz]; C[iz] = k. All
   * z-lists are "new" (unmarked). */
  for (int32_t k = 0; k < n; k++) {
    int32_t iz = nbs__nbs_cell(g, x, 3, k, 2);
    Z[k] = C[iz];
    C[iz] = k;
  }

  /* Step 2: loop over the elements; the first one in a "new" z-list makes it the central
   * layer. */
  for (int32_t k = 0; k < n; k++) {
    int32_t iz = nbs__nbs_cell(g, x, 3, k, 2);
    if (nbs__is_marked(C[iz])) continue;
    const int32_t layer = C[iz];
    C[iz] = nbs__mark(layer); /* mark the layer "old" */
    /* Layer iz-1 may have been central already: read its head unmarked. */
    const int32_t under = nbs__unmark(C[iz - 1]);

    /* Step 3: the elements of the central layer onto the y-lists of set 0; step 4: the
     * elements of the neighbouring layer iz-1 onto the y-lists of set 1. The two walks go
     * side by side, so that their cache misses overlap; each list still gets its elements
     * in the book's order. RB0 records the rows of the central layer in the order in which
     * this walk meets their first element. */
    int32_t nb0 = 0, nb1 = 0;
    int32_t e0 = layer, e1 = under;
    while (e0 != NBS__EMPTY && e1 != NBS__EMPTY) {
      const int32_t n0 = Z[e0], n1 = Z[e1];
      NBS__NBS_PUSH_Y(e0, B0, RB0, nb0);
      NBS__NBS_PUSH_Y(e1, B1, RB1, nb1);
      e0 = n0;
      e1 = n1;
    }
    for (; e0 != NBS__EMPTY; e0 = Z[e0]) NBS__NBS_PUSH_Y(e0, B0, RB0, nb0);
    for (; e1 != NBS__EMPTY; e1 = Z[e1]) NBS__NBS_PUSH_Y(e1, B1, RB1, nb1);

    /* Step 5: loop over the central layer; the first element in a "new" row (iy,iz) makes
     * it the central row. Those first elements, in the order of the layer, are the ones
     * step 3 met first in their rows: RB0 lists their rows in that order, so the loop runs
     * over RB0 instead of walking the layer a second time. */
    for (int32_t i = 0; i < nb0; i++) {
      const int32_t iy = RB0[i];
      const int32_t row = B0[iy];
      B0[iy] = nbs__mark(row); /* mark the row "old" */
      /* The neighbouring rows of eq. 3.79: (iy-1,iz) may have been central already (read
       * unmarked); rows of layer iz-1 are set 1 and never marked. */
      const int32_t nrow[4] = {nbs__unmark(B0[iy - 1]), B1[iy - 1], B1[iy], B1[iy + 1]};

      /* The five rows of steps 6-10 walked once side by side, so that their cache misses
       * overlap and the walks of steps 6-8 find them cached. */
      const int32_t rows[5] = {row, nrow[0], nrow[1], nrow[2], nrow[3]};
      nbs__nbs_touch_rows(Y, x, 3, rows);

      /* Step 6: the elements of the central row onto the x-lists of set 0; step 7: the
       * elements of the neighbouring rows onto the x-lists of set 1 (the central row side by
       * side with the first of them). */
      int32_t na0 = 0, na1 = 0;
      NBS__NBS_PUSH_ROWS(row, nrow[0], 3);
      for (int l = 1; l < 4; l++) {
        for (int32_t e = nrow[l]; e != NBS__EMPTY; e = Y[e]) NBS__NBS_PUSH_X(e, A1, RA1, na1, 3);
      }

      /* Step 8: loop over the central row; the first element in a "new" cell (ix,iy,iz)
       * makes it the central cell: mark it and check it with the 13-cell mask (eq. 3.73). */
      for (int32_t e = row; e != NBS__EMPTY; e = Y[e]) {
        int32_t ix = nbs__nbs_cell(g, x, 3, e, 0);
        if (nbs__is_marked(A0[ix])) continue;
        const int32_t c = A0[ix];
        A0[ix] = nbs__mark(c);
        const int32_t nb[4] = {nbs__unmark(A0[ix - 1]), A1[ix - 1], A1[ix], A1[ix + 1]};
        NBS__NBS_TRY(nbs__nbs_check_cell(run, X, c, nb));
      }

      /* Steps 9 and 10: remove the x-lists of the central and of the neighbouring rows,
       * resetting the heads they started. */
      nbs__nbs_clear(A0, RA0, na0);
      nbs__nbs_clear(A1, RA1, na1);
    }

    /* Step 11: remove the y-lists of the central layer and of layer iz-1. */
    nbs__nbs_clear(B0, RB0, nb0);
    nbs__nbs_clear(B1, RB1, nb1);
  }

  /* Finally remove the z-lists, by a loop over the elements. */
  for (int32_t k = 0; k < n; k++) C[nbs__nbs_cell(g, x, 3, k, 2)] = NBS__EMPTY;
  return NBS_OK;
}

#undef NBS__NBS_PUSH
#undef NBS__NBS_PUSH_X
#undef NBS__NBS_PUSH_Y
#undef NBS__NBS_PUSH_ROWS
#undef NBS__NBS_TRY

/* ---- the dispatcher ------------------------------------------------------------------ */

/* An axis capacity grown with 1/8 slack, so that a domain creeping outwards step after
 * step does not re-lay the block every time; never beyond what an axis can need. */
static int64_t nbs__nbs_grow(int64_t need) {
  int64_t c = need + need / 8;
  return c < NBS__AXIS_MAX ? c : NBS__AXIS_MAX;
}

nbs_status nbs__nbs(nbs__run *run) {
  nbs_context *ctx = run->ctx;
  const nbs__grid *g = &run->grid;
  const int dim = run->dim;

  run->ran = NBS_NBS;
  run->compressed = false;
  run->work_bytes = 0;
  run->cells[0] = g->n[0];
  run->cells[1] = g->n[1];
  run->cells[2] = dim == 3 ? g->n[2] : 1;

  if (!g->fits) {
    return nbs__fail(ctx, NBS_ERR_EXTENT, -1,
                     "nbs: the grid needs more than %lld cells on an axis (cells per axis: x "
                     "%lld, y %lld%s%lld; -1 means too many); use 'auto' or 'sorting'",
                     (long long)NBS__AXIS_MAX, (long long)g->n[0], (long long)g->n[1],
                     dim == 3 ? ", z " : "", dim == 3 ? (long long)g->n[2] : 0LL);
  }

  /* What this detection needs: {nx, ny, nz (0 in 2D), N}. */
  const int64_t need[4] = {g->n[0], g->n[1], dim == 3 ? g->n[2] : 0, run->n};
  const uint64_t need_heads = nbs__nbs_axis_bytes(dim, need);
  if (need_heads > ctx->cell_budget) {
    return nbs__fail(ctx, NBS_ERR_BUDGET, -1,
                     "nbs: the head arrays and their records need %llu bytes (%lld x %lld%s%lld "
                     "cells), the cell budget is %zu bytes",
                     (unsigned long long)need_heads, (long long)g->n[0], (long long)g->n[1],
                     dim == 3 ? " x " : "", dim == 3 ? (long long)g->n[2] : 0LL,
                     ctx->cell_budget);
  }

  const bool same = ctx->work_kind == NBS__WORK_NBS && nbs__nbs_layout_dim(ctx) == dim;
  bool fits = same;
  for (int a = 0; a < 4 && fits; a++) fits = need[a] <= ctx->work_cap[a];

  if (!fits) {
    int64_t cap[4];
    if (!same) {
      /* First use (or another layout was in the block): exactly the need. */
      for (int a = 0; a < 4; a++) cap[a] = need[a];
    } else {
      /* Growth: keep what the old layout could hold; axes that grow get 1/8 slack. */
      for (int a = 0; a < 3; a++) {
        cap[a] = need[a] > ctx->work_cap[a] ? nbs__nbs_grow(need[a]) : ctx->work_cap[a];
      }
      cap[3] = need[3] > ctx->work_cap[3] ? need[3] : ctx->work_cap[3];
      /* Heads and records must stay within the budget: drop the slack, then the old capacities. */
      if (nbs__nbs_axis_bytes(dim, cap) > ctx->cell_budget) {
        for (int a = 0; a < 3; a++) {
          cap[a] = need[a] > ctx->work_cap[a] ? need[a] : ctx->work_cap[a];
        }
      }
      if (nbs__nbs_axis_bytes(dim, cap) > ctx->cell_budget) {
        for (int a = 0; a < 3; a++) cap[a] = need[a];
      }
    }
    const uint64_t bytes = nbs__nbs_layout_bytes(dim, cap);
    if (bytes > SIZE_MAX) {
      return nbs__fail(ctx, NBS_ERR_NOMEM, -1, "nbs: %llu bytes of work arrays cannot be addressed",
                       (unsigned long long)bytes);
    }
    NBS__TRY(nbs__work_reserve(ctx, (size_t)bytes));
    /* Step 0 (eqs. 3.32-3.33 for lists): every head empty, once for this layout. */
    int32_t *h = ctx->work;
    const int64_t count = nbs__nbs_head_count(dim, cap);
    for (int64_t i = 0; i < count; i++) h[i] = NBS__EMPTY;
    ctx->work_kind = NBS__WORK_NBS;
    for (int a = 0; a < 4; a++) ctx->work_cap[a] = cap[a];
  }

  nbs__nbs_layout L;
  nbs__nbs_layout_at(&L, ctx->work, dim, ctx->work_cap);
  run->work_bytes = L.bytes;
  return dim == 3 ? nbs__nbs_3d(run, &L) : nbs__nbs_2d(run, &L);
}
