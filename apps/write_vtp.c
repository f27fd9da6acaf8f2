/*
 * The scene and its contact network as VTK XML PolyData (.vtp), the way VTK and ParaView
 * write it: version 1.0, UInt64 headers, little-endian, data appended raw (or inline base64,
 * or ASCII), zlib-compressed in blocks of 32 KiB.
 *
 *   Points               the centres (z = 0 in 2D), Float64 x 3
 *   PointData radius     Float64, the radius of each element (Scalars, for glyphs)
 *   PointData contacts   Int32, the number of contacts of each element
 *   Verts                one vertex per element, so that the points are drawn
 *   Lines                one line per contacting pair
 *
 * Layout of a binary array (VTK's): uncompressed, a UInt64 byte count then the bytes;
 * compressed, a header [nblocks, block size, size of the last block, compressed size of each
 * block] (UInt64 each) then the zlib blocks. Inline base64 encodes an uncompressed array as
 * one stream and a compressed one as two (header, then blocks), as VTK does.
 */
#include "cli.h"

#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#define CLI_VTP_BLOCK 32768u

typedef enum { CLI_T_F64, CLI_T_I32, CLI_T_I64 } cli_vtype;

/* An array produced on demand, value by value, so that nothing is materialised twice. */
typedef struct cli_varray {
  const char *name;
  cli_vtype type;
  int ncomp;
  size_t count; /* values (tuples x components) */
  /* The value at index k, as double or int64. */
  double (*f64)(const void *src, size_t k);
  int64_t (*i64)(const void *src, size_t k);
  const void *src;
  /* Encoded bytes (binary encodings), built before the XML is written. */
  unsigned char *blob;
  size_t blob_len;
  size_t offset; /* appended: offset after the '_' */
} cli_varray;

typedef struct cli_vsrc {
  const cli_elements *e;
  const nbs_pair *pairs;
  size_t count;
  const int32_t *contacts;
} cli_vsrc;

static size_t cli_vtype_size(cli_vtype t) { return t == CLI_T_I32 ? 4 : 8; }
static const char *cli_vtype_name(cli_vtype t) {
  return t == CLI_T_F64 ? "Float64" : t == CLI_T_I32 ? "Int32" : "Int64";
}

static double cli_v_points(const void *p, size_t k) {
  const cli_vsrc *s = p;
  size_t el = k / 3, a = k % 3;
  return (int)a < s->e->dim ? s->e->coords[el * (size_t)s->e->dim + a] : 0.0;
}
static double cli_v_radius(const void *p, size_t k) {
  const cli_vsrc *s = p;
  return s->e->radii ? s->e->radii[k] : 0.5 * s->e->diameter;
}
static int64_t cli_v_contacts(const void *p, size_t k) {
  const cli_vsrc *s = p;
  return s->contacts[k];
}
static int64_t cli_v_iota(const void *p, size_t k) {
  (void)p;
  return (int64_t)k;
}
static int64_t cli_v_iota1(const void *p, size_t k) {
  (void)p;
  return (int64_t)k + 1;
}
static int64_t cli_v_line_conn(const void *p, size_t k) {
  const cli_vsrc *s = p;
  return k % 2 ? s->pairs[k / 2].j : s->pairs[k / 2].i;
}
static int64_t cli_v_line_off(const void *p, size_t k) {
  (void)p;
  return 2 * ((int64_t)k + 1);
}

static void cli_put_u64(unsigned char *d, uint64_t v) {
  for (int b = 0; b < 8; b++) d[b] = (unsigned char)(v >> (8 * b));
}

/* Little-endian bytes of values [from, from + count) into dst. */
static void cli_varray_bytes(const cli_varray *a, size_t from, size_t count, unsigned char *dst) {
  size_t w = cli_vtype_size(a->type);
  for (size_t k = 0; k < count; k++) {
    uint64_t bits;
    if (a->type == CLI_T_F64) {
      double v = a->f64(a->src, from + k);
      memcpy(&bits, &v, 8);
    } else {
      bits = (uint64_t)a->i64(a->src, from + k);
    }
    for (size_t b = 0; b < w; b++) dst[k * w + b] = (unsigned char)(bits >> (8 * b));
  }
}

