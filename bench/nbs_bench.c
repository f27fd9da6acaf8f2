/*
 * nbs_bench: times every nbs algorithm on one scene and prints one machine-readable line
 * per algorithm (key=value fields, see bench/README.md).
 *
 * The scene is either generated with the shared scene generators (--scene) or read from a
 * raw file of little-endian f64 coordinates, dim per element (--file). --write saves the
 * scene in that format so that the peer drivers (nanoflann, CGAL, LAMMPS, scipy) time
 * exactly the same elements in the same order.
 *
 * What is timed: nbs_detect() alone (coordinates in, pairs in the context's buffer out),
 * with one context per algorithm reused over the repeats, as a simulation reuses its
 * context every step. The first detection allocates; the minimum over the repeats is the
 * steady state.
 * Order: cellsort starts a detection from the last detection's cell order when the elements
 * have moved little (nbs.h, "time steps"). On a scene that does not move, every repeat
 * after the first would find nothing to sort, which is not a time step: --fresh makes each
 * detection sort from scratch (the cold case: a first step, or unrelated inputs), and
 * --move D moves every element before each repeat after the first by a random step of up
 * to D diameters per axis (not timed), as a simulation's time step does. The tool is then
 * named nbs-ALG-steps; after the last step a fresh context detects the same coordinates
 * from scratch, and the line says whether its pairs were the same bytes (same_as_fresh).
 * Threads: --threads T sets nbs_context_def.threads (default 1: the targets are for one
 * thread; the library's own default, 0, would take every core). With T > 1 the tool is
 * named nbs-ALG-Tt. hash= is an order-sensitive hash of the pair list, so that runs with
 * different thread counts can be checked to give identical output.
 * Decoys: a detection repeated on the same scene runs on a processor that has just done
 * exactly that detection, and at small N its branch predictor has learned every loop exit
 * of it (3D N = 1e4, cellsort's ~1,400 blocks; bench/README.md): a simulation's step comes
 * after other work, and a first detection has nothing to learn from. --decoys K detects K
 * other scenes before each timed detection, untimed, in a context of their own (so that
 * the timed context's last order, for time steps, stays its own): the scene's coordinates
 * shifted by k * 0.382 diameters on every axis (k = 1..K), which puts the elements in
 * other cells, so that the sweep's rows and windows differ while N and the density stay.
 * Memory: nbs_context_peak_bytes() (everything the library held), and the
 * process's peak resident memory above what it held before the algorithm ran (VmHWM after
 * a reset through /proc/self/clear_refs), the figure the peer drivers report too.
 */
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "nbs/nbs.h"
#include "scenes.h"

