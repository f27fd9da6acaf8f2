#include "util.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#if defined(__GLIBC__)
#include <malloc.h>
#include <stdatomic.h>
#define PAIR_SLOTS 8
#else
#define PAIR_SLOTS 0
#endif

/* ---- the buffers of pair lists, kept for the next list ---------------------------------
 * The tests make thousands of lists of up to a few megabytes, the pairs of one detection
 * each. Allocated and freed every time, each list was new pages from the kernel (glibc hands
 * a large freed block back; AddressSanitizer maps every large block and unmaps it after its
 * quarantine): their page faults and copies were half of test_determinism's time, a third
 * of it system time even in Release. A freed list's buffer goes to one of a few slots
 * instead, and the next list takes one that is large enough (and frees those it passes
 * that are not, so that small lists do not fill the slots). The slots are atomic: lists
 * are made and freed on OpenMP threads too. Only the tests' own lists: the library's
 * allocations are untouched. Elsewhere than glibc (no malloc_usable_size) nothing is kept. */
#if PAIR_SLOTS
static _Atomic(nbs_pair *) pair_slots[PAIR_SLOTS];
#endif

static nbs_pair *pairs_alloc(size_t count) {
  const size_t bytes = (count ? count : 1) * sizeof(nbs_pair);
#if PAIR_SLOTS
  for (int k = 0; k < PAIR_SLOTS; k++) {
    nbs_pair *p = atomic_exchange(&pair_slots[k], NULL);
    if (!p) continue;
    if (malloc_usable_size(p) >= bytes) return p;
    free(p); /* too small: the slots keep the largest lists of the test */
  }
#endif
  nbs_pair *p = malloc(bytes);
  if (!p) abort();
  return p;
}

static void pairs_release(nbs_pair *p) {
  if (!p) return;
#if PAIR_SLOTS
  for (int k = 0; k < PAIR_SLOTS; k++) {
    nbs_pair *none = NULL;
    if (atomic_compare_exchange_strong(&pair_slots[k], &none, p)) return;
  }
#endif
  free(p);
}

void pair_list_copy(pair_list *out, const nbs_pair *p, size_t count) {
  out->p = pairs_alloc(count);
  if (count) memcpy(out->p, p, count * sizeof *p);
  out->count = count;
}

nbs_input scene_input(const scene *s) {
  nbs_input in;
  memset(&in, 0, sizeof in);
  in.dim = s->dim;
  in.n = s->n;
  in.coords = s->coords;
  in.radii = s->radii;
  in.diameter = s->diameter;
  return in;
}

scene scene_view(int dim, int64_t n, double *coords, double *radii) {
  scene s;
  memset(&s, 0, sizeof s);
  s.dim = dim;
  s.n = n;
  s.coords = coords;
  s.radii = radii;
  s.diameter = 1.0;
  return s;
}

double test_unit(uint64_t *state) {
  *state = *state * 6364136223846793005u + 1442695040888963407u;
  return (double)(*state >> 11) * 0x1p-53;
}

scene test_scene(scene_kind kind, int dim, int64_t n, double fraction) {
  scene_def def = scene_default_def();
  def.kind = kind;
  def.dim = dim;
  def.n = n;
  def.fraction = fraction;
  scene s;
  char err[200];
  if (scene_generate(&def, &s, err, sizeof err) != 0) {
    fprintf(stderr, "scene: %s\n", err);
    abort();
  }
  return s;
}

nbs_status detect_raw(nbs_context *ctx, const scene *s, nbs_algorithm algo, nbs_mode mode,
                      pair_list *out) {
  out->p = NULL;
  out->count = 0;
  nbs_input in = scene_input(s);
  nbs_detect_def def = nbs_default_detect_def();
  def.algorithm = algo;
  def.mode = mode;
  nbs_status st = nbs_detect(ctx, &in, &def);
  if (st != NBS_OK) return st;
  size_t count;
  const nbs_pair *p = nbs_pairs(ctx, &count);
  pair_list_copy(out, p, count);
  return NBS_OK;
}

nbs_status detect_sorted(nbs_context *ctx, const scene *s, nbs_algorithm algo, nbs_mode mode,
                         pair_list *out) {
  nbs_status st = detect_raw(ctx, s, algo, mode, out);
  if (st == NBS_OK) nbs_sort_pairs(out->p, out->count);
  return st;
}

