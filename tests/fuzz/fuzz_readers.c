/*
 * Fuzz target for the file readers of the nbs tool (apps/read*.c): CSV, raw f64, LAMMPS /
 * LIGGGHTS dumps, legacy VTK and VTK XML (.vtp / .vtu: ascii, base64, raw or base64 appended
 * data, zlib or not). The fuzz bytes are 3 bytes of options followed by the file; the file is
 * read through the tool's own entry points:
 *   - cli_read on a temporary file whose name has one of the extensions the tool knows, or
 *     none (the format recognised from the content, then the name);
 *   - cli_read("-") with the file as standard input (read whole into memory);
 *   - each per-format reader (cli_read_csv, ...) on the bytes in memory (fmemopen), and on the
 *     temporary file (a regular file: the f64 reader sizes its buffer from it);
 * with --dim unset, 2 or 3, with and without --diameter, dump snapshot / timestep selection,
 * CSV --columns and --radius NAME.
 *
 * Checked for every read (beyond ASan + UBSan + leaks):
 *   - a failure is CLI_INPUT with exactly one message line "FILE:LINE[:COLUMN]: text" whose
 *     position lies in the file (LINE <= lines + 1, COLUMN <= that line's length + 1; for raw
 *     f64, the element and the value within it), or "FILE: text" for the few whole-file
 *     complaints (no such snapshot, no radius array); or CLI_USAGE ("nbs detect: ..." and
 *     the hint line) only for the options that need one (f64 or CSV without --dim, --columns);
 *     never CLI_RESOURCE or anything else on these small inputs;
 *   - a success prints nothing and returns the dimension asked for (dump, VTK: 3 by default),
 *     1 <= n < 2^31 elements, n * dim finite coordinates and n finite radii > 0 (every value
 *     is read, so ASan checks the arrays' sizes against n), or no radii and the diameter of
 *     --diameter; and, for n <= 256, the library detects its contacts with auto (no refusal
 *     for finite input) and finds as many as direct;
 *   - raw f64 against an independent oracle: the status, the error position and the values;
 *   - consistency between reads of the same bytes: cli_read (file or standard input) and the
 *     reader of the format cli_sniff names on the bytes in memory give the same status, the
 *     same message and the same elements; memory and regular file alike; dump, VTK and VTK
 *     XML give with --dim 2 the elements of --dim 3 without z (and the default is 3); a read
 *     that succeeds without --diameter succeeds with it, with the same coordinates (CSV,
 *     dump, VTK, VTK XML).
 *
 * Options (byte 0):
 *   bits 0-2  0 cli_read on the temporary file, 1 csv, 2 f64, 3 dump, 4 vtk, 5 vtp,
 *             6 cli_read("-") on standard input, 7 every reader in turn
 *   bits 3-4  --dim: unset, 2, 3, or each of the three
 *   bit 5     --diameter (from byte 2)
 *   bit 6     with and without --diameter
 *   bit 7     the per-format readers also on the temporary file (compared with memory)
 * byte 1: bits 0-2 dump snapshot / timestep (dump_select[]), bits 3-5 CSV --columns
 *   (columns[]), bits 6-7 --radius (radius_names[]);
 * byte 2: bits 0-3 the diameter (diameters[]), bits 4-7 the temporary file's extension
 *   (extensions[]).
 */
#include "cli.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define FZ_DETECT_MAX 256

static const char *fz_what = "";

#define FZ_FAIL(...)                                                                          \
  do {                                                                                        \
    fprintf(fz_stderr(), "fuzz_readers: %s: ", fz_what);                                      \
    fprintf(fz_stderr(), __VA_ARGS__);                                                        \
    fputc('\n', fz_stderr());                                                                 \
    abort();                                                                                  \
  } while (0)

/* ---- the reader's messages -------------------------------------------------------------- */

/* The readers report on stderr; it is replaced by a memory stream around each read (glibc's
 * stderr is an ordinary variable). The sanitizers and libFuzzer write to fd 2 directly. */
static FILE *fz_real_stderr;

static FILE *fz_stderr(void) { return fz_real_stderr ? fz_real_stderr : stderr; }