static double now_seconds(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* A field of /proc/self/status in bytes ("VmHWM:", "VmRSS:"), or 0 where there is none. */
static long long proc_status_bytes(const char *field) {
  FILE *f = fopen("/proc/self/status", "r");
  if (!f) return 0;
  char line[256];
  long long kb = 0;
  size_t len = strlen(field);
  while (fgets(line, sizeof line, f)) {
    if (strncmp(line, field, len) == 0) {
      kb = strtoll(line + len, NULL, 10);
      break;
    }
  }
  fclose(f);
  return kb * 1024;
}

/* Resets VmHWM to the current resident size (Linux >= 4.0); harmless where unsupported. */
static void reset_peak_rss(void) {
  FILE *f = fopen("/proc/self/clear_refs", "w");
  if (!f) return;
  fputs("5", f);
  fclose(f);
}

static void usage(FILE *out) {
  fputs(
      "usage: nbs_bench (--scene NAME [--n N] [--fraction F] [--seed S] [--sorted]\n"
      "                  | --file PATH) [options]\n"
      "  --scene NAME       uniform, sparse, clustered, huge, ... (scenes/scenes.h)\n"
      "  --file PATH        raw little-endian f64 coordinates, DIM per element\n"
      "  --dim D            2 or 3 (default 3)\n"
      "  --n N              elements of a generated scene (default 1000)\n"
      "  --fraction F       volume/area fraction of a generated scene (default 0.5)\n"
      "  --seed S           seed of a generated scene (default 1)\n"
      "  --sorted           order a generated scene's elements by cell (row-major)\n"
      "  --diameter D       common diameter (default 1)\n"
      "  --write PATH       write the scene's coordinates to PATH (raw f64)\n"
      "  --algorithms LIST  comma-separated names (auto,nbs,sorting,screening,direct,...)\n"
      "                     (default: every algorithm of the library, auto first, direct\n"
      "                     only when N <= --direct-max)\n"
      "  --threads T        nbs_context_def.threads (default 1; 0: the library's default)\n"
      "  --direct-max N     largest N for direct by default (default 20000)\n"
      "  --repeats K        detections per algorithm; the minimum time is reported (5)\n"
      "  --min-time T       repeat at least until T seconds have been spent (default 0)\n"
      "  --fresh            every detection sorts from scratch (nbs_detect_def.fresh)\n"
      "  --move D           before each repeat after the first, move every element by up\n"
      "                     to D diameters per axis (time steps; tool nbs-ALG-steps);\n"
      "                     exactly --repeats steps (--min-time is ignored), so that runs\n"
      "                     with other thread counts end on the same coordinates\n"
      "  --decoys K         before each timed detection, detect K shifted copies of the\n"
      "                     scene in another context, untimed (0-16; default 0)\n"
      "Output, one line per algorithm:\n"
      "  tool=nbs-ALG[-Tt] status=ok seconds=.. ns_per_element=.. pairs=.. ran=ALG\n"
      "  peak_bytes=.. work_bytes=.. pair_bytes=.. rss_extra_bytes=.. hash=.. threads=..\n"
      "  reused=.. moved=.. [same_as_fresh=0|1] input_ns=.. prepare_ns=.. search_ns=..\n"
      "  n=.. dim=.. [decoys=K]\n"
      "  (input_ns, prepare_ns, search_ns: ns per element of each part of a detection,\n"
      "  nbs_stats: the input's check, the algorithm's preparation, the search; each the\n"
      "  fastest over the repeats)\n",
      out);
}

typedef struct options {
  const char *scene_name;
  const char *file;
  const char *write;
  const char *algorithms;
  scene_def def;
  int repeats;
  double min_time;
  long long direct_max;
  int threads;
  int fresh;
  double move;
  int decoys;
} options;

static int parse_args(int argc, char **argv, options *o) {
  o->def = scene_default_def();
  o->repeats = 5;
  o->direct_max = 20000;
  o->threads = 1;
  for (int k = 1; k < argc; k++) {
    const char *a = argv[k];
    const char *v = k + 1 < argc ? argv[k + 1] : NULL;
#define NEEDS_VALUE                                                                          \
  if (!v) {                                                                                  \
    fprintf(stderr, "nbs_bench: %s needs a value\n", a);                                     \
    return -1;                                                                               \
  }                                                                                          \
  k++
    if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
      usage(stdout);
      exit(0);
    } else if (strcmp(a, "--scene") == 0) {
      NEEDS_VALUE;
      o->scene_name = v;
    } else if (strcmp(a, "--file") == 0) {
      NEEDS_VALUE;
      o->file = v;
    } else if (strcmp(a, "--write") == 0) {
      NEEDS_VALUE;
      o->write = v;
    } else if (strcmp(a, "--algorithms") == 0) {
      NEEDS_VALUE;
      o->algorithms = v;
    } else if (strcmp(a, "--dim") == 0) {
      NEEDS_VALUE;
      o->def.dim = atoi(v);
    } else if (strcmp(a, "--n") == 0) {
      NEEDS_VALUE;
      o->def.n = (int64_t)strtod(v, NULL);
    } else if (strcmp(a, "--fraction") == 0) {
      NEEDS_VALUE;
      o->def.fraction = strtod(v, NULL);
    } else if (strcmp(a, "--seed") == 0) {
      NEEDS_VALUE;
      o->def.seed = strtoull(v, NULL, 10);
    } else if (strcmp(a, "--diameter") == 0) {
      NEEDS_VALUE;
      o->def.diameter = strtod(v, NULL);
    } else if (strcmp(a, "--repeats") == 0) {
      NEEDS_VALUE;
      o->repeats = atoi(v);
    } else if (strcmp(a, "--min-time") == 0) {
      NEEDS_VALUE;
      o->min_time = strtod(v, NULL);
    } else if (strcmp(a, "--direct-max") == 0) {
      NEEDS_VALUE;
      o->direct_max = (long long)strtod(v, NULL);
    } else if (strcmp(a, "--threads") == 0) {
      NEEDS_VALUE;
      o->threads = atoi(v);
    } else if (strcmp(a, "--fresh") == 0) {
      o->fresh = 1;
    } else if (strcmp(a, "--move") == 0) {
      NEEDS_VALUE;
      o->move = strtod(v, NULL);
      if (!(o->move >= 0.0)) {
        fprintf(stderr, "nbs_bench: --move needs a step >= 0\n");
        return -1;
      }
    } else if (strcmp(a, "--decoys") == 0) {
      NEEDS_VALUE;
      char *end = NULL;
      const long d = strtol(v, &end, 10);
      if (end == v || *end != '\0' || d < 0 || d > 16) {
        fprintf(stderr, "nbs_bench: --decoys needs a count of 0 to 16\n");
        return -1;
      }
      o->decoys = (int)d;
    } else if (strcmp(a, "--sorted") == 0) {
      o->def.sorted = 1;
    } else {
      fprintf(stderr, "nbs_bench: unknown argument %s\n", a);
      usage(stderr);
      return -1;
    }
#undef NEEDS_VALUE
  }
  if (!o->scene_name == !o->file) {
    fprintf(stderr, "nbs_bench: give exactly one of --scene and --file\n");
    return -1;
  }
  if (o->repeats < 1) o->repeats = 1;
  return 0;
}

