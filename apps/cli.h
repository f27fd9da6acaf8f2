/*
 * The nbs command-line tool: what its files share.
 *
 * Built only on the public API (nbs/nbs.h) and the scene library (scenes.h).
 *
 * Errors. Every failure is reported once, on stderr, where it is found, and turned into an
 * exit code that the caller passes up unchanged:
 *   CLI_USAGE (2)     a bad command line (unknown option, bad --dim, unknown algorithm);
 *   CLI_INPUT (3)     a missing or malformed input file, reported as FILE:LINE:COLUMN:;
 *   CLI_RESOURCE (4)  out of memory, the library's budgets and limits, an unwritable output;
 *   CLI_FAIL (1)      anything else (algorithms that disagree in the demo).
 * For binary files (raw f64, binary VTK) LINE:COLUMN name the element (1-based) and the value
 * within it, and the message gives the byte offset.
 */
#ifndef NBS_CLI_H
#define NBS_CLI_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "nbs/nbs.h"

enum { CLI_OK = 0, CLI_FAIL = 1, CLI_USAGE = 2, CLI_INPUT = 3, CLI_RESOURCE = 4 };

#if defined(__GNUC__)
#define CLI_PRINTF(f, a) __attribute__((format(printf, f, a)))
#else
#define CLI_PRINTF(f, a)
#endif

/* ---- util.c: messages ---------------------------------------------------------------- */

/* "nbs: <message>" on stderr; returns code. */
int cli_fail(int code, const char *fmt, ...) CLI_PRINTF(2, 3);
/* "nbs COMMAND: <message>\nTry 'nbs COMMAND --help'." on stderr; returns CLI_USAGE. */
int cli_usage(const char *command, const char *fmt, ...) CLI_PRINTF(2, 3);
/* "FILE:LINE:COLUMN: <message>" on stderr (LINE and COLUMN omitted when 0); returns
 * CLI_INPUT. */
int cli_input_error(const char *file, long line, long column, const char *fmt, ...)
    CLI_PRINTF(4, 5);
/* The exit code for a library status: input for bad numbers, resource for memory and
 * limits. */
int cli_status_code(nbs_status s);

/* s as a JSON string, quoted and escaped. */
void cli_json_string(FILE *f, const char *s);
/* "16.4 MB": bytes in decimal units. */
void cli_format_bytes(char *buf, size_t len, double bytes);

/* -q: no progress bar, no informational lines. */
extern bool cli_quiet;

/* ---- util.c: numbers and options ------------------------------------------------------ */

/* Parses the whole of s as a finite double / a non-negative integer; false otherwise. */
bool cli_parse_double(const char *s, double *out);
bool cli_parse_int64(const char *s, int64_t *out);

/* Monotonic seconds. */
double cli_now(void);

/* ---- util.c: growable arrays (geometric growth: linear total time) -------------------- */

typedef struct cli_dbuf {
  double *v;
  size_t n, cap;
} cli_dbuf;

/* Makes room for `more` values; false on allocation failure. */
bool cli_dbuf_reserve(cli_dbuf *b, size_t more);
static inline bool cli_dbuf_push(cli_dbuf *b, double x) {
  if (b->n == b->cap && !cli_dbuf_reserve(b, 1)) return false;
  b->v[b->n++] = x;
  return true;
}
void cli_dbuf_free(cli_dbuf *b);

/* ---- util.c: output files written atomically ------------------------------------------ */

/* An output opened under a temporary name in the target's directory and renamed to the
 * target by cli_out_commit, so that a failed or interrupted run never leaves a partial file
 * under the final name. "-" is standard output (written directly). */
typedef struct cli_out {
  FILE *f;
  char *path; /* the final name */
  char *tmp;  /* the temporary name, NULL for stdout */
} cli_out;

/* CLI_OK or CLI_RESOURCE (reported). */
int cli_out_open(cli_out *o, const char *path);
/* Flushes, closes and renames; on any write error removes the temporary file and reports
 * it. CLI_OK or CLI_RESOURCE. */
int cli_out_commit(cli_out *o);
/* Closes and removes the temporary file (after an error elsewhere). */
void cli_out_abort(cli_out *o);

/* ---- util.c: progress bar ------------------------------------------------------------- */

/* A bar on stderr for work that has run for more than a second, only when stderr is a
 * terminal and not -q. progress_update is cheap: call it as often as convenient. */
typedef struct cli_progress {
  const char *label;
  double total, start, last, after;
  bool shown, enabled;
} cli_progress;

void cli_progress_begin(cli_progress *p, const char *label, double total);
void cli_progress_update(cli_progress *p, double done);
void cli_progress_end(cli_progress *p);

/* ---- elements ------------------------------------------------------------------------- */

typedef struct cli_elements {
  int dim;
  int64_t n;
  double *coords;  /* n * dim */
  double *radii;   /* n, or NULL when every element has `diameter` */
  double diameter; /* the common diameter when radii is NULL */
} cli_elements;

void cli_elements_free(cli_elements *e);

/* ---- read.c: input formats ------------------------------------------------------------ */

