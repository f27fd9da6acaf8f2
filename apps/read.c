/*
 * Reading elements: recognising the format, and the two simplest formats, CSV and raw f64.
 * The other readers are in read_dump.c, read_vtk.c and read_vtp.c.
 */
#include "cli.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

static const char *const cli_format_names[CLI_FORMAT_COUNT] = {"auto", "csv", "f64",
                                                                "dump", "vtk",  "vtp"};

const char *cli_format_name(cli_format f) {
  return (int)f >= 0 && f < CLI_FORMAT_COUNT ? cli_format_names[f] : "unknown";
}

int cli_format_from_name(const char *name) {
  if (!name) return CLI_FORMAT_AUTO;
  for (int k = 0; k < CLI_FORMAT_COUNT; k++) {
    if (strcasecmp(name, cli_format_names[k]) == 0) return k;
  }
  return -1;
}

cli_read_opts cli_default_read_opts(void) {
  cli_read_opts o;
  memset(&o, 0, sizeof o);
  o.format = CLI_FORMAT_AUTO;
  o.snapshot = 0;
  o.timestep = -1;
  return o;
}

const char *cli_value_problem(double v, bool radius) {
  static char negative[64];
  if (isnan(v)) return "is NaN";
  if (isinf(v)) return "is infinite";
  if (radius && v < 0) {
    snprintf(negative, sizeof negative, "%g is negative", v);
    return negative;
  }
  if (radius && v == 0) return "is 0: it must be > 0";
  return NULL;
}

int cli_check_value(const char *file, long line, long column, double v, bool radius,
                    const char *what) {
  const char *p = cli_value_problem(v, radius);
  if (!p) return CLI_OK;
  return cli_input_error(file, line, column, "%s %s", what, p);
}

/* ---- recognising the format ----------------------------------------------------------- */

static bool cli_ends_with(const char *s, const char *suffix) {
  size_t a = strlen(s), b = strlen(suffix);
  return a >= b && strcasecmp(s + a - b, suffix) == 0;
}

cli_format cli_sniff(const char *path, const unsigned char *head, size_t len) {
  size_t k = 0;
  if (len >= 3 && head[0] == 0xef && head[1] == 0xbb && head[2] == 0xbf) k = 3; /* BOM */
  size_t text = k;
  while (text < len && isspace(head[text])) text++;
  const char *h = (const char *)head + k;
  size_t hl = len - k;
  if (hl >= 14 && memcmp(h, "# vtk DataFile", 14) == 0) return CLI_FORMAT_VTK;
  if (len - text >= 5 && (memcmp(head + text, "<?xml", 5) == 0 ||
                          (len - text >= 8 && memcmp(head + text, "<VTKFile", 8) == 0))) {
    return CLI_FORMAT_VTP;
  }
  if (hl >= 5 && memcmp(h, "ITEM:", 5) == 0) return CLI_FORMAT_DUMP;

  static const struct {
    const char *ext;
    cli_format format;
  } exts[] = {{".csv", CLI_FORMAT_CSV},      {".txt", CLI_FORMAT_CSV},
              {".xyz", CLI_FORMAT_CSV},      {".f64", CLI_FORMAT_F64},
              {".bin", CLI_FORMAT_F64},      {".raw", CLI_FORMAT_F64},
              {".vtk", CLI_FORMAT_VTK},      {".vtp", CLI_FORMAT_VTP},
              {".dump", CLI_FORMAT_DUMP},    {".lammpstrj", CLI_FORMAT_DUMP},
              {".liggghts", CLI_FORMAT_DUMP}};
  for (size_t e = 0; e < sizeof exts / sizeof exts[0]; e++) {
    if (path && cli_ends_with(path, exts[e].ext)) return exts[e].format;
  }
  /* Text is CSV; anything else is taken as raw doubles. */
  for (size_t b = k; b < len; b++) {
    unsigned char c = head[b];
    if (c < 0x20 && c != '\n' && c != '\r' && c != '\t') return CLI_FORMAT_F64;
    if (c >= 0x7f) return CLI_FORMAT_F64;
  }
  return CLI_FORMAT_CSV;
}

