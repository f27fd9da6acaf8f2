/*
 * nbs detect: read elements, find the contacting pairs, write them.
 */
#include "args.h"
#include "cli.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static const char cli_detect_help[] =
    "Usage: nbs detect --input FILE [options]\n"
    "\n"
    "Finds every pair of elements whose circles (2D) or spheres (3D) touch:\n"
    "|xi - xj| <= ri + rj. Pairs are 0-based element indices in file order, i < j, sorted\n"
    "by i then j.\n"
    "\n"
    "Input:\n"
    "  --input FILE        elements; '-' reads standard input. The format is recognised from\n"
    "                      the content or the extension:\n"
    "                        CSV   one element per line: x,y[,z][,radius]; a header line is\n"
    "                              allowed (columns x, y, z, radius or diameter by name);\n"
    "                              commas, semicolons or blanks separate values; # comments\n"
    "                        f64   raw little-endian doubles, D (or D+1 with the radius) per\n"
    "                              element\n"
    "                        dump  LAMMPS/LIGGGHTS text dump: ITEM: ATOMS id type x y z radius\n"
    "                        vtk   legacy VTK (ASCII or BINARY) with a radius point array\n"
    "                        vtp   VTK XML PolyData: ascii, base64 or appended raw, zlib or not\n"
    "  --format NAME       csv, f64, dump, vtk or vtp: do not guess\n"
    "  --dim 2|3           dimension: needed for f64, and for CSV without a header naming\n"
    "                      x, y (and z for 3D); dump and VTK files are 3D unless --dim 2\n"
    "                      drops z\n"
    "  --diameter D        every element has diameter D (radii in the file are ignored);\n"
    "                      without it, the radius comes from the file\n"
    "  --columns LIST      CSV columns as x,y[,z][,radius] by header name or 1-based index,\n"
    "                      with --dim: e.g. --dim 3 --columns 2,3,4,6, or px,py,pz,rad\n"
    "  --radius NAME       dump/VTK: the radius column or array (default radius, then\n"
    "                      diameter, halved)\n"
    "  --snapshot K        dump: the K-th snapshot, 0-based, or 'last' (default 0)\n"
    "  --timestep T        dump: the snapshot of timestep T\n"
    "\n"
    "Detection:\n"
    "  --algorithm NAME    direct, screening, sorting, nbs or auto (default auto)\n"
    "  --candidates        report every pair the algorithm's cell mask yields instead of\n"
    "                      the contacts (a superset that depends on the algorithm)\n"
    "  --repeat K          detect K times with one context, each from scratch; report the\n"
    "                      fastest (default 1)\n"
    "  --cell-budget BYTES largest cell array the library may allocate (default 1 GiB)\n"
    "  --max-pairs N       stop with exit 4 past N pairs (default: what a quarter of the\n"
    "                      machine's memory holds; 0: no limit)\n"
    "  --threads T         threads for the algorithms that use them (0, the default: the\n"
    "                      cores; the pairs do not depend on it)\n"
    "\n"
    "Output:\n"
    "  --output FILE       the pairs; without it, print 'pairs: N'\n"
    "  --pairs-format F    csv (one 'i,j' per line, the default), u32 or u64 (raw\n"
    "                      little-endian pairs of unsigned integers)\n"
    "  --vtp FILE          the elements and their contacts (lines) as ParaView XML PolyData\n"
    "  --vtp-encoding E    appended (raw, the default), base64 or ascii\n"
    "  --no-compress       do not zlib-compress the .vtp's binary data\n"
    "  --stats             one JSON object on stderr: algorithm, dim, n, pairs, seconds,\n"
    "                      ns_per_element, bytes, candidates, cells, compressed, work_bytes,\n"
    "                      input_seconds and search_seconds (the last detection's check of\n"
    "                      the input, and its search once every element was in place)...\n"
    "  -q, --quiet         no progress bar (shown on a terminal for work over a second)\n"
    "\n"
    "Exit status: 0 success, 2 usage error, 3 bad input (FILE:LINE:COLUMN: message),\n"
    "4 out of memory or over a limit, 1 other failure.\n"
    "\n"
    "Examples:\n"
    "  nbs generate uniform --n 100000 --output spheres.csv\n"
    "  nbs detect --input spheres.csv --dim 3 --output pairs.csv --stats\n"
    "  nbs detect --input dump.liggghts --snapshot last --vtp contacts.vtp\n";