typedef struct fz_capture {
  char *text;
  size_t len;
  FILE *mem;
} fz_capture;

static void fz_capture_begin(fz_capture *c) {
  c->text = NULL;
  c->len = 0;
  c->mem = open_memstream(&c->text, &c->len);
  if (!c->mem) abort();
  fz_real_stderr = stderr;
  stderr = c->mem;
}

static void fz_capture_end(fz_capture *c) {
  stderr = fz_real_stderr;
  fz_real_stderr = NULL;
  fclose(c->mem);
  c->mem = NULL;
}

/* ---- options ---------------------------------------------------------------------------- */

enum { FZ_SRC_MEMORY, FZ_SRC_FILE, FZ_SRC_READ, FZ_SRC_STDIN };

static const struct {
  int64_t snapshot, timestep;
} dump_select[8] = {{0, -1}, {1, -1}, {2, -1}, {-1, -1}, {0, 0}, {0, 1000}, {0, 1}, {7, -1}};

static const char *const columns[8] = {NULL,           "1,2",     "1,2,3",      "1,2,3,4",
                                       "x,y,z,radius", "5,4,3,2", "px,py,rad", "x,y,diameter"};

static const char *const radius_names[4] = {NULL, "radius", "diameter", "mass"};

static const double diameters[16] = {1.0,  0.5,    2.0,    2.6,     1e-3,     1e3,
                                     0.1,  1.0 / 3, 1e-300, 5e-324, 1e300,    DBL_MAX,
                                     1e-160, 1e154, 7.0,   1e-6};

static const char *const extensions[16] = {"",     ".csv",  ".txt",       ".xyz",
                                           ".f64", ".bin",  ".raw",       ".vtk",
                                           ".vtp", ".vtu",  ".dump",      ".lammpstrj",
                                           ".liggghts", ".CSV", ".VTK",   ".dat"};

/* ---- the file ----------------------------------------------------------------------------- */

typedef struct fz_file {
  const unsigned char *p; /* the file's bytes (after the option bytes) */
  size_t len;
  char path[4200];        /* the temporary file */
  bool written;
} fz_file;

static char fz_dir[4096];

static void fz_remove_dir(void) {
  if (!fz_dir[0]) return;
  for (size_t e = 0; e < sizeof extensions / sizeof extensions[0]; e++) {
    char p[sizeof fz_dir + 32];
    int k = snprintf(p, sizeof p, "%s/in%s", fz_dir, extensions[e]);
    if (k > 0 && (size_t)k < sizeof p) unlink(p);
  }
  rmdir(fz_dir);
}

/* The path of the temporary file with extension ext (created on first use). */
static void fz_path(fz_file *f, const char *ext) {
  if (!fz_dir[0]) {
    const char *t = getenv("TMPDIR");
    snprintf(fz_dir, sizeof fz_dir, "%s/nbs-fuzz-readers.XXXXXX", t && *t ? t : "/tmp");
    if (!mkdtemp(fz_dir)) {
      perror("fuzz_readers: mkdtemp");
      abort();
    }
    atexit(fz_remove_dir);
  }
  int k = snprintf(f->path, sizeof f->path, "%s/in%s", fz_dir, ext);
  if (k < 0 || (size_t)k >= sizeof f->path) abort();
}

static void fz_write(fz_file *f) {
  if (f->written) return;
  FILE *out = fopen(f->path, "wb");
  if (!out || fwrite(f->p, 1, f->len, out) != f->len || fclose(out) != 0) {
    perror("fuzz_readers: writing the temporary file");
    abort();
  }
  f->written = true;
}

/* fmemopen needs a writable buffer and, portably, a non-zero size; an empty file is a
 * truncated read-write stream. */
static FILE *fz_memory(fz_file *f, unsigned char **copy) {
  *copy = malloc(f->len ? f->len : 1);
  if (!*copy) abort();
  if (f->len) memcpy(*copy, f->p, f->len);
  FILE *m = f->len ? fmemopen(*copy, f->len, "rb") : fmemopen(*copy, 1, "w+b");
  if (!m) abort();
  return m;
}

