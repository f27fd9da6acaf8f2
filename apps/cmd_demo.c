/*
 * nbs demo: every algorithm side by side on a million spheres (3D) and a million circles
 * (2D), checked against each other, with a ParaView file of the contact network and a
 * picture.
 *
 * Each algorithm runs with a context of its own (so the bytes are its own), --repeat times,
 * and reports its fastest run. Direct, which checks every pair, runs on a window of each
 * scene holding about --subsample elements, and every other algorithm runs on that window
 * too, so that all are compared with the reference on the same elements. Agreement means
 * the same sorted pair list: the same count and the same FNV-1a hash.
 * Every run of the table is a detection from scratch. Below it, auto runs time steps on each
 * whole scene: every element moves by up to 1e-3 diameters per axis before each detection,
 * one context throughout, as in a simulation, where the library starts from the last step's
 * cell order; the last step's pairs must be the bytes, in order, of a fresh detection.
 */
#include "args.h"
#include "cli.h"
#include "scenes.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static const char cli_demo_help[] =
    "Usage: nbs demo [options]\n"
    "\n"
    "Generates a 3D scene of 1,000,000 spheres and a 2D scene of 1,000,000 circles (uniform\n"
    "random, volume or area fraction 0.5, diameter 1), runs every algorithm of the library\n"
    "on them, checks that all find the same contacts, and prints one table: algorithm,\n"
    "pairs, time, ns per element, the library's bytes and agreement. Direct, whose time is\n"
    "quadratic, runs on a window of each scene (--subsample elements), where every other\n"
    "algorithm runs too. Screening runs where its cell array fits the cell budget.\n"
    "Every run of the table sorts from scratch; below it, auto runs --repeat time steps on\n"
    "each whole scene (every element moved by up to 0.001 diameters per axis before each\n"
    "detection, one context, as in a simulation) and says whether the last step's pairs are\n"
    "those of a detection from scratch.\n"
    "Writes a ParaView file (.vtp) of the 3D window with its contact network, and a PNG of\n"
    "a window of the 2D scene with its circles and contact lines, and prints where they are.\n"
    "\n"
    "Options:\n"
    "  --n N               elements of each scene (default 1000000)\n"
    "  --subsample M       elements of the window where direct runs (default 20000)\n"
    "  --repeat K          runs of each algorithm; the fastest is reported (default 3)\n"
    "  --out DIR           where to write the pictures (default nbs-demo)\n"
    "  --png-size PX       width and height of the PNG (default 1024)\n"
    "  --png-circles C     about how many circles the PNG shows (default 1200)\n"
    "  --seed S            random seed of the scenes (default 1)\n"
    "  --threads T         threads for the algorithms that use them (default: the cores)\n"
    "  --cell-budget BYTES the library's cell budget (default 1 GiB)\n"
    "  --vtp-encoding E    appended (default), base64 or ascii; --no-compress: no zlib\n"
    "  -q, --quiet         no progress bar\n"
    "\n"
    "Exit status: 0 when every algorithm agrees, 1 when one does not, 4 out of memory.\n"
    "\n"
    "Examples:\n"
    "  nbs demo\n"
    "  nbs demo --n 20000 --out /tmp/demo --png-size 400\n";

typedef struct cli_demo_opts {
  int64_t n, subsample, repeat, circles, seed;
  int png_size, threads;
  size_t budget;
  const char *out;
  cli_vtp_opts vtp;
} cli_demo_opts;

typedef struct cli_demo_row {
  char scene[32];
  char algorithm[32];
  int64_t n;
  nbs_status status;
  char error[256];
  uint64_t pairs;
  double seconds;
  size_t bytes;
  uint64_t hash;
  bool agrees;
} cli_demo_row;