typedef struct cli_detect_opts {
  const char *input;
  const char *output;
  const char *vtp;
  cli_read_opts read;
  nbs_algorithm algorithm;
  bool candidates;
  bool stats;
  int64_t repeat;
  size_t cell_budget;
  int64_t max_pairs; /* -1: the default */
  int threads;
  cli_pairs_format pairs_format;
  cli_vtp_opts vtp_opts;
} cli_detect_opts;

static int cli_detect_parse(int argc, char **argv, cli_detect_opts *o, bool *help) {
  memset(o, 0, sizeof *o);
  o->read = cli_default_read_opts();
  o->algorithm = NBS_AUTO;
  o->repeat = 1;
  o->cell_budget = NBS_DEFAULT_CELL_BUDGET;
  o->max_pairs = -1;
  o->pairs_format = CLI_PAIRS_CSV;
  o->vtp_opts.encoding = CLI_VTP_APPENDED;
  o->vtp_opts.compress = true;
  *help = false;
  const char *cmd = "detect";
  cli_args a = {argc, argv, 1, cmd, NULL, false};
  for (; a.k < argc; a.k++) {
    const char *arg = argv[a.k];
    if (cli_flag(&a, "--help", "-h")) {
      *help = true;
      return CLI_OK;
    } else if (cli_opt(&a, "--input") || cli_opt(&a, "-i")) {
      if (a.missing) return cli_usage(cmd, "%s needs a file name", arg);
      o->input = a.val;
    } else if (cli_opt(&a, "--output") || cli_opt(&a, "-o")) {
      if (a.missing) return cli_usage(cmd, "%s needs a file name", arg);
      o->output = a.val;
    } else if (cli_opt(&a, "--vtp")) {
      if (a.missing) return cli_usage(cmd, "--vtp needs a file name");
      o->vtp = a.val;
    } else if (cli_opt(&a, "--dim")) {
      if (a.missing || (strcmp(a.val, "2") != 0 && strcmp(a.val, "3") != 0)) {
        return cli_usage(cmd, "--dim %s: the dimension must be 2 or 3", a.missing ? "" : a.val);
      }
      o->read.dim = a.val[0] - '0';
    } else if (cli_opt(&a, "--diameter")) {
      double d;
      if (a.missing || !cli_parse_double(a.val, &d) || !(d > 0)) {
        return cli_usage(cmd, "--diameter %s: it must be a finite number > 0",
                         a.missing ? "" : a.val);
      }
      o->read.has_diameter = true;
      o->read.diameter = d;
    } else if (cli_opt(&a, "--algorithm")) {
      if (a.missing || nbs_algorithm_from_name(a.val, &o->algorithm) != NBS_OK) {
        return cli_usage(cmd, "unknown algorithm '%s': use direct, screening, sorting, nbs or auto",
                         a.missing ? "" : a.val);
      }
    } else if (cli_flag(&a, "--candidates", NULL)) {
      o->candidates = true;
    } else if (cli_flag(&a, "--stats", NULL)) {
      o->stats = true;
    } else if (cli_flag(&a, "--quiet", "-q")) {
      cli_quiet = true;
    } else if (cli_opt(&a, "--repeat")) {
      if (a.missing || !cli_parse_int64(a.val, &o->repeat) || o->repeat < 1 ||
          o->repeat > 1000000) {
        return cli_usage(cmd, "--repeat %s: give a count from 1 to 1000000", a.missing ? "" : a.val);
      }
    } else if (cli_opt(&a, "--cell-budget")) {
      int64_t b;
      if (a.missing || !cli_parse_int64(a.val, &b)) {
        return cli_usage(cmd, "--cell-budget %s: give a number of bytes", a.missing ? "" : a.val);
      }
      o->cell_budget = (size_t)b;
    } else if (cli_opt(&a, "--max-pairs")) {
      if (a.missing || !cli_parse_int64(a.val, &o->max_pairs)) {
        return cli_usage(cmd, "--max-pairs %s: give a count (0: no limit)", a.missing ? "" : a.val);
      }
    } else if (cli_opt(&a, "--threads")) {
      int64_t t;
      if (a.missing || !cli_parse_int64(a.val, &t) || t > 1024) {
        return cli_usage(cmd, "--threads %s: give 0 (the cores) to 1024", a.missing ? "" : a.val);
      }
      o->threads = (int)t;
    } else if (cli_opt(&a, "--format")) {
      int f = a.missing ? -1 : cli_format_from_name(a.val);
      if (f <= 0) return cli_usage(cmd, "--format %s: use csv, f64, dump, vtk or vtp", a.missing ? "" : a.val);
      o->read.format = (cli_format)f;
    } else if (cli_opt(&a, "--columns")) {
      if (a.missing) return cli_usage(cmd, "--columns needs a list such as x,y,z,radius");
      o->read.columns = a.val;
    } else if (cli_opt(&a, "--radius")) {
      if (a.missing) return cli_usage(cmd, "--radius needs a column or array name");
      o->read.radius = a.val;
    } else if (cli_opt(&a, "--snapshot")) {
      if (!a.missing && strcmp(a.val, "last") == 0) {
        o->read.snapshot = -1;
      } else if (a.missing || !cli_parse_int64(a.val, &o->read.snapshot)) {
        return cli_usage(cmd, "--snapshot %s: give an index from 0, or 'last'", a.missing ? "" : a.val);
      }
    } else if (cli_opt(&a, "--timestep")) {
      if (a.missing || !cli_parse_int64(a.val, &o->read.timestep)) {
        return cli_usage(cmd, "--timestep %s: give a timestep >= 0", a.missing ? "" : a.val);
      }
    } else if (cli_opt(&a, "--pairs-format")) {
      if (a.missing) return cli_usage(cmd, "--pairs-format needs csv, u32 or u64");
      if (strcmp(a.val, "csv") == 0) o->pairs_format = CLI_PAIRS_CSV;
      else if (strcmp(a.val, "u32") == 0) o->pairs_format = CLI_PAIRS_U32;
      else if (strcmp(a.val, "u64") == 0) o->pairs_format = CLI_PAIRS_U64;
      else return cli_usage(cmd, "--pairs-format %s: use csv, u32 or u64", a.val);
    } else if (cli_opt(&a, "--vtp-encoding")) {
      if (a.missing) return cli_usage(cmd, "--vtp-encoding needs appended, base64 or ascii");
      if (strcmp(a.val, "appended") == 0) o->vtp_opts.encoding = CLI_VTP_APPENDED;
      else if (strcmp(a.val, "base64") == 0) o->vtp_opts.encoding = CLI_VTP_BASE64;
      else if (strcmp(a.val, "ascii") == 0) o->vtp_opts.encoding = CLI_VTP_ASCII;
      else return cli_usage(cmd, "--vtp-encoding %s: use appended, base64 or ascii", a.val);
    } else if (cli_flag(&a, "--no-compress", NULL)) {
      o->vtp_opts.compress = false;
    } else if (arg[0] == '-' && arg[1] != '\0') {
      return cli_usage(cmd, "unknown option '%s'", arg);
    } else if (!o->input) {
      o->input = arg;
    } else {
      return cli_usage(cmd, "unexpected argument '%s'", arg);
    }
  }
  if (!o->input) return cli_usage(cmd, "no input: give --input FILE");
  return CLI_OK;
}

