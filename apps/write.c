/*
 * Writing pairs and element sets. Every file goes through cli_out (a temporary name renamed
 * on success), so a failed run leaves no partial file under the final name.
 */
#include "cli.h"

#include <stdlib.h>
#include <string.h>

/* Decimal digits of v at the end of buf; returns the start. */
static char *cli_utoa(char *end, uint64_t v) {
  do {
    *--end = (char)('0' + v % 10);
    v /= 10;
  } while (v);
  return end;
}

static void cli_put_le(unsigned char *dst, uint64_t v, int bytes) {
  for (int b = 0; b < bytes; b++) dst[b] = (unsigned char)(v >> (8 * b));
}

int cli_write_pairs(const char *path, cli_pairs_format fmt, const nbs_pair *pairs, size_t count) {
  cli_out o;
  int code = cli_out_open(&o, path);
  if (code != CLI_OK) return code;
  cli_progress prog;
  cli_progress_begin(&prog, "writing pairs", (double)count);
  /* One buffer of lines at a time: fprintf per pair would dominate the run. */
  enum { CHUNK = 4096 };
  static char buf[CHUNK * 24];
  for (size_t k = 0; k < count; k += CHUNK) {
    size_t m = count - k < CHUNK ? count - k : CHUNK;
    size_t len = 0;
    for (size_t q = 0; q < m; q++) {
      const nbs_pair p = pairs[k + q];
      if (fmt == CLI_PAIRS_CSV) {
        char tmp[24];
        char *e = tmp + sizeof tmp;
        *--e = '\n';
        e = cli_utoa(e, (uint32_t)p.j);
        *--e = ',';
        e = cli_utoa(e, (uint32_t)p.i);
        size_t l = (size_t)(tmp + sizeof tmp - e);
        memcpy(buf + len, e, l);
        len += l;
      } else {
        int w = fmt == CLI_PAIRS_U32 ? 4 : 8;
        cli_put_le((unsigned char *)buf + len, (uint32_t)p.i, w);
        cli_put_le((unsigned char *)buf + len + w, (uint32_t)p.j, w);
        len += 2 * (size_t)w;
      }
    }
    if (fwrite(buf, 1, len, o.f) != len) break;
    cli_progress_update(&prog, (double)(k + m));
  }
  cli_progress_end(&prog);
  return cli_out_commit(&o);
}

/* ---- element sets --------------------------------------------------------------------- */

static double cli_radius_of(const cli_elements *e, size_t k) {
  return e->radii ? e->radii[k] : 0.5 * e->diameter;
}

/* Shortest text that reads back as the same double. */
static int cli_fmt_double(char *buf, size_t len, double v) {
  for (int prec = 16; prec <= 17; prec++) {
    int l = snprintf(buf, len, "%.*g", prec, v);
    if (strtod(buf, NULL) == v) return l;
  }
  return snprintf(buf, len, "%.17g", v);
}

static void cli_write_csv_elements(FILE *f, const cli_elements *e, cli_progress *prog) {
  fputs(e->dim == 3 ? "x,y,z,radius\n" : "x,y,radius\n", f);
  char buf[40];
  for (size_t k = 0; k < (size_t)e->n; k++) {
    for (int a = 0; a < e->dim; a++) {
      cli_fmt_double(buf, sizeof buf, e->coords[k * (size_t)e->dim + (size_t)a]);
      fputs(buf, f);
      fputc(',', f);
    }
    cli_fmt_double(buf, sizeof buf, cli_radius_of(e, k));
    fputs(buf, f);
    fputc('\n', f);
    if ((k & 0xffff) == 0) cli_progress_update(prog, (double)k);
  }
}

static void cli_write_f64_elements(FILE *f, const cli_elements *e, cli_progress *prog) {
  unsigned char rec[32];
  for (size_t k = 0; k < (size_t)e->n; k++) {
    int a = 0;
    for (; a <= e->dim; a++) {
      double v = a < e->dim ? e->coords[k * (size_t)e->dim + (size_t)a] : cli_radius_of(e, k);
      uint64_t bits;
      memcpy(&bits, &v, 8);
      cli_put_le(rec + 8 * a, bits, 8);
    }
    fwrite(rec, 8, (size_t)a, f);
    if ((k & 0xffff) == 0) cli_progress_update(prog, (double)k);
  }
}