/* ---- one read ------------------------------------------------------------------------------ */

typedef struct fz_result {
  int code;
  char *msg; /* what was written on stderr ("" for nothing) */
  cli_elements e;
  cli_format format; /* the format read */
  const char *label; /* the name the messages use */
} fz_result;

static void fz_result_free(fz_result *r) {
  free(r->msg);
  r->msg = NULL;
  if (r->code == CLI_OK) cli_elements_free(&r->e);
}

static int fz_call(cli_format fmt, FILE *in, const char *label, const cli_read_opts *o,
                   cli_elements *e) {
  switch (fmt) {
  case CLI_FORMAT_CSV: return cli_read_csv(in, label, o, e);
  case CLI_FORMAT_F64: return cli_read_f64(in, label, o, e);
  case CLI_FORMAT_DUMP: return cli_read_dump(in, label, o, e);
  case CLI_FORMAT_VTK: return cli_read_vtk(in, label, o, e);
  case CLI_FORMAT_VTP: return cli_read_vtp(in, label, o, e);
  default: abort();
  }
}

/* Reads f from src; fmt is the format of a per-format read (ignored by cli_read). */
static fz_result fz_read(fz_file *f, int src, cli_format fmt, const cli_read_opts *o,
                         const char *label) {
  fz_result r;
  memset(&r, 0, sizeof r);
  r.label = label;
  r.format = fmt;
  fz_capture cap;
  if (src == FZ_SRC_MEMORY || src == FZ_SRC_FILE) {
    unsigned char *copy = NULL;
    FILE *in = src == FZ_SRC_MEMORY ? fz_memory(f, &copy) : fopen(f->path, "rb");
    if (!in) abort();
    fz_capture_begin(&cap);
    r.code = fz_call(fmt, in, label, o, &r.e);
    fz_capture_end(&cap);
    fclose(in);
    free(copy);
  } else if (src == FZ_SRC_READ) {
    fz_capture_begin(&cap);
    r.code = cli_read(f->path, o, &r.e, &r.format);
    fz_capture_end(&cap);
  } else {
    FILE *in = fopen(f->path, "rb");
    if (!in) abort();
    FILE *saved = stdin;
    stdin = in;
    fz_capture_begin(&cap);
    r.code = cli_read("-", o, &r.e, &r.format);
    fz_capture_end(&cap);
    stdin = saved;
    fclose(in);
  }
  r.msg = cap.text;
  /* A reader may leave arrays behind on an error (the dump reader when lines follow the
   * atoms): cli_read frees them, as here. */
  if (r.code != CLI_OK) cli_elements_free(&r.e);
  return r;
}

/* ---- the message of a failure -------------------------------------------------------------- */

/* Line l (1-based) of the file: its length without the line end; false past the end. */
static bool fz_line_length(const fz_file *f, long l, size_t *len) {
  size_t at = 0;
  for (long k = 1; k < l; k++) {
    const unsigned char *nl = memchr(f->p + at, '\n', f->len - at);
    if (!nl) return false;
    at = (size_t)(nl - f->p) + 1;
  }
  const unsigned char *nl = memchr(f->p + at, '\n', f->len - at);
  size_t e = nl ? (size_t)(nl - f->p) : f->len;
  *len = e - at;
  return true;
}

static long fz_number(const char **s) {
  long v = 0;
  while (**s >= '0' && **s <= '9') {
    if (v > 100000000) FZ_FAIL("absurd position in the message");
    v = v * 10 + (**s - '0');
    (*s)++;
  }
  return v;
}

/* Whole-file complaints, reported as "FILE: text". */
static const char *const fz_whole_file[] = {"no snapshot ", "no point array ", NULL};