/* Standard input is read whole into memory, so that every reader can seek. */
static FILE *cli_slurp_stdin(char **data) {
  size_t n = 0, cap = 1 << 16;
  char *buf = malloc(cap);
  if (!buf) return NULL;
  for (;;) {
    if (n == cap) {
      char *b = cap > SIZE_MAX / 2 ? NULL : realloc(buf, cap * 2);
      if (!b) {
        free(buf);
        return NULL;
      }
      buf = b;
      cap *= 2;
    }
    size_t got = fread(buf + n, 1, cap - n, stdin);
    n += got;
    if (got == 0) break;
  }
  *data = buf;
  /* fmemopen of a zero-length buffer is not portable: an empty input is a one-byte buffer
   * opened "w+", which truncates it to an empty stream (opened "rb", its byte, never
   * written, would be read as the input). */
  return n > 0 ? fmemopen(buf, n, "rb") : fmemopen(buf, 1, "w+b");
}

int cli_read(const char *path, const cli_read_opts *o, cli_elements *out, cli_format *format) {
  memset(out, 0, sizeof *out);
  char *stdin_data = NULL;
  FILE *f;
  bool is_stdin = strcmp(path, "-") == 0;
  if (is_stdin) {
    f = cli_slurp_stdin(&stdin_data);
    if (!f) {
      free(stdin_data);
      return cli_fail(CLI_RESOURCE, "standard input: out of memory");
    }
    path = "<stdin>";
  } else {
    f = fopen(path, "rb");
    if (!f) return cli_input_error(path, 0, 0, "cannot open: %s", strerror(errno));
    struct stat st;
    if (fstat(fileno(f), &st) == 0 && S_ISDIR(st.st_mode)) {
      fclose(f);
      return cli_input_error(path, 0, 0, "is a directory");
    }
  }
  cli_format fmt = o->format;
  if (fmt == CLI_FORMAT_AUTO) {
    unsigned char head[512];
    size_t len = fread(head, 1, sizeof head, f);
    if (ferror(f)) {
      int e = errno;
      fclose(f);
      free(stdin_data);
      return cli_input_error(path, 0, 0, "cannot read: %s", strerror(e));
    }
    fmt = cli_sniff(is_stdin ? NULL : path, head, len);
    rewind(f);
  }
  int code;
  switch (fmt) {
  case CLI_FORMAT_CSV:
    code = cli_read_csv(f, path, o, out);
    break;
  case CLI_FORMAT_F64:
    code = cli_read_f64(f, path, o, out);
    break;
  case CLI_FORMAT_DUMP:
    code = cli_read_dump(f, path, o, out);
    break;
  case CLI_FORMAT_VTK:
    code = cli_read_vtk(f, path, o, out);
    break;
  case CLI_FORMAT_VTP:
    code = cli_read_vtp(f, path, o, out);
    break;
  default:
    code = cli_fail(CLI_USAGE, "unknown format %d", (int)fmt);
    break;
  }
  fclose(f);
  free(stdin_data);
  if (code != CLI_OK) {
    cli_elements_free(out);
    return code;
  }
  if (out->n > INT32_MAX) {
    cli_elements_free(out);
    return cli_input_error(path, 0, 0, "more than 2^31 - 1 elements");
  }
  if (format) *format = fmt;
  return CLI_OK;
}

/* ---- CSV ------------------------------------------------------------------------------ */

typedef struct cli_field {
  size_t start, end; /* byte offsets in the line, trimmed */
} cli_field;

typedef struct cli_csv {
  const char *path;
  char delim; /* ',', ';' or ' ' for runs of blanks */
  cli_field *fields;
  size_t nfields, cap;
} cli_csv;