static const char cli_b64[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

/* Base64 of src into a new buffer (NUL-terminated); NULL on allocation failure. */
static char *cli_base64(const unsigned char *src, size_t len, size_t *outlen) {
  size_t n = (len + 2) / 3 * 4;
  char *out = malloc(n + 1);
  if (!out) return NULL;
  size_t o = 0;
  for (size_t k = 0; k < len; k += 3) {
    uint32_t v = (uint32_t)src[k] << 16;
    if (k + 1 < len) v |= (uint32_t)src[k + 1] << 8;
    if (k + 2 < len) v |= src[k + 2];
    out[o++] = cli_b64[v >> 18 & 63];
    out[o++] = cli_b64[v >> 12 & 63];
    out[o++] = k + 1 < len ? cli_b64[v >> 6 & 63] : '=';
    out[o++] = k + 2 < len ? cli_b64[v & 63] : '=';
  }
  out[o] = '\0';
  *outlen = o;
  return out;
}

/* Builds a->blob: the array's binary block (header + data), compressed or not. For base64
 * the blob is already the text. false on allocation failure. */
static bool cli_varray_encode(cli_varray *a, bool compress, bool base64) {
  size_t w = cli_vtype_size(a->type);
  size_t total = a->count * w;
  size_t per_block = CLI_VTP_BLOCK / w; /* values per block */
  unsigned char *block = malloc(CLI_VTP_BLOCK);
  if (!block) return false;
  unsigned char *head = NULL, *data = NULL;
  size_t head_len, data_len = 0;
  bool ok = false;
  if (!compress) {
    head_len = 8;
    head = malloc(8 + total);
    if (!head) goto done;
    cli_put_u64(head, total);
    for (size_t k = 0; k < a->count; k += per_block) {
      size_t m = a->count - k < per_block ? a->count - k : per_block;
      cli_varray_bytes(a, k, m, head + 8 + k * w);
    }
    head_len += total; /* header and data are one stream */
  } else {
    size_t nblocks = (total + CLI_VTP_BLOCK - 1) / CLI_VTP_BLOCK;
    head_len = 8 * (3 + nblocks);
    head = malloc(head_len);
    uLong bound = compressBound(CLI_VTP_BLOCK);
    size_t cap = nblocks * 64 + 1024;
    data = malloc(cap);
    if (!head || !data) goto done;
    cli_put_u64(head, nblocks);
    cli_put_u64(head + 8, CLI_VTP_BLOCK);
    cli_put_u64(head + 16, total % CLI_VTP_BLOCK);
    for (size_t b = 0; b < nblocks; b++) {
      size_t k = b * per_block;
      size_t m = a->count - k < per_block ? a->count - k : per_block;
      cli_varray_bytes(a, k, m, block);
      if (cap - data_len < bound) {
        size_t ncap = cap * 2 > data_len + bound ? cap * 2 : data_len + bound;
        unsigned char *d = realloc(data, ncap);
        if (!d) goto done;
        data = d;
        cap = ncap;
      }
      uLongf clen = (uLongf)(cap - data_len);
      if (compress2(data + data_len, &clen, block, (uLong)(m * w), 1) != Z_OK) goto done;
      cli_put_u64(head + 24 + 8 * b, clen);
      data_len += clen;
    }
  }
  if (base64) {
    size_t l1, l2 = 0;
    char *t1 = cli_base64(head, head_len, &l1);
    char *t2 = data ? cli_base64(data, data_len, &l2) : NULL;
    if (!t1 || (data && !t2)) {
      free(t1);
      free(t2);
      goto done;
    }
    a->blob = malloc(l1 + l2 + 1);
    if (!a->blob) {
      free(t1);
      free(t2);
      goto done;
    }
    memcpy(a->blob, t1, l1);
    if (t2) memcpy(a->blob + l1, t2, l2);
    a->blob_len = l1 + l2;
    free(t1);
    free(t2);
  } else {
    a->blob = malloc(head_len + data_len + 1);
    if (!a->blob) goto done;
    memcpy(a->blob, head, head_len);
    if (data) memcpy(a->blob + head_len, data, data_len);
    a->blob_len = head_len + data_len;
  }
  ok = true;
done:
  free(block);
  free(head);
  free(data);
  return ok;
}

static void cli_varray_xml(FILE *f, const cli_varray *a, const cli_vtp_opts *o) {
  fprintf(f, "        <DataArray type=\"%s\" Name=\"%s\"", cli_vtype_name(a->type), a->name);
  if (a->ncomp > 1) fprintf(f, " NumberOfComponents=\"%d\"", a->ncomp);
  if (o->encoding == CLI_VTP_APPENDED) {
    fprintf(f, " format=\"appended\" offset=\"%zu\"/>\n", a->offset);
    return;
  }
  if (o->encoding == CLI_VTP_BASE64) {
    fputs(" format=\"binary\">\n          ", f);
    fwrite(a->blob, 1, a->blob_len, f);
    fputs("\n        </DataArray>\n", f);
    return;
  }
  fputs(" format=\"ascii\">\n", f);
  int per_line = a->ncomp > 1 ? a->ncomp * 2 : 8;
  for (size_t k = 0; k < a->count; k++) {
    if (k % (size_t)per_line == 0) fputs("          ", f);
    if (a->type == CLI_T_F64) {
      fprintf(f, "%.17g", a->f64(a->src, k));
    } else {
      fprintf(f, "%lld", (long long)a->i64(a->src, k));
    }
    fputc((k + 1) % (size_t)per_line == 0 || k + 1 == a->count ? '\n' : ' ', f);
  }
  fputs("        </DataArray>\n", f);
}

int cli_write_vtp(const char *path, const cli_vtp_opts *o, const cli_elements *e,
                  const nbs_pair *pairs, size_t count) {
  const size_t n = (size_t)e->n;
  int32_t *contacts = calloc(n > 0 ? n : 1, sizeof *contacts);
  if (!contacts) return cli_fail(CLI_RESOURCE, "%s: out of memory", path);
  for (size_t k = 0; k < count; k++) {
    contacts[pairs[k].i]++;
    contacts[pairs[k].j]++;
  }
  cli_vsrc src = {e, pairs, count, contacts};
  cli_varray arrays[7] = {
      {"radius", CLI_T_F64, 1, n, cli_v_radius, NULL, &src, NULL, 0, 0},
      {"contacts", CLI_T_I32, 1, n, NULL, cli_v_contacts, &src, NULL, 0, 0},
      {"Points", CLI_T_F64, 3, 3 * n, cli_v_points, NULL, &src, NULL, 0, 0},
      {"connectivity", CLI_T_I64, 1, n, NULL, cli_v_iota, &src, NULL, 0, 0},
      {"offsets", CLI_T_I64, 1, n, NULL, cli_v_iota1, &src, NULL, 0, 0},
      {"connectivity", CLI_T_I64, 1, 2 * count, NULL, cli_v_line_conn, &src, NULL, 0, 0},
      {"offsets", CLI_T_I64, 1, count, NULL, cli_v_line_off, &src, NULL, 0, 0},
  };
  enum { NARR = 7 };
  int code = CLI_OK;
  cli_progress prog;
  cli_progress_begin(&prog, "writing vtp", NARR + 1);
  if (o->encoding != CLI_VTP_ASCII) {
    size_t offset = 0;
    for (int k = 0; k < NARR && code == CLI_OK; k++) {
      if (!cli_varray_encode(&arrays[k], o->compress, o->encoding == CLI_VTP_BASE64)) {
        code = cli_fail(CLI_RESOURCE, "%s: out of memory encoding %s", path, arrays[k].name);
      }
      arrays[k].offset = offset;
      offset += arrays[k].blob_len;
      cli_progress_update(&prog, k + 1);
    }
  }
  cli_out out;
  if (code == CLI_OK) code = cli_out_open(&out, path);
  if (code == CLI_OK) {
    FILE *f = out.f;
    bool bin = o->encoding != CLI_VTP_ASCII;
    fprintf(f, "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"1.0\" "
               "byte_order=\"LittleEndian\" header_type=\"UInt64\"%s>\n",
            bin && o->compress ? " compressor=\"vtkZLibDataCompressor\"" : "");
    fprintf(f, "  <PolyData>\n    <Piece NumberOfPoints=\"%zu\" NumberOfVerts=\"%zu\" "
               "NumberOfLines=\"%zu\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">\n",
            n, n, count);
    fputs("      <PointData Scalars=\"radius\">\n", f);
    cli_varray_xml(f, &arrays[0], o);
    cli_varray_xml(f, &arrays[1], o);
    fputs("      </PointData>\n      <Points>\n", f);
    cli_varray_xml(f, &arrays[2], o);
    fputs("      </Points>\n      <Verts>\n", f);
    cli_varray_xml(f, &arrays[3], o);
    cli_varray_xml(f, &arrays[4], o);
    fputs("      </Verts>\n      <Lines>\n", f);
    cli_varray_xml(f, &arrays[5], o);
    cli_varray_xml(f, &arrays[6], o);
    fputs("      </Lines>\n    </Piece>\n  </PolyData>\n", f);
    if (o->encoding == CLI_VTP_APPENDED) {
      fputs("  <AppendedData encoding=\"raw\">\n   _", f);
      for (int k = 0; k < NARR; k++) fwrite(arrays[k].blob, 1, arrays[k].blob_len, f);
      fputs("\n  </AppendedData>\n", f);
    }
    fputs("</VTKFile>\n", f);
    code = cli_out_commit(&out);
  }
  cli_progress_end(&prog);
  for (int k = 0; k < NARR; k++) free(arrays[k].blob);
  free(contacts);
  return code;
}
