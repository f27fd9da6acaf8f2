/*
 * Messages, numbers, growable arrays, atomic output files and the progress bar.
 */
#include "cli.h"

#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

bool cli_quiet = false;

/* ---- messages ------------------------------------------------------------------------- */

int cli_fail(int code, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  fputs("nbs: ", stderr);
  vfprintf(stderr, fmt, ap);
  fputc('\n', stderr);
  va_end(ap);
  return code;
}

int cli_usage(const char *command, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  fprintf(stderr, "nbs%s%s: ", command ? " " : "", command ? command : "");
  vfprintf(stderr, fmt, ap);
  fprintf(stderr, "\nTry 'nbs%s%s --help'.\n", command ? " " : "", command ? command : "");
  va_end(ap);
  return CLI_USAGE;
}

int cli_input_error(const char *file, long line, long column, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  if (line > 0 && column > 0) {
    fprintf(stderr, "%s:%ld:%ld: ", file, line, column);
  } else if (line > 0) {
    fprintf(stderr, "%s:%ld: ", file, line);
  } else {
    fprintf(stderr, "%s: ", file);
  }
  vfprintf(stderr, fmt, ap);
  fputc('\n', stderr);
  va_end(ap);
  return CLI_INPUT;
}

int cli_status_code(nbs_status s) {
  switch (s) {
  case NBS_OK:
    return CLI_OK;
  case NBS_ERR_DIM:
  case NBS_ERR_COUNT:
  case NBS_ERR_COORD:
  case NBS_ERR_RADIUS:
    return CLI_INPUT;
  case NBS_ERR_BUDGET:
  case NBS_ERR_EXTENT:
  case NBS_ERR_NOMEM:
  case NBS_ERR_PAIRS:
    return CLI_RESOURCE;
  default:
    return CLI_FAIL;
  }
}

void cli_json_string(FILE *f, const char *s) {
  fputc('"', f);
  for (; *s; s++) {
    unsigned char c = (unsigned char)*s;
    if (c == '"' || c == '\\') {
      fputc('\\', f);
      fputc(c, f);
    } else if (c < 0x20) {
      fprintf(f, "\\u%04x", c);
    } else {
      fputc(c, f);
    }
  }
  fputc('"', f);
}

/* ---- numbers -------------------------------------------------------------------------- */

bool cli_parse_double(const char *s, double *out) {
  if (!s || !*s) return false;
  char *end;
  errno = 0;
  double v = strtod(s, &end);
  if (end == s || *end != '\0' || !isfinite(v)) return false;
  *out = v;
  return true;
}

bool cli_parse_int64(const char *s, int64_t *out) {
  if (!s || !*s) return false;
  /* Accept 1e6 style for counts, exactly. */
  char *end;
  errno = 0;
  long long v = strtoll(s, &end, 10);
  if (*end == '\0' && end != s && errno == 0) {
    if (v < 0) return false;
    *out = v;
    return true;
  }
  double d;
  if (!cli_parse_double(s, &d) || d < 0 || d > 9.0e18 || d != floor(d)) return false;
  *out = (int64_t)d;
  return true;
}

double cli_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ---- growable arrays ------------------------------------------------------------------ */

bool cli_dbuf_reserve(cli_dbuf *b, size_t more) {
  if (more <= b->cap - b->n) return true;
  if (more > SIZE_MAX / sizeof(double) - b->n) return false;
  size_t need = b->n + more;
  size_t cap = b->cap < 1024 ? 1024 : b->cap;
  while (cap < need) cap = cap > SIZE_MAX / 4 ? need : cap * 2;
  if (cap > SIZE_MAX / sizeof(double)) cap = need;
  double *v = realloc(b->v, cap * sizeof(double));
  if (!v) return false;
  b->v = v;
  b->cap = cap;
  return true;
}

void cli_dbuf_free(cli_dbuf *b) {
  free(b->v);
  b->v = NULL;
  b->n = b->cap = 0;
}

void cli_elements_free(cli_elements *e) {
  if (!e) return;
  free(e->coords);
  free(e->radii);
  e->coords = NULL;
  e->radii = NULL;
  e->n = 0;
}

/* ---- atomic output files -------------------------------------------------------------- */

/* Temporary files to remove if a signal ends the process before they are renamed. The
 * handler only calls unlink, which is async-signal-safe. */
#define CLI_MAX_TEMPS 8
static char *volatile cli_temps[CLI_MAX_TEMPS];
static bool cli_handlers_set;

static void cli_on_signal(int sig) {
  for (int k = 0; k < CLI_MAX_TEMPS; k++) {
    if (cli_temps[k]) unlink(cli_temps[k]);
  }
  signal(sig, SIG_DFL);
  raise(sig);
}

static void cli_track_temp(char *tmp, bool add) {
  for (int k = 0; k < CLI_MAX_TEMPS; k++) {
    if (add ? cli_temps[k] == NULL : cli_temps[k] == tmp) {
      cli_temps[k] = add ? tmp : NULL;
      return;
    }
  }
}