/* Splits line[0, len) into fields; false on allocation failure. */
static bool cli_csv_split(cli_csv *c, const char *line, size_t len) {
  c->nfields = 0;
  size_t k = 0;
  for (;;) {
    if (c->delim == ' ') {
      while (k < len && (line[k] == ' ' || line[k] == '\t')) k++;
      if (k == len) break;
    }
    size_t s = k;
    if (c->delim == ' ') {
      while (k < len && line[k] != ' ' && line[k] != '\t') k++;
    } else {
      while (k < len && line[k] != c->delim) k++;
    }
    size_t e = k;
    while (s < e && (line[s] == ' ' || line[s] == '\t')) s++;
    while (e > s && (line[e - 1] == ' ' || line[e - 1] == '\t')) e--;
    if (c->nfields == c->cap) {
      size_t cap = c->cap ? c->cap * 2 : 16;
      cli_field *f = realloc(c->fields, cap * sizeof *f);
      if (!f) return false;
      c->fields = f;
      c->cap = cap;
    }
    c->fields[c->nfields].start = s;
    c->fields[c->nfields].end = e;
    c->nfields++;
    if (c->delim == ' ') continue;
    if (k == len) break;
    k++; /* past the delimiter */
  }
  return true;
}

/* Parses field f of line (writable: a NUL is placed at its end) as a double. */
static bool cli_csv_number(char *line, const cli_field *f, double *out) {
  if (f->start == f->end) return false;
  char save = line[f->end];
  line[f->end] = '\0';
  char *end;
  double v = strtod(line + f->start, &end);
  bool ok = end == line + f->end;
  line[f->end] = save;
  /* strtod takes "nan(...)", "infinity", hex floats: all are numbers; NaN and infinities are
   * refused later with their own message. */
  *out = v;
  return ok;
}

static bool cli_name_is(const char *name, const char *const *list) {
  for (; *list; list++) {
    if (strcasecmp(name, *list) == 0) return true;
  }
  return false;
}

static const char *const cli_x_names[] = {"x", "px", "pos_x", "position_x", "xu", NULL};
static const char *const cli_y_names[] = {"y", "py", "pos_y", "position_y", "yu", NULL};
static const char *const cli_z_names[] = {"z", "pz", "pos_z", "position_z", "zu", NULL};
static const char *const cli_r_names[] = {"radius", "r", "rad", NULL};
static const char *const cli_d_names[] = {"diameter", "d", "diam", NULL};

/* The columns to read: col[0..dim-1] coordinates, col[3] the radius or -1; halve when the
 * radius column holds diameters. 0-based. */
typedef struct cli_csv_map {
  int dim;
  long col[4];
  bool halve;
} cli_csv_map;

/* Resolves --columns (names from the header, or 1-based indices). */
static int cli_csv_map_spec(const char *path, const char *spec, char **names, size_t nnames,
                            const cli_read_opts *o, cli_csv_map *m) {
  char buf[256];
  if (strlen(spec) >= sizeof buf) return cli_usage("detect", "--columns: too long");
  strcpy(buf, spec);
  long cols[8];
  bool diam[8] = {false};
  int count = 0;
  for (char *tok = strtok(buf, ","); tok; tok = strtok(NULL, ",")) {
    while (*tok == ' ') tok++;
    if (count == 4) return cli_usage("detect", "--columns %s: at most 4 columns (x,y,z,radius)", spec);
    int64_t idx;
    if (cli_parse_int64(tok, &idx) && idx >= 1) {
      cols[count] = (long)idx - 1;
      diam[count] = false;
    } else {
      size_t k = 0;
      while (k < nnames && strcasecmp(names[k], tok) != 0) k++;
      if (k == nnames) {
        if (!names) {
          return cli_input_error(path, 1, 1,
                                 "--columns names '%s' but the file has no header line", tok);
        }
        return cli_input_error(path, 1, 1, "--columns: no column '%s' in the header", tok);
      }
      cols[count] = (long)k;
      diam[count] = cli_name_is(tok, cli_d_names);
    }
    count++;
  }
  int dim = o->dim;
  if (dim == 0) {
    /* Without --dim, 2 or 3 names (or 3 or 4 with a radius) are ambiguous; ask. */
    return cli_usage("detect", "--columns needs --dim 2 or 3");
  }
  if (count != dim && count != dim + 1) {
    return cli_usage("detect", "--columns %s: give %d columns, or %d with the radius last", spec,
                     dim, dim + 1);
  }
  m->dim = dim;
  for (int a = 0; a < 3; a++) m->col[a] = a < dim ? cols[a] : -1;
  m->col[3] = count == dim + 1 ? cols[dim] : -1;
  m->halve = count == dim + 1 && diam[dim];
  return CLI_OK;
}

