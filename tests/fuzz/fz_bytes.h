/*
 * Reading a fuzz input (shared by fuzz_detect.c and fuzz_partition.c): every read past the
 * end yields 0, so that any byte string is a scene.
 */
#ifndef NBS_FZ_BYTES_H
#define NBS_FZ_BYTES_H

#include <stddef.h>
#include <stdint.h>

typedef struct fz_reader {
  const uint8_t *p;
  size_t left;
} fz_reader;

static inline unsigned fz_u8(fz_reader *r) {
  if (r->left == 0) return 0;
  r->left--;
  return *r->p++;
}

/* little-endian */
static inline unsigned fz_u16(fz_reader *r) {
  const unsigned lo = fz_u8(r);
  return lo | fz_u8(r) << 8;
}

#endif
