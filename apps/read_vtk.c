/*
 * Legacy VTK files (.vtk), ASCII or BINARY (big-endian), versions 2 to 5.1:
 *
 *   # vtk DataFile Version 5.1
 *   title
 *   ASCII | BINARY
 *   DATASET POLYDATA | UNSTRUCTURED_GRID | STRUCTURED_GRID
 *   POINTS n type
 *   ... cells (VERTICES, LINES, POLYGONS, TRIANGLE_STRIPS, CELLS, CELL_TYPES), skipped ...
 *   POINT_DATA n
 *   SCALARS radius double 1         or   FIELD FieldData k
 *   LOOKUP_TABLE default                 radius 1 n double
 *   values ...                           values ...
 *
 * Elements are the points; the radius is the point array named `radius` (or --radius NAME),
 * else `diameter` halved, from SCALARS or FIELD arrays. Every other section is read past,
 * by its declared size: counts are checked against the bytes left in the file before
 * anything is allocated or skipped. Version 5 cell sections (OFFSETS / CONNECTIVITY) and
 * METADATA blocks are understood.
 *
 * Positions: ASCII values are reported at their own LINE:COLUMN; binary values at the line of
 * their section's header, with the element and the byte offset in the message.
 */
#include "cli.h"

#include <stdlib.h>
#include <string.h>
#include <strings.h>

typedef struct cli_vtk {
  FILE *f;
  const char *path;
  long line, col;   /* position of the next character, 1-based */
  long tline, tcol; /* position of the last token */
  char tok[128];
  int sep; /* the character that ended the last token */
  bool binary;
  int version;      /* major version */
  int64_t size;     /* bytes in the file */
  cli_progress prog;
  /* the header line being looked at, split into tokens */
  char hdr[512];
  char *h[8];
  long hcol[8];
  int nh;
  long hline;
} cli_vtk;

static int cli_vtk_getc(cli_vtk *v) {
  int c = getc_unlocked(v->f);
  if (c == '\n') {
    v->line++;
    v->col = 1;
  } else if (c != EOF) {
    v->col++;
  }
  return c;
}

static int64_t cli_vtk_left(const cli_vtk *v) {
  off_t at = ftello(v->f);
  return at < 0 ? 0 : v->size - (int64_t)at;
}

/* Next blank-separated token; false at the end of the file. Too long a token is cut (and
 * then fails to parse as whatever it was meant to be). */