/* Columns from header names x, y, [z], radius|diameter. 1 when the header names them, 0
 * when it does not name x and y, -1 when it names x and y but no z for a 3D read. */
static int cli_csv_map_names(char **names, size_t nnames, const cli_read_opts *o, cli_csv_map *m) {
  long x = -1, y = -1, z = -1, r = -1, d = -1;
  for (size_t k = 0; k < nnames; k++) {
    const char *s = names[k];
    if (x < 0 && cli_name_is(s, cli_x_names)) x = (long)k;
    else if (y < 0 && cli_name_is(s, cli_y_names)) y = (long)k;
    else if (z < 0 && cli_name_is(s, cli_z_names)) z = (long)k;
    else if (r < 0 && cli_name_is(s, cli_r_names)) r = (long)k;
    else if (d < 0 && cli_name_is(s, cli_d_names)) d = (long)k;
  }
  if (x < 0 || y < 0) return 0;
  int dim = o->dim ? o->dim : (z >= 0 ? 3 : 2);
  if (dim == 3 && z < 0) return -1; /* x and y by name, and no z: not positional either */
  m->dim = dim;
  m->col[0] = x;
  m->col[1] = y;
  m->col[2] = dim == 3 ? z : -1;
  m->col[3] = r >= 0 ? r : d;
  m->halve = r < 0 && d >= 0;
  return 1;
}

static void cli_free_names(char **names, size_t n) {
  for (size_t k = 0; k < n; k++) free(names[k]);
  free(names);
}

