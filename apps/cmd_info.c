/*
 * nbs info FILE: what a file holds (count, dimension, box, radii) and what each algorithm
 * needs in memory for it, measured by running it with a counting callback (so that the pair
 * buffer does not grow): its work arrays from nbs_last_stats, the pair buffer from the count.
 */
#include "args.h"
#include "cli.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static const char cli_info_help[] =
    "Usage: nbs info FILE [options]\n"
    "       nbs info --algorithms\n"
    "\n"
    "Prints the number of elements, the dimension, the bounding box and the range of radii of\n"
    "FILE, and what each algorithm needs in memory for it: its work arrays (measured by\n"
    "running it) and the pair buffer that holds the contacts. Direct is not run above\n"
    "--direct-max elements (its time is quadratic; it needs no arrays).\n"
    "\n"
    "Options:\n"
    "  --format, --dim, --diameter, --columns, --radius, --snapshot, --timestep\n"
    "                      as for 'nbs detect'\n"
    "  --cell-budget BYTES the library's cell budget (default 1 GiB)\n"
    "  --direct-max N      run direct only up to N elements (default 20000)\n"
    "  --json              one JSON object on standard output instead of the table\n"
    "  --algorithms        the algorithms of the library, one per line\n"
    "  -q, --quiet         no progress bar\n"
    "\n"
    "Examples:\n"
    "  nbs info spheres.vtp\n"
    "  nbs info dump.liggghts --snapshot last --json\n";

void cli_format_bytes(char *buf, size_t len, double bytes) {
  static const char *const unit[] = {"B", "kB", "MB", "GB", "TB", "PB", "EB"};
  int u = 0;
  while (bytes >= 1000.0 && u < 6) {
    bytes /= 1000.0;
    u++;
  }
  if (u == 0) {
    snprintf(buf, len, "%.0f B", bytes);
  } else {
    snprintf(buf, len, bytes < 10 ? "%.2f %s" : bytes < 100 ? "%.1f %s" : "%.0f %s", bytes, unit[u]);
  }
}

static int cli_count_pairs(void *user, const nbs_pair *pairs, size_t count) {
  (void)pairs;
  *(uint64_t *)user += count;
  return 0;
}

typedef struct cli_info_row {
  const char *name;
  bool ran;
  nbs_status status;
  char error[256];
  nbs_stats stats;
  uint64_t pairs;
  double seconds;
} cli_info_row;