static bool cli_vtk_token(cli_vtk *v) {
  int c;
  do {
    c = cli_vtk_getc(v);
  } while (c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v');
  if (c == EOF) return false;
  v->tline = v->line;
  v->tcol = v->col - 1;
  size_t n = 0;
  while (c != EOF && c != ' ' && c != '\t' && c != '\n' && c != '\r' && c != '\f' && c != '\v') {
    if (n + 1 < sizeof v->tok) v->tok[n++] = (char)c;
    c = cli_vtk_getc(v);
  }
  v->tok[n] = '\0';
  v->sep = c;
  return true;
}

/* Reads the rest of the current line; used for the first lines and headers. */
static bool cli_vtk_rawline(cli_vtk *v, char *buf, size_t len) {
  size_t n = 0;
  int c = cli_vtk_getc(v);
  if (c == EOF) return false;
  while (c != EOF && c != '\n') {
    if (n + 1 < len) buf[n++] = (char)c;
    c = cli_vtk_getc(v);
  }
  while (n > 0 && buf[n - 1] == '\r') n--;
  buf[n] = '\0';
  return true;
}

/* The next non-blank header line, split into tokens; false at the end of the file. */
static bool cli_vtk_header(cli_vtk *v) {
  for (;;) {
    long line = v->line;
    if (!cli_vtk_rawline(v, v->hdr, sizeof v->hdr)) return false;
    v->nh = 0;
    char *p = v->hdr;
    while (*p && v->nh < 8) {
      while (*p == ' ' || *p == '\t') p++;
      if (!*p) break;
      v->h[v->nh] = p;
      v->hcol[v->nh] = (long)(p - v->hdr) + 1;
      v->nh++;
      while (*p && *p != ' ' && *p != '\t') p++;
      if (*p) *p++ = '\0';
    }
    v->hline = line;
    if (v->nh > 0) return true;
  }
}

static bool cli_vtk_is(const cli_vtk *v, const char *kw) {
  return v->nh > 0 && strcasecmp(v->h[0], kw) == 0;
}

static bool cli_vtk_count(const char *s, int64_t *out) {
  return cli_parse_int64(s, out) && *out <= INT64_MAX / 64;
}

typedef struct cli_vtk_type {
  const char *name;
  int size;
  bool is_float, is_signed;
} cli_vtk_type;

static const cli_vtk_type cli_vtk_types[] = {
    {"bit", 0, false, false},          {"unsigned_char", 1, false, false},
    {"char", 1, false, true},          {"unsigned_short", 2, false, false},
    {"short", 2, false, true},         {"unsigned_int", 4, false, false},
    {"int", 4, false, true},           {"unsigned_long", 8, false, false},
    {"long", 8, false, true},          {"float", 4, true, true},
    {"double", 8, true, true},         {"vtktypeint64", 8, false, true},
    {"vtktypeuint64", 8, false, false}, {"vtktypeint32", 4, false, true},
    {"vtktypeuint32", 4, false, false}, {"vtkidtype", 8, false, true},
};

static const cli_vtk_type *cli_vtk_find_type(const char *name) {
  for (size_t k = 0; k < sizeof cli_vtk_types / sizeof cli_vtk_types[0]; k++) {
    if (strcasecmp(name, cli_vtk_types[k].name) == 0) return &cli_vtk_types[k];
  }
  return NULL;
}

/* The type named by header token k, or an error. */
static int cli_vtk_type_at(cli_vtk *v, int k, const cli_vtk_type **t) {
  if (k >= v->nh) {
    return cli_input_error(v->path, v->hline, (long)strlen(v->hdr) + 1, "%s: the data type is missing",
                           v->h[0]);
  }
  *t = cli_vtk_find_type(v->h[k]);
  if (!*t || (*t)->size == 0) {
    return cli_input_error(v->path, v->hline, v->hcol[k], "unsupported data type '%s'", v->h[k]);
  }
  return CLI_OK;
}

static double cli_vtk_decode(const unsigned char *b, const cli_vtk_type *t) {
  uint64_t u = 0;
  for (int k = 0; k < t->size; k++) u = u << 8 | b[k]; /* big-endian */
  if (t->is_float) {
    if (t->size == 4) {
      uint32_t w = (uint32_t)u;
      float f;
      memcpy(&f, &w, 4);
      return f;
    }
    double d;
    memcpy(&d, &u, 8);
    return d;
  }
  if (t->is_signed) {
    int shift = 64 - 8 * t->size;
    return (double)((int64_t)(u << shift) >> shift);
  }
  return (double)u;
}

enum { CLI_VTK_SKIP = 0, CLI_VTK_COORD, CLI_VTK_RADIUS, CLI_VTK_DIAMETER };

/* Reads count values of type t (ASCII tokens, or big-endian binary), into dst when not NULL.
 * check: what the values are, for their validation. */
static int cli_vtk_values(cli_vtk *v, int64_t count, const cli_vtk_type *t, double *dst,
                          int check, bool binary_uchar) {
  const char *what = check == CLI_VTK_COORD ? "coordinate"
                     : check == CLI_VTK_RADIUS ? "radius" : "diameter";
  long hline = v->hline;
  if (v->binary) {
    int size = binary_uchar ? 1 : t->size;
    if (count > cli_vtk_left(v) / size) {
      return cli_input_error(v->path, hline, 1,
                             "%s declares %lld values (%lld bytes), more than the %lld bytes left",
                             v->h[0], (long long)count, (long long)count * size,
                             (long long)cli_vtk_left(v));
    }
    static const cli_vtk_type uchar = {"unsigned_char", 1, false, false};
    const cli_vtk_type *tt = binary_uchar ? &uchar : t;
    unsigned char buf[8192];
    int64_t done = 0;
    off_t start = ftello(v->f);
    while (done < count) {
      int64_t m = count - done;
      if (m > (int64_t)(sizeof buf / (size_t)size)) m = (int64_t)(sizeof buf / (size_t)size);
      if (fread(buf, (size_t)size, (size_t)m, v->f) != (size_t)m) {
        return cli_input_error(v->path, hline, 1, "truncated: the file ends inside %s's data",
                               v->h[0]);
      }
      for (const unsigned char *q = buf, *e = buf + m * size;
           (q = memchr(q, '\n', (size_t)(e - q))) != NULL; q++) {
        v->line++; /* keep line numbers those of an editor */
      }
      for (int64_t k = 0; k < m && dst; k++) {
        double x = cli_vtk_decode(buf + k * size, tt);
        if (check != CLI_VTK_SKIP) {
          const char *p = cli_value_problem(x, check != CLI_VTK_COORD);
          if (p) {
            int64_t i = done + k;
            return cli_input_error(v->path, hline, 1, "%s %s (value %lld of %s, byte %lld)", what,
                                   p, (long long)i + 1, v->h[0],
                                   (long long)(start + (off_t)(i * size)));
          }
        }
        dst[done + k] = x;
      }
      done += m;
      cli_progress_update(&v->prog, (double)ftello(v->f));
    }
    /* The line end after binary data is read as part of the next header search. */
    return CLI_OK;
  }
  if (count > (cli_vtk_left(v) + 1) / 2) {
    return cli_input_error(v->path, hline, 1,
                           "%s declares %lld values, more than the %lld bytes left can hold",
                           v->h[0], (long long)count, (long long)cli_vtk_left(v));
  }
  for (int64_t k = 0; k < count; k++) {
    if (!cli_vtk_token(v)) {
      return cli_input_error(v->path, v->line, v->col,
                             "truncated: %s declares %lld values, the file ends after %lld",
                             v->h[0], (long long)count, (long long)k);
    }
    char *end;
    double x = strtod(v->tok, &end);
    if (*end || end == v->tok) {
      return cli_input_error(v->path, v->tline, v->tcol, "'%s' is not a number (value %lld of %s)",
                             v->tok, (long long)k + 1, v->h[0]);
    }
    if (check != CLI_VTK_SKIP) {
      int code = cli_check_value(v->path, v->tline, v->tcol, x, check != CLI_VTK_COORD, what);
      if (code != CLI_OK) return code;
    }
    if (dst) dst[k] = x;
    if ((k & 0xfffff) == 0) cli_progress_update(&v->prog, (double)ftello(v->f));
  }
  /* The rest of the line of the last value belongs to no one. */
  if (v->sep != '\n' && v->sep != EOF) {
    int c;
    do {
      c = cli_vtk_getc(v);
    } while (c != '\n' && c != EOF);
  }
  return CLI_OK;
}

/* METADATA blocks (version 5) end at a blank line. */
static void cli_vtk_skip_metadata(cli_vtk *v) {
  char buf[512];
  while (cli_vtk_rawline(v, buf, sizeof buf)) {
    char *p = buf;
    while (*p == ' ' || *p == '\t') p++;
    if (!*p) return;
  }
}

/* The state of the reader: points and the chosen radius array. */
typedef struct cli_vtk_data {
  int64_t npoints; /* -1 before POINTS */
  double *points;  /* 3 * npoints */
  double *radius;  /* npoints, or NULL */
  int radius_rank; /* 2: named by --radius or 'radius'; 1: 'diameter' (halved) */
  bool halve;
  bool in_points;  /* in POINT_DATA (else CELL_DATA or dataset FIELD) */
  int64_t tuples;  /* of the current attribute section */
} cli_vtk_data;

/* 2 when name is the radius array, 1 a diameter, 0 neither. */
static int cli_vtk_radius_rank(const cli_read_opts *o, const char *name) {
  if (o->radius) return strcmp(name, o->radius) == 0 ? 2 : 0;
  if (strcasecmp(name, "radius") == 0 || strcasecmp(name, "r") == 0 || strcasecmp(name, "rad") == 0) {
    return 2;
  }
  if (strcasecmp(name, "diameter") == 0 || strcasecmp(name, "d") == 0 ||
      strcasecmp(name, "diam") == 0) {
    return 1;
  }
  return 0;
}

/* An attribute array of `tuples` x `ncomp` values: kept if it is the radius. */
static int cli_vtk_array(cli_vtk *v, const cli_read_opts *o, cli_vtk_data *d, const char *name,
                         int64_t ncomp, const cli_vtk_type *t) {
  int64_t count;
  if (ncomp < 1 || d->tuples > INT64_MAX / 64 / ncomp) {
    return cli_input_error(v->path, v->hline, 1, "bad component count %lld", (long long)ncomp);
  }
  count = d->tuples * ncomp;
  int rank = d->in_points && !o->has_diameter ? cli_vtk_radius_rank(o, name) : 0;
  if (rank > d->radius_rank && ncomp == 1) {
    double *r = malloc((size_t)(d->tuples > 0 ? d->tuples : 1) * sizeof *r);
    if (!r) return cli_fail(CLI_RESOURCE, "%s: out of memory", v->path);
    int code = cli_vtk_values(v, count, t, r, rank == 2 ? CLI_VTK_RADIUS : CLI_VTK_DIAMETER, false);
    if (code != CLI_OK) {
      free(r);
      return code;
    }
    free(d->radius);
    d->radius = r;
    d->radius_rank = rank;
    d->halve = rank == 1;
    return CLI_OK;
  }
  return cli_vtk_values(v, count, t, NULL, CLI_VTK_SKIP, false);
}

/* FIELD name k, then k arrays "name ncomp ntuples type". */
static int cli_vtk_field(cli_vtk *v, const cli_read_opts *o, cli_vtk_data *d) {
  int64_t k;
  if (v->nh < 3 || !cli_vtk_count(v->h[2], &k)) {
    return cli_input_error(v->path, v->hline, 1, "FIELD: expected 'FIELD name count'");
  }
  if (k > cli_vtk_left(v) / 4) {
    return cli_input_error(v->path, v->hline, v->hcol[2], "FIELD declares %lld arrays, more than "
                           "the rest of the file can hold", (long long)k);
  }
  for (int64_t a = 0; a < k; a++) {
    if (!cli_vtk_header(v)) {
      return cli_input_error(v->path, v->line, 1, "truncated: FIELD declares %lld arrays, the "
                             "file ends after %lld", (long long)k, (long long)a);
    }
    if (cli_vtk_is(v, "METADATA")) {
      cli_vtk_skip_metadata(v);
      a--;
      continue;
    }
    if (cli_vtk_is(v, "NULL_ARRAY")) continue;
    int64_t ncomp, ntuples;
    const cli_vtk_type *t;
    if (v->nh < 4 || !cli_vtk_count(v->h[1], &ncomp) || !cli_vtk_count(v->h[2], &ntuples)) {
      return cli_input_error(v->path, v->hline, 1,
                             "FIELD array: expected 'name components tuples type'");
    }
    int code = cli_vtk_type_at(v, 3, &t);
    if (code != CLI_OK) return code;
    int64_t saved = d->tuples;
    bool in_points = d->in_points;
    /* A field array of the point data is a point array only if it has a tuple per point. */
    d->in_points = in_points && ntuples == d->npoints;
    d->tuples = ntuples;
    char name[128];
    snprintf(name, sizeof name, "%s", v->h[0]);
    code = cli_vtk_array(v, o, d, name, ncomp, t);
    d->tuples = saved;
    d->in_points = in_points;
    if (code != CLI_OK) return code;
  }
  return CLI_OK;
}

/* Cell sections: "KEY n size" then the lists (before version 5), or OFFSETS / CONNECTIVITY
 * arrays (version 5). */
static int cli_vtk_cells(cli_vtk *v) {
  int64_t n, size;
  if (v->nh < 3 || !cli_vtk_count(v->h[1], &n) || !cli_vtk_count(v->h[2], &size)) {
    return cli_input_error(v->path, v->hline, 1, "%s: expected '%s count size'", v->h[0], v->h[0]);
  }
  static const cli_vtk_type int32 = {"int", 4, false, true};
  if (v->version < 5) return cli_vtk_values(v, size, &int32, NULL, CLI_VTK_SKIP, false);
  char key[32];
  snprintf(key, sizeof key, "%s", v->h[0]);
  for (int part = 0; part < 2; part++) {
    const char *want = part == 0 ? "OFFSETS" : "CONNECTIVITY";
    if (!cli_vtk_header(v) || !cli_vtk_is(v, want)) {
      return cli_input_error(v->path, v->hline, 1, "%s: expected %s (a version %d file)", key, want,
                             v->version);
    }
    const cli_vtk_type *t;
    int code = cli_vtk_type_at(v, 1, &t);
    if (code != CLI_OK) return code;
    code = cli_vtk_values(v, part == 0 ? n : size, t, NULL, CLI_VTK_SKIP, false);
    if (code != CLI_OK) return code;
  }
  return CLI_OK;
}

static int cli_vtk_body(cli_vtk *v, const cli_read_opts *o, cli_vtk_data *d) {
  static const cli_vtk_type int32 = {"int", 4, false, true};
  static const cli_vtk_type f32 = {"float", 4, true, true};
  int code = CLI_OK;
  bool dataset = false;
  while (code == CLI_OK && cli_vtk_header(v)) {
    const char *kw = v->h[0];
    if (cli_vtk_is(v, "DATASET")) {
      if (v->nh < 2) return cli_input_error(v->path, v->hline, 1, "DATASET: the type is missing");
      const char *t = v->h[1];
      if (strcasecmp(t, "POLYDATA") != 0 && strcasecmp(t, "UNSTRUCTURED_GRID") != 0 &&
          strcasecmp(t, "STRUCTURED_GRID") != 0) {
        return cli_input_error(v->path, v->hline, v->hcol[1],
                               "DATASET %s has no list of points: use POLYDATA, "
                               "UNSTRUCTURED_GRID or STRUCTURED_GRID", t);
      }
      dataset = true;
    } else if (cli_vtk_is(v, "POINTS")) {
      int64_t n;
      const cli_vtk_type *t;
      if (d->npoints >= 0) return cli_input_error(v->path, v->hline, 1, "a second POINTS section");
      if (v->nh < 2 || !cli_vtk_count(v->h[1], &n)) {
        return cli_input_error(v->path, v->hline, v->nh < 2 ? 7 : v->hcol[1],
                               "POINTS: the count is not an integer >= 0");
      }
      code = cli_vtk_type_at(v, 2, &t);
      if (code != CLI_OK) return code;
      if (n > INT32_MAX) {
        return cli_input_error(v->path, v->hline, v->hcol[1], "%lld points: more than 2^31 - 1",
                               (long long)n);
      }
      /* Checked against the file's size before allocating. */
      int64_t least = v->binary ? 3 * n * t->size : 6 * n - 1;
      if (least > cli_vtk_left(v)) {
        return cli_input_error(v->path, v->hline, v->hcol[1],
                               "POINTS declares %lld points, more than the %lld bytes left can "
                               "hold", (long long)n, (long long)cli_vtk_left(v));
      }
      d->points = malloc((size_t)(n > 0 ? n : 1) * 3 * sizeof(double));
      if (!d->points) return cli_fail(CLI_RESOURCE, "%s: out of memory for %lld points", v->path, (long long)n);
      d->npoints = n;
      code = cli_vtk_values(v, 3 * n, t, d->points, CLI_VTK_COORD, false);
    } else if (cli_vtk_is(v, "METADATA")) {
      cli_vtk_skip_metadata(v);
    } else if (cli_vtk_is(v, "DIMENSIONS")) {
      /* STRUCTURED_GRID: the sizes; the points follow. */
    } else if (cli_vtk_is(v, "VERTICES") || cli_vtk_is(v, "LINES") || cli_vtk_is(v, "POLYGONS") ||
               cli_vtk_is(v, "TRIANGLE_STRIPS") || cli_vtk_is(v, "CELLS")) {
      code = cli_vtk_cells(v);
    } else if (cli_vtk_is(v, "CELL_TYPES")) {
      int64_t n;
      if (v->nh < 2 || !cli_vtk_count(v->h[1], &n)) {
        return cli_input_error(v->path, v->hline, 1, "CELL_TYPES: the count is missing");
      }
      code = cli_vtk_values(v, n, &int32, NULL, CLI_VTK_SKIP, false);
    } else if (cli_vtk_is(v, "POINT_DATA") || cli_vtk_is(v, "CELL_DATA")) {
      int64_t n;
      if (v->nh < 2 || !cli_vtk_count(v->h[1], &n)) {
        return cli_input_error(v->path, v->hline, 1, "%s: the count is missing", kw);
      }
      d->in_points = cli_vtk_is(v, "POINT_DATA");
      if (d->in_points && n != d->npoints) {
        return cli_input_error(v->path, v->hline, v->hcol[1],
                               "POINT_DATA %lld, but POINTS declared %lld", (long long)n,
                               (long long)d->npoints);
      }
      d->tuples = n;
    } else if (cli_vtk_is(v, "FIELD")) {
      code = cli_vtk_field(v, o, d);
    } else if (cli_vtk_is(v, "SCALARS")) {
      const cli_vtk_type *t;
      int64_t ncomp = 1;
      if (v->nh < 3) return cli_input_error(v->path, v->hline, 1, "SCALARS: expected 'SCALARS name type'");
      code = cli_vtk_type_at(v, 2, &t);
      if (code != CLI_OK) return code;
      if (v->nh >= 4 && (!cli_vtk_count(v->h[3], &ncomp) || ncomp < 1 || ncomp > 4)) {
        return cli_input_error(v->path, v->hline, v->hcol[3], "SCALARS: bad component count '%s'",
                               v->h[3]);
      }
      char name[128];
      snprintf(name, sizeof name, "%s", v->h[1]);
      if (!cli_vtk_header(v) || !cli_vtk_is(v, "LOOKUP_TABLE")) {
        return cli_input_error(v->path, v->hline, 1, "SCALARS %s: expected 'LOOKUP_TABLE name'", name);
      }
      code = cli_vtk_array(v, o, d, name, ncomp, t);
    } else if (cli_vtk_is(v, "LOOKUP_TABLE")) {
      int64_t n;
      if (v->nh < 3 || !cli_vtk_count(v->h[2], &n)) {
        return cli_input_error(v->path, v->hline, 1, "LOOKUP_TABLE: expected 'LOOKUP_TABLE name size'");
      }
      code = cli_vtk_values(v, 4 * n, &f32, NULL, CLI_VTK_SKIP, true);
    } else if (cli_vtk_is(v, "COLOR_SCALARS")) {
      int64_t m;
      if (v->nh < 3 || !cli_vtk_count(v->h[2], &m) || m < 1 || m > 16) {
        return cli_input_error(v->path, v->hline, 1,
                               "COLOR_SCALARS: expected 'COLOR_SCALARS name count' (count 1 to 16)");
      }
      code = cli_vtk_values(v, m * d->tuples, &f32, NULL, CLI_VTK_SKIP, true);
    } else if (cli_vtk_is(v, "VECTORS") || cli_vtk_is(v, "NORMALS") || cli_vtk_is(v, "TENSORS") ||
               cli_vtk_is(v, "TENSORS6") || cli_vtk_is(v, "GLOBAL_IDS") ||
               cli_vtk_is(v, "PEDIGREE_IDS")) {
      const cli_vtk_type *t;
      code = cli_vtk_type_at(v, 2, &t);
      if (code != CLI_OK) return code;
      int64_t per = cli_vtk_is(v, "VECTORS") || cli_vtk_is(v, "NORMALS") ? 3
                    : cli_vtk_is(v, "TENSORS") ? 9
                    : cli_vtk_is(v, "TENSORS6") ? 6 : 1;
      code = cli_vtk_values(v, per * d->tuples, t, NULL, CLI_VTK_SKIP, false);
    } else if (cli_vtk_is(v, "TEXTURE_COORDINATES")) {
      int64_t dim;
      const cli_vtk_type *t;
      if (v->nh < 4 || !cli_vtk_count(v->h[2], &dim) || dim < 1 || dim > 3) {
        return cli_input_error(v->path, v->hline, 1, "TEXTURE_COORDINATES: expected 'name dim type'");
      }
      code = cli_vtk_type_at(v, 3, &t);
      if (code != CLI_OK) return code;
      code = cli_vtk_values(v, dim * d->tuples, t, NULL, CLI_VTK_SKIP, false);
    } else {
      return cli_input_error(v->path, v->hline, 1, "unknown keyword '%.40s'", kw);
    }
  }
  if (code == CLI_OK && !dataset) {
    return cli_input_error(v->path, v->line, 1, "no DATASET line");
  }
  return code;
}

int cli_read_vtk(FILE *f, const char *path, const cli_read_opts *o, cli_elements *out) {
  cli_vtk v;
  memset(&v, 0, sizeof v);
  v.f = f;
  v.path = path;
  v.line = 1;
  v.col = 1;
  if (fseeko(f, 0, SEEK_END) != 0) return cli_input_error(path, 0, 0, "cannot seek");
  v.size = (int64_t)ftello(f);
  rewind(f);
  if (v.size == 0) return cli_input_error(path, 1, 1, "empty file: no elements");

  char buf[512];
  int major = 0, minor = 0;
  if (!cli_vtk_rawline(&v, buf, sizeof buf) ||
      sscanf(buf, "# vtk DataFile Version %d.%d", &major, &minor) != 2) {
    return cli_input_error(path, 1, 1, "not a legacy VTK file: the first line is not "
                                       "'# vtk DataFile Version x.y'");
  }
  v.version = major;
  /* At the end of the file, errors point at its end (not at lines it does not have). */
  if (!cli_vtk_rawline(&v, buf, sizeof buf)) {
    return cli_input_error(path, v.line, v.col, "truncated: no title line");
  }
  if (!cli_vtk_header(&v)) {
    return cli_input_error(path, v.line, v.col, "truncated: no ASCII or BINARY line");
  }
  if (!cli_vtk_is(&v, "ASCII") && !cli_vtk_is(&v, "BINARY")) {
    return cli_input_error(path, v.hline, 1, "the third line must be ASCII or BINARY");
  }
  v.binary = cli_vtk_is(&v, "BINARY");

  cli_progress_begin(&v.prog, "reading", (double)v.size);
  cli_vtk_data d;
  memset(&d, 0, sizeof d);
  d.npoints = -1;
  int code = cli_vtk_body(&v, o, &d);
  cli_progress_end(&v.prog);
  if (code == CLI_OK && d.npoints < 0) code = cli_input_error(path, v.line, 1, "no POINTS section");
  if (code == CLI_OK && d.npoints == 0) code = cli_input_error(path, v.line, 1, "no elements: POINTS 0");
  if (code == CLI_OK && !o->has_diameter && !d.radius) {
    code = o->radius ? cli_input_error(path, 0, 0, "no point array '%s'", o->radius)
                     : cli_input_error(path, 0, 0, "no point array 'radius' or 'diameter'; give "
                                                   "--diameter or --radius NAME");
  }
  if (code != CLI_OK) {
    free(d.points);
    free(d.radius);
    return code;
  }
  const int dim = o->dim ? o->dim : 3;
  if (dim == 2) {
    for (int64_t k = 0; k < d.npoints; k++) {
      d.points[2 * k] = d.points[3 * k];
      d.points[2 * k + 1] = d.points[3 * k + 1];
    }
  }
  if (d.halve) {
    for (int64_t k = 0; k < d.npoints; k++) d.radius[k] *= 0.5;
  }
  out->dim = dim;
  out->n = d.npoints;
  out->coords = d.points;
  if (o->has_diameter) {
    free(d.radius);
    out->radii = NULL;
    out->diameter = o->diameter;
  } else {
    out->radii = d.radius;
  }
  return CLI_OK;
}