int cli_out_open(cli_out *o, const char *path) {
  memset(o, 0, sizeof *o);
  if (strcmp(path, "-") == 0) {
    o->f = stdout;
    return CLI_OK;
  }
  if (!cli_handlers_set) {
    signal(SIGINT, cli_on_signal);
    signal(SIGTERM, cli_on_signal);
    signal(SIGHUP, cli_on_signal);
    cli_handlers_set = true;
  }
  size_t len = strlen(path);
  o->path = malloc(len + 1);
  o->tmp = malloc(len + 16);
  if (!o->path || !o->tmp) {
    free(o->path);
    free(o->tmp);
    memset(o, 0, sizeof *o);
    return cli_fail(CLI_RESOURCE, "%s: out of memory", path);
  }
  memcpy(o->path, path, len + 1);
  /* The temporary file sits next to the target, so that rename stays on one file system;
   * it starts with '.' so that it does not look like a result. */
  const char *slash = strrchr(path, '/');
  size_t dir = slash ? (size_t)(slash - path) + 1 : 0;
  memcpy(o->tmp, path, dir);
  snprintf(o->tmp + dir, len + 16 - dir, ".%s.XXXXXX", path + dir);
  int fd = mkstemp(o->tmp);
  if (fd < 0) {
    int e = errno;
    free(o->path);
    free(o->tmp);
    memset(o, 0, sizeof *o);
    return cli_fail(CLI_RESOURCE, "%s: cannot create: %s", path, strerror(e));
  }
  /* mkstemp makes the file 0600; give it the permissions a plain fopen would. */
  mode_t mask = umask(0);
  umask(mask);
  fchmod(fd, 0666 & ~mask);
  o->f = fdopen(fd, "wb");
  if (!o->f) {
    int e = errno;
    close(fd);
    unlink(o->tmp);
    free(o->path);
    free(o->tmp);
    memset(o, 0, sizeof *o);
    return cli_fail(CLI_RESOURCE, "%s: cannot open: %s", path, strerror(e));
  }
  cli_track_temp(o->tmp, true);
  return CLI_OK;
}

int cli_out_commit(cli_out *o) {
  if (!o->tmp) {
    int bad = fflush(o->f) != 0 || ferror(o->f);
    memset(o, 0, sizeof *o);
    return bad ? cli_fail(CLI_RESOURCE, "standard output: write error: %s", strerror(errno))
               : CLI_OK;
  }
  int bad = ferror(o->f);
  int e = errno;
  if (fflush(o->f) != 0) {
    bad = 1;
    e = errno;
  }
  if (fclose(o->f) != 0 && !bad) {
    bad = 1;
    e = errno;
  }
  o->f = NULL;
  if (!bad && rename(o->tmp, o->path) != 0) {
    bad = 1;
    e = errno;
  }
  int code = CLI_OK;
  if (bad) {
    unlink(o->tmp);
    code = cli_fail(CLI_RESOURCE, "%s: cannot write: %s", o->path, strerror(e));
  }
  cli_track_temp(o->tmp, false);
  free(o->path);
  free(o->tmp);
  memset(o, 0, sizeof *o);
  return code;
}

void cli_out_abort(cli_out *o) {
  if (o->tmp) {
    if (o->f) fclose(o->f);
    unlink(o->tmp);
    cli_track_temp(o->tmp, false);
  }
  free(o->path);
  free(o->tmp);
  memset(o, 0, sizeof *o);
}

/* ---- progress bar --------------------------------------------------------------------- */

/* The bar appears after this many seconds of work: 1, or NBS_PROGRESS_AFTER (which the
 * tests set to 0 to see the bar without waiting). */
static double cli_progress_after(void) {
  const char *s = getenv("NBS_PROGRESS_AFTER");
  double v;
  return s && cli_parse_double(s, &v) && v >= 0 ? v : 1.0;
}

void cli_progress_begin(cli_progress *p, const char *label, double total) {
  memset(p, 0, sizeof *p);
  p->label = label;
  p->total = total;
  p->start = cli_now();
  p->enabled = !cli_quiet && isatty(STDERR_FILENO);
  p->after = p->enabled ? cli_progress_after() : 0;
  p->last = -1.0;
}

void cli_progress_update(cli_progress *p, double done) {
  if (!p->enabled) return;
  double t = cli_now();
  if (t - p->start < p->after || t - p->last < 0.1) return;
  p->last = t;
  p->shown = true;
  double f = p->total > 0 ? done / p->total : 0.0;
  if (f < 0) f = 0;
  if (f > 1) f = 1;
  char bar[41];
  int fill = (int)(f * 40.0);
  for (int k = 0; k < 40; k++) bar[k] = k < fill ? '#' : '.';
  bar[40] = '\0';
  fprintf(stderr, "\r%-24.24s [%s] %3d%% %6.1fs", p->label, bar, (int)(f * 100.0), t - p->start);
  fflush(stderr);
}

void cli_progress_end(cli_progress *p) {
  if (p->enabled && p->shown) {
    fprintf(stderr, "\r%80s\r", "");
    fflush(stderr);
  }
  p->shown = false;
}

/* ---- pairs ---------------------------------------------------------------------------- */

nbs_pair *cli_sorted_pairs(const nbs_context *ctx, size_t *count, bool *ok) {
  size_t n = 0;
  const nbs_pair *p = nbs_pairs(ctx, &n);
  *ok = true;
  *count = 0;
  if (!p || n == 0) return NULL;
  nbs_pair *copy = malloc(n * sizeof *copy);
  if (!copy) {
    *ok = false;
    return NULL;
  }
  memcpy(copy, p, n * sizeof *copy);
  nbs_sort_pairs(copy, n);
  *count = n;
  return copy;
}

uint64_t cli_pairs_hash(const nbs_pair *pairs, size_t count) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (size_t k = 0; k < count; k++) {
    uint32_t v[2] = {(uint32_t)pairs[k].i, (uint32_t)pairs[k].j};
    for (int w = 0; w < 2; w++) {
      for (int b = 0; b < 4; b++) {
        h ^= (v[w] >> (8 * b)) & 0xffu;
        h *= 0x100000001b3ull;
      }
    }
  }
  return h;
}