/* LAMMPS "custom" dump of one snapshot: ITEM: ATOMS id type x y z radius. */
static void cli_write_dump_elements(FILE *f, const cli_elements *e, cli_progress *prog) {
  double lo[3] = {0, 0, -0.5}, hi[3] = {0, 0, 0.5};
  for (size_t k = 0; k < (size_t)e->n; k++) {
    for (int a = 0; a < e->dim; a++) {
      double v = e->coords[k * (size_t)e->dim + (size_t)a];
      if (k == 0 || v < lo[a]) lo[a] = v;
      if (k == 0 || v > hi[a]) hi[a] = v;
    }
  }
  fprintf(f, "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n%lld\nITEM: BOX BOUNDS ff ff ff\n",
          (long long)e->n);
  char b1[40], b2[40];
  for (int a = 0; a < 3; a++) {
    cli_fmt_double(b1, sizeof b1, lo[a]);
    cli_fmt_double(b2, sizeof b2, hi[a]);
    fprintf(f, "%s %s\n", b1, b2);
  }
  fputs("ITEM: ATOMS id type x y z radius\n", f);
  char buf[40];
  for (size_t k = 0; k < (size_t)e->n; k++) {
    fprintf(f, "%zu 1", k + 1);
    for (int a = 0; a < 3; a++) {
      if (a < e->dim) {
        cli_fmt_double(buf, sizeof buf, e->coords[k * (size_t)e->dim + (size_t)a]);
        fprintf(f, " %s", buf);
      } else {
        fputs(" 0", f);
      }
    }
    cli_fmt_double(buf, sizeof buf, cli_radius_of(e, k));
    fprintf(f, " %s\n", buf);
    if ((k & 0xffff) == 0) cli_progress_update(prog, (double)k);
  }
}

/* Legacy VTK, ASCII, POLYDATA with vertices and a radius point array. */
static void cli_write_vtk_elements(FILE *f, const cli_elements *e, cli_progress *prog) {
  fprintf(f, "# vtk DataFile Version 3.0\nnbs elements\nASCII\nDATASET POLYDATA\nPOINTS %lld double\n",
          (long long)e->n);
  char buf[40];
  for (size_t k = 0; k < (size_t)e->n; k++) {
    for (int a = 0; a < 3; a++) {
      if (a < e->dim) {
        cli_fmt_double(buf, sizeof buf, e->coords[k * (size_t)e->dim + (size_t)a]);
        fputs(buf, f);
      } else {
        fputc('0', f);
      }
      fputc(a < 2 ? ' ' : '\n', f);
    }
    if ((k & 0xffff) == 0) cli_progress_update(prog, (double)k);
  }
  fprintf(f, "VERTICES %lld %lld\n", (long long)e->n, 2 * (long long)e->n);
  for (size_t k = 0; k < (size_t)e->n; k++) fprintf(f, "1 %zu\n", k);
  fprintf(f, "POINT_DATA %lld\nSCALARS radius double 1\nLOOKUP_TABLE default\n", (long long)e->n);
  for (size_t k = 0; k < (size_t)e->n; k++) {
    cli_fmt_double(buf, sizeof buf, cli_radius_of(e, k));
    fputs(buf, f);
    fputc('\n', f);
  }
}

int cli_write_elements(const char *path, cli_format fmt, const cli_vtp_opts *vo,
                       const cli_elements *e) {
  if (fmt == CLI_FORMAT_VTP) return cli_write_vtp(path, vo, e, NULL, 0);
  cli_out o;
  int code = cli_out_open(&o, path);
  if (code != CLI_OK) return code;
  cli_progress prog;
  cli_progress_begin(&prog, "writing", (double)e->n);
  switch (fmt) {
  case CLI_FORMAT_F64:
    cli_write_f64_elements(o.f, e, &prog);
    break;
  case CLI_FORMAT_DUMP:
    cli_write_dump_elements(o.f, e, &prog);
    break;
  case CLI_FORMAT_VTK:
    cli_write_vtk_elements(o.f, e, &prog);
    break;
  default:
    cli_write_csv_elements(o.f, e, &prog);
    break;
  }
  cli_progress_end(&prog);
  return cli_out_commit(&o);
}