static void fz_check_failure(const fz_file *f, const fz_result *r, const cli_read_opts *o) {
  const char *m = r->msg;
  size_t ml = strlen(m);
  if (ml == 0) FZ_FAIL("status %d without a message", r->code);
  if (m[ml - 1] != '\n') FZ_FAIL("the message does not end a line: '%s'", m);

  if (r->code == CLI_USAGE) {
    /* Only the options can be wrong: f64 and headerless CSV need --dim, --columns. */
    bool allowed = (r->format == CLI_FORMAT_F64 && o->dim == 0) ||
                   (r->format == CLI_FORMAT_CSV && (o->dim == 0 || o->columns));
    if (!allowed) FZ_FAIL("a usage error for the %s reader: %s", cli_format_name(r->format), m);
    static const char hint[] = "\nTry 'nbs detect --help'.\n";
    size_t hl = sizeof hint - 1;
    if (strncmp(m, "nbs detect: ", 12) != 0 || ml < 12 + hl ||
        strcmp(m + ml - hl, hint) != 0 || memchr(m, '\n', ml - hl) != NULL) {
      FZ_FAIL("a malformed usage message: '%s'", m);
    }
    return;
  }
  if (r->code != CLI_INPUT) FZ_FAIL("status %d on a %zu-byte file: %s", r->code, f->len, m);
  if (memchr(m, '\n', ml - 1)) FZ_FAIL("more than one line: '%s'", m);

  size_t ll = strlen(r->label);
  if (strncmp(m, r->label, ll) != 0 || m[ll] != ':') {
    FZ_FAIL("the message does not start with '%s:': '%s'", r->label, m);
  }
  const char *s = m + ll + 1;
  long line = 0, col = 0;
  if (*s >= '0' && *s <= '9') {
    line = fz_number(&s);
    if (*s != ':' || line < 1) FZ_FAIL("malformed position: '%s'", m);
    s++;
    if (*s >= '0' && *s <= '9') {
      col = fz_number(&s);
      if (*s != ':' || col < 1) FZ_FAIL("malformed position: '%s'", m);
      s++;
    }
  }
  if (*s != ' ' || s[1] == '\n' || s[1] == ' ') FZ_FAIL("malformed message: '%s'", m);
  s++;
  if (line == 0) {
    bool ok = false;
    for (const char *const *w = fz_whole_file; *w; w++) ok |= strncmp(s, *w, strlen(*w)) == 0;
    if (!ok) FZ_FAIL("a message without a line: '%s'", m);
    return;
  }
  if (r->format == CLI_FORMAT_F64) {
    /* LINE is the element, COLUMN the value within it. */
    size_t rec = (size_t)o->dim + (o->has_diameter ? 0 : 1);
    if ((size_t)line > f->len / (8 * rec) + 1 || col < 1 || (size_t)col > rec) {
      FZ_FAIL("element %ld, value %ld: not in a %zu-byte file of %zu-value elements: '%s'",
              line, col, f->len, rec, m);
    }
    return;
  }
  size_t len;
  if (!fz_line_length(f, line, &len)) FZ_FAIL("line %ld is past the end of the file: %s", line, m);
  if (col > 0 && (size_t)col > len + 1) {
    FZ_FAIL("column %ld is past the end of line %ld (%zu bytes): '%s'", col, line, len, m);
  }
}

/* ---- a success ----------------------------------------------------------------------------- */

static nbs_context *fz_ctx;

static void fz_destroy_context(void) { nbs_context_destroy(fz_ctx); }

static void fz_check_detect(const cli_elements *e) {
  if (e->n > FZ_DETECT_MAX) return;
  if (!fz_ctx) {
    if (nbs_context_create(NULL, &fz_ctx) != NBS_OK) FZ_FAIL("nbs_context_create");
    atexit(fz_destroy_context);
  }
  nbs_input in = {.dim = e->dim, .n = e->n, .coords = e->coords, .radii = e->radii,
                  .diameter = e->diameter};
  nbs_detect_def def = nbs_default_detect_def();
  def.algorithm = NBS_AUTO;
  nbs_status st = nbs_detect(fz_ctx, &in, &def);
  if (st != NBS_OK) {
    FZ_FAIL("the library refuses what the reader returned: %s (%s)", nbs_status_name(st),
            nbs_context_error(fz_ctx));
  }
  size_t count, direct;
  nbs_pairs(fz_ctx, &count);
  def.algorithm = NBS_DIRECT;
  st = nbs_detect(fz_ctx, &in, &def);
  if (st != NBS_OK) FZ_FAIL("direct: %s (%s)", nbs_status_name(st), nbs_context_error(fz_ctx));
  nbs_pairs(fz_ctx, &direct);
  if (count != direct) FZ_FAIL("auto finds %zu contacts, direct %zu", count, direct);
}