typedef struct collector {
  pair_list l;
  size_t cap;
} collector;

static int collect(void *user, const nbs_pair *pairs, size_t count) {
  collector *c = user;
  if (c->l.count + count > c->cap) {
    c->cap = 2 * (c->l.count + count);
    if (!c->l.p) {
      c->l.p = pairs_alloc(c->cap);
    } else {
      c->l.p = realloc(c->l.p, c->cap * sizeof *c->l.p);
      if (!c->l.p) abort();
    }
  }
  memcpy(c->l.p + c->l.count, pairs, count * sizeof *pairs);
  c->l.count += count;
  return 0;
}

nbs_status detect_callback(nbs_context *ctx, const scene *s, nbs_algorithm algo, nbs_mode mode,
                           pair_list *out) {
  collector c = {{NULL, 0}, 0};
  nbs_input in = scene_input(s);
  nbs_detect_def def = nbs_default_detect_def();
  def.algorithm = algo;
  def.mode = mode;
  def.callback = collect;
  def.user = &c;
  nbs_status st = nbs_detect(ctx, &in, &def);
  *out = c.l;
  if (!out->p) out->p = pairs_alloc(1);
  return st;
}

void pair_list_free(pair_list *l) {
  pairs_release(l->p);
  l->p = NULL;
  l->count = 0;
}

bool pair_lists_equal(const pair_list *a, const pair_list *b) {
  return a->count == b->count &&
         (a->count == 0 || memcmp(a->p, b->p, a->count * sizeof *a->p) == 0);
}

bool pair_list_contains(const pair_list *super, const pair_list *sub) {
  size_t i = 0;
  for (size_t k = 0; k < sub->count; k++) {
    while (i < super->count &&
           (super->p[i].i < sub->p[k].i ||
            (super->p[i].i == sub->p[k].i && super->p[i].j < sub->p[k].j)))
      i++;
    if (i == super->count || super->p[i].i != sub->p[k].i || super->p[i].j != sub->p[k].j)
      return false;
  }
  return true;
}

/* The size is stored in front of each block so that free can check it. */
static void *test_alloc_fn(void *opaque, size_t size) {
  test_alloc *ta = opaque;
  long call = ta->calls++;
  if (ta->fail_at >= 0 && call == ta->fail_at) {
    ta->failures++;
    return NULL;
  }
  size_t *p = malloc(size + 16);
  if (!p) return NULL;
  p[0] = size;
  ta->live++;
  ta->live_bytes += size;
  return (char *)p + 16;
}

static void test_free_fn(void *opaque, void *ptr, size_t size) {
  test_alloc *ta = opaque;
  size_t *p = (size_t *)(void *)((char *)ptr - 16);
  if (p[0] != size) {
    fprintf(stderr, "free with size %zu of a block of %zu bytes\n", size, p[0]);
    abort();
  }
  ta->live--;
  ta->live_bytes -= size;
  free(p);
}

static void *test_realloc_fn(void *opaque, void *ptr, size_t old_size, size_t size) {
  test_alloc *ta = opaque;
  size_t *p = (size_t *)(void *)((char *)ptr - 16);
  if (p[0] != old_size) {
    fprintf(stderr, "realloc with size %zu of a block of %zu bytes\n", old_size, p[0]);
    abort();
  }
  long call = ta->calls++;
  if (ta->fail_at >= 0 && call == ta->fail_at) {
    ta->failures++;
    return NULL;
  }
  size_t *q = realloc(p, size + 16);
  if (!q) return NULL;
  q[0] = size;
  ta->live_bytes = ta->live_bytes - old_size + size;
  return (char *)q + 16;
}

nbs_allocator test_allocator(test_alloc *ta) {
  nbs_allocator a = {test_alloc_fn, test_free_fn, ta, ta->with_realloc ? test_realloc_fn : NULL};
  return a;
}

nbs_status detect_stats(nbs_context *ctx, const scene *s, nbs_algorithm algo, nbs_stats *st) {
  nbs_input in = scene_input(s);
  nbs_detect_def def = nbs_default_detect_def();
  def.algorithm = algo;
  nbs_status status = nbs_detect(ctx, &in, &def);
  nbs_last_stats(ctx, st);
  return status;
}