static int read_scene_file(const char *path, int dim, double diameter, scene *s) {
  memset(s, 0, sizeof *s);
  FILE *f = fopen(path, "rb");
  if (!f) {
    fprintf(stderr, "nbs_bench: %s: %s\n", path, strerror(errno));
    return -1;
  }
  if (fseek(f, 0, SEEK_END) != 0) goto fail;
  long size = ftell(f);
  if (size < 0 || size % (long)(dim * sizeof(double)) != 0) {
    fprintf(stderr, "nbs_bench: %s: size %ld is not a multiple of %d doubles\n", path, size,
            dim);
    fclose(f);
    return -1;
  }
  rewind(f);
  s->dim = dim;
  s->n = size / (long)(dim * sizeof(double));
  s->diameter = diameter;
  s->coords = malloc(size > 0 ? (size_t)size : 1);
  if (!s->coords) goto fail;
  if (fread(s->coords, 1, (size_t)size, f) != (size_t)size) goto fail;
  fclose(f);
  return 0;
fail:
  fprintf(stderr, "nbs_bench: cannot read %s\n", path);
  fclose(f);
  free(s->coords);
  s->coords = NULL;
  return -1;
}

static int write_scene_file(const char *path, const scene *s) {
  FILE *f = fopen(path, "wb");
  if (!f) {
    fprintf(stderr, "nbs_bench: %s: %s\n", path, strerror(errno));
    return -1;
  }
  size_t count = (size_t)s->n * (size_t)s->dim;
  int ok = fwrite(s->coords, sizeof(double), count, f) == count;
  ok = (fclose(f) == 0) && ok;
  if (!ok) fprintf(stderr, "nbs_bench: cannot write %s\n", path);
  return ok ? 0 : -1;
}

/* FNV-1a over the pairs in their order: equal lists give equal hashes. */
static unsigned long long pairs_hash(const nbs_pair *pairs, size_t count) {
  unsigned long long h = 1469598103934665603ull;
  for (size_t k = 0; k < count; k++) {
    uint32_t v[2] = {(uint32_t)pairs[k].i, (uint32_t)pairs[k].j};
    for (int w = 0; w < 2; w++) {
      for (int b = 0; b < 4; b++) {
        h ^= (v[w] >> (8 * b)) & 0xffu;
        h *= 1099511628211ull;
      }
    }
  }
  return h;
}

/* Runs one algorithm; prints its line. Returns 0, or 1 if it failed for another reason
 * than not fitting the scene (budget, extent). */