int cli_read_csv(FILE *f, const char *path, const cli_read_opts *o, cli_elements *out) {
  cli_csv c;
  memset(&c, 0, sizeof c);
  c.path = path;
  char *line = NULL;
  size_t linecap = 0;
  char **names = NULL;
  size_t nnames = 0;
  long header_line = 0;
  cli_csv_map m;
  memset(&m, 0, sizeof m);
  bool mapped = false;
  size_t ncols = 0;   /* columns of every data line */
  long first_data = 0; /* line of the first data line */
  cli_dbuf xs = {0}, rs = {0};
  int code = CLI_OK;
  long lineno = 0;
  double done = 0;

  struct stat st;
  double total = fstat(fileno(f), &st) == 0 && S_ISREG(st.st_mode) ? (double)st.st_size : 0.0;
  cli_progress prog;
  cli_progress_begin(&prog, "reading", total);

  for (;;) {
    errno = 0;
    ssize_t got = getline(&line, &linecap, f);
    if (got < 0) {
      if (ferror(f)) code = cli_input_error(path, lineno + 1, 0, "cannot read: %s", strerror(errno));
      break;
    }
    lineno++;
    done += (double)got;
    if ((lineno & 0xfff) == 0) cli_progress_update(&prog, done);
    size_t len = (size_t)got;
    while (len > 0 && (line[len - 1] == '\n' || line[len - 1] == '\r')) len--;
    if (memchr(line, '\0', len)) {
      code = cli_input_error(path, lineno, (long)((char *)memchr(line, '\0', len) - line) + 1,
                             "a NUL byte: this is not a text file (use --format f64 for raw "
                             "doubles)");
      break;
    }
    size_t s = 0;
    while (s < len && (line[s] == ' ' || line[s] == '\t')) s++;
    if (s == len || line[s] == '#') continue; /* blank or comment */

    if (c.delim == 0) {
      c.delim = memchr(line, ',', len) ? ',' : memchr(line, ';', len) ? ';' : ' ';
    }
    if (!cli_csv_split(&c, line, len)) {
      code = cli_fail(CLI_RESOURCE, "%s: out of memory", path);
      break;
    }

    if (!mapped) {
      /* The first content line: a header if none of its fields is a number. */
      size_t numeric = 0;
      for (size_t k = 0; k < c.nfields; k++) {
        double v;
        if (cli_csv_number(line, &c.fields[k], &v)) numeric++;
      }
      if (numeric == 0 && header_line == 0) {
        header_line = lineno;
        names = calloc(c.nfields, sizeof *names);
        if (!names) {
          code = cli_fail(CLI_RESOURCE, "%s: out of memory", path);
          break;
        }
        nnames = c.nfields;
        for (size_t k = 0; k < c.nfields; k++) {
          size_t a = c.fields[k].start, b = c.fields[k].end;
          if (b - a >= 2 && (line[a] == '"' || line[a] == '\'') && line[b - 1] == line[a]) {
            a++;
            b--;
          }
          names[k] = malloc(b - a + 1);
          if (!names[k]) {
            code = cli_fail(CLI_RESOURCE, "%s: out of memory", path);
            break;
          }
          memcpy(names[k], line + a, b - a);
          names[k][b - a] = '\0';
        }
        if (code != CLI_OK) break;
        continue;
      }
      /* The first data line fixes the columns. */
      ncols = c.nfields;
      first_data = lineno;
      if (names && nnames != ncols) {
        code = cli_input_error(path, lineno, 1, "%zu values, but the header on line %ld names %zu columns",
                               ncols, header_line, nnames);
        break;
      }
      if (o->columns) {
        code = cli_csv_map_spec(path, o->columns, names, nnames, o, &m);
        if (code != CLI_OK) break;
      } else if (names && cli_csv_map_names(names, nnames, o, &m) < 0) {
        code = cli_input_error(path, header_line, 1,
                               "the header names x and y but no z column (z, pz, pos_z, "
                               "position_z, zu) for --dim 3");
        break;
      } else if (!names || !cli_csv_map_names(names, nnames, o, &m)) {
        /* By position: D values, or D + 1 with the radius last. */
        if (o->dim == 0) {
          code = cli_usage("detect", "%s: give --dim 2 or 3 (the file has no header naming x, y, z)",
                           path);
          break;
        }
        int d = o->dim;
        if (ncols != (size_t)d && ncols != (size_t)d + 1) {
          code = cli_input_error(path, lineno, 1,
                                 "%zu values: expected %d (x,y%s) with --diameter, or %d "
                                 "(x,y%s,radius)",
                                 ncols, d, d == 3 ? ",z" : "", d + 1, d == 3 ? ",z" : "");
          break;
        }
        m.dim = d;
        for (int a = 0; a < 3; a++) m.col[a] = a < d ? a : -1;
        m.col[3] = ncols == (size_t)d + 1 ? d : -1;
        m.halve = false;
      }
      for (int a = 0; a < 4; a++) {
        if (m.col[a] >= (long)ncols) {
          code = cli_input_error(path, lineno, 1, "--columns: column %ld, but the line has %zu",
                                 m.col[a] + 1, ncols);
          break;
        }
      }
      if (code != CLI_OK) break;
      if (m.col[3] < 0 && !o->has_diameter) {
        code = cli_input_error(path, lineno, 1,
                               "%zu values: no radius column (the last of %d values, or a "
                               "header 'radius' or 'diameter'), and no --diameter",
                               ncols, m.dim + 1);
        break;
      }
      mapped = true;
    }

    if (c.nfields != ncols) {
      long col = c.nfields > ncols ? (long)c.fields[ncols].start + 1 : (long)len + 1;
      code = cli_input_error(path, lineno, col, "%zu values, expected %zu as on line %ld", c.nfields,
                             ncols, first_data);
      break;
    }
    static const char *const what[4] = {"x", "y", "z", "radius"};
    if (!cli_dbuf_reserve(&xs, (size_t)m.dim)) {
      code = cli_fail(CLI_RESOURCE, "%s: out of memory after %zu elements", path, rs.n);
      break;
    }
    for (int a = 0; a < 4 && code == CLI_OK; a++) {
      if (a >= m.dim && a < 3) continue;
      if (a == 3 && (m.col[3] < 0 || o->has_diameter)) continue;
      const cli_field *fl = &c.fields[m.col[a]];
      double v;
      if (!cli_csv_number(line, fl, &v)) {
        code = cli_input_error(path, lineno, (long)fl->start + 1, "'%.*s' is not a number",
                               (int)(fl->end - fl->start > 40 ? 40 : fl->end - fl->start),
                               line + fl->start);
        break;
      }
      const char *w = a == 3 && m.halve ? "diameter" : what[a];
      code = cli_check_value(path, lineno, (long)fl->start + 1, v, a == 3, w);
      if (code != CLI_OK) break;
      if (a < 3) {
        xs.v[xs.n++] = v;
      } else if (!cli_dbuf_push(&rs, m.halve ? 0.5 * v : v)) {
        code = cli_fail(CLI_RESOURCE, "%s: out of memory", path);
      }
    }
    if (code != CLI_OK) break;
    if (xs.n / (size_t)m.dim > (size_t)INT32_MAX) {
      code = cli_input_error(path, lineno, 1, "more than 2^31 - 1 elements");
      break;
    }
  }
  cli_progress_end(&prog);
  free(line);
  free(c.fields);
  cli_free_names(names, nnames);
  if (code == CLI_OK && !mapped) {
    code = cli_input_error(path, lineno > 0 ? lineno : 1, 1,
                           lineno == 0 ? "empty file: no elements" : "no elements (no data lines)");
  }
  if (code != CLI_OK) {
    cli_dbuf_free(&xs);
    cli_dbuf_free(&rs);
    return code;
  }
  out->dim = m.dim;
  out->n = (int64_t)(xs.n / (size_t)m.dim);
  out->coords = xs.v;
  if (o->has_diameter) {
    out->radii = NULL;
    out->diameter = o->diameter;
    cli_dbuf_free(&rs);
  } else {
    out->radii = rs.v;
  }
  return CLI_OK;
}