/* Runs one algorithm on e; fills row. When keep is not NULL it receives the sorted pairs. */
static int cli_demo_run(const cli_demo_opts *o, const cli_elements *e, nbs_algorithm a,
                        cli_demo_row *row, nbs_pair **keep, size_t *kept) {
  nbs_context_def cdef = nbs_default_context_def();
  cdef.cell_budget = o->budget;
  cdef.threads = o->threads;
  nbs_context *ctx;
  nbs_status s = nbs_context_create(&cdef, &ctx);
  if (s != NBS_OK) return cli_fail(cli_status_code(s), "cannot create a context: %s", nbs_status_message(s));
  nbs_input in = {.dim = e->dim, .n = e->n, .coords = e->coords, .radii = e->radii,
                  .diameter = e->diameter};
  nbs_detect_def def = nbs_default_detect_def();
  def.algorithm = a;
  /* the same elements again are not a time step: each run sorts from scratch */
  def.fresh = 1;
  row->n = e->n;
  row->seconds = INFINITY;
  for (int64_t r = 0; r < o->repeat; r++) {
    double t0 = cli_now();
    s = nbs_detect(ctx, &in, &def);
    double t = cli_now() - t0;
    if (s != NBS_OK) break;
    if (t < row->seconds) row->seconds = t;
  }
  row->status = s;
  nbs_stats st;
  nbs_last_stats(ctx, &st);
  if (s != NBS_OK) {
    snprintf(row->error, sizeof row->error, "%s", nbs_context_error(ctx));
    nbs_context_destroy(ctx);
    /* Over a budget or a limit is a row of the table; out of memory ends the demo. */
    return s == NBS_ERR_NOMEM ? cli_fail(CLI_RESOURCE, "%s: %s", nbs_algorithm_name(a), row->error)
                              : CLI_OK;
  }
  if (a == NBS_AUTO) {
    snprintf(row->algorithm, sizeof row->algorithm, "auto (%s)", nbs_algorithm_name(st.algorithm));
  }
  row->bytes = nbs_context_peak_bytes(ctx);
  size_t count;
  bool ok;
  nbs_pair *pairs = cli_sorted_pairs(ctx, &count, &ok);
  nbs_context_destroy(ctx);
  if (!ok) return cli_fail(CLI_RESOURCE, "out of memory sorting the pairs");
  row->pairs = count;
  row->hash = cli_pairs_hash(pairs, count);
  if (keep) {
    *keep = pairs;
    *kept = count;
  } else {
    free(pairs);
  }
  return CLI_OK;
}

/* The elements whose centres lie in the cube (square) [lo, lo + w), in their order. */
static int cli_demo_window(const cli_elements *e, const double lo[3], double w, cli_elements *out) {
  memset(out, 0, sizeof *out);
  int64_t m = 0;
  const int dim = e->dim;
  for (int pass = 0; pass < 2; pass++) {
    if (pass == 1) {
      out->coords = malloc((size_t)(m > 0 ? m : 1) * (size_t)dim * sizeof(double));
      out->radii = e->radii ? malloc((size_t)(m > 0 ? m : 1) * sizeof(double)) : NULL;
      if (!out->coords || (e->radii && !out->radii)) {
        cli_elements_free(out);
        return cli_fail(CLI_RESOURCE, "out of memory for a window of %lld elements", (long long)m);
      }
      m = 0;
    }
    for (int64_t k = 0; k < e->n; k++) {
      const double *x = e->coords + k * dim;
      bool in = true;
      for (int a = 0; a < dim; a++) in = in && x[a] >= lo[a] && x[a] < lo[a] + w;
      if (!in) continue;
      if (pass == 1) {
        memcpy(out->coords + m * dim, x, (size_t)dim * sizeof(double));
        if (e->radii) out->radii[m] = e->radii[k];
      }
      m++;
    }
  }
  out->dim = dim;
  out->n = m;
  out->diameter = e->diameter;
  return CLI_OK;
}

/* Bounding box of a scene. */
static void cli_demo_box(const cli_elements *e, double lo[3], double hi[3]) {
  for (int a = 0; a < 3; a++) {
    lo[a] = 0;
    hi[a] = 0;
  }
  for (int64_t k = 0; k < e->n; k++) {
    for (int a = 0; a < e->dim; a++) {
      double v = e->coords[k * e->dim + a];
      if (k == 0 || v < lo[a]) lo[a] = v;
      if (k == 0 || v > hi[a]) hi[a] = v;
    }
  }
}

/* A cube (square) in the middle of the scene expected to hold about m of its n elements. */
static void cli_demo_window_of(const cli_elements *e, int64_t m, double lo[3], double *w) {
  double blo[3], bhi[3];
  cli_demo_box(e, blo, bhi);
  double frac = e->n > 0 ? (double)m / (double)e->n : 1.0;
  if (frac > 1) frac = 1;
  double edge = bhi[0] - blo[0];
  *w = edge * pow(frac, 1.0 / e->dim) * (1.0 + 1e-9);
  if (frac >= 1) *w = edge * 1.01 + 1.0;
  for (int a = 0; a < 3; a++) {
    double mid = 0.5 * (blo[a] + bhi[a]);
    lo[a] = frac >= 1 ? blo[a] : mid - 0.5 * *w;
  }
}

