/*
 * LAMMPS / LIGGGHTS text dumps ("dump custom" / "dump atom"):
 *
 *   ITEM: TIMESTEP
 *   1000
 *   ITEM: NUMBER OF ATOMS
 *   2
 *   ITEM: BOX BOUNDS pp pp ff          (triclinic: ITEM: BOX BOUNDS xy xz yz pp pp ff)
 *   0 10                               (triclinic: xlo_bound xhi_bound xy)
 *   0 10
 *   0 10
 *   ITEM: ATOMS id type x y z radius ...
 *   1 1 0.5 0.5 0.5 0.25
 *   2 1 1.0 0.5 0.5 0.25
 *   ITEM: TIMESTEP                     (the next snapshot)
 *
 * Columns in any order; coordinates x y z, unwrapped xu yu zu, or scaled xs ys zs (xsu ...),
 * unscaled with the box of the snapshot; the radius from the column `radius` (or --radius
 * NAME), else `diameter` halved. ITEM: TIME and ITEM: UNITS lines are allowed. One snapshot
 * is read: --snapshot K (0-based), --snapshot last, or --timestep T; the others are skipped
 * without parsing their atoms. Elements are the atom lines of that snapshot in file order.
 */
#include "cli.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

typedef struct cli_dump {
  FILE *f;
  const char *path;
  char *line;
  size_t cap;
  size_t len;
  long lineno;
  int64_t size, pos; /* file size and bytes consumed, for checking counts */
  size_t last_len;   /* the last line read, without its '\n' */
  bool last_eol;     /* ... ended with '\n' */
  cli_progress prog;
} cli_dump;

/* Where the file ends, for "the file ends ..." errors: the start of the line after the last
 * '\n', or the end of a last line without one. */
static long cli_dump_end_line(const cli_dump *d) {
  return d->lineno == 0 || d->last_eol ? d->lineno + 1 : d->lineno;
}
static long cli_dump_end_column(const cli_dump *d) {
  return d->lineno == 0 || d->last_eol ? 1 : (long)d->last_len + 1;
}

/* Next line into d->line (without its end); false at the end of the file. */
static bool cli_dump_next(cli_dump *d) {
  ssize_t got = getline(&d->line, &d->cap, d->f);
  if (got < 0) return false;
  d->lineno++;
  d->pos += got;
  size_t len = (size_t)got;
  d->last_eol = d->line[len - 1] == '\n';
  d->last_len = d->last_eol ? len - 1 : len;
  while (len > 0 && (d->line[len - 1] == '\n' || d->line[len - 1] == '\r')) len--;
  d->line[len] = '\0';
  d->len = len;
  if ((d->lineno & 0xffff) == 0) cli_progress_update(&d->prog, (double)d->pos);
  return true;
}

static bool cli_dump_is(const cli_dump *d, const char *item) {
  size_t n = strlen(item);
  return strncmp(d->line, item, n) == 0;
}

/* Splits a line into blank-separated tokens (in place); returns the count, up to max. Fills
 * col with 1-based columns. */
static int cli_dump_tokens(char *line, char **tok, long *col, int max, bool *more) {
  int n = 0;
  char *p = line;
  *more = false;
  for (;;) {
    while (*p == ' ' || *p == '\t') p++;
    if (!*p) break;
    if (n == max) {
      *more = true;
      break;
    }
    tok[n] = p;
    col[n] = (long)(p - line) + 1;
    n++;
    while (*p && *p != ' ' && *p != '\t') p++;
    if (*p) *p++ = '\0';
  }
  return n;
}

static bool cli_dump_int(const char *s, int64_t *out) {
  char *end;
  errno = 0;
  long long v = strtoll(s, &end, 10);
  while (*end == ' ' || *end == '\t') end++;
  if (end == s || *end || errno) return false;
  *out = v;
  return true;
}

enum { CLI_DUMP_MAXCOLS = 256 };

/* The columns of an ATOMS line. */
typedef struct cli_dump_cols {
  int ncols;
  int coord[3]; /* column of x, y, z (-1: absent) */
  bool scaled[3];
  int radius;
  bool halve;
} cli_dump_cols;