/* ---- raw little-endian f64 ------------------------------------------------------------ */

static bool cli_host_is_little(void) {
  const uint16_t one = 1;
  unsigned char b;
  memcpy(&b, &one, 1);
  return b == 1;
}

static void cli_swap8(double *v, size_t count) {
  for (size_t k = 0; k < count; k++) {
    unsigned char b[8], t;
    memcpy(b, &v[k], 8);
    for (int i = 0; i < 4; i++) {
      t = b[i];
      b[i] = b[7 - i];
      b[7 - i] = t;
    }
    memcpy(&v[k], b, 8);
  }
}

int cli_read_f64(FILE *f, const char *path, const cli_read_opts *o, cli_elements *out) {
  if (o->dim != 2 && o->dim != 3) {
    return cli_usage("detect", "%s: a raw f64 file needs --dim 2 or 3", path);
  }
  const int dim = o->dim;
  const size_t rec = (size_t)dim + (o->has_diameter ? 0 : 1); /* values per element */
  cli_dbuf all = {0};

  struct stat st;
  bool regular = fstat(fileno(f), &st) == 0 && S_ISREG(st.st_mode);
  cli_progress prog;
  cli_progress_begin(&prog, "reading", regular ? (double)st.st_size : 0.0);
  if (regular) {
    /* The size is known: one allocation of exactly what the file holds. */
    if ((uint64_t)st.st_size > (uint64_t)SIZE_MAX / 2) {
      return cli_fail(CLI_RESOURCE, "%s: too large for this machine", path);
    }
    size_t values = (size_t)st.st_size / 8 + 1;
    if (!cli_dbuf_reserve(&all, values)) {
      return cli_fail(CLI_RESOURCE, "%s: out of memory for %zu doubles", path, values);
    }
  }
  size_t bytes = 0;
  unsigned char tail[8];
  size_t ntail = 0;
  for (;;) {
    if (all.cap - all.n < 1 && !cli_dbuf_reserve(&all, 1 << 16)) {
      cli_progress_end(&prog);
      cli_dbuf_free(&all);
      return cli_fail(CLI_RESOURCE, "%s: out of memory", path);
    }
    size_t room = (all.cap - all.n) * 8;
    unsigned char *dst = (unsigned char *)(all.v + all.n);
    memcpy(dst, tail, ntail);
    size_t got = fread(dst + ntail, 1, room - ntail, f);
    if (got == 0) break;
    bytes += got;
    size_t have = ntail + got;
    all.n += have / 8;
    ntail = have % 8;
    memcpy(tail, dst + have - ntail, ntail);
    cli_progress_update(&prog, (double)bytes);
  }
  cli_progress_end(&prog);
  if (ferror(f)) {
    int e = errno;
    cli_dbuf_free(&all);
    return cli_input_error(path, 0, 0, "cannot read: %s", strerror(e));
  }
  if (bytes == 0) {
    cli_dbuf_free(&all);
    return cli_input_error(path, 1, 1, "empty file: no elements");
  }
  if (ntail != 0 || all.n % rec != 0) {
    size_t whole = all.n / rec;
    size_t extra = bytes - whole * rec * 8;
    long value = (long)(extra / 8) + 1;
    cli_dbuf_free(&all);
    return cli_input_error(path, (long)whole + 1, value,
                           "truncated: %zu bytes are not a whole number of elements of %zu "
                           "doubles (%zu bytes); element %zu, at byte %zu, has only %zu bytes",
                           bytes, rec, rec * 8, whole + 1, whole * rec * 8, extra);
  }
  if (!cli_host_is_little()) cli_swap8(all.v, all.n);
  const size_t n = all.n / rec;
  if (n > (size_t)INT32_MAX) {
    cli_dbuf_free(&all);
    return cli_input_error(path, 0, 0, "%zu elements: more than 2^31 - 1", n);
  }
  static const char *const what[4] = {"x", "y", "z", "radius"};
  for (size_t k = 0; k < n; k++) {
    for (size_t a = 0; a < rec; a++) {
      bool radius = a == (size_t)dim;
      double v = all.v[k * rec + a];
      const char *p = cli_value_problem(v, radius);
      if (p) {
        cli_dbuf_free(&all);
        return cli_input_error(path, (long)k + 1, (long)a + 1, "%s %s (element %zu, byte %zu)",
                               radius ? what[3] : what[a], p, k + 1, (k * rec + a) * 8);
      }
    }
  }
  out->dim = dim;
  out->n = (int64_t)n;
  if (o->has_diameter) {
    out->coords = all.v; /* rec == dim: already interleaved */
    out->radii = NULL;
    out->diameter = o->diameter;
    return CLI_OK;
  }
  /* Split x y [z] r records into coordinates and radii, in place for the coordinates. */
  double *r = malloc((n > 0 ? n : 1) * sizeof *r);
  if (!r) {
    cli_dbuf_free(&all);
    return cli_fail(CLI_RESOURCE, "%s: out of memory", path);
  }
  for (size_t k = 0; k < n; k++) {
    r[k] = all.v[k * rec + (size_t)dim];
    for (int a = 0; a < dim; a++) all.v[k * (size_t)dim + (size_t)a] = all.v[k * rec + (size_t)a];
  }
  out->coords = all.v;
  out->radii = r;
  return CLI_OK;
}
