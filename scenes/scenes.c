/*
 * Scene generators (see scenes.h). Each one is a few lines on purpose: a scene is a test
 * input, a benchmark input and a demo input at once, so it must be easy to read.
 */
#include "scenes.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const scene_names[SCENE_KIND_COUNT] = {
    "uniform", "lattice", "clustered", "sparse", "wide", "faces", "identical", "far", "huge",
    "slab",
};

const char *scene_kind_name(scene_kind kind) {
  return (int)kind >= 0 && kind < SCENE_KIND_COUNT ? scene_names[kind] : NULL;
}

int scene_kind_from_name(const char *name) {
  for (int k = 0; k < SCENE_KIND_COUNT; k++) {
    if (name && strcmp(name, scene_names[k]) == 0) return k;
  }
  return -1;
}

scene_def scene_default_def(void) {
  scene_def d;
  memset(&d, 0, sizeof d);
  d.kind = SCENE_UNIFORM;
  d.dim = 3;
  d.n = 1000;
  d.seed = 1;
  d.fraction = 0.5;
  d.diameter = 1.0;
  d.size_ratio = 10.0;
  return d;
}

/* splitmix64: small, fast, and the same sequence everywhere. */
static uint64_t scene_next(uint64_t *state) {
  uint64_t z = (*state += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

/* Uniform in [0, 1). */
static double scene_uniform(uint64_t *state) {
  return (double)(scene_next(state) >> 11) * 0x1p-53;
}

/* Edge of the box in which n elements of mean volume v fill `fraction` of the space. */
static double scene_box(int dim, int64_t n, double v, double fraction) {
  return pow((double)n * v / fraction, 1.0 / dim);
}

static double scene_volume(int dim, double d) {
  const double pi = 3.14159265358979323846;
  return dim == 3 ? pi / 6.0 * d * d * d : pi / 4.0 * d * d;
}

static void scene_fill_uniform(scene *s, int64_t from, int64_t to, double lo, double edge,
                               uint64_t *rng) {
  for (int64_t k = from; k < to; k++) {
    for (int a = 0; a < s->dim; a++) s->coords[k * s->dim + a] = lo + edge * scene_uniform(rng);
  }
}

typedef struct scene_key {
  uint64_t key;
  int64_t index;
} scene_key;

static int scene_key_cmp(const void *a, const void *b) {
  const scene_key *x = a, *y = b;
  return x->key < y->key ? -1 : x->key > y->key;
}

/* Reorders the elements by the row-major order of diameter-sized cells. */
static int scene_sort(scene *s) {
  int64_t n = s->n;
  int dim = s->dim;
  if (n < 2) return 0;
  double lo[3] = {INFINITY, INFINITY, INFINITY};
  for (int64_t k = 0; k < n; k++) {
    for (int a = 0; a < dim; a++) lo[a] = fmin(lo[a], s->coords[k * dim + a]);
  }
  scene_key *keys = malloc((size_t)n * sizeof *keys);
  double *c = malloc((size_t)n * (size_t)dim * sizeof *c);
  double *r = s->radii ? malloc((size_t)n * sizeof *r) : NULL;
  if (!keys || !c || (s->radii && !r)) {
    free(keys);
    free(c);
    free(r);
    return -1;
  }
  for (int64_t k = 0; k < n; k++) {
    uint64_t key = 0;
    for (int a = dim - 1; a >= 0; a--) {
      double q = floor((s->coords[k * dim + a] - lo[a]) / s->diameter);
      uint64_t cell = q < 2097151.0 ? (uint64_t)q : 2097151u; /* 21 bits per axis */
      key = key << 21 | cell;
    }
    keys[k].key = key;
    keys[k].index = k;
  }
  qsort(keys, (size_t)n, sizeof *keys, scene_key_cmp);
  for (int64_t k = 0; k < n; k++) {
    memcpy(c + k * dim, s->coords + keys[k].index * dim, (size_t)dim * sizeof *c);
    if (r) r[k] = s->radii[keys[k].index];
  }
  free(s->coords);
  s->coords = c;
  if (r) {
    free(s->radii);
    s->radii = r;
  }
  free(keys);
  return 0;
}

int scene_generate(const scene_def *def, scene *out, char *err, size_t errlen) {
  memset(out, 0, sizeof *out);
  if (def->dim != 2 && def->dim != 3) {
    snprintf(err, errlen, "dimension %d: it must be 2 or 3", def->dim);
    return -1;
  }
  if (def->n < 0 || def->n > 2000000000) {
    snprintf(err, errlen, "%lld elements: the count must be 0 <= n <= 2e9", (long long)def->n);
    return -1;
  }
  if (!(def->diameter > 0 && isfinite(def->diameter))) {
    snprintf(err, errlen, "diameter %g: it must be a finite number > 0", def->diameter);
    return -1;
  }
  if (!(def->fraction > 0 && def->fraction < 1)) {
    snprintf(err, errlen, "fraction %g: it must be in (0, 1)", def->fraction);
    return -1;
  }
  if (def->kind == SCENE_WIDE && !(def->size_ratio >= 1 && isfinite(def->size_ratio))) {
    snprintf(err, errlen, "size ratio %g: it must be a finite number >= 1", def->size_ratio);
    return -1;
  }
  const int dim = def->dim;
  const int64_t n = def->n;
  const double d = def->diameter;
  out->dim = dim;
  out->n = n;
  out->diameter = d;
  out->coords = malloc((size_t)(n > 0 ? n : 1) * (size_t)dim * sizeof(double));
  if (def->kind == SCENE_WIDE) out->radii = malloc((size_t)(n > 0 ? n : 1) * sizeof(double));
  if (!out->coords || (def->kind == SCENE_WIDE && !out->radii)) {
    scene_free(out);
    snprintf(err, errlen, "out of memory for %lld elements", (long long)n);
    return -1;
  }
  uint64_t rng = def->seed * 0x2545f4914f6cdd1dull + 1;
  double box = scene_box(dim, n > 0 ? n : 1, scene_volume(dim, d), def->fraction);

  switch (def->kind) {
  case SCENE_UNIFORM:
    scene_fill_uniform(out, 0, n, 0.0, box, &rng);
    break;
  case SCENE_LATTICE: {
    int64_t m = (int64_t)ceil(pow((double)n, 1.0 / dim) - 1e-9);
    if (m < 1) m = 1;
    while ((dim == 2 ? m * m : m * m * m) < n) m++;
    for (int64_t k = 0; k < n; k++) {
      int64_t q = k;
      for (int a = 0; a < dim; a++) {
        out->coords[k * dim + a] = (double)(q % m) * d;
        q /= m;
      }
    }
    break;
  }
  case SCENE_CLUSTERED: {
    /* 99% packed at the scene's fraction in a box of their own; 1% over a box 1000 times
     * the uniform one's edge, around it: a domain mostly empty, its elements mostly crowded. */
    int64_t far = n / 100;
    double near = scene_box(dim, n - far > 0 ? n - far : 1, scene_volume(dim, d), def->fraction);
    scene_fill_uniform(out, 0, n - far, 0.0, near, &rng);
    scene_fill_uniform(out, n - far, n, -500.0 * box, 1000.0 * box, &rng);
    break;
  }
  case SCENE_SPARSE: {
    int64_t far = n / 1000 + (n > 1 ? 1 : 0);
    scene_fill_uniform(out, 0, n - far, 0.0, box, &rng);
    for (int64_t k = n - far; k < n; k++) {
      for (int a = 0; a < dim; a++) {
        out->coords[k * dim + a] = 1e6 * d * (scene_uniform(&rng) < 0.5 ? -1.0 : 1.0) +
                                   box * scene_uniform(&rng);
      }
    }
    break;
  }
  case SCENE_WIDE: {
    /* Diameters log-uniform in [d / ratio, d]; the box is sized by the mean volume. */
    double mean = 0.0;
    for (int64_t k = 0; k < n; k++) {
      double dk = d * pow(def->size_ratio, -scene_uniform(&rng));
      out->radii[k] = 0.5 * dk;
      mean += scene_volume(dim, dk);
    }
    mean = n > 0 ? mean / (double)n : scene_volume(dim, d);
    scene_fill_uniform(out, 0, n, 0.0, scene_box(dim, n > 0 ? n : 1, mean, def->fraction), &rng);
    break;
  }
  case SCENE_FACES: {
    /* Centres on a lattice of half nbs's cell edge (diameter * (1 + 2^-18)), with the
     * lowest at 0: every other centre lies exactly on a cell face. */
    double e = d * (1.0 + 0x1p-18);
    int64_t m = (int64_t)ceil(pow((double)n, 1.0 / dim) - 1e-9);
    if (m < 1) m = 1;
    while ((dim == 2 ? m * m : m * m * m) < n) m++;
    for (int64_t k = 0; k < n; k++) {
      int64_t q = k;
      for (int a = 0; a < dim; a++) {
        out->coords[k * dim + a] = (double)(q % m) * (0.5 * e);
        q /= m;
      }
    }
    break;
  }
  case SCENE_IDENTICAL:
    for (int64_t k = 0; k < n * dim; k++) out->coords[k] = 0.0;
    break;
  case SCENE_FAR:
    scene_fill_uniform(out, 0, n, 0.0, box, &rng);
    if (n > 0) {
      for (int a = 0; a < dim; a++) out->coords[(n - 1) * dim + a] = 1e15 * d;
    }
    break;
  case SCENE_HUGE: {
    /* n elements over n * 1e6 cells of edge d (1e12 cells for n = 1e6). */
    double edge = d * pow((double)(n > 0 ? n : 1) * 1e6, 1.0 / dim);
    scene_fill_uniform(out, 0, n, 0.0, edge, &rng);
    break;
  }
  case SCENE_SLAB: {
    /* A bed on a floor (3D) or a strip (2D): the last axis two diameters thick, the others
     * wide enough for `fraction`. */
    const double thick = 2.0 * d;
    const double area = (double)(n > 0 ? n : 1) * scene_volume(dim, d) / (def->fraction * thick);
    const double wide = pow(area, 1.0 / (dim - 1));
    for (int64_t k = 0; k < n; k++) {
      for (int a = 0; a < dim; a++) {
        out->coords[k * dim + a] = (a == dim - 1 ? thick : wide) * scene_uniform(&rng);
      }
    }
    break;
  }
  default:
    scene_free(out);
    snprintf(err, errlen, "unknown scene kind %d", (int)def->kind);
    return -1;
  }
  if (def->offset != 0.0) {
    for (int64_t k = 0; k < n * dim; k++) out->coords[k] += def->offset;
  }
  if (def->sorted && scene_sort(out) != 0) {
    scene_free(out);
    snprintf(err, errlen, "out of memory sorting %lld elements", (long long)n);
    return -1;
  }
  return 0;
}

void scene_step(double *coords, size_t count, double step, uint64_t *state) {
  for (size_t k = 0; k < count; k++) coords[k] += step * (2.0 * scene_uniform(state) - 1.0);
}

void scene_free(scene *s) {
  if (!s) return;
  free(s->coords);
  free(s->radii);
  s->coords = NULL;
  s->radii = NULL;
}