static int run_algorithm(nbs_algorithm alg, const scene *s, const options *o) {
  const size_t ncoords = (size_t)s->n * (size_t)s->dim;
  /* time steps move a copy, so that every algorithm starts from the same scene */
  double *moving = NULL;
  if (o->move > 0.0) {
    moving = malloc(ncoords > 0 ? ncoords * sizeof *moving : 1);
    if (!moving) {
      fprintf(stderr, "nbs_bench: out of memory\n");
      return 1;
    }
    memcpy(moving, s->coords, ncoords * sizeof *moving);
  }
  nbs_input in = {.dim = s->dim, .n = s->n, .coords = moving ? moving : s->coords,
                  .radii = s->radii, .diameter = s->diameter};
  /* the decoys: K shifted copies of the scene, one after the other */
  double *decoy = NULL;
  if (o->decoys > 0) {
    decoy = malloc(ncoords > 0 ? (size_t)o->decoys * ncoords * sizeof *decoy : 1);
    if (!decoy) {
      fprintf(stderr, "nbs_bench: out of memory for %d decoys\n", o->decoys);
      free(moving);
      return 1;
    }
    for (int k = 0; k < o->decoys; k++) {
      const double shift = 0.382 * (double)(k + 1) * s->diameter;
      for (size_t c = 0; c < ncoords; c++) decoy[(size_t)k * ncoords + c] = s->coords[c] + shift;
    }
  }
  nbs_detect_def ddef = nbs_default_detect_def();
  ddef.algorithm = alg;
  ddef.fresh = o->fresh;
  uint64_t rng = 12345;
  reset_peak_rss();
  long long rss_base = proc_status_bytes("VmRSS:");
  nbs_context *ctx = NULL;
  nbs_context_def cdef = nbs_default_context_def();
  cdef.threads = o->threads;
  nbs_status st = nbs_context_create(&cdef, &ctx);
  nbs_context *dctx = NULL;
  nbs_detect_def dfresh = ddef;
  dfresh.fresh = 1;
  if (st == NBS_OK && decoy) st = nbs_context_create(&cdef, &dctx);
  nbs_context *failing = dctx; /* the context whose error a failure reports */
  double best = -1.0, spent = 0.0;
  /* the fastest of each part of the detection over the repeats (nbs_stats): the input's
   * check, the algorithm's preparation, the search */
  double part[3] = {-1.0, -1.0, -1.0};
  int done = 0;
  while (st == NBS_OK && (done < o->repeats || (!moving && spent < o->min_time))) {
    if (moving && done > 0) scene_step(moving, ncoords, o->move * s->diameter, &rng);
    for (int k = 0; k < o->decoys && st == NBS_OK; k++) {
      nbs_input din = in;
      din.coords = decoy + (size_t)k * ncoords;
      st = nbs_detect(dctx, &din, &dfresh);
    }
    if (st != NBS_OK) break;
    failing = ctx;
    double t0 = now_seconds();
    st = nbs_detect(ctx, &in, &ddef);
    double t = now_seconds() - t0;
    spent += t;
    if (best < 0 || t < best) best = t;
    nbs_stats ps;
    if (st == NBS_OK && nbs_last_stats(ctx, &ps) == NBS_OK) {
      const double p[3] = {ps.seconds_input, ps.seconds - ps.seconds_input - ps.seconds_search,
                           ps.seconds_search};
      for (int k = 0; k < 3; k++) {
        if (part[k] < 0 || p[k] < part[k]) part[k] = p[k];
      }
    }
    done++;
  }
  long long rss_extra = proc_status_bytes("VmHWM:") - rss_base;
  char name[64];
  snprintf(name, sizeof name, "%s%s", nbs_algorithm_name(alg), moving ? "-steps" : "");
  if (o->threads != 1) {
    size_t len = strlen(name);
    snprintf(name + len, sizeof name - len, "-%dt", o->threads);
  }
  int failed = 0;
  if (st != NBS_OK) {
    const char *why = failing ? nbs_context_error(failing) : nbs_status_message(st);
    /* Spaces would break the key=value line: the reason goes to stderr. */
    fprintf(stderr, "nbs_bench: %s: %s\n", name, why);
    printf("tool=nbs-%s status=%s n=%lld dim=%d\n", name, nbs_status_name(st), (long long)s->n,
           s->dim);
    failed = !(st == NBS_ERR_BUDGET || st == NBS_ERR_EXTENT);
  } else {
    size_t count = 0;
    const nbs_pair *pairs = nbs_pairs(ctx, &count);
    nbs_stats stats;
    nbs_last_stats(ctx, &stats);
    const unsigned long long hash = pairs_hash(pairs, count);
    const double per = s->n > 0 ? 1e9 / (double)s->n : 0.0; /* seconds to ns per element */
    char decoys[32] = "";
    if (o->decoys > 0) snprintf(decoys, sizeof decoys, " decoys=%d", o->decoys);
    /* after time steps: the same coordinates from scratch must give the same bytes */
    char same[32] = "";
    if (moving) {
      nbs_context *fctx = NULL;
      nbs_detect_def fdef = ddef;
      fdef.fresh = 1;
      size_t fcount = 0;
      int equal = nbs_context_create(&cdef, &fctx) == NBS_OK &&
                  nbs_detect(fctx, &in, &fdef) == NBS_OK;
      const nbs_pair *fpairs = equal ? nbs_pairs(fctx, &fcount) : NULL;
      equal = equal && fcount == count && pairs_hash(fpairs, fcount) == hash;
      nbs_context_destroy(fctx);
      snprintf(same, sizeof same, " same_as_fresh=%d", equal);
      failed = !equal;
    }
    printf("tool=nbs-%s status=ok seconds=%.9g ns_per_element=%.6g pairs=%zu ran=%s "
           "peak_bytes=%zu work_bytes=%zu pair_bytes=%zu rss_extra_bytes=%lld repeats=%d "
           "candidates=%llu compressed=%d hash=%016llx threads=%d reused=%d moved=%lld%s "
           "input_ns=%.4g prepare_ns=%.4g search_ns=%.4g n=%lld dim=%d%s\n",
           name, best, s->n > 0 ? 1e9 * best / (double)s->n : 0.0, count,
           nbs_algorithm_name(stats.algorithm), nbs_context_peak_bytes(ctx), stats.work_bytes,
           stats.pair_bytes, rss_extra, done, (unsigned long long)stats.candidates,
           stats.compressed, hash, o->threads, stats.reused_order, (long long)stats.moved, same,
           per * part[0], per * part[1], per * part[2], (long long)s->n, s->dim, decoys);
  }
  fflush(stdout);
  nbs_context_destroy(ctx);
  nbs_context_destroy(dctx);
  free(decoy);
  free(moving);
  return failed;
}