typedef enum cli_format {
  CLI_FORMAT_AUTO = 0,
  CLI_FORMAT_CSV,
  CLI_FORMAT_F64,
  CLI_FORMAT_DUMP, /* LAMMPS / LIGGGHTS text dump */
  CLI_FORMAT_VTK,  /* legacy .vtk */
  CLI_FORMAT_VTP,  /* XML PolyData .vtp */
  CLI_FORMAT_COUNT
} cli_format;

const char *cli_format_name(cli_format f);
/* Parses "csv", "f64", "dump", "vtk", "vtp"; CLI_FORMAT_AUTO for NULL, -1 if unknown. */
int cli_format_from_name(const char *name);

typedef struct cli_read_opts {
  int dim;                /* 2 or 3; 0: from the file where it can tell (dump, VTK: 3) */
  bool has_diameter;      /* --diameter: every element has this diameter, radii ignored */
  double diameter;
  cli_format format;      /* CLI_FORMAT_AUTO: recognised from content, then extension */
  const char *columns;    /* CSV: "x,y,z,radius" by header name or 1-based index; NULL */
  const char *radius;     /* VTK, dump: name of the radius array/column; NULL: radius, ... */
  int64_t snapshot;       /* dump: 0-based snapshot; -1 the last one */
  int64_t timestep;       /* dump: the snapshot of this timestep; -1 not set */
} cli_read_opts;

cli_read_opts cli_default_read_opts(void);

/* Reads path ("-" for standard input) into *out. CLI_OK, or a reported CLI_INPUT /
 * CLI_USAGE / CLI_RESOURCE. On success *format is the format that was read. */
int cli_read(const char *path, const cli_read_opts *o, cli_elements *out, cli_format *format);

/* The format a file's first bytes and name suggest. */
cli_format cli_sniff(const char *path, const unsigned char *head, size_t len);

/* What is wrong with a value ("is NaN", "-1 is negative", ...), or NULL: coordinates must
 * be finite, radii finite and > 0. The text is valid until the next call. */
const char *cli_value_problem(double v, bool radius);
/* Reports a value's problem as FILE:LINE:COLUMN: WHAT PROBLEM; CLI_OK or CLI_INPUT. */
int cli_check_value(const char *file, long line, long column, double v, bool radius,
                    const char *what);

/* Per-format readers (read_*.c). f is open on the file, positioned at its start. */
int cli_read_csv(FILE *f, const char *path, const cli_read_opts *o, cli_elements *out);
int cli_read_f64(FILE *f, const char *path, const cli_read_opts *o, cli_elements *out);
int cli_read_dump(FILE *f, const char *path, const cli_read_opts *o, cli_elements *out);
int cli_read_vtk(FILE *f, const char *path, const cli_read_opts *o, cli_elements *out);
int cli_read_vtp(FILE *f, const char *path, const cli_read_opts *o, cli_elements *out);

/* ---- write.c: output formats ---------------------------------------------------------- */

typedef enum cli_pairs_format { CLI_PAIRS_CSV = 0, CLI_PAIRS_U32, CLI_PAIRS_U64 } cli_pairs_format;

/* Writes pairs (sorted by the caller) to path atomically. */
int cli_write_pairs(const char *path, cli_pairs_format fmt, const nbs_pair *pairs, size_t count);

typedef enum cli_vtp_encoding {
  CLI_VTP_APPENDED = 0, /* raw appended data, as ParaView writes by default */
  CLI_VTP_BASE64,       /* inline base64 ("binary") */
  CLI_VTP_ASCII
} cli_vtp_encoding;

typedef struct cli_vtp_opts {
  cli_vtp_encoding encoding;
  bool compress; /* zlib, for the binary encodings */
} cli_vtp_opts;

/* The elements (points with a radius array) and the pairs (lines) as XML PolyData. */
int cli_write_vtp(const char *path, const cli_vtp_opts *o, const cli_elements *e,
                  const nbs_pair *pairs, size_t count);
/* The format to write path in: `asked` unless AUTO, else from the extension, else CSV. */
cli_format cli_output_format(const char *path, cli_format asked);
/* The elements alone, in an element format (csv, f64, dump, vtk, vtp). */
int cli_write_elements(const char *path, cli_format fmt, const cli_vtp_opts *vo,
                       const cli_elements *e);

/* ---- draw.c: pictures ----------------------------------------------------------------- */

/* A PNG of the 2D elements whose centres lie in [x0, x0 + w] x [y0, y0 + w]: circles and the
 * contact lines of pairs (indices into e), width x width pixels. */
int cli_draw_png(const char *path, const cli_elements *e, const nbs_pair *pairs, size_t count,
                 double x0, double y0, double w, int width);

/* ---- subcommands ---------------------------------------------------------------------- */

int cli_detect(int argc, char **argv);
int cli_generate(int argc, char **argv);
int cli_info(int argc, char **argv);
int cli_demo(int argc, char **argv);

/* ---- pairs ---------------------------------------------------------------------------- */

/* A copy of the context's pairs, sorted (nbs_sort_pairs); NULL with *count 0 when there are
 * none. *ok false on allocation failure. */
nbs_pair *cli_sorted_pairs(const nbs_context *ctx, size_t *count, bool *ok);
/* FNV-1a over the sorted pairs: equal lists have equal hashes. */
uint64_t cli_pairs_hash(const nbs_pair *pairs, size_t count);

#endif
