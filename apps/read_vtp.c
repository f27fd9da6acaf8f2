/*
 * VTK XML PolyData (.vtp; also UnstructuredGrid .vtu), as VTK and ParaView write it:
 *
 *   <VTKFile type="PolyData" version="1.0" byte_order="LittleEndian" header_type="UInt64"
 *            compressor="vtkZLibDataCompressor">
 *     <PolyData><Piece NumberOfPoints="n" ...>
 *       <PointData><DataArray type="Float64" Name="radius" format="appended" offset="0"/>
 *       <Points><DataArray type="Float32" NumberOfComponents="3" format="..." .../></Points>
 *     </Piece></PolyData>
 *     <AppendedData encoding="raw">_<binary data></AppendedData>
 *   </VTKFile>
 *
 * Data arrays may be format="ascii" (numbers in the element), "binary" (base64 in the
 * element) or "appended" (at `offset` after the '_' of AppendedData, raw or base64). Binary
 * data is [header][bytes]: the header is one UInt32/UInt64 byte count, or, with the zlib
 * compressor, [blocks, block size, last block size, compressed size of each block] followed
 * by the zlib blocks. In base64, VTK encodes the header and the data as separate streams;
 * decoding quantum by quantum (4 characters to 1-3 bytes, padding included) reads both that
 * and a single stream.
 *
 * Several pieces are concatenated. Elements are the points; the radius is the point array
 * `radius` (or --radius NAME), else `diameter` halved.
 *
 * Hostile files: every count is checked against the bytes that are really there before
 * memory is allocated for it; compressed blocks are inflated one at a time into a buffer
 * that grows only as they succeed, each block at most what zlib can expand its bytes to.
 */
#include "cli.h"

#include <errno.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <zlib.h>

typedef struct cli_xattr {
  const char *name, *value; /* pointers into the file, not terminated */
  size_t nlen, vlen;
} cli_xattr;

enum { CLI_VTP_MAXATTR = 32, CLI_VTP_DEPTH = 32 };

typedef struct cli_darray {
  char name[64];
  char type[16];
  char format[16];
  int64_t ncomp;
  uint64_t offset;
  size_t text, text_end; /* inline content, for ascii and binary */
  size_t at;             /* the tag, for messages */
  bool present;
} cli_darray;

typedef struct cli_piece {
  int64_t n;
  size_t at;
  cli_darray points;
  cli_darray radius; /* the best radius candidate */
  int rank;          /* 2 radius, 1 diameter */
} cli_piece;

typedef struct cli_vtp {
  const char *path;
  unsigned char *buf; /* the whole file, NUL-terminated */
  size_t len;
  bool big;           /* byte_order BigEndian */
  int hsize;          /* header word: 4 or 8 bytes */
  bool zlib;
  bool appended;      /* an AppendedData section was found */
  bool app_base64;
  size_t app_start;   /* the byte after '_' */
  cli_piece *pieces;
  size_t npieces, cap;
  cli_progress prog;
} cli_vtp;

/* LINE:COLUMN of a byte offset (only on errors: a scan from the start). */
static int cli_vtp_error(const cli_vtp *x, size_t at, const char *fmt, ...) CLI_PRINTF(3, 4);
static int cli_vtp_error(const cli_vtp *x, size_t at, const char *fmt, ...) {
  long line = 1, col = 1;
  for (size_t k = 0; k < at && k < x->len; k++) {
    if (x->buf[k] == '\n') {
      line++;
      col = 1;
    } else {
      col++;
    }
  }
  char msg[512];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  /* Names and excerpts come from the file: the message stays one line. */
  for (char *m = msg; *m; m++) {
    if ((unsigned char)*m < 0x20 || *m == 0x7f) *m = '?';
  }
  return cli_input_error(x->path, line, col, "%s", msg);
}

static bool cli_vtp_space(unsigned char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }

static bool cli_attr_is(const cli_xattr *a, const char *name) {
  return a->nlen == strlen(name) && memcmp(a->name, name, a->nlen) == 0;
}

static const cli_xattr *cli_attr_find(const cli_xattr *a, int n, const char *name) {
  for (int k = 0; k < n; k++) {
    if (cli_attr_is(&a[k], name)) return &a[k];
  }
  return NULL;
}

static bool cli_attr_eq(const cli_xattr *a, const char *value) {
  return a && a->vlen == strlen(value) && memcmp(a->value, value, a->vlen) == 0;
}