static int cli_dump_columns(cli_dump *d, const cli_read_opts *o, int dim, cli_dump_cols *c) {
  char *tok[CLI_DUMP_MAXCOLS];
  long col[CLI_DUMP_MAXCOLS];
  bool more;
  char *rest = d->line + strlen("ITEM: ATOMS");
  long shift = (long)strlen("ITEM: ATOMS");
  int n = cli_dump_tokens(rest, tok, col, CLI_DUMP_MAXCOLS, &more);
  if (more) return cli_input_error(d->path, d->lineno, 1, "more than %d columns", CLI_DUMP_MAXCOLS);
  if (n == 0) return cli_input_error(d->path, d->lineno, shift + 1, "ITEM: ATOMS names no columns");
  c->ncols = n;
  c->radius = -1;
  c->halve = false;
  static const char *const names[3][4] = {
      {"x", "xu", "xs", "xsu"}, {"y", "yu", "ys", "ysu"}, {"z", "zu", "zs", "zsu"}};
  int diam = -1;
  for (int a = 0; a < 3; a++) c->coord[a] = -1;
  for (int k = 0; k < n; k++) {
    for (int a = 0; a < 3; a++) {
      for (int v = 0; v < 4; v++) {
        if (c->coord[a] < 0 && strcmp(tok[k], names[a][v]) == 0) {
          c->coord[a] = k;
          c->scaled[a] = v >= 2;
        }
      }
    }
    if (o->radius) {
      if (strcmp(tok[k], o->radius) == 0) c->radius = k;
    } else if (c->radius < 0 && strcmp(tok[k], "radius") == 0) {
      c->radius = k;
    } else if (diam < 0 && strcmp(tok[k], "diameter") == 0) {
      diam = k;
    }
  }
  if (c->radius < 0 && diam >= 0 && !o->radius) {
    c->radius = diam;
    c->halve = true;
  }
  static const char axis[3] = {'x', 'y', 'z'};
  for (int a = 0; a < dim; a++) {
    if (c->coord[a] < 0) {
      return cli_input_error(d->path, d->lineno, 1,
                             "ITEM: ATOMS has no %c column (%c, %cu, %cs or %csu)%s", axis[a],
                             axis[a], axis[a], axis[a], axis[a],
                             a == 2 ? "; use --dim 2 for a 2D dump" : "");
    }
  }
  if (!o->has_diameter && c->radius < 0) {
    if (o->radius) {
      return cli_input_error(d->path, d->lineno, 1, "ITEM: ATOMS has no column '%s'", o->radius);
    }
    return cli_input_error(d->path, d->lineno, 1,
                           "ITEM: ATOMS has no radius or diameter column; give --diameter");
  }
  return CLI_OK;
}

/* The box of a snapshot, to unscale xs ys zs (triclinic included). */
typedef struct cli_dump_box {
  double lo[3], len[3];
  double xy, xz, yz;
} cli_dump_box;

static int cli_dump_read_box(cli_dump *d, cli_dump_box *b) {
  bool triclinic = strstr(d->line, "xy") != NULL;
  double bound[3][3] = {{0}};
  for (int a = 0; a < 3; a++) {
    if (!cli_dump_next(d)) {
      return cli_input_error(d->path, cli_dump_end_line(d), cli_dump_end_column(d),
                             "the file ends inside BOX BOUNDS");
    }
    char *tok[4];
    long col[4];
    bool more;
    int n = cli_dump_tokens(d->line, tok, col, 4, &more);
    int want = triclinic ? 3 : 2;
    if (n != want || more) {
      return cli_input_error(d->path, d->lineno, 1, "BOX BOUNDS: %d values, expected %d", n, want);
    }
    for (int k = 0; k < n; k++) {
      char *end;
      bound[a][k] = strtod(tok[k], &end);
      if (*end) return cli_input_error(d->path, d->lineno, col[k], "'%s' is not a number", tok[k]);
      int code = cli_check_value(d->path, d->lineno, col[k], bound[a][k], false, "box bound");
      if (code != CLI_OK) return code;
    }
  }
  b->xy = triclinic ? bound[0][2] : 0;
  b->xz = triclinic ? bound[1][2] : 0;
  b->yz = triclinic ? bound[2][2] : 0;
  /* Triclinic bounds are those of the bounding box; the lows of the cell itself follow
   * LAMMPS's documentation (Howto triclinic). */
  double xlo = bound[0][0], xhi = bound[0][1], ylo = bound[1][0], yhi = bound[1][1];
  if (triclinic) {
    double mn = 0, mx = 0;
    double c[3] = {b->xy, b->xz, b->xy + b->xz};
    for (int k = 0; k < 3; k++) {
      if (c[k] < mn) mn = c[k];
      if (c[k] > mx) mx = c[k];
    }
    xlo -= mn;
    xhi -= mx;
    ylo -= b->yz < 0 ? b->yz : 0;
    yhi -= b->yz > 0 ? b->yz : 0;
  }
  b->lo[0] = xlo;
  b->len[0] = xhi - xlo;
  b->lo[1] = ylo;
  b->len[1] = yhi - ylo;
  b->lo[2] = bound[2][0];
  b->len[2] = bound[2][1] - bound[2][0];
  return CLI_OK;
}