static void cli_demo_print_row(const cli_demo_row *r) {
  if (r->status != NBS_OK) {
    printf("  %-20s %-17s %9lld  %s\n", r->scene, r->algorithm, (long long)r->n,
           r->status == NBS_ERR_BUDGET ? "not run: its cell array exceeds the cell budget"
                                       : r->error);
    return;
  }
  char b[32];
  cli_format_bytes(b, sizeof b, (double)r->bytes);
  printf("  %-20s %-17s %9lld %10llu %9.1f %8.1f %12s  %s\n", r->scene, r->algorithm,
         (long long)r->n, (unsigned long long)r->pairs, r->seconds * 1e3,
         r->n > 0 ? r->seconds * 1e9 / (double)r->n : 0.0, b, r->agrees ? "yes" : "NO");
}

/* Runs every algorithm on one scene (direct only when with_direct) and appends the rows;
 * the agreement is with the first row that ran. */
static int cli_demo_scene(const cli_demo_opts *o, const char *label, const cli_elements *e,
                          bool with_direct, cli_demo_row *rows, int *nrows, int maxrows,
                          cli_progress *prog, int *step, int steps, nbs_pair **keep,
                          size_t *kept) {
  int first = *nrows;
  for (int k = 0; nbs_algorithm_name((nbs_algorithm)k) && *nrows < maxrows; k++) {
    nbs_algorithm a = (nbs_algorithm)k;
    if (a == NBS_DIRECT && !with_direct) continue;
    /* On the window, direct is the reference: it goes first. */
    if (with_direct && k == 0) a = NBS_DIRECT;
    else if (with_direct && k == NBS_DIRECT) a = NBS_AUTO;
    cli_demo_row *r = &rows[(*nrows)++];
    memset(r, 0, sizeof *r);
    snprintf(r->scene, sizeof r->scene, "%s", *nrows - 1 == first ? label : "");
    snprintf(r->algorithm, sizeof r->algorithm, "%s", nbs_algorithm_name(a));
    bool want = keep && *nrows - 1 == first;
    int code = cli_demo_run(o, e, a, r, want ? keep : NULL, want ? kept : NULL);
    if (code != CLI_OK) return code;
    cli_progress_update(prog, ++*step);
    (void)steps;
  }
  const cli_demo_row *ref = NULL;
  for (int k = first; k < *nrows; k++) {
    if (rows[k].status != NBS_OK) continue;
    if (!ref) ref = &rows[k];
    rows[k].agrees = rows[k].pairs == ref->pairs && rows[k].hash == ref->hash;
  }
  return CLI_OK;
}

/* Time steps (see the file comment): how far each element moves per axis and step, in
 * diameters. */
#define CLI_DEMO_STEP 1e-3

typedef struct cli_demo_steps_result {
  bool ran;
  nbs_status status;
  char algorithm[16];
  double seconds;   /* the fastest step */
  int64_t moved;    /* elements sorted again in the last step */
  int reused;       /* the last step started from the step before's order */
  bool same;        /* its pairs are the bytes of a detection from scratch */
  double fresh_ns;  /* ns per element of auto from scratch, the table's row */
} cli_demo_steps_result;

static int cli_demo_steps(const cli_demo_opts *o, const cli_elements *e,
                          cli_demo_steps_result *res) {
  memset(res, 0, sizeof *res);
  res->ran = true;
  res->seconds = INFINITY;
  const size_t count = (size_t)e->n * (size_t)e->dim;
  double *x = malloc((count ? count : 1) * sizeof *x);
  if (!x) return cli_fail(CLI_RESOURCE, "out of memory for the time steps");
  if (count) memcpy(x, e->coords, count * sizeof *x);
  nbs_context_def cdef = nbs_default_context_def();
  cdef.cell_budget = o->budget;
  cdef.threads = o->threads;
  nbs_context *ctx = NULL, *fresh = NULL;
  nbs_status s = nbs_context_create(&cdef, &ctx);
  if (s == NBS_OK) s = nbs_context_create(&cdef, &fresh);
  nbs_input in = {.dim = e->dim, .n = e->n, .coords = x, .radii = e->radii,
                  .diameter = e->diameter};
  nbs_detect_def def = nbs_default_detect_def();
  uint64_t rng = (uint64_t)o->seed + 7;
  const double step = CLI_DEMO_STEP * e->diameter;
  if (s == NBS_OK) s = nbs_detect(ctx, &in, &def); /* the first step sorts from scratch */
  for (int64_t r = 0; r < o->repeat && s == NBS_OK; r++) {
    scene_step(x, count, step, &rng);
    double t0 = cli_now();
    s = nbs_detect(ctx, &in, &def);
    double t = cli_now() - t0;
    if (t < res->seconds) res->seconds = t;
  }
  if (s == NBS_OK) {
    nbs_stats st;
    nbs_last_stats(ctx, &st);
    res->moved = st.moved;
    res->reused = st.reused_order;
    snprintf(res->algorithm, sizeof res->algorithm, "%s", nbs_algorithm_name(st.algorithm));
    nbs_detect_def fdef = def;
    fdef.fresh = 1;
    s = nbs_detect(fresh, &in, &fdef);
    size_t c1 = 0, c2 = 0;
    const nbs_pair *p1 = nbs_pairs(ctx, &c1), *p2 = s == NBS_OK ? nbs_pairs(fresh, &c2) : NULL;
    res->same = s == NBS_OK && c1 == c2 && (c1 == 0 || memcmp(p1, p2, c1 * sizeof *p1) == 0);
  }
  res->status = s;
  nbs_context_destroy(ctx);
  nbs_context_destroy(fresh);
  free(x);
  if (s == NBS_ERR_NOMEM) return cli_fail(CLI_RESOURCE, "time steps: out of memory");
  return CLI_OK;
}