int main(int argc, char **argv) {
  options o;
  memset(&o, 0, sizeof o);
  if (parse_args(argc, argv, &o) != 0) return 2;

  scene s;
  char err[256];
  if (o.file) {
    if (read_scene_file(o.file, o.def.dim, o.def.diameter, &s) != 0) return 2;
  } else {
    int kind = scene_kind_from_name(o.scene_name);
    if (kind < 0) {
      fprintf(stderr, "nbs_bench: unknown scene %s\n", o.scene_name);
      return 2;
    }
    o.def.kind = (scene_kind)kind;
    if (scene_generate(&o.def, &s, err, sizeof err) != 0) {
      fprintf(stderr, "nbs_bench: %s\n", err);
      return 2;
    }
  }
  if (o.write && write_scene_file(o.write, &s) != 0) {
    scene_free(&s);
    return 2;
  }

  int failures = 0;
  char list[512] = "";
  if (o.algorithms) {
    snprintf(list, sizeof list, "%s", o.algorithms);
  } else {
    for (int k = 0; k < NBS_ALGORITHM_COUNT; k++) { /* auto is 0: first */
      const char *nm = nbs_algorithm_name((nbs_algorithm)k);
      if (!nm) continue;
      size_t len = strlen(list);
      snprintf(list + len, sizeof list - len, "%s%s", len ? "," : "", nm);
    }
  }
  for (char *save = NULL, *tok = strtok_r(list, ",", &save); tok;
       tok = strtok_r(NULL, ",", &save)) {
    if (strcmp(tok, "none") == 0) continue;
    nbs_algorithm alg;
    if (nbs_algorithm_from_name(tok, &alg) != NBS_OK) {
      fprintf(stderr, "nbs_bench: unknown algorithm %s\n", tok);
      failures++;
      continue;
    }
    if (alg == NBS_DIRECT && !o.algorithms && s.n > o.direct_max) continue;
    failures += run_algorithm(alg, &s, &o);
  }
  scene_free(&s);
  return failures ? 1 : 0;
}