int cli_info(int argc, char **argv) {
  const char *cmd = "info";
  cli_read_opts ro = cli_default_read_opts();
  const char *input = NULL;
  bool json = false, list = false;
  size_t budget = NBS_DEFAULT_CELL_BUDGET;
  int64_t direct_max = 20000;
  cli_args a = {argc, argv, 1, cmd, NULL, false};
  for (; a.k < argc; a.k++) {
    const char *arg = argv[a.k];
    if (cli_flag(&a, "--help", "-h")) {
      fputs(cli_info_help, stdout);
      return CLI_OK;
    } else if (cli_flag(&a, "--algorithms", NULL)) {
      list = true;
    } else if (cli_flag(&a, "--json", NULL)) {
      json = true;
    } else if (cli_flag(&a, "--quiet", "-q")) {
      cli_quiet = true;
    } else if (cli_opt(&a, "--input") || cli_opt(&a, "-i")) {
      if (a.missing) return cli_usage(cmd, "%s needs a file name", arg);
      input = a.val;
    } else if (cli_opt(&a, "--dim")) {
      if (a.missing || (strcmp(a.val, "2") != 0 && strcmp(a.val, "3") != 0)) {
        return cli_usage(cmd, "--dim %s: the dimension must be 2 or 3", a.missing ? "" : a.val);
      }
      ro.dim = a.val[0] - '0';
    } else if (cli_opt(&a, "--diameter")) {
      if (a.missing || !cli_parse_double(a.val, &ro.diameter) || !(ro.diameter > 0)) {
        return cli_usage(cmd, "--diameter %s: it must be a finite number > 0", a.missing ? "" : a.val);
      }
      ro.has_diameter = true;
    } else if (cli_opt(&a, "--format")) {
      int f = a.missing ? -1 : cli_format_from_name(a.val);
      if (f <= 0) return cli_usage(cmd, "--format %s: use csv, f64, dump, vtk or vtp", a.missing ? "" : a.val);
      ro.format = (cli_format)f;
    } else if (cli_opt(&a, "--columns")) {
      if (a.missing) return cli_usage(cmd, "--columns needs a list such as x,y,z,radius");
      ro.columns = a.val;
    } else if (cli_opt(&a, "--radius")) {
      if (a.missing) return cli_usage(cmd, "--radius needs a column or array name");
      ro.radius = a.val;
    } else if (cli_opt(&a, "--snapshot")) {
      if (!a.missing && strcmp(a.val, "last") == 0) {
        ro.snapshot = -1;
      } else if (a.missing || !cli_parse_int64(a.val, &ro.snapshot)) {
        return cli_usage(cmd, "--snapshot %s: give an index from 0, or 'last'", a.missing ? "" : a.val);
      }
    } else if (cli_opt(&a, "--timestep")) {
      if (a.missing || !cli_parse_int64(a.val, &ro.timestep)) {
        return cli_usage(cmd, "--timestep %s: give a timestep >= 0", a.missing ? "" : a.val);
      }
    } else if (cli_opt(&a, "--cell-budget")) {
      int64_t b;
      if (a.missing || !cli_parse_int64(a.val, &b)) {
        return cli_usage(cmd, "--cell-budget %s: give a number of bytes", a.missing ? "" : a.val);
      }
      budget = (size_t)b;
    } else if (cli_opt(&a, "--direct-max")) {
      if (a.missing || !cli_parse_int64(a.val, &direct_max)) {
        return cli_usage(cmd, "--direct-max %s: give a count", a.missing ? "" : a.val);
      }
    } else if (arg[0] == '-' && arg[1] != '\0') {
      return cli_usage(cmd, "unknown option '%s'", arg);
    } else if (!input) {
      input = arg;
    } else {
      return cli_usage(cmd, "unexpected argument '%s'", arg);
    }
  }
  if (list) {
    for (int k = 0; nbs_algorithm_name((nbs_algorithm)k); k++) {
      printf("%s\n", nbs_algorithm_name((nbs_algorithm)k));
    }
    return CLI_OK;
  }
  if (!input) return cli_usage(cmd, "which file? (nbs info FILE)");

  cli_elements e;
  cli_format fmt;
  int code = cli_read(input, &ro, &e, &fmt);
  if (code != CLI_OK) return code;

  /* The file's own figures. */
  double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  double rmin = DBL_MAX, rmax = 0, rsum = 0;
  for (int64_t k = 0; k < e.n; k++) {
    for (int ax = 0; ax < e.dim; ax++) {
      double v = e.coords[k * e.dim + ax];
      if (k == 0 || v < lo[ax]) lo[ax] = v;
      if (k == 0 || v > hi[ax]) hi[ax] = v;
    }
    double r = e.radii ? e.radii[k] : 0.5 * e.diameter;
    rmin = r < rmin ? r : rmin;
    rmax = r > rmax ? r : rmax;
    rsum += r;
  }

  /* Each algorithm, with a counting callback. */
  nbs_context_def cdef = nbs_default_context_def();
  cdef.cell_budget = budget;
  enum { MAXROWS = 16 };
  cli_info_row rows[MAXROWS];
  int nrows = 0;
  nbs_input in = {.dim = e.dim, .n = e.n, .coords = e.coords, .radii = e.radii,
                  .diameter = e.diameter};
  uint64_t contacts = 0;
  const char *found_by = NULL;
  for (int k = 1; nbs_algorithm_name((nbs_algorithm)k) && nrows < MAXROWS; k++) {
    cli_info_row *row = &rows[nrows++];
    memset(row, 0, sizeof *row);
    row->name = nbs_algorithm_name((nbs_algorithm)k);
    if (k == NBS_DIRECT && e.n > direct_max) continue;
    nbs_context *ctx;
    nbs_status s = nbs_context_create(&cdef, &ctx);
    if (s != NBS_OK) {
      cli_elements_free(&e);
      return cli_fail(cli_status_code(s), "cannot create a context: %s", nbs_status_message(s));
    }
    nbs_detect_def def = nbs_default_detect_def();
    def.algorithm = (nbs_algorithm)k;
    def.callback = cli_count_pairs;
    def.user = &row->pairs;
    double t0 = cli_now();
    row->status = nbs_detect(ctx, &in, &def);
    row->seconds = cli_now() - t0;
    row->ran = true;
    nbs_last_stats(ctx, &row->stats);
    snprintf(row->error, sizeof row->error, "%s", nbs_context_error(ctx));
    nbs_context_destroy(ctx);
    if (row->status == NBS_OK && !found_by) {
      contacts = row->pairs;
      found_by = row->name;
    }
  }
  const char axis[3] = {'x', 'y', 'z'};
  if (json) {
    fputs("{\"file\": ", stdout);
    cli_json_string(stdout, input);
    printf(", \"format\": \"%s\", \"n\": %lld, \"dim\": %d, \"box\": [", cli_format_name(fmt),
           (long long)e.n, e.dim);
    for (int ax = 0; ax < e.dim; ax++) printf("%s[%.17g, %.17g]", ax ? ", " : "", lo[ax], hi[ax]);
    printf("], \"radius\": {\"min\": %.17g, \"mean\": %.17g, \"max\": %.17g}, \"contacts\": %llu",
           rmin, rsum / (double)e.n, rmax, (unsigned long long)contacts);
    printf(", \"algorithms\": [");
    for (int k = 0; k < nrows; k++) {
      const cli_info_row *r = &rows[k];
      printf("%s{\"algorithm\": \"%s\", \"ran\": %s", k ? ", " : "", r->name, r->ran ? "true" : "false");
      if (r->ran) {
        printf(", \"status\": \"%s\", \"work_bytes\": %zu, \"pair_bytes\": %llu, \"seconds\": %.6g",
               nbs_status_name(r->status), r->stats.work_bytes,
               (unsigned long long)(contacts * sizeof(nbs_pair)), r->seconds);
        if (r->status == NBS_OK) printf(", \"pairs\": %llu", (unsigned long long)r->pairs);
      }
      printf("}");
    }
    printf("]}\n");
  } else {
    printf("file        %s (%s)\n", input, cli_format_name(fmt));
    printf("elements    %lld in %dD\n", (long long)e.n, e.dim);
    printf("box        ");
    for (int ax = 0; ax < e.dim; ax++) printf(" %c [%g, %g]", axis[ax], lo[ax], hi[ax]);
    printf("\n");
    if (rmin == rmax) {
      printf("radius      %g (every element)\n", rmin);
    } else {
      printf("radius      %g to %g, mean %g (largest / smallest %.3g)\n", rmin, rmax,
             rsum / (double)e.n, rmax / rmin);
    }
    printf("contacts    %llu%s%s%s\n", (unsigned long long)contacts, found_by ? " (found by " : "",
           found_by ? found_by : "", found_by ? ")" : "");
    char pb[32];
    cli_format_bytes(pb, sizeof pb, (double)contacts * (double)sizeof(nbs_pair));
    printf("\nmemory for this file (the pair buffer holds the contacts: %s)\n", pb);
    printf("  %-10s %12s  %-30s %s\n", "algorithm", "work arrays", "cells", "");
    for (int k = 0; k < nrows; k++) {
      const cli_info_row *r = &rows[k];
      char wb[32], cells[48] = "-";
      if (!r->ran) {
        printf("  %-10s %12s  %-30s %s\n", r->name, "0 B", "-",
               "no arrays; quadratic time: not run (see --direct-max)");
        continue;
      }
      cli_format_bytes(wb, sizeof wb, (double)r->stats.work_bytes);
      if (r->stats.cells[0] > 0) {
        if (e.dim == 3) {
          snprintf(cells, sizeof cells, "%lld x %lld x %lld%s", (long long)r->stats.cells[0],
                   (long long)r->stats.cells[1], (long long)r->stats.cells[2],
                   r->stats.compressed ? " (comp.)" : "");
        } else {
          snprintf(cells, sizeof cells, "%lld x %lld%s", (long long)r->stats.cells[0],
                   (long long)r->stats.cells[1], r->stats.compressed ? " (comp.)" : "");
        }
      }
      if (r->status == NBS_OK) {
        printf("  %-10s %12s  %-30s %.3g s\n", r->name, wb, cells, r->seconds);
      } else {
        printf("  %-10s %12s  %-30s refused: %s\n", r->name, "-", cells, r->error);
      }
    }
  }
  cli_elements_free(&e);
  return CLI_OK;
}