/* Parses the n atom lines of the chosen snapshot. */
static int cli_dump_atoms(cli_dump *d, const cli_read_opts *o, int dim, const cli_dump_cols *c,
                          const cli_dump_box *box, int64_t n, cli_elements *out) {
  double *x = malloc((size_t)(n > 0 ? n : 1) * (size_t)dim * sizeof *x);
  double *r = o->has_diameter ? NULL : malloc((size_t)(n > 0 ? n : 1) * sizeof *r);
  if (!x || (!o->has_diameter && !r)) {
    free(x);
    free(r);
    return cli_fail(CLI_RESOURCE, "%s: out of memory for %lld atoms", d->path, (long long)n);
  }
  char *tok[CLI_DUMP_MAXCOLS];
  long col[CLI_DUMP_MAXCOLS];
  int code = CLI_OK;
  static const char *const what[3] = {"x", "y", "z"};
  for (int64_t k = 0; k < n && code == CLI_OK; k++) {
    if (!cli_dump_next(d)) {
      code = cli_input_error(d->path, cli_dump_end_line(d), cli_dump_end_column(d),
                             "truncated: NUMBER OF ATOMS is %lld, the file ends after %lld atom "
                             "lines", (long long)n, (long long)k);
      break;
    }
    if (cli_dump_is(d, "ITEM:")) {
      code = cli_input_error(d->path, d->lineno, 1,
                             "NUMBER OF ATOMS is %lld, but the snapshot has %lld atom lines",
                             (long long)n, (long long)k);
      break;
    }
    bool more;
    long linelen = (long)d->len;
    int got = cli_dump_tokens(d->line, tok, col, CLI_DUMP_MAXCOLS, &more);
    if (got != c->ncols || more) {
      long at = got > c->ncols && c->ncols < CLI_DUMP_MAXCOLS ? col[c->ncols] : linelen + 1;
      code = cli_input_error(d->path, d->lineno, at,
                             "%s%d values, expected %d as named by ITEM: ATOMS",
                             more ? "more than " : "", got, c->ncols);
      break;
    }
    /* Scaled x and y are unscaled with zs when the cell is tilted in z: then z is read in
     * 2D too (--dim 2 gives the x and y of --dim 3). */
    const int parsed = dim == 2 && c->coord[2] >= 0 &&
                               ((c->scaled[0] && box->xz != 0) || (c->scaled[1] && box->yz != 0))
                           ? 3
                           : dim;
    double s[3] = {0, 0, 0};
    for (int a = 0; a < parsed && code == CLI_OK; a++) {
      int j = c->coord[a];
      char *end;
      s[a] = strtod(tok[j], &end);
      if (*end) {
        code = cli_input_error(d->path, d->lineno, col[j], "'%s' is not a number", tok[j]);
      } else {
        code = cli_check_value(d->path, d->lineno, col[j], s[a], false, what[a]);
      }
    }
    if (code != CLI_OK) break;
    for (int a = 0; a < dim; a++) {
      double v = s[a];
      if (c->scaled[a]) {
        /* Scaled to the (possibly tilted) cell: x = lo + xs lx + ys xy + zs xz, ... */
        if (a == 0) v = box->lo[0] + s[0] * box->len[0] + s[1] * box->xy + s[2] * box->xz;
        if (a == 1) v = box->lo[1] + s[1] * box->len[1] + s[2] * box->yz;
        if (a == 2) v = box->lo[2] + s[2] * box->len[2];
      }
      x[(size_t)k * (size_t)dim + (size_t)a] = v;
    }
    if (!o->has_diameter) {
      int j = c->radius;
      char *end;
      double v = strtod(tok[j], &end);
      if (*end) {
        code = cli_input_error(d->path, d->lineno, col[j], "'%s' is not a number", tok[j]);
        break;
      }
      code = cli_check_value(d->path, d->lineno, col[j], v, true, c->halve ? "diameter" : "radius");
      if (code != CLI_OK) break;
      r[k] = c->halve ? 0.5 * v : v;
    }
  }
  if (code != CLI_OK) {
    free(x);
    free(r);
    return code;
  }
  out->dim = dim;
  out->n = n;
  out->coords = x;
  out->radii = r;
  out->diameter = o->has_diameter ? o->diameter : 0;
  return CLI_OK;
}

