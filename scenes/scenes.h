/*
 * Scenes: the element sets used by the tests, the nbs tool (generate, demo) and the
 * benchmarks, written once here. Deterministic for a given definition (seed included) on
 * every platform: the generator is splitmix64 and only +, *, / and sqrt are used, which are
 * correctly rounded.
 */
#ifndef NBS_SCENES_H
#define NBS_SCENES_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef enum scene_kind {
  SCENE_UNIFORM = 0,   /* uniform random in a box sized for the volume fraction */
  SCENE_LATTICE,       /* square/cubic lattice of spacing exactly the diameter: all neighbours touch */
  SCENE_CLUSTERED,     /* 99% packed at `fraction` in a small box, 1% over a box 1000x larger */
  SCENE_SPARSE,        /* uniform at a low fraction plus a few outliers 1e6 diameters away */
  SCENE_WIDE,          /* per-element radii spread over `size_ratio` (max/min), uniform box */
  SCENE_FACES,         /* centres exactly on the faces of nbs's cells */
  SCENE_IDENTICAL,     /* every element at one point */
  SCENE_FAR,           /* uniform, and one element 1e15 diameters away */
  SCENE_HUGE,          /* uniform over a domain of ~1e12 cells (spread far beyond contact) */
  SCENE_SLAB,          /* uniform at `fraction` in a layer two diameters thick (2D: a strip) */
  SCENE_KIND_COUNT
} scene_kind;

typedef struct scene_def {
  scene_kind kind;
  int dim;           /* 2 or 3 */
  int64_t n;         /* number of elements */
  uint64_t seed;     /* random seed */
  double fraction;   /* volume (3D) or area (2D) fraction of the box, e.g. 0.5 */
  double diameter;   /* diameter (largest diameter for SCENE_WIDE) */
  double offset;     /* added to every coordinate (e.g. 1e9) */
  double size_ratio; /* SCENE_WIDE: largest over smallest diameter */
  int sorted;        /* 1: order elements along a space-filling order of their cells */
} scene_def;

typedef struct scene {
  int dim;
  int64_t n;
  double *coords;  /* n * dim */
  double *radii;   /* n radii, or NULL when every element has `diameter` */
  double diameter; /* the common diameter (or the largest) */
} scene;

/* Defaults: uniform, 3D, 1000 elements, seed 1, fraction 0.5, diameter 1. */
scene_def scene_default_def(void);
/* Parses "uniform", "lattice", ...; -1 if unknown. */
int scene_kind_from_name(const char *name);
const char *scene_kind_name(scene_kind kind);

/* Fills *out (allocated with malloc). Returns 0, or -1 with a message in err on bad
 * definitions or allocation failure. */
int scene_generate(const scene_def *def, scene *out, char *err, size_t errlen);
void scene_free(scene *s);
/* A time step: moves each of the `count` coordinates by an amount uniform in [-step, step),
 * drawn from *state (splitmix64: the same sequence everywhere). */
void scene_step(double *coords, size_t count, double step, uint64_t *state);

#ifdef __cplusplus
}
#endif
#endif