static void fz_check_success(const fz_file *f, const fz_result *r, const cli_read_opts *o) {
  const cli_elements *e = &r->e;
  if (r->msg[0]) FZ_FAIL("a success with a message: '%s'", r->msg);
  int want = o->dim;
  if (want == 0 && r->format != CLI_FORMAT_CSV) want = 3;
  if (want ? e->dim != want : e->dim != 2 && e->dim != 3) {
    FZ_FAIL("dimension %d (--dim %d, %s)", e->dim, o->dim, cli_format_name(r->format));
  }
  if (e->n < 1 || e->n > INT32_MAX) FZ_FAIL("%lld elements", (long long)e->n);
  if (!e->coords) FZ_FAIL("no coordinates");
  const size_t n = (size_t)e->n;
  for (size_t k = 0; k < n * (size_t)e->dim; k++) {
    if (!isfinite(e->coords[k])) FZ_FAIL("coordinate %zu is %g", k, e->coords[k]);
  }
  if (o->has_diameter) {
    if (e->radii) FZ_FAIL("radii returned with --diameter");
    if (e->diameter != o->diameter) FZ_FAIL("diameter %g, --diameter %g", e->diameter, o->diameter);
  } else {
    if (!e->radii) FZ_FAIL("no radii without --diameter");
    for (size_t k = 0; k < n; k++) {
      if (!(e->radii[k] > 0 && e->radii[k] <= DBL_MAX)) FZ_FAIL("radius %zu is %g", k, e->radii[k]);
    }
  }
  (void)f;
  fz_check_detect(e);
}

/* Raw f64 against its definition. */
static void fz_check_f64(const fz_file *f, const fz_result *r, const cli_read_opts *o) {
  if (o->dim == 0) {
    if (r->code != CLI_USAGE) FZ_FAIL("f64 without --dim: status %d", r->code);
    return;
  }
  const size_t rec = (size_t)o->dim + (o->has_diameter ? 0 : 1);
  long bad_line = 0, bad_col = 0;
  if (f->len == 0 || f->len % (8 * rec) != 0) {
    bad_line = (long)(f->len / (8 * rec)) + 1;
    bad_col = (long)(f->len % (8 * rec) / 8) + 1;
  } else {
    for (size_t k = 0; k < f->len / 8 && !bad_line; k++) {
      double v;
      memcpy(&v, f->p + 8 * k, 8);
      bool radius = k % rec == (size_t)o->dim;
      if (!isfinite(v) || (radius && !(v > 0))) {
        bad_line = (long)(k / rec) + 1;
        bad_col = (long)(k % rec) + 1;
      }
    }
  }
  if (bad_line) {
    char want[64];
    snprintf(want, sizeof want, "%s:%ld:%ld: ", r->label, bad_line, bad_col);
    if (r->code != CLI_INPUT || strncmp(r->msg, want, strlen(want)) != 0) {
      FZ_FAIL("f64: status %d '%s', expected an error at %s", r->code, r->msg, want);
    }
    return;
  }
  if (r->code != CLI_OK) FZ_FAIL("f64: a valid file refused: %s", r->msg);
  const size_t n = f->len / (8 * rec);
  if ((size_t)r->e.n != n) FZ_FAIL("f64: %lld elements, the file has %zu", (long long)r->e.n, n);
  for (size_t k = 0; k < n; k++) {
    for (size_t a = 0; a < rec; a++) {
      double v;
      memcpy(&v, f->p + 8 * (k * rec + a), 8);
      double got = a < (size_t)o->dim ? r->e.coords[k * (size_t)o->dim + a] : r->e.radii[k];
      if (memcmp(&v, &got, 8) != 0) FZ_FAIL("f64: element %zu value %zu differs", k, a);
    }
  }
}