/* Runs the detection K times and reports the fastest; the context keeps the last pairs. */
static int cli_detect_run(const cli_detect_opts *o, const cli_elements *e, nbs_context *ctx,
                          double *best) {
  nbs_input in = {.dim = e->dim, .n = e->n, .coords = e->coords, .radii = e->radii,
                  .diameter = e->diameter};
  nbs_detect_def def = nbs_default_detect_def();
  def.algorithm = o->algorithm;
  def.mode = o->candidates ? NBS_MODE_CANDIDATES : NBS_MODE_CONTACTS;
  /* the same elements again are not a time step: each repeat sorts from scratch */
  def.fresh = 1;
  cli_progress prog;
  cli_progress_begin(&prog, "detecting", (double)o->repeat);
  *best = INFINITY;
  for (int64_t r = 0; r < o->repeat; r++) {
    double t0 = cli_now();
    nbs_status s = nbs_detect(ctx, &in, &def);
    double t = cli_now() - t0;
    if (s != NBS_OK) {
      cli_progress_end(&prog);
      if (s == NBS_ERR_PAIRS) {
        return cli_fail(CLI_RESOURCE, "%s: more pairs than the limit of --max-pairs (%s)", o->input,
                        nbs_status_name(s));
      }
      return cli_fail(cli_status_code(s), "%s: %s (%s)", o->input, nbs_context_error(ctx),
                      nbs_status_name(s));
    }
    if (t < *best) *best = t;
    cli_progress_update(&prog, (double)(r + 1));
  }
  cli_progress_end(&prog);
  return CLI_OK;
}

