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

nbs_status nbs__prepare(nbs__run *run, const nbs_input *in) {
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
    return NBS_OK;
  }

  /* The pass: every coordinate finite, every radius finite and > 0; box and rmax. The
   * comparisons are written so that a NaN fails them. */
  double lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX};
  const double *x = in->coords;
  for (int32_t k = 0; k < n; k++) {
    for (int a = 0; a < dim; a++) {
      double v = x[(size_t)k * (size_t)dim + (size_t)a];
      if (!(v >= -DBL_MAX && v <= DBL_MAX)) {
        return nbs__fail(ctx, NBS_ERR_COORD, k, "element %d: %s coordinate is %s", (int)k,
                         nbs__axis_name[a], isnan(v) ? "NaN" : "infinite");
      }
      if (v < lo[a]) lo[a] = v;
      if (v > hi[a]) hi[a] = v;
    }
  }
  double rmax;
  if (in->radii) {
    rmax = 0.0;
    for (int32_t k = 0; k < n; k++) {
      double r = in->radii[k];
      if (!(r > 0 && r <= DBL_MAX)) {
        return nbs__fail(ctx, NBS_ERR_RADIUS, k,
                         "element %d: radius %g is not a finite number > 0", (int)k, r);
      }
      if (r > rmax) rmax = r;
    }
  } else {
    rmax = 0.5 * in->diameter;
  }
  g->rmax = rmax;

  double dmax = in->radii ? 2.0 * rmax : in->diameter;
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
  return NBS_OK;
}