static void fz_check(const fz_file *f, const fz_result *r, const cli_read_opts *o) {
  if (r->code == CLI_OK) {
    fz_check_success(f, r, o);
  } else {
    fz_check_failure(f, r, o);
  }
  if (r->format == CLI_FORMAT_F64) fz_check_f64(f, r, o);
}

/* ---- comparisons between reads --------------------------------------------------------------- */

static bool fz_same_values(const double *a, const double *b, size_t count) {
  if (!a || !b) return a == b;
  return memcmp(a, b, count * sizeof *a) == 0;
}

/* The same status, message and elements. */
static void fz_same(const fz_result *a, const fz_result *b, const char *what) {
  if (a->code != b->code || strcmp(a->msg, b->msg) != 0) {
    FZ_FAIL("%s: status %d '%s' against %d '%s'", what, a->code, a->msg, b->code, b->msg);
  }
  if (a->code != CLI_OK) return;
  const cli_elements *x = &a->e, *y = &b->e;
  if (x->dim != y->dim || x->n != y->n || x->diameter != y->diameter ||
      !fz_same_values(x->coords, y->coords, (size_t)x->n * (size_t)x->dim) ||
      !fz_same_values(x->radii, y->radii, (size_t)x->n)) {
    FZ_FAIL("%s: different elements (%lld and %lld)", what, (long long)x->n, (long long)y->n);
  }
}

/* b read with --dim 2 what a read with --dim 3 (dump, VTK, VTK XML). */
static void fz_projection(const fz_result *a3, const fz_result *b2, cli_format fmt) {
  if (fmt == CLI_FORMAT_VTK || fmt == CLI_FORMAT_VTP) {
    /* The dimension only drops z at the end: the same status and message. */
    if (a3->code != b2->code || strcmp(a3->msg, b2->msg) != 0) {
      FZ_FAIL("--dim 3 gives %d '%s', --dim 2 %d '%s'", a3->code, a3->msg, b2->code, b2->msg);
    }
  }
  if (a3->code != CLI_OK) return;
  if (b2->code != CLI_OK) FZ_FAIL("read with --dim 3, refused with --dim 2: %s", b2->msg);
  const cli_elements *x = &a3->e, *y = &b2->e;
  if (x->n != y->n || !fz_same_values(x->radii, y->radii, (size_t)x->n)) {
    FZ_FAIL("--dim 2: other elements than --dim 3");
  }
  for (int64_t k = 0; k < x->n; k++) {
    if (memcmp(&x->coords[3 * k], &y->coords[2 * k], 2 * sizeof(double)) != 0) {
      FZ_FAIL("--dim 2: element %lld is not the one of --dim 3 without z: (%.17g, %.17g) "
              "against (%.17g, %.17g, %.17g)",
              (long long)k, y->coords[2 * k], y->coords[2 * k + 1], x->coords[3 * k],
              x->coords[3 * k + 1], x->coords[3 * k + 2]);
    }
  }
}

/* b read with --diameter what a read without it. */
static void fz_with_diameter(const fz_result *a, const fz_result *b) {
  if (a->code != CLI_OK) return;
  if (b->code != CLI_OK) FZ_FAIL("read without --diameter, refused with it: %s", b->msg);
  const cli_elements *x = &a->e, *y = &b->e;
  if (x->dim != y->dim || x->n != y->n ||
      !fz_same_values(x->coords, y->coords, (size_t)x->n * (size_t)x->dim)) {
    FZ_FAIL("--diameter changes the coordinates");
  }
}

/* ---- the entry point ------------------------------------------------------------------------- */