int cli_read_dump(FILE *f, const char *path, const cli_read_opts *o, cli_elements *out) {
  cli_dump d;
  memset(&d, 0, sizeof d);
  d.f = f;
  d.path = path;
  if (fseeko(f, 0, SEEK_END) == 0) {
    d.size = (int64_t)ftello(f);
    rewind(f);
  } else {
    d.size = INT64_MAX;
  }
  const int dim = o->dim ? o->dim : 3;
  cli_progress_begin(&d.prog, "reading", (double)d.size);

  int code = CLI_OK;
  int64_t index = 0;            /* snapshot index */
  bool found = false;
  off_t last_at = -1;           /* where the last snapshot starts, for --snapshot last */
  long last_line = 0;
  int64_t last_pos = 0;
  bool rereading = false;       /* reading the last snapshot again, after a first pass */
  int64_t timestep = 0;
  for (;;) {
    off_t start = ftello(f);
    long start_line = d.lineno;
    int64_t start_pos = d.pos;
    if (!cli_dump_next(&d)) break;
    if (d.len == 0) continue;
    /* Optional items before the timestep. */
    if (strcmp(d.line, "ITEM: UNITS") == 0 || strcmp(d.line, "ITEM: TIME") == 0) {
      if (!cli_dump_next(&d)) {
        code = cli_input_error(path, cli_dump_end_line(&d), cli_dump_end_column(&d),
                               "the file ends after an ITEM line");
        break;
      }
      continue;
    }
    if (!cli_dump_is(&d, "ITEM: TIMESTEP")) {
      code = cli_input_error(path, d.lineno, 1, "expected 'ITEM: TIMESTEP', found '%.40s'", d.line);
      break;
    }
    if (!cli_dump_next(&d) || !cli_dump_int(d.line, &timestep) || timestep < 0) {
      code = cli_input_error(path, d.lineno, 1, "the timestep is not an integer >= 0");
      break;
    }
    if (!cli_dump_next(&d) || !cli_dump_is(&d, "ITEM: NUMBER OF ATOMS")) {
      code = cli_input_error(path, d.lineno, 1, "expected 'ITEM: NUMBER OF ATOMS'");
      break;
    }
    int64_t n;
    if (!cli_dump_next(&d) || !cli_dump_int(d.line, &n) || n < 0) {
      code = cli_input_error(path, d.lineno, 1, "NUMBER OF ATOMS '%.40s' is not an integer >= 0",
                             d.line);
      break;
    }
    long count_line = d.lineno;
    /* Each atom line takes at least 2 bytes ("1\n"): a count the rest of the file cannot hold
     * is refused before anything is allocated for it. */
    if (n > (d.size - d.pos) / 2 || n > INT32_MAX) {
      code = cli_input_error(path, d.lineno, 1,
                             "NUMBER OF ATOMS is %lld, more than the rest of the file (%lld "
                             "bytes) can hold", (long long)n, (long long)(d.size - d.pos));
      break;
    }
    if (!cli_dump_next(&d) || !cli_dump_is(&d, "ITEM: BOX BOUNDS")) {
      code = cli_input_error(path, d.lineno, 1, "expected 'ITEM: BOX BOUNDS'");
      break;
    }
    cli_dump_box box;
    code = cli_dump_read_box(&d, &box);
    if (code != CLI_OK) break;
    if (!cli_dump_next(&d) || !cli_dump_is(&d, "ITEM: ATOMS")) {
      code = cli_input_error(path, d.lineno, 1, "expected 'ITEM: ATOMS ...'");
      break;
    }
    bool chosen = rereading || (o->timestep >= 0 ? timestep == o->timestep
                                                 : o->snapshot >= 0 && index == o->snapshot);
    if (chosen) {
      cli_dump_cols c;
      code = cli_dump_columns(&d, o, dim, &c);
      if (code != CLI_OK) break;
      if (n > (d.size - d.pos) / (2 * c.ncols)) {
        code = cli_input_error(path, count_line, 1,
                               "NUMBER OF ATOMS is %lld, more than the rest of the file (%lld "
                               "bytes) can hold with %d columns",
                               (long long)n, (long long)(d.size - d.pos), c.ncols);
        break;
      }
      if (n == 0) {
        code = cli_input_error(path, count_line, 1, "the snapshot has no atoms");
        break;
      }
      code = cli_dump_atoms(&d, o, dim, &c, &box, n, out);
      found = code == CLI_OK;
      /* What follows must be the next snapshot or the end: more atom lines than the count
       * means the count is wrong. */
      while (code == CLI_OK && cli_dump_next(&d)) {
        if (d.len == 0) continue;
        if (!cli_dump_is(&d, "ITEM:")) {
          code = cli_input_error(path, d.lineno, 1,
                                 "NUMBER OF ATOMS is %lld, but the snapshot has more atom lines",
                                 (long long)n);
        }
        break;
      }
      break;
    }
    /* Not this one: skip its atom lines. */
    last_at = start;
    last_line = start_line;
    last_pos = start_pos;
    for (int64_t k = 0; k < n; k++) {
      if (!cli_dump_next(&d)) {
        code = cli_input_error(path, cli_dump_end_line(&d), cli_dump_end_column(&d),
                               "truncated: NUMBER OF ATOMS is %lld, the file ends after %lld atom "
                               "lines", (long long)n, (long long)k);
        break;
      }
      if (cli_dump_is(&d, "ITEM:")) {
        code = cli_input_error(path, d.lineno, 1,
                               "NUMBER OF ATOMS is %lld, but the snapshot has %lld atom lines",
                               (long long)n, (long long)k);
        break;
      }
    }
    if (code != CLI_OK) break;
    index++;
    /* --snapshot last: at the end of the file, go back to the start of the last one. */
    if (o->timestep < 0 && o->snapshot < 0) {
      off_t here = ftello(f);
      long here_line = d.lineno;
      int64_t here_pos = d.pos;
      bool end = true;
      for (;;) {
        if (!cli_dump_next(&d)) break;
        if (d.len > 0) {
          end = false;
          break;
        }
      }
      if (end) {
        if (fseeko(f, last_at, SEEK_SET) != 0) {
          code = cli_input_error(path, 0, 0, "cannot seek back to the last snapshot");
          break;
        }
        d.lineno = last_line;
        d.pos = last_pos;
        rereading = true;
      } else {
        fseeko(f, here, SEEK_SET);
        d.lineno = here_line;
        d.pos = here_pos;
      }
    }
  }
  cli_progress_end(&d.prog);
  free(d.line);
  if (code == CLI_OK && !found) {
    if (index == 0) {
      code = cli_input_error(path, 1, 1, d.lineno == 0 ? "empty file: no elements"
                                                       : "no snapshot in the file");
    } else if (o->timestep >= 0) {
      code = cli_input_error(path, 0, 0, "no snapshot of timestep %lld (the file has %lld)",
                             (long long)o->timestep, (long long)index);
    } else {
      code = cli_input_error(path, 0, 0, "no snapshot %lld: the file has %lld (0 to %lld)",
                             (long long)o->snapshot, (long long)index, (long long)index - 1);
    }
  }
  return code;
}