static void cli_detect_stats(const cli_detect_opts *o, cli_format fmt, const nbs_context *ctx,
                             double seconds) {
  nbs_stats st;
  nbs_last_stats(ctx, &st);
  FILE *f = stderr;
  fputs("{\"algorithm\": ", f);
  cli_json_string(f, nbs_algorithm_name(st.algorithm));
  fputs(", \"requested\": ", f);
  cli_json_string(f, nbs_algorithm_name(o->algorithm));
  fprintf(f, ", \"mode\": \"%s\"", st.mode == NBS_MODE_CANDIDATES ? "candidates" : "contacts");
  fprintf(f, ", \"dim\": %d, \"n\": %lld, \"pairs\": %llu, \"candidates\": %llu", st.dim,
          (long long)st.n, (unsigned long long)st.pairs, (unsigned long long)st.candidates);
  fprintf(f, ", \"seconds\": %.9g, \"ns_per_element\": %.6g, \"repeat\": %lld", seconds,
          st.n > 0 ? seconds * 1e9 / (double)st.n : 0.0, (long long)o->repeat);
  /* the library's split of the last detection's time (nbs_stats) */
  fprintf(f, ", \"input_seconds\": %.9g, \"search_seconds\": %.9g", st.seconds_input,
          st.seconds_search);
  fprintf(f, ", \"bytes\": %zu, \"work_bytes\": %zu, \"pair_bytes\": %zu",
          nbs_context_peak_bytes(ctx), st.work_bytes, st.pair_bytes);
  fprintf(f, ", \"cells\": [%lld, %lld, %lld]", (long long)st.cells[0], (long long)st.cells[1],
          (long long)st.cells[2]);
  if (isfinite(st.cell_size)) {
    fprintf(f, ", \"cell_size\": %.17g", st.cell_size);
  } else {
    fputs(", \"cell_size\": null", f);
  }
  fprintf(f, ", \"compressed\": %s, \"input\": ", st.compressed ? "true" : "false");
  cli_json_string(f, o->input);
  fputs(", \"format\": ", f);
  cli_json_string(f, cli_format_name(fmt));
  fputs("}\n", f);
}

int cli_detect(int argc, char **argv) {
  cli_detect_opts o;
  bool help;
  int code = cli_detect_parse(argc, argv, &o, &help);
  if (code != CLI_OK) return code;
  if (help) {
    fputs(cli_detect_help, stdout);
    return CLI_OK;
  }

  cli_elements e;
  cli_format fmt;
  code = cli_read(o.input, &o.read, &e, &fmt);
  if (code != CLI_OK) return code;

  nbs_context_def cdef = nbs_default_context_def();
  cdef.cell_budget = o.cell_budget;
  cdef.threads = o.threads;
  /* A file whose radii make every element touch every other would otherwise grow the pair
   * buffer until the system kills the tool; past the limit the library stops cleanly. */
  if (o.max_pairs >= 0) {
    cdef.max_pairs = (size_t)o.max_pairs;
  } else {
    long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
    double mem = pages > 0 && page > 0 ? (double)pages * (double)page : 8e9;
    cdef.max_pairs = (size_t)(mem / 4 / (double)sizeof(nbs_pair));
  }
  nbs_context *ctx = NULL;
  nbs_status s = nbs_context_create(&cdef, &ctx);
  if (s != NBS_OK) {
    cli_elements_free(&e);
    return cli_fail(cli_status_code(s), "cannot create a context: %s", nbs_status_message(s));
  }
  double best = 0;
  code = cli_detect_run(&o, &e, ctx, &best);
  if (code == CLI_OK) {
    if (o.stats) cli_detect_stats(&o, fmt, ctx, best);
    size_t count = 0;
    bool ok = true;
    nbs_pair *pairs = NULL;
    if (o.output || o.vtp) {
      pairs = cli_sorted_pairs(ctx, &count, &ok);
      if (!ok) code = cli_fail(CLI_RESOURCE, "out of memory sorting the pairs");
    } else {
      nbs_pairs(ctx, &count);
    }
    if (code == CLI_OK && o.output) code = cli_write_pairs(o.output, o.pairs_format, pairs, count);
    if (code == CLI_OK && o.vtp) code = cli_write_vtp(o.vtp, &o.vtp_opts, &e, pairs, count);
    if (code == CLI_OK && !o.output) printf("pairs: %zu\n", count);
    free(pairs);
  }
  nbs_context_destroy(ctx);
  cli_elements_free(&e);
  return code;
}