static int cli_demo_mkdir(const char *dir) {
  if (mkdir(dir, 0777) == 0 || errno == EEXIST) {
    struct stat st;
    if (stat(dir, &st) == 0 && S_ISDIR(st.st_mode)) return CLI_OK;
  }
  return cli_fail(CLI_RESOURCE, "%s: cannot create the directory: %s", dir, strerror(errno));
}

int cli_demo(int argc, char **argv) {
  const char *cmd = "demo";
  cli_demo_opts o = {1000000, 20000, 3, 1200, 1, 1024, 0, NBS_DEFAULT_CELL_BUDGET, "nbs-demo",
                     {CLI_VTP_APPENDED, true}};
  cli_args a = {argc, argv, 1, cmd, NULL, false};
  for (; a.k < argc; a.k++) {
    const char *arg = argv[a.k];
    int64_t v;
    if (cli_flag(&a, "--help", "-h")) {
      fputs(cli_demo_help, stdout);
      return CLI_OK;
    } else if (cli_flag(&a, "--quiet", "-q")) {
      cli_quiet = true;
    } else if (cli_opt(&a, "--n")) {
      if (a.missing || !cli_parse_int64(a.val, &o.n) || o.n < 2 || o.n > INT32_MAX) {
        return cli_usage(cmd, "--n %s: give a count from 2 to 2^31 - 1", a.missing ? "" : a.val);
      }
    } else if (cli_opt(&a, "--subsample")) {
      if (a.missing || !cli_parse_int64(a.val, &o.subsample) || o.subsample < 2 ||
          o.subsample > 1000000) {
        return cli_usage(cmd, "--subsample %s: give a count from 2 to 1000000", a.missing ? "" : a.val);
      }
    } else if (cli_opt(&a, "--repeat")) {
      if (a.missing || !cli_parse_int64(a.val, &o.repeat) || o.repeat < 1 || o.repeat > 1000) {
        return cli_usage(cmd, "--repeat %s: give a count from 1 to 1000", a.missing ? "" : a.val);
      }
    } else if (cli_opt(&a, "--png-size")) {
      if (a.missing || !cli_parse_int64(a.val, &v) || v < 16 || v > 16384) {
        return cli_usage(cmd, "--png-size %s: give 16 to 16384 pixels", a.missing ? "" : a.val);
      }
      o.png_size = (int)v;
    } else if (cli_opt(&a, "--png-circles")) {
      if (a.missing || !cli_parse_int64(a.val, &o.circles) || o.circles < 1) {
        return cli_usage(cmd, "--png-circles %s: give a count >= 1", a.missing ? "" : a.val);
      }
    } else if (cli_opt(&a, "--seed")) {
      if (a.missing || !cli_parse_int64(a.val, &o.seed)) {
        return cli_usage(cmd, "--seed %s: give an integer >= 0", a.missing ? "" : a.val);
      }
    } else if (cli_opt(&a, "--threads")) {
      if (a.missing || !cli_parse_int64(a.val, &v) || v > 1024) {
        return cli_usage(cmd, "--threads %s: give 0 (the cores) to 1024", a.missing ? "" : a.val);
      }
      o.threads = (int)v;
    } else if (cli_opt(&a, "--cell-budget")) {
      if (a.missing || !cli_parse_int64(a.val, &v)) {
        return cli_usage(cmd, "--cell-budget %s: give a number of bytes", a.missing ? "" : a.val);
      }
      o.budget = (size_t)v;
    } else if (cli_opt(&a, "--out")) {
      if (a.missing || !*a.val) return cli_usage(cmd, "--out needs a directory");
      o.out = a.val;
    } else if (cli_opt(&a, "--vtp-encoding")) {
      if (a.missing) return cli_usage(cmd, "--vtp-encoding needs appended, base64 or ascii");
      if (strcmp(a.val, "appended") == 0) o.vtp.encoding = CLI_VTP_APPENDED;
      else if (strcmp(a.val, "base64") == 0) o.vtp.encoding = CLI_VTP_BASE64;
      else if (strcmp(a.val, "ascii") == 0) o.vtp.encoding = CLI_VTP_ASCII;
      else return cli_usage(cmd, "--vtp-encoding %s: use appended, base64 or ascii", a.val);
    } else if (cli_flag(&a, "--no-compress", NULL)) {
      o.vtp.compress = false;
    } else {
      return cli_usage(cmd, arg[0] == '-' ? "unknown option '%s'" : "unexpected argument '%s'", arg);
    }
  }
  const double t_start = cli_now();
  int code = cli_demo_mkdir(o.out);
  if (code != CLI_OK) return code;

  int nalg = 0;
  while (nbs_algorithm_name((nbs_algorithm)nalg)) nalg++;
  const int steps = 2 + 2 * (nalg - 1) + 2 * nalg + 2 + 2;
  int step = 0;
  cli_progress prog;
  cli_progress_begin(&prog, "demo", steps);

  enum { MAXROWS = 64 };
  cli_demo_row rows[MAXROWS];
  int nrows = 0;
  scene sc[2];
  memset(sc, 0, sizeof sc);
  cli_elements full[2], win[2];
  memset(win, 0, sizeof win);
  nbs_pair *win3_pairs = NULL, *pic_pairs = NULL;
  size_t win3_count = 0, pic_count = 0;
  cli_elements pic;
  memset(&pic, 0, sizeof pic);
  cli_demo_steps_result timesteps[2];
  memset(timesteps, 0, sizeof timesteps);
  /* The paths are printed in full, so that they can be opened from anywhere. */
  char vtp_path[4096 + 16], png_path[4096 + 16], dir[4096];
  if (!realpath(o.out, dir)) snprintf(dir, sizeof dir, "%s", o.out);
  snprintf(vtp_path, sizeof vtp_path, "%s/demo3d.vtp", dir);
  snprintf(png_path, sizeof png_path, "%s/demo2d.png", dir);

  for (int s = 0; s < 2 && code == CLI_OK; s++) {
    const int dim = s == 0 ? 3 : 2;
    scene_def def = scene_default_def();
    def.kind = SCENE_UNIFORM;
    def.dim = dim;
    def.n = o.n;
    def.seed = (uint64_t)o.seed;
    def.fraction = 0.5;
    def.diameter = 1.0;
    def.sorted = 1; /* the order a DEM code keeps its elements in */
    char err[256];
    if (scene_generate(&def, &sc[s], err, sizeof err) != 0) {
      code = cli_fail(strstr(err, "memory") ? CLI_RESOURCE : CLI_FAIL, "demo: %s", err);
      break;
    }
    cli_progress_update(&prog, ++step);
    full[s] = (cli_elements){sc[s].dim, sc[s].n, sc[s].coords, sc[s].radii, sc[s].diameter};
    char label[32];
    snprintf(label, sizeof label, "%dD uniform", dim);
    const int auto_row = nrows; /* auto runs first on a whole scene */
    code = cli_demo_scene(&o, label, &full[s], false, rows, &nrows, MAXROWS, &prog, &step, steps,
                          NULL, NULL);
    if (code != CLI_OK) break;
    code = cli_demo_steps(&o, &full[s], &timesteps[s]);
    if (code != CLI_OK) break;
    if (rows[auto_row].status == NBS_OK && full[s].n > 0) {
      timesteps[s].fresh_ns = rows[auto_row].seconds * 1e9 / (double)full[s].n;
    }
    cli_progress_update(&prog, ++step);
    double lo[3], w;
    cli_demo_window_of(&full[s], o.subsample, lo, &w);
    code = cli_demo_window(&full[s], lo, w, &win[s]);
    if (code != CLI_OK) break;
    snprintf(label, sizeof label, "%dD window", dim);
    code = cli_demo_scene(&o, label, &win[s], true, rows, &nrows, MAXROWS, &prog, &step, steps,
                          s == 0 ? &win3_pairs : NULL, s == 0 ? &win3_count : NULL);
    if (code != CLI_OK) break;
    if (s == 1) {
      /* The picture: a smaller window of the 2D scene. */
      cli_demo_window_of(&full[s], o.circles, lo, &w);
      code = cli_demo_window(&full[s], lo, w, &pic);
      if (code != CLI_OK) break;
      cli_demo_row r;
      memset(&r, 0, sizeof r);
      cli_demo_opts once = o;
      once.repeat = 1;
      code = cli_demo_run(&once, &pic, NBS_AUTO, &r, &pic_pairs, &pic_count);
      if (code == CLI_OK && r.status != NBS_OK) code = cli_fail(CLI_FAIL, "demo: %s", r.error);
      if (code == CLI_OK) code = cli_draw_png(png_path, &pic, pic_pairs, pic_count, lo[0], lo[1], w, o.png_size);
      cli_progress_update(&prog, ++step);
    } else {
      code = cli_write_vtp(vtp_path, &o.vtp, &win[s], win3_pairs, win3_count);
      cli_progress_update(&prog, ++step);
    }
  }
  cli_progress_end(&prog);

  bool all_agree = true;
  if (nrows > 0) {
    printf("nbs demo: %lld spheres (3D) and %lld circles (2D), uniform random, volume/area "
           "fraction 0.5,\ndiameter 1, ordered along their cells; fastest of %lld runs; library "
           "%s\n\n", (long long)o.n, (long long)o.n, (long long)o.repeat, nbs_version());
    printf("  %-20s %-17s %9s %10s %9s %8s %12s  %s\n", "scene", "algorithm", "elements", "pairs",
           "time ms", "ns/elem", "lib. bytes", "agrees");
    for (int k = 0; k < nrows; k++) {
      if (k > 0 && rows[k].scene[0]) printf("\n");
      cli_demo_print_row(&rows[k]);
      if (rows[k].status == NBS_OK && !rows[k].agrees) all_agree = false;
    }
    printf("\n");
  }
  for (int s = 0; s < 2 && code == CLI_OK; s++) {
    const cli_demo_steps_result *t = &timesteps[s];
    if (!t->ran) continue;
    if (t->status != NBS_OK) {
      printf("time steps, %dD: %s\n", s == 0 ? 3 : 2, nbs_status_name(t->status));
      all_agree = false;
      continue;
    }
    const double ns = full[s].n > 0 ? t->seconds * 1e9 / (double)full[s].n : 0.0;
    printf("time steps, %dD: auto (%s), every element moved by up to %g diameters per axis "
           "before each detection:\n  %.1f ns per element (fastest of %lld steps; %.1f from "
           "scratch above), %lld elements sorted again in the last\n  step (%s); %s\n",
           s == 0 ? 3 : 2, t->algorithm, CLI_DEMO_STEP, ns, (long long)o.repeat, t->fresh_ns,
           (long long)t->moved, t->reused ? "from the step before's order" : "from scratch",
           t->same ? "its pairs are those of a detection from scratch, byte for byte"
                   : "FAILED: its pairs differ from a detection from scratch");
    if (!t->same) all_agree = false;
  }
  if (code == CLI_OK && (timesteps[0].ran || timesteps[1].ran)) printf("\n");
  if (code == CLI_OK) {
    printf("%s\n", all_agree ? "agreement: on every scene, every algorithm found the same "
                               "sorted pair list (same count, same FNV-1a hash)"
                             : "agreement: FAILED: some algorithm found other pairs (NO above)");
    printf("wrote %s: %lld spheres (points with a radius array) and %zu contacts (lines) of the "
           "3D window, for ParaView\n", vtp_path, (long long)win[0].n, win3_count);
    printf("wrote %s: %d x %d pixels, %lld circles and %zu contacts of the 2D scene\n", png_path,
           o.png_size, o.png_size, (long long)pic.n, pic_count);
    printf("done in %.1f s\n", cli_now() - t_start);
  }
  free(win3_pairs);
  free(pic_pairs);
  cli_elements_free(&pic);
  for (int s = 0; s < 2; s++) {
    cli_elements_free(&win[s]);
    scene_free(&sc[s]);
  }
  if (code != CLI_OK) return code;
  return all_agree ? CLI_OK : CLI_FAIL;
}