static void cli_attr_copy(const cli_xattr *a, char *dst, size_t len) {
  size_t n = a ? (a->vlen < len - 1 ? a->vlen : len - 1) : 0;
  if (n) memcpy(dst, a->value, n);
  dst[n] = '\0';
}

static bool cli_attr_int(const cli_xattr *a, int64_t *out) {
  char tmp[32];
  if (!a || a->vlen == 0 || a->vlen >= sizeof tmp) return false;
  cli_attr_copy(a, tmp, sizeof tmp);
  return cli_parse_int64(tmp, out);
}

static int cli_vtp_rank(const cli_read_opts *o, const char *name) {
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

/* ---- the XML structure ---------------------------------------------------------------- */

static int cli_vtp_tag_attrs(cli_vtp *x, size_t *pos, cli_xattr *attrs, int *nattrs, bool *empty) {
  const unsigned char *b = x->buf;
  size_t p = *pos;
  *nattrs = 0;
  *empty = false;
  for (;;) {
    while (p < x->len && cli_vtp_space(b[p])) p++;
    if (p >= x->len) return cli_vtp_error(x, p, "the file ends inside a tag");
    if (b[p] == '>') {
      p++;
      break;
    }
    if (b[p] == '/' && p + 1 < x->len && b[p + 1] == '>') {
      *empty = true;
      p += 2;
      break;
    }
    size_t ns = p;
    while (p < x->len && !cli_vtp_space(b[p]) && b[p] != '=' && b[p] != '>' && b[p] != '/') p++;
    size_t ne = p;
    while (p < x->len && cli_vtp_space(b[p])) p++;
    if (ne == ns || p >= x->len || b[p] != '=') return cli_vtp_error(x, ns, "malformed attribute");
    p++;
    while (p < x->len && cli_vtp_space(b[p])) p++;
    if (p >= x->len || (b[p] != '"' && b[p] != '\'')) {
      return cli_vtp_error(x, p, "an attribute value must be quoted");
    }
    unsigned char q = b[p++];
    size_t vs = p;
    while (p < x->len && b[p] != q) p++;
    if (p >= x->len) return cli_vtp_error(x, vs, "unterminated attribute value");
    if (*nattrs < CLI_VTP_MAXATTR) {
      cli_xattr *a = &attrs[(*nattrs)++];
      a->name = (const char *)b + ns;
      a->nlen = ne - ns;
      a->value = (const char *)b + vs;
      a->vlen = p - vs;
    }
    p++;
  }
  *pos = p;
  return CLI_OK;
}

static int cli_vtp_darray(cli_vtp *x, size_t at, const cli_xattr *attrs, int n, size_t content,
                          cli_darray *d) {
  memset(d, 0, sizeof *d);
  d->present = true;
  d->at = at;
  cli_attr_copy(cli_attr_find(attrs, n, "Name"), d->name, sizeof d->name);
  const cli_xattr *t = cli_attr_find(attrs, n, "type");
  const cli_xattr *f = cli_attr_find(attrs, n, "format");
  if (!t) return cli_vtp_error(x, at, "DataArray without a type");
  if (!f) return cli_vtp_error(x, at, "DataArray without a format");
  cli_attr_copy(t, d->type, sizeof d->type);
  cli_attr_copy(f, d->format, sizeof d->format);
  d->ncomp = 1;
  const cli_xattr *c = cli_attr_find(attrs, n, "NumberOfComponents");
  if (c && (!cli_attr_int(c, &d->ncomp) || d->ncomp < 1 || d->ncomp > 64)) {
    return cli_vtp_error(x, at, "bad NumberOfComponents");
  }
  if (strcmp(d->format, "appended") == 0) {
    int64_t off;
    if (!cli_attr_int(cli_attr_find(attrs, n, "offset"), &off)) {
      return cli_vtp_error(x, at, "an appended DataArray needs an offset >= 0");
    }
    d->offset = (uint64_t)off;
  } else if (strcmp(d->format, "ascii") != 0 && strcmp(d->format, "binary") != 0) {
    return cli_vtp_error(x, at, "unknown DataArray format '%s'", d->format);
  }
  d->text = content;
  const unsigned char *lt = memchr(x->buf + content, '<', x->len - content);
  d->text_end = lt ? (size_t)(lt - x->buf) : x->len;
  return CLI_OK;
}

static int cli_vtp_structure(cli_vtp *x, const cli_read_opts *o) {
  const unsigned char *b = x->buf;
  char stack[CLI_VTP_DEPTH][24];
  int depth = 0;
  bool root = false;
  size_t p = 0;
  while (p < x->len) {
    const unsigned char *lt = memchr(b + p, '<', x->len - p);
    if (!lt) break;
    p = (size_t)(lt - b);
    size_t at = p;
    if (x->len - p >= 4 && memcmp(b + p, "<!--", 4) == 0) {
      const char *e = strstr((const char *)b + p + 4, "-->");
      if (!e) return cli_vtp_error(x, at, "unterminated comment");
      p = (size_t)((const unsigned char *)e - b) + 3;
      continue;
    }
    if (x->len - p >= 2 && (b[p + 1] == '?' || b[p + 1] == '!')) {
      const unsigned char *gt = memchr(b + p, '>', x->len - p);
      if (!gt) return cli_vtp_error(x, at, "unterminated declaration");
      p = (size_t)(gt - b) + 1;
      continue;
    }
    bool closing = p + 1 < x->len && b[p + 1] == '/';
    p += closing ? 2 : 1;
    size_t ns = p;
    while (p < x->len && !cli_vtp_space(b[p]) && b[p] != '>' && b[p] != '/') p++;
    char name[24];
    size_t nl = p - ns < sizeof name - 1 ? p - ns : sizeof name - 1;
    memcpy(name, b + ns, nl);
    name[nl] = '\0';
    if (nl == 0) return cli_vtp_error(x, at, "malformed tag");
    if (closing) {
      const unsigned char *gt = memchr(b + p, '>', x->len - p);
      if (!gt) return cli_vtp_error(x, at, "unterminated end tag");
      p = (size_t)(gt - b) + 1;
      if (depth == 0 || strcmp(stack[depth - 1], name) != 0) {
        return cli_vtp_error(x, at, "</%s> does not close <%s>", name, depth ? stack[depth - 1] : "");
      }
      depth--;
      continue;
    }
    cli_xattr attrs[CLI_VTP_MAXATTR];
    int nattrs;
    bool empty;
    int code = cli_vtp_tag_attrs(x, &p, attrs, &nattrs, &empty);
    if (code != CLI_OK) return code;
    const char *parent = depth ? stack[depth - 1] : "";

    if (strcmp(name, "VTKFile") == 0) {
      if (depth != 0) return cli_vtp_error(x, at, "nested VTKFile");
      root = true;
      const cli_xattr *type = cli_attr_find(attrs, nattrs, "type");
      if (!cli_attr_eq(type, "PolyData") && !cli_attr_eq(type, "UnstructuredGrid")) {
        char t[32];
        cli_attr_copy(type, t, sizeof t);
        return cli_vtp_error(x, at, "VTKFile type '%s': only PolyData and UnstructuredGrid "
                             "hold a list of points", t);
      }
      const cli_xattr *bo = cli_attr_find(attrs, nattrs, "byte_order");
      x->big = cli_attr_eq(bo, "BigEndian");
      if (bo && !x->big && !cli_attr_eq(bo, "LittleEndian")) {
        return cli_vtp_error(x, at, "unknown byte_order");
      }
      const cli_xattr *ht = cli_attr_find(attrs, nattrs, "header_type");
      x->hsize = !ht || cli_attr_eq(ht, "UInt32") ? 4 : cli_attr_eq(ht, "UInt64") ? 8 : 0;
      if (!x->hsize) return cli_vtp_error(x, at, "header_type must be UInt32 or UInt64");
      const cli_xattr *cz = cli_attr_find(attrs, nattrs, "compressor");
      x->zlib = cz && cz->vlen > 0;
      if (x->zlib && !cli_attr_eq(cz, "vtkZLibDataCompressor")) {
        char t[48];
        cli_attr_copy(cz, t, sizeof t);
        return cli_vtp_error(x, at, "compressor '%s' is not supported: save with ZLib or no "
                             "compression", t);
      }
    } else if (!root) {
      return cli_vtp_error(x, at, "not a VTK XML file: <%s> before <VTKFile>", name);
    } else if (strcmp(name, "Piece") == 0) {
      int64_t n;
      if (!cli_attr_int(cli_attr_find(attrs, nattrs, "NumberOfPoints"), &n)) {
        return cli_vtp_error(x, at, "Piece without a NumberOfPoints >= 0");
      }
      if (x->npieces == x->cap) {
        size_t cap = x->cap ? 2 * x->cap : 4;
        cli_piece *np = realloc(x->pieces, cap * sizeof *np);
        if (!np) return cli_fail(CLI_RESOURCE, "%s: out of memory", x->path);
        x->pieces = np;
        x->cap = cap;
      }
      cli_piece *pc = &x->pieces[x->npieces++];
      memset(pc, 0, sizeof *pc);
      pc->n = n;
      pc->at = at;
    } else if (strcmp(name, "DataArray") == 0 && x->npieces > 0 &&
               (strcmp(parent, "Points") == 0 || strcmp(parent, "PointData") == 0)) {
      cli_piece *pc = &x->pieces[x->npieces - 1];
      cli_darray d;
      code = cli_vtp_darray(x, at, attrs, nattrs, p, &d);
      if (code != CLI_OK) return code;
      if (strcmp(parent, "Points") == 0) {
        if (pc->points.present) return cli_vtp_error(x, at, "a second Points array");
        pc->points = d;
      } else {
        int rank = o->has_diameter ? 0 : cli_vtp_rank(o, d.name);
        if (rank > pc->rank) {
          pc->radius = d;
          pc->rank = rank;
        }
      }
    } else if (strcmp(name, "AppendedData") == 0) {
      const cli_xattr *enc = cli_attr_find(attrs, nattrs, "encoding");
      x->app_base64 = cli_attr_eq(enc, "base64");
      if (!x->app_base64 && !cli_attr_eq(enc, "raw")) {
        return cli_vtp_error(x, at, "AppendedData encoding must be raw or base64");
      }
      while (p < x->len && cli_vtp_space(b[p])) p++;
      if (p >= x->len || b[p] != '_') {
        return cli_vtp_error(x, p, "AppendedData must start with '_'");
      }
      x->appended = true;
      x->app_start = p + 1;
      return CLI_OK; /* the rest is data */
    }
    if (!empty) {
      if (depth == CLI_VTP_DEPTH) return cli_vtp_error(x, at, "elements nested too deeply");
      snprintf(stack[depth++], sizeof stack[0], "%s", name);
    }
  }
  if (!root) return cli_vtp_error(x, 0, "not a VTK XML file: no <VTKFile>");
  if (depth > 0) return cli_vtp_error(x, x->len, "truncated: the file ends before </%s>", stack[depth - 1]);
  return CLI_OK;
}

/* ---- data ----------------------------------------------------------------------------- */

/* Bytes of an array: raw, or base64 decoded quantum by quantum. */
typedef struct cli_bsrc {
  const unsigned char *s;
  size_t n, pos;
  bool b64;
  unsigned char pend[3];
  int npend, pend_at;
  bool bad; /* a character that is not base64 */
} cli_bsrc;

static int cli_b64_value(unsigned char c) {
  if (c >= 'A' && c <= 'Z') return c - 'A';
  if (c >= 'a' && c <= 'z') return c - 'a' + 26;
  if (c >= '0' && c <= '9') return c - '0' + 52;
  if (c == '+') return 62;
  if (c == '/') return 63;
  return -1;
}

/* Decodes the next quantum into pend; false at the end or on a bad character. */
static bool cli_bsrc_quantum(cli_bsrc *r) {
  int v[4], k = 0, pad = 0;
  while (k < 4) {
    while (r->pos < r->n && cli_vtp_space(r->s[r->pos])) r->pos++;
    if (r->pos >= r->n) return false;
    unsigned char c = r->s[r->pos];
    if (c == '=') {
      if (k < 2) {
        r->bad = true;
        return false;
      }
      pad++;
      v[k++] = 0;
    } else {
      int d = cli_b64_value(c);
      if (d < 0 || pad) {
        r->bad = d < 0;
        return false;
      }
      v[k++] = d;
    }
    r->pos++;
  }
  uint32_t w = (uint32_t)v[0] << 18 | (uint32_t)v[1] << 12 | (uint32_t)v[2] << 6 | (uint32_t)v[3];
  r->pend[0] = (unsigned char)(w >> 16);
  r->pend[1] = (unsigned char)(w >> 8);
  r->pend[2] = (unsigned char)w;
  r->npend = 3 - pad;
  r->pend_at = 0;
  return true;
}

/* Reads want bytes; false if the data ends first. */
static bool cli_bsrc_read(cli_bsrc *r, unsigned char *dst, size_t want) {
  if (want == 0) return true; /* dst may be NULL (an empty zlib block) */
  if (!r->b64) {
    if (want > r->n - r->pos) return false;
    memcpy(dst, r->s + r->pos, want);
    r->pos += want;
    return true;
  }
  size_t got = 0;
  while (got < want) {
    if (r->pend_at == r->npend && !cli_bsrc_quantum(r)) return false;
    while (got < want && r->pend_at < r->npend) dst[got++] = r->pend[r->pend_at++];
  }
  return true;
}

/* An upper bound of the bytes left. */
static size_t cli_bsrc_left(const cli_bsrc *r) {
  size_t chars = r->n - r->pos;
  return (r->b64 ? chars / 4 * 3 + 3 : chars) + (size_t)(r->npend - r->pend_at);
}

static uint64_t cli_vtp_word(const cli_vtp *x, const unsigned char *b, int size) {
  uint64_t u = 0;
  for (int k = 0; k < size; k++) {
    int i = x->big ? k : size - 1 - k;
    u = u << 8 | b[i];
  }
  return u;
}

typedef struct cli_vtype_info {
  const char *name;
  int size;
  char kind; /* 'f' float, 'i' signed, 'u' unsigned */
} cli_vtype_info;

static const cli_vtype_info cli_vtp_types[] = {
    {"Float32", 4, 'f'}, {"Float64", 8, 'f'}, {"Int8", 1, 'i'},   {"UInt8", 1, 'u'},
    {"Int16", 2, 'i'},   {"UInt16", 2, 'u'},  {"Int32", 4, 'i'},  {"UInt32", 4, 'u'},
    {"Int64", 8, 'i'},   {"UInt64", 8, 'u'},
};

static const cli_vtype_info *cli_vtp_type(const char *name) {
  for (size_t k = 0; k < sizeof cli_vtp_types / sizeof cli_vtp_types[0]; k++) {
    if (strcmp(name, cli_vtp_types[k].name) == 0) return &cli_vtp_types[k];
  }
  return NULL;
}

static double cli_vtp_value(const cli_vtp *x, const unsigned char *b, const cli_vtype_info *t) {
  uint64_t u = cli_vtp_word(x, b, t->size);
  if (t->kind == 'f') {
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
  if (t->kind == 'i') {
    int shift = 64 - 8 * t->size;
    return (double)((int64_t)(u << shift) >> shift);
  }
  return (double)u;
}

/* The decoded bytes of a binary or appended array of `bytes` bytes, into a new buffer. */
static int cli_vtp_binary(cli_vtp *x, const cli_darray *d, uint64_t bytes, unsigned char **out) {
  cli_bsrc r;
  memset(&r, 0, sizeof r);
  if (strcmp(d->format, "appended") == 0) {
    if (!x->appended) return cli_vtp_error(x, d->at, "appended DataArray, but no AppendedData");
    if (d->offset > x->len - x->app_start) {
      return cli_vtp_error(x, d->at, "offset %llu is past the end of the appended data (%zu bytes)",
                           (unsigned long long)d->offset, x->len - x->app_start);
    }
    r.s = x->buf + x->app_start + d->offset;
    r.n = x->len - x->app_start - (size_t)d->offset;
    r.b64 = x->app_base64;
  } else {
    r.s = x->buf + d->text;
    r.n = d->text_end - d->text;
    r.b64 = true;
  }
  const int hs = x->hsize;
  unsigned char w[8];
  unsigned char *data = NULL;
  if (!x->zlib) {
    if (!cli_bsrc_read(&r, w, (size_t)hs)) {
      return cli_vtp_error(x, d->at, "%s: truncated: no header", d->name[0] ? d->name : "array");
    }
    uint64_t nbytes = cli_vtp_word(x, w, hs);
    if (nbytes != bytes) {
      return cli_vtp_error(x, d->at, "%s: the header says %llu bytes, %llu expected", d->name,
                           (unsigned long long)nbytes, (unsigned long long)bytes);
    }
    if (bytes > cli_bsrc_left(&r)) {
      return cli_vtp_error(x, d->at, "%s: truncated: %llu bytes of data expected, at most %zu left",
                           d->name, (unsigned long long)bytes, cli_bsrc_left(&r));
    }
    data = malloc(bytes > 0 ? (size_t)bytes : 1);
    if (!data) return cli_fail(CLI_RESOURCE, "%s: out of memory", x->path);
    if (!cli_bsrc_read(&r, data, (size_t)bytes)) {
      free(data);
      return cli_vtp_error(x, d->at, "%s: truncated%s", d->name,
                           r.bad ? ": a character that is not base64" : "");
    }
    *out = data;
    return CLI_OK;
  }
  /* zlib: [nblocks, block size, last size, compressed sizes...] then the blocks. */
  uint64_t head[3];
  for (int k = 0; k < 3; k++) {
    if (!cli_bsrc_read(&r, w, (size_t)hs)) {
      return cli_vtp_error(x, d->at, "%s: truncated compression header", d->name);
    }
    head[k] = cli_vtp_word(x, w, hs);
  }
  uint64_t nb = head[0], bs = head[1], last = head[2];
  if (nb > cli_bsrc_left(&r) / (size_t)hs) {
    return cli_vtp_error(x, d->at, "%s: the header claims %llu blocks, more than the file holds",
                         d->name, (unsigned long long)nb);
  }
  if (nb > 0 && (bs == 0 || last > bs)) {
    return cli_vtp_error(x, d->at, "%s: bad block sizes (%llu, last %llu)", d->name,
                         (unsigned long long)bs, (unsigned long long)last);
  }
  uint64_t total = nb == 0 ? 0 : (nb - 1) * bs + (last ? last : bs);
  if (nb > 0 && (bs > UINT64_MAX / nb || total != bytes)) {
    return cli_vtp_error(x, d->at, "%s: the blocks hold %llu bytes, %llu expected", d->name,
                         (unsigned long long)total, (unsigned long long)bytes);
  }
  if (nb == 0 && bytes != 0) {
    return cli_vtp_error(x, d->at, "%s: no data blocks, %llu bytes expected", d->name,
                         (unsigned long long)bytes);
  }
  uint64_t *csize = malloc((size_t)(nb > 0 ? nb : 1) * sizeof *csize);
  if (!csize) return cli_fail(CLI_RESOURCE, "%s: out of memory", x->path);
  uint64_t csum = 0;
  for (uint64_t k = 0; k < nb; k++) {
    if (!cli_bsrc_read(&r, w, (size_t)hs)) {
      free(csize);
      return cli_vtp_error(x, d->at, "%s: truncated compression header", d->name);
    }
    csize[k] = cli_vtp_word(x, w, hs);
    csum += csize[k];
    if (csize[k] > cli_bsrc_left(&r) || csum > cli_bsrc_left(&r)) {
      free(csize);
      return cli_vtp_error(x, d->at, "%s: truncated: the blocks need %llu bytes, at most %zu left",
                           d->name, (unsigned long long)csum, cli_bsrc_left(&r));
    }
  }
  size_t cap = 0;
  unsigned char *in = NULL;
  size_t incap = 0;
  uint64_t done = 0;
  int code = CLI_OK;
  for (uint64_t k = 0; k < nb && code == CLI_OK; k++) {
    uint64_t ub = k + 1 == nb && last ? last : bs;
    /* zlib expands at most about 1032:1; a block claiming more is refused unread. */
    if (ub > csize[k] * 1032 + 1024) {
      code = cli_vtp_error(x, d->at, "%s: block %llu claims %llu bytes from %llu compressed",
                           d->name, (unsigned long long)k, (unsigned long long)ub,
                           (unsigned long long)csize[k]);
      break;
    }
    if (csize[k] > incap) {
      unsigned char *ni = realloc(in, (size_t)csize[k]);
      if (!ni) {
        code = cli_fail(CLI_RESOURCE, "%s: out of memory", x->path);
        break;
      }
      in = ni;
      incap = (size_t)csize[k];
    }
    if (!cli_bsrc_read(&r, in, (size_t)csize[k])) {
      code = cli_vtp_error(x, d->at, "%s: truncated block %llu", d->name, (unsigned long long)k);
      break;
    }
    if (done + ub > cap) {
      size_t ncap = cap ? cap * 2 : (size_t)ub;
      if (ncap < done + ub) ncap = (size_t)(done + ub);
      if (ncap > bytes) ncap = (size_t)bytes;
      unsigned char *nd = realloc(data, ncap);
      if (!nd) {
        code = cli_fail(CLI_RESOURCE, "%s: out of memory", x->path);
        break;
      }
      data = nd;
      cap = ncap;
    }
    uLongf got = (uLongf)ub;
    int z = uncompress(data + done, &got, in, (uLong)csize[k]);
    if (z != Z_OK || got != ub) {
      code = cli_vtp_error(x, d->at, "%s: block %llu is not valid zlib data of %llu bytes (%s)",
                           d->name, (unsigned long long)k, (unsigned long long)ub,
                           z == Z_OK ? "short" : zError(z));
      break;
    }
    done += ub;
    cli_progress_update(&x->prog, (double)(r.s - x->buf) + (double)r.pos);
  }
  free(in);
  free(csize);
  if (code != CLI_OK) {
    free(data);
    return code;
  }
  if (!data) data = malloc(1);
  if (!data) return cli_fail(CLI_RESOURCE, "%s: out of memory", x->path);
  *out = data;
  return CLI_OK;
}

/* Reads `count` values of array d into dst (which has room), checking each. */
static int cli_vtp_values(cli_vtp *x, const cli_darray *d, int64_t count, double *dst, int check,
                          const char *what) {
  const cli_vtype_info *t = cli_vtp_type(d->type);
  if (!t) return cli_vtp_error(x, d->at, "unsupported DataArray type '%s'", d->type);
  if (strcmp(d->format, "ascii") == 0) {
    const char *s = (const char *)x->buf + d->text;
    const char *end = (const char *)x->buf + d->text_end;
    int64_t k = 0;
    for (;;) {
      while (s < end && cli_vtp_space((unsigned char)*s)) s++;
      if (s >= end) break;
      if (k == count) {
        return cli_vtp_error(x, (size_t)(s - (const char *)x->buf),
                             "%s: more than the %lld values expected", d->name, (long long)count);
      }
      char *e;
      errno = 0;
      double v = strtod(s, &e);
      if (e == s || (e < end && !cli_vtp_space((unsigned char)*e))) {
        int tl = 0; /* the token, up to 20 characters */
        while (tl < 20 && s + tl < end && !cli_vtp_space((unsigned char)s[tl])) tl++;
        return cli_vtp_error(x, (size_t)(s - (const char *)x->buf), "%s: '%.*s' is not a number",
                             d->name, tl, s);
      }
      const char *p = check ? cli_value_problem(v, check == 2) : NULL;
      if (p) return cli_vtp_error(x, (size_t)(s - (const char *)x->buf), "%s %s", what, p);
      dst[k++] = v;
      s = e;
    }
    if (k != count) {
      return cli_vtp_error(x, d->at, "%s: %lld values, %lld expected", d->name, (long long)k,
                           (long long)count);
    }
    return CLI_OK;
  }
  unsigned char *raw = NULL;
  int code = cli_vtp_binary(x, d, (uint64_t)count * (uint64_t)t->size, &raw);
  if (code != CLI_OK) return code;
  for (int64_t k = 0; k < count; k++) {
    double v = cli_vtp_value(x, raw + k * t->size, t);
    const char *p = check ? cli_value_problem(v, check == 2) : NULL;
    if (p) {
      free(raw);
      return cli_vtp_error(x, d->at, "%s %s (value %lld of array %s)", what, p, (long long)k + 1,
                           d->name);
    }
    dst[k] = v;
  }
  free(raw);
  return CLI_OK;
}

/* An upper bound of the values an array can really hold, to check a count before
 * allocating for it. */
static uint64_t cli_vtp_capacity(const cli_vtp *x, const cli_darray *d) {
  const cli_vtype_info *t = cli_vtp_type(d->type);
  int size = t ? t->size : 1;
  if (strcmp(d->format, "ascii") == 0) return (d->text_end - d->text + 1) / 2;
  size_t bytes = strcmp(d->format, "appended") == 0
                     ? (d->offset <= x->len - x->app_start ? x->len - x->app_start - d->offset : 0)
                     : d->text_end - d->text;
  bool b64 = strcmp(d->format, "binary") == 0 || x->app_base64;
  if (b64) bytes = bytes / 4 * 3 + 3;
  uint64_t raw = x->zlib ? (uint64_t)bytes * 1032 + 1024 : bytes;
  return raw / (uint64_t)size;
}

int cli_read_vtp(FILE *f, const char *path, const cli_read_opts *o, cli_elements *out) {
  cli_vtp x;
  memset(&x, 0, sizeof x);
  x.path = path;
  if (fseeko(f, 0, SEEK_END) != 0) return cli_input_error(path, 0, 0, "cannot seek");
  off_t size = ftello(f);
  rewind(f);
  if (size <= 0) return cli_input_error(path, 1, 1, "empty file: no elements");
  if ((uint64_t)size >= SIZE_MAX / 2) return cli_fail(CLI_RESOURCE, "%s: too large", path);
  x.len = (size_t)size;
  x.buf = malloc(x.len + 1);
  if (!x.buf) return cli_fail(CLI_RESOURCE, "%s: out of memory for %zu bytes", path, x.len);
  cli_progress_begin(&x.prog, "reading", (double)x.len);
  if (fread(x.buf, 1, x.len, f) != x.len) {
    free(x.buf);
    cli_progress_end(&x.prog);
    return cli_input_error(path, 0, 0, "cannot read: %s", strerror(errno));
  }
  x.buf[x.len] = '\0';

  int code = cli_vtp_structure(&x, o);
  const int dim = o->dim ? o->dim : 3;
  int64_t total = 0;
  for (size_t k = 0; k < x.npieces && code == CLI_OK; k++) {
    cli_piece *pc = &x.pieces[k];
    if (pc->n == 0) continue;
    if (!pc->points.present) {
      code = cli_vtp_error(&x, pc->at, "a Piece of %lld points without a Points array", (long long)pc->n);
    } else if (pc->points.ncomp != 3) {
      code = cli_vtp_error(&x, pc->points.at, "Points must have 3 components");
    } else if (!o->has_diameter && !pc->rank) {
      code = o->radius ? cli_vtp_error(&x, pc->at, "no point array '%s'", o->radius)
                       : cli_vtp_error(&x, pc->at, "no point array 'radius' or 'diameter'; give "
                                                   "--diameter or --radius NAME");
    } else if (!o->has_diameter && pc->radius.ncomp != 1) {
      code = cli_vtp_error(&x, pc->radius.at, "the radius array has %lld components",
                           (long long)pc->radius.ncomp);
    } else if ((uint64_t)pc->n > cli_vtp_capacity(&x, &pc->points) / 3 ||
               (!o->has_diameter && (uint64_t)pc->n > cli_vtp_capacity(&x, &pc->radius))) {
      code = cli_vtp_error(&x, pc->at, "NumberOfPoints %lld: more than the file's data can hold (truncated?)",
                           (long long)pc->n);
    } else if (pc->n > INT32_MAX - total) {
      code = cli_vtp_error(&x, pc->at, "more than 2^31 - 1 points");
    }
    total += pc->n;
  }
  if (code == CLI_OK && total == 0) code = cli_vtp_error(&x, 0, "no elements: no points");
  double *coords = NULL, *radii = NULL, *tmp = NULL;
  if (code == CLI_OK) {
    coords = malloc((size_t)total * (size_t)dim * sizeof *coords);
    radii = o->has_diameter ? NULL : malloc((size_t)total * sizeof *radii);
    int64_t most = 0;
    for (size_t k = 0; k < x.npieces; k++) most = x.pieces[k].n > most ? x.pieces[k].n : most;
    tmp = malloc((size_t)most * 3 * sizeof *tmp);
    if (!coords || !tmp || (!o->has_diameter && !radii)) {
      code = cli_fail(CLI_RESOURCE, "%s: out of memory for %lld points", path, (long long)total);
    }
  }
  int64_t at = 0;
  for (size_t k = 0; k < x.npieces && code == CLI_OK; k++) {
    cli_piece *pc = &x.pieces[k];
    if (pc->n == 0) continue;
    code = cli_vtp_values(&x, &pc->points, 3 * pc->n, tmp, 1, "coordinate");
    if (code != CLI_OK) break;
    for (int64_t i = 0; i < pc->n; i++) {
      for (int a = 0; a < dim; a++) coords[(size_t)(at + i) * (size_t)dim + (size_t)a] = tmp[3 * i + a];
    }
    if (!o->has_diameter) {
      code = cli_vtp_values(&x, &pc->radius, pc->n, radii + at, 2,
                            pc->rank == 1 ? "diameter" : "radius");
      if (code != CLI_OK) break;
      if (pc->rank == 1) {
        for (int64_t i = 0; i < pc->n; i++) radii[at + i] *= 0.5;
      }
    }
    at += pc->n;
  }
  cli_progress_end(&x.prog);
  free(tmp);
  free(x.pieces);
  free(x.buf);
  if (code != CLI_OK) {
    free(coords);
    free(radii);
    return code;
  }
  out->dim = dim;
  out->n = total;
  out->coords = coords;
  out->radii = radii;
  out->diameter = o->has_diameter ? o->diameter : 0;
  return CLI_OK;
}