static const int dim_sets[4][3] = {{0, -1, -1}, {2, -1, -1}, {3, -1, -1}, {0, 2, 3}};

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  cli_quiet = true;
  uint8_t opt[3] = {0, 0, 0};
  for (size_t k = 0; k < 3 && k < size; k++) opt[k] = data[k];
  fz_file f;
  memset(&f, 0, sizeof f);
  f.p = size > 3 ? data + 3 : data;
  f.len = size > 3 ? size - 3 : 0;

  const unsigned mode = opt[0] & 7;
  const int *dims = dim_sets[(opt[0] >> 3) & 3];
  const bool both_diam = (opt[0] & 64) != 0;
  const bool also_file = (opt[0] & 128) != 0;
  cli_read_opts base = cli_default_read_opts();
  base.snapshot = dump_select[opt[1] & 7].snapshot;
  base.timestep = dump_select[opt[1] & 7].timestep;
  base.columns = columns[(opt[1] >> 3) & 7];
  base.radius = radius_names[opt[1] >> 6];
  base.diameter = diameters[opt[2] & 15];
  const char *ext = mode == 0 ? extensions[opt[2] >> 4] : "";
  fz_path(&f, ext);

  cli_format fmts[5];
  int nfmts = 0;
  if (mode == 0 || mode == 6) {
    /* cli_read recognises the format as the tool does: from the first 512 bytes and the
     * name (none for standard input). */
    fmts[nfmts++] = cli_sniff(mode == 0 ? f.path : NULL, f.p, f.len < 512 ? f.len : 512);
    fz_write(&f);
  } else if (mode == 7) {
    for (int k = CLI_FORMAT_CSV; k < CLI_FORMAT_COUNT; k++) fmts[nfmts++] = (cli_format)k;
  } else {
    fmts[nfmts++] = (cli_format)mode;
  }
  if (also_file) fz_write(&f);

  for (int fi = 0; fi < nfmts; fi++) {
    const cli_format fmt = fmts[fi];
    fz_result res[3][2]; /* [dim 0, 2, 3][without, with --diameter] */
    bool have[3][2] = {{false}};
    for (int di = 0; di < 3 && dims[di] >= 0; di++) {
      const int dim = dims[di];
      const int slot = dim == 0 ? 0 : dim == 2 ? 1 : 2;
      for (int hd = 0; hd < 2; hd++) {
        if (!both_diam && hd != ((opt[0] >> 5) & 1)) continue;
        cli_read_opts o = base;
        o.dim = dim;
        o.has_diameter = hd;
        char what[160];
        snprintf(what, sizeof what, "%s, --dim %d%s", cli_format_name(fmt), dim,
                 hd ? ", --diameter" : "");
        fz_what = what;
        fz_result r;
        if (mode == 0 || mode == 6) {
          const char *label = mode == 0 ? f.path : "<stdin>";
          fz_result via = fz_read(&f, mode == 0 ? FZ_SRC_READ : FZ_SRC_STDIN, fmt, &o, label);
          r = fz_read(&f, FZ_SRC_MEMORY, fmt, &o, label);
          fz_same(&via, &r, mode == 0 ? "cli_read and the reader it chose" :
                                        "standard input and the reader it chose");
          if (via.code == CLI_OK && via.format != fmt) FZ_FAIL("cli_read read another format");
          fz_result_free(&via);
        } else {
          r = fz_read(&f, FZ_SRC_MEMORY, fmt, &o, f.path);
          if (also_file) {
            fz_result g = fz_read(&f, FZ_SRC_FILE, fmt, &o, f.path);
            fz_same(&r, &g, "memory and a regular file");
            fz_result_free(&g);
          }
        }
        fz_check(&f, &r, &o);
        res[slot][hd] = r;
        have[slot][hd] = true;
      }
    }
    fz_what = cli_format_name(fmt);
    if (fmt != CLI_FORMAT_CSV && fmt != CLI_FORMAT_F64) {
      for (int hd = 0; hd < 2; hd++) {
        if (have[0][hd] && have[2][hd]) fz_same(&res[0][hd], &res[2][hd], "no --dim and --dim 3");
        if (have[2][hd] && have[1][hd]) fz_projection(&res[2][hd], &res[1][hd], fmt);
      }
    }
    if (fmt != CLI_FORMAT_F64) {
      for (int s = 0; s < 3; s++) {
        if (have[s][0] && have[s][1]) fz_with_diameter(&res[s][0], &res[s][1]);
      }
    }
    for (int s = 0; s < 3; s++) {
      for (int hd = 0; hd < 2; hd++) {
        if (have[s][hd]) fz_result_free(&res[s][hd]);
      }
    }
  }
  if (f.written) unlink(f.path);
  return 0;
}
