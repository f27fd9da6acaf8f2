/*
 * cellsort: nbs's fast path, beyond the book. The same cells and the same half mask as
 * screening and NBS, but the elements are first put in cell order so that every distance
 * test reads memory that is next to the last one read.
 *
 * Why it is fast. For a million elements in random order, the book's algorithms spend most
 * of their time waiting for memory: each candidate pair reads two coordinates that lie
 * anywhere in 24 MB, far beyond the caches (measured: NBS is 5x faster on the same scene in
 * spatially sorted order). cellsort pays for one sort instead:
 *   1. key = (iz, iy, x sub-cell) packed in 64 bits, one pass over the input (with
 *      AVX-512, 8 elements at a time); x counts sub-cells of edge / 8 (fewer when the key
 *      needs the bits);
 *   2. LSD radix sort of (key, element) by the key's significant bits only, in as few
 *      passes of at most 9 bits as they need; the scatter of each pass writes into at most
 *      2^9 sequential streams, which caches handle well (measured: a pass of 11 bits costs
 *      more than twice one of 8). Where the key and the element's number fit 63 bits
 *      together (every scene of the benchmarks but the 3D sparse and clustered ones), they
 *      share one 64-bit word, so that a pass moves 8 bytes, not 12, and the sweep reads one
 *      array for both (3D, N = 1e6: sort 5.4 -> 3.4 ns per element, detection 34 -> 31).
 *      Where they do not, but would for a crowded core of the elements (those two scenes:
 *      a few elements far out widen the keys), the core is sorted so and the others apart,
 *      and the two merged (nbs__cs_core); so too where they do, but the core's keys take
 *      two passes fewer (2D sparse and clustered);
 *   3. gather the coordinates (and radii) in cell order, prefetching both ends of the
 *      element 256 places ahead into L2 and 32 ahead into L1 (nbs__cs_prefetch) where the
 *      input is over 8 MiB (NBS__CS_PREFETCH_MIN; below, the prefetches only cost): the last
 *      random access. Where the input is larger than 1 GiB (3D N = 4.5e7, 2D 6.7e7),
 *      steps 1-3 are instead one partition by the top digit that carries the coordinates
 *      along in whole lines, then each bucket put in order in cache (nbs__cs_partition:
 *      3D N = 1e8, Zen 4, one thread, 52.8-78.6 -> 43.8-45.7 ns per element; until its top
 *      digit was widened, nbs__cs_part_digits, it gave way there to the sort and the gather,
 *      whose random reads of 2.4 GB miss the TLB too, its buckets too large for a cache);
 *      from 8 MiB to 1 GiB,
 *      which of the two is faster depends on the machine's memory, and the context times
 *      its first detections both ways and keeps the faster (nbs__cs_way: on an Intel guest
 *      whose random reads of memory cost 4x the AMD instances', the partition, 3D N = 1e6
 *      75-78 -> 62-66 ns per element). So too the crowded core's keys of step 2: the core's
 *      elements partitioned by their keys relative to its box, the outliers put in their
 *      places apart (nbs__cs_core_part: on that guest, sparse 3D 82.0 -> 71.4, 2D 62.3 ->
 *      44.6).
 *      Tried and left out: the gather deferred into the sweep, each block gathering the
 *      places it is about to read (and, with threads, each thread first the places the next
 *      one reads before its range), so that the kernel's work would hide the gather's waits
 *      on memory. On an instance where the gather took 10 ns per element (3D, N = 1e6) the
 *      detection was the same (36.0 against 36.0 ns, min of 5, for gathers of exactly the
 *      block's places; 32 places ahead 1-2 ns slower): perf moved the waits from the gather
 *      (25% -> 19%) to the kernel (32% -> 40%). The random reads are limited by how many
 *      lines the core can have in flight, not by when they are asked for. Nor did a gather
 *      of 4,096 places at a time (512 to 32,768 alike) each followed by the sweep of those
 *      places, so that the sweep reads them from L2, not from memory (Zen 5, one thread,
 *      min of 2: 3D N = 1e7 27.4 / 26.4-27.9, 1e6 25.3 / 25.3, 2D 1e6 12.6 / 12.5; the
 *      sweep's time grew by what the gather's fell); nor a gather of each bucket of the radix
 *      sort's top digit just after the bucket was sorted (the one before it, so that the
 *      prefetches run on into the bucket just sorted), its coordinates' lines still in the
 *      cache from the sort's passes, the idx array the buckets' scratch (3D, one thread,
 *      interleaved, medians of 8 and 3, preparation 7.69 -> 7.57 ns per element at N = 1e6,
 *      8.98 -> 9.16 at 1e7);
 *      Tried and left out: the same partition with a plain store of each entry to each of
 *      the 5 arrays (word, element and coordinates) of its bucket: it cost more than the
 *      gather and the key pass it replaced (3D, one thread, interleaved, min of 4: N = 1e6
 *      32.1 -> 35.1 ns per element, 1e7 45.6 -> 53.3);
 *   4. sweep the rows in key order, in blocks of 8 consecutive elements of a row. A block
 *      meets a few ranges of the cell order: itself and the elements before it in its own
 *      row within one edge in x, and a window of each neighbouring row of the half mask
 *      (within one edge in x either side of the block: one row in 2D, four in 3D). Each
 *      window's edges only move forwards as the sweep advances, sixteen keys compared at a
 *      time: no binary search (but once per thread), no cell array, no hash. The kernel then
 *      tests one element of the ranges against the whole block at once: with AVX-512 (chosen
 *      at run time) that is one instruction per operation of the distance test for 8 pairs,
 *      and a compress that stores the pairs found without a branch. Per element that is
 *      about 5 kernel steps and 5/8 of a window update in 3D, instead of 9 candidate tests
 *      and 5 window updates, each ending in a mispredicted branch, for one element at a time
 *      (measured at N = 1e6, one thread: the sweep went from 60 to about 20 ns per element).
 *      In 2D a row of fewer than 4 elements is swept element by element instead, each
 *      element's ranges counted among the sixteen keys before it, with nothing carried from
 *      one element to the next (nbs__cs_sweep2_body): a sparse domain's rows hold an element
 *      or two, and by blocks each row waited on finding its end, the row below and its
 *      windows (2D huge domain, N = 1e6, one thread, interleaved, min of 5: 23.8 -> 18.8 ns
 *      per element; uniform, whose rows are long, 15.7 and 15.8). So too in 3D a row of
 *      fewer than 4, the three rows of the layer below found from one cursor, and with
 *      AVX-512 the candidates picked from sixteen keys each side at once (nbs__cs_sweep3_body;
 *      uniform scenes of mean spacing S diameters, one thread, interleaved, medians of 4,
 *      search in ns per element, blocks / rows of fewer than 3 with the windows' edges
 *      counted / the picks and rows of fewer than 4: N = 1e5 (the benchmarks' density
 *      sweep) S = 5 29.1 / 24.5 / 19.5, S = 10 38.4 / 23.0 / 18.8, S = 20 24.5 / 15.5 / 15.2,
 *      S = 50 11.2 / 8.9 / 10.0; N = 1e6, S = 10 38.1 / 26.2 / 20.1, S = 20 33.6 / 21.1 /
 *      19.0; huge domain, minima of 5, 11.1 / 9.1 / 10.1; S = 5 at N = 1e6, the sparse scene
 *      (fraction 0.005), uniform and clustered the same within noise).
 *      An AVX2 kernel (two registers of 4 lanes, and a table of permutations for the
 *      compress that AVX2 lacks) serves processors without AVX-512, and a generic kernel in
 *      plain C any other; all three give the same bytes in the same order (3D, N = 1e6, on
 *      the benchmark machine: 28, 36 and 71 ns per element in all).
 *      The rows lie along the axis with the most cells, where it has at least twice as many
 *      as x (nbs__axis_order; the key's x, y and z are then the caller's coordinates in another
 *      order, and the coordinates themselves are kept as they are): a wall thin in x, or a
 *      column along z, would otherwise make rows of an element or two (3D, N = 1e6, the
 *      scene `slab`, two diameters thick, turned to be thin in x: 58.6 -> 27.9 ns per
 *      element, against 27.1 thin in z; a rod along z 47.4 -> 22.6, 22.3 along x; 2D, a
 *      strip along y 33.8 -> 17.9, 15.0 along x; interleaved, min of 3).
 * Time steps. A simulation detects the same elements every step, and they move little in a
 * step. The context keeps the cell order of the last detection (the sorted packed words,
 * ctx->cs_order_n), and a detection of the same n (and the same element bits in its words,
 * ctx->cs_order_eb) starts from it. For the keys to stay put, the grid's origin is a point
 * of a fixed lattice of spacing the edge below the lowest coordinate (nbs__cs_anchor), not
 * the lowest coordinate itself. The result, sorted by the whole word, is the order of a
 * sort from scratch, so nothing else differs. Two ways:
 *  - where the words' low half is the element alone (eb = 32: keys of at most 31 bits, every
 *    uniform scene of the benchmarks), nbs__cs_rekey: the idx array, which packed words
 *    leave free, holds each element's key of the last order (ctx->cs_keys; the first start
 *    from an order after a sort from scratch writes them, nbs__cs_keys_of). One pass over
 *    the input in element order, sequential like the key pass, computes each key again
 *    against idx[e]; the few elements whose key changed are sorted (their old words and
 *    their new) and merged into the last order's words, 8 bytes per element; and the
 *    coordinates are gathered once, as from scratch. That replaces the key pass and the
 *    radix sort (steps 1-2) by a pass like the key pass and a merge of words.
 *    Where the context has the keys, that pass also replaces
 *    input.c's pass over the input: it runs with the last detection's keying, before the
 *    grid is known, and measures the bounding box as it goes; its keys stand where the
 *    grid gives the same keying, which it does but where the box crosses a lattice line
 *    or a power of two of cells (nbs__cellsort_step; 3D steps 2-3% faster, 2D not);
 *  - else nbs__cs_warm: one pass gathers the elements in the last order, a chunk at a time,
 *    and computes each one's key again from the copies; the few whose key changed are sorted
 *    again and merged back, words and coordinates, in place: the words kept move only where
 *    the elements taken out and put back lie on either side of them (nbs__cs_warm_merge).
 *    That replaces steps 1-3 by one pass like the gather and a merge of the few.
 * Either way a step still reads every coordinate once in the order's places, at random;
 * where a detection from scratch would take the partition, which reads the input in order,
 * the context times its first steps both from the order and from scratch and takes the
 * faster (nbs__cs_steps_way: at 3D N = 1e8, 2.4 GB, from scratch).
 * Measured (3D, N = 1e6, fraction 0.5, random order, one thread, interleaved, min of 3-5
 * processes, ns per element; nbs_bench --move D against --fresh; the same bytes):
 *   nbs__cs_warm (before nbs__cs_rekey): from scratch 33.0-33.3, unmoved 29.6, steps of
 *     1e-4 32.5, 1e-3 33.0-33.2, 1e-2 34.6;
 *   nbs__cs_rekey: from scratch 33.0-33.4, unmoved 27.6, steps of 1e-4 29.7, 1e-3
 *     29.1-29.2, 1e-2 31.4
 * (steps of up to D diameters per axis: 481, 5,051, 49,645 elements sorted again). 2D: from
 * scratch 19.5-19.8, steps of 1e-3 18.2 -> 15.3, unmoved 15.8 -> 15.3. Two threads, 3D at
 * 1e-3: 18.7 -> 15.4. N = 1e7, 3D at 1e-3: 36.7 -> 31.4; 1e5 25.8 -> 24.3; 1e4 22.3 -> 22.5,
 * and 2D 1e4 11.0 and 10.9, where everything is in the caches. nbs__cs_warm's pass read the
 * input in the last order, at random, and computed the keys there; done as a gather then a
 * key check from the L1 cache, a chunk at a time, it was no faster then, in 3D uniform scenes
 * with a plain check (unmoved 29.4 / 29.4, 1e-3 33.8 -> 35.0): the merge's moves were the
 * cost. It now serves only keys of more than 31 bits (domains of many cells: the huge one,
 * and 2D sparse and clustered), where it is done so with the check 8 at a time (AVX-512),
 * and the chunk left in place where its words all stand: preparation, unmoved (interleaved,
 * min of 4): 2D huge 5.44 -> 4.02, sparse 5.64 -> 4.01, clustered 6.02 -> 4.20, 3D huge 10.44
 * -> 7.83, two threads 2D huge 3.08 -> 2.14; the plain check (NBS_SIMD=generic) 5.67 ->
 * 5.42; steps of 1e-2 (3D huge) 14.41 -> 13.65. The first start after a sort from
 * scratch pays for writing the keys (a scatter, about a nanosecond per element); stored by
 * the key pass instead, they cost every detection from scratch 0.3 ns (33.1 -> 33.4, 2D
 * 19.6 -> 19.9). More than n / 16 changed keys (steps of 3e-2 here) stop either way, and the
 * detection sorts from scratch.
 * Where the time goes (3D, N = 1e6, fraction 0.5, random order, one thread, AVX-512; about
 * 28 ns per element in all): input validation 0.8, keys 1.2, sort 3.5, gather 3, sweep 19
 * (the kernel about 13.5 of it, finding windows and rows 5.5). Later (perf, Zen 5, about
 * 26 ns): input 0.8, keys 1.35, sort 3.8, gather 4.5, sweep 4.9 and kernel 8.9. A detection
 * from scratch in a context that holds the work arrays now computes the keys in input.c's
 * place, validating and measuring as it goes (nbs__cellsort_fresh): one pass instead of
 * two, 0.7-1.5 ns per element less in 3D.
 * Memory: 8 (key) + 4 (element) + 8 * dim (coordinates) bytes per element, + 8 with radii:
 * 36 B per element in 3D, whatever the extent of the domain (packed keys leave the 4 bytes
 * of the element free for the time steps' keys or scratch; they are held all the same, so
 * that a scene that spreads out never makes a detection allocate). The radix sort's
 * scratch lives in the coordinate arrays before the gather: x's for the passes over all
 * keys, y's (and z's) for each thread's bucket (nbs__radix).
 * Time: O(N * passes) for the sort, with passes = ceil(bits of the cell count / 9), i.e.
 * linear in N for any domain whose cell count fits 64 bits, plus O(candidates).
 *
 * With OpenMP the key pass, the radix sort, the gather and the sweep run in parallel; the
 * sweep's threads take contiguous ranges of the cell order, cut at rows' starts or at blocks
 * of a row (nbs__cs_thread_start), in chunks that a thread done with its own takes from the
 * back of another's (nbs__cs_sweep_parts), and their pairs are concatenated in range order,
 * so the output is identical for any number of threads. The gather and the sort's buckets
 * are shared the same way (nbs__share), so that a core slower than the other at the time
 * does less of them. Two threads halve the key pass, the
 * gather and the sweep; the radix sort's passes by digit did not scale at all (each reads
 * and writes every key, the machine's memory the limit), so where the keys are
 * many it sorts by the top digit first and then each bucket in cache (nbs__radix). 3D,
 * N = 1e6, one thread and two, ns per element: key pass 1.43 and 0.71, sort 4.4-5.3 and 5.9
 * (3.3 with the top digit first), gather 5.4-6.6 and 2.7-3.4, sweep 18.1-18.4 and 9.1-9.4,
 * the second thread's pairs appended 0.45; a detection 31.6 and 21.0 ns (1.50x), 19.3 with
 * the top digit first (1.65x; 2D 16.2 and 10.9, 9.7: 1.49x and 1.67x). Both threads now
 * append the pairs (nbs__cs_append, 0.55 -> 0.30 ns) and share input.c's pass over the
 * coordinates (1.00 -> 0.52): 3D two threads 19.4 -> 18.6 ns, minimum of 8 processes each.
 */
#include "internal.h"

#include <float.h>
#include <stdlib.h>
#if defined(_OPENMP)
#include <stdatomic.h>
#endif
/* The AVX-512 and AVX2 kernels where the compiler can target them (NBS__X86_SIMD); the
 * processor is asked at run time. */
#if NBS__X86_SIMD
#define NBS__CS_AVX512 1
#define NBS__CS_AVX512_TARGET __attribute__((target("avx512f,avx512vl,avx512dq,popcnt")))
/* AVX2 without FMA: the distance test must not be contracted */
#define NBS__CS_AVX2_TARGET __attribute__((target("avx2,popcnt")))
#else
#define NBS__CS_AVX512 0
#endif

/* The AVX-512 sweep starts on a cache line, so that its loops lie in the instruction
 * fetch's windows the same way whatever code comes before it in the file. Code placement
 * moves the search by up to a nanosecond per element here, and not the same way for every
 * scene: an unrelated function added above moved the sweep and the kernel by 32 bytes, and
 * the search took 0.2-0.3 ns per element more (3D, N = 1e6, interleaved, median of 8: time
 * steps of 1e-3 14.71 -> 14.91 ns, from scratch 14.43 -> 14.71); both aligned, later, the
 * uniform scene's search was 0.2 ns faster than with the sweep alone aligned, but the sparse
 * scene's (fraction 0.005) 1.2 slower (19.4 -> 20.6), so the kernel is not.
 * Both lie in a section of their own (NBS__CS_PLACED, on ELF targets), which the linker
 * puts together with other hot code ahead of the rest: so code added or removed elsewhere in
 * this file no longer moves them against each other. Before, a change to the radix sort's
 * local passes alone (the two digits counted in one pass) left the kernel where it was and
 * moved the sweep by 256 bytes, and the search took 0.16-0.35 ns per element more (3D,
 * N = 1e6, interleaved, medians of 8, three runs); in the section, 13.00 -> 12.89 against
 * the build before that change, and sparse, huge, clustered and 2D within noise. */
#if defined(__GNUC__) && defined(__ELF__)
#define NBS__CS_PLACED __attribute__((section(".text.hot.nbs_cellsort")))
#else
#define NBS__CS_PLACED
#endif
#if defined(__GNUC__)
#define NBS__CS_HOT __attribute__((aligned(64))) NBS__CS_PLACED
#else
#define NBS__CS_HOT NBS__CS_PLACED
#endif

#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
#define NBS__BIG_ENDIAN 1
#else
#define NBS__BIG_ENDIAN 0
#endif

#define NBS__RADIX_BITS 9
/* The most keys of a bucket of the radix sort's top digit for the buckets to be sorted one
 * by one (nbs__radix): 256 kB of packed keys, twice (the bucket and its scratch), within a
 * core's cache. */
#define NBS__RADIX_LOCAL_MAX 32768
/* How far ahead the gather prefetches: far enough for the memory's latency at the rate the
 * loop runs (3D, N = 1e6, both ends of each element prefetched into L1: 16 ahead 6.6 ns per
 * element, 64 ahead 3.6, 128 ahead 2.9; 2D 5.0, 3.0, 2.2, on an instance whose L3 held the
 * input). In two stages: into the L2 cache NBS__CS_AHEAD places ahead, then into L1
 * NBS__CS_NEAR places ahead. A prefetch into L1 holds one of the core's few L1 miss buffers
 * until its line comes from memory, and where the input is not in L3 those, not the
 * distance, bounded the random reads (see nbs__cs_prefetch). */
#define NBS__CS_AHEAD 256
#define NBS__CS_NEAR 32
/* (On Zen 3, 72fa429, 3D N = 1e6, NBS_PARTITION=never, interleaved, min of 4, preparation
 * in ns per element: 256 and 32 19.42, 512 and 32 19.86, 1024 and 64 20.31, 256 and 64
 * 19.77: within noise. With the caller's coordinates on huge pages the same gather takes
 * about 2.6 less: its reads also miss the TLB; see the README, "The C API".) */
/* The input's size (bytes of coordinates and radii) above which the gather and the warm
 * pass prefetch at all. Below it the input is in the caches by the time it is read, and
 * the prefetches, with the reads of the words ahead that name their elements, only cost
 * (interleaved, min of 4, ns per element, one thread, random order, prefetching against
 * not: 3D N = 1e4, 240 kB, 25.6 / 23.3; 1e5, 2.4 MB, 29.5 / 27.6; 3e5, 7.2 MB, 31.1 / 30.3;
 * 5e5, 12 MB, 33.4 / 34.2; 1e6 34.1 / 37.5; 2D 1e4 14.1 / 12.0; 7e5, 11.2 MB, 19.7 / 18.8;
 * 1e6, 16 MB, 20.1 / 20.4). */
#define NBS__CS_PREFETCH_MIN ((size_t)8 << 20)
/* How far ahead the sweep asks for its own rows' keys and coordinates (see the sweep). */
#define NBS__CS_SWEEP_AHEAD 64
/* Entries after the end of the key array, read by NBS__CS_ADVANCE: the keys it compares at
 * once. */
#define NBS__CS_PAD 16
/* Sub-cells per cell edge on the x axis: a power of two, so that scaling is exact; fewer
 * when the key would not fit 64 bits otherwise. (4 and 16 were no different: interleaved,
 * min of 5, N = 1e6, 8 / 4 / 16 sub-cells, 2D 20.15 / 20.16 / 20.36 ns per element, 3D
 * 34.20 / 34.21 / 34.29.) */
#define NBS__CS_FINE_BITS 3

typedef struct nbs__cs nbs__cs;
/* A block kernel (see below). */
typedef struct nbs__cs_ranges nbs__cs_ranges;
typedef size_t (*nbs__cs_block_fn)(const nbs__cs *c, int32_t c0, int lanes,
                                   const nbs__cs_ranges *rg, nbs_pair *out);

struct nbs__cs {
  nbs__run *run;
  int dim;
  bool contacts;
  nbs__cs_block_fn block;
  int32_t n;
  uint64_t *key;
  int32_t *idx;        /* the element at each place of the cell order (unpacked keys only) */
  const int32_t *ids;  /* where the sweep reads the element at place q: ids[q * istep] */
  int istep;           /* 1 (idx), or 2 (the low half of the packed key word) */
  double *xs, *ys, *zs; /* coordinates in cell order, one array per axis */
  double *rs; /* radii in cell order, or NULL */
  double d2;
  int64_t nx, ny, nz;
  int bx, by;     /* bits of the key for the x sub-cell and for iy (iz takes the rest) */
  int ks;         /* where the key starts in a word of key[]: the element's bits when
                   * packed, else 0 */
  uint32_t imask; /* the element's bits in the low half of a word (all ones where that
                   * is the element alone: unpacked, or packed with 32 element bits) */
  uint64_t fine;  /* sub-cells per cell edge on x */
};

/* Number of bits needed for values < count (count >= 1). */
static int nbs__bits(uint64_t count) {
  int b = 0;
  while (b < 64 && (count - 1) >> b) b++;
  return b;
}

/* The radix sort's passes: as few digits of at most NBS__RADIX_BITS bits as `bits` needs,
 * all of the same width. */
typedef struct nbs__digits {
  int passes, width;
  size_t buckets;
  int bits; /* the key's significant bits: at most passes * width */
} nbs__digits;

static nbs__digits nbs__radix_digits(int bits) {
  nbs__digits d = {0, 0, 1, bits > 0 ? bits : 0};
  if (bits > 0) {
    d.passes = (bits + NBS__RADIX_BITS - 1) / NBS__RADIX_BITS;
    d.width = (bits + d.passes - 1) / d.passes;
    d.buckets = (size_t)1 << d.width;
  }
  return d;
}

/* The counts of the digits at `shift` (dg's width) of sk[from, to), into h. */
static inline void nbs__radix_count(const uint64_t *sk, int32_t from, int32_t to, int shift,
                                    nbs__digits dg, uint32_t *h) {
  const uint64_t mask = dg.buckets - 1;
  memset(h, 0, dg.buckets * sizeof *h);
  for (int32_t k = from; k < to; k++) h[(sk[k] >> shift) & mask]++;
}

/* The same over a whole array, in NBS__RADIX_WAYS histograms that take the keys in turn,
 * summed at the end. Where neighbouring keys share the digit (an input in cell order, or
 * nearly), one histogram makes every count wait for the one before it (a load of the count
 * the last store wrote, several cycles); in turn, the ways' counts run side by side.
 * Measured with nbs__radix_local's two-digit count done the same way (two ways a digit):
 * input in cell order (nbs_bench --sorted), interleaved, medians of 3, preparation 3D N =
 * 1e6 7.02 -> 6.44 ns per element (detection 19.56 -> 19.03), 1e7 7.68 -> 6.76 (20.62 ->
 * 19.83), 2D 1e6 4.74 -> 4.50; random order, the clustered and sparse scenes, time steps,
 * two threads and N = 1e4 the same or a little faster (1e4: 2.41 -> 2.30); the same hashes.
 * perf at 3D 1e7 in cell order: the count pass 4.2% -> below 2% of the detection, as in
 * random order. Tried and left out: the scatter two words at a time, both places read
 * before either is stored (the second's the first's plus one where they share the digit):
 * preparation 6.7 -> 7.0 (the scatter's waits on its stores were not what cost). Nor, for
 * the top digit's pass over words far beyond the last-level cache (80 MB at 3D N = 1e7),
 * each bucket's words gathered a line at a time and the line written with streaming stores,
 * which do not read it first (as nbs__cs_part_scatter does): preparation 16.1-16.6 ->
 * 31.1-37.9 ns per element (three runs of each, alternating, in a slow spell): the buckets'
 * passes then read every word from memory, where the plain stores had left many in L3. */
#define NBS__RADIX_WAYS 4
static void nbs__radix_count_ways(const uint64_t *sk, int32_t from, int32_t to, int shift,
                                  nbs__digits dg, uint32_t *h) {
  const uint64_t mask = dg.buckets - 1;
  uint32_t w[NBS__RADIX_WAYS][(size_t)1 << NBS__RADIX_BITS];
  for (int i = 0; i < NBS__RADIX_WAYS; i++) memset(w[i], 0, dg.buckets * sizeof **w);
  int32_t k = from;
  for (; k + NBS__RADIX_WAYS <= to; k += NBS__RADIX_WAYS) {
    for (int i = 0; i < NBS__RADIX_WAYS; i++) w[i][(sk[k + i] >> shift) & mask]++;
  }
  for (; k < to; k++) w[0][(sk[k] >> shift) & mask]++;
  for (size_t b = 0; b < dg.buckets; b++) {
    uint32_t c = 0;
    for (int i = 0; i < NBS__RADIX_WAYS; i++) c += w[i][b];
    h[b] = c;
  }
}

/* sk[from, to) (and si) to dk (and di), each key to the place h gives for its digit, which
 * then moves on: h holds where each bucket's part starts. */
static inline void nbs__radix_scatter(const uint64_t *sk, const int32_t *si, uint64_t *dk,
                                      int32_t *di, int32_t from, int32_t to, int shift,
                                      nbs__digits dg, uint32_t *h) {
  const uint64_t mask = dg.buckets - 1;
  if (si) {
    for (int32_t k = from; k < to; k++) {
      uint32_t at = h[(sk[k] >> shift) & mask]++;
      dk[at] = sk[k];
      di[at] = si[k];
    }
  } else {
    for (int32_t k = from; k < to; k++) dk[h[(sk[k] >> shift) & mask]++] = sk[k];
  }
}

/* The counts of `threads` histograms of `buckets` each (hist, thread t's at t * buckets)
 * turned into places: each thread's part of a bucket after the threads' before it, the
 * buckets one after the other. top[b] (where top is not NULL) receives where bucket b
 * starts, top[buckets] the total. Returns the largest bucket's size. */
static uint32_t nbs__radix_offsets(uint32_t *hist, size_t buckets, int threads,
                                   uint32_t *top) {
  uint32_t sum = 0, most = 0;
  for (size_t b = 0; b < buckets; b++) {
    const uint32_t b0 = sum;
    if (top) top[b] = b0;
    for (int t = 0; t < threads; t++) {
      const uint32_t c = hist[(size_t)t * buckets + b];
      hist[(size_t)t * buckets + b] = sum;
      sum += c;
    }
    if (sum - b0 > most) most = sum - b0;
  }
  if (top) top[buckets] = sum;
  return most;
}

/* ---- work shared by threads: a part each, then the rest taken from the back --------- */

#if defined(_OPENMP)
/* Items [0, n) cut into parts, part t thread t's (NBS__PARTS), each taken in ranges: by its
 * owner from the front, then by any thread done with its own parts from the back of the
 * part with the most left. Where one core runs slower than the other (this machine's
 * virtual cores ran the same work up to 1.45x apart at times; with another process on one
 * core, about twice), the faster one takes on part of the slower one's share, where even
 * halves waited for the slower one; on cores alike each thread does its own part, as
 * before. Used where the result does not depend on which thread does which range: the
 * buckets' sorts, the gather, and the sweep's chunks (whose pairs are placed by chunk). */
typedef struct nbs__share {
  /* part t: its next item from the front (low half), the end of those left (high half) */
  _Atomic uint64_t left[NBS__THREADS_MAX];
  int parts;
  /* the tests' (NBS_STEAL=first, nbs__cellsort_steal_first): each thread first takes the
   * last range of the next part, so that ranges taken from others' parts are seen */
  bool first;
} nbs__share;

/* Part t is the items [cut[t], cut[t + 1]). */
static void nbs__share_init(nbs__share *s, int parts, const uint32_t *cut, bool first) {
  s->parts = parts;
  s->first = first;
  for (int t = 0; t < parts; t++) {
    atomic_init(&s->left[t], (uint64_t)cut[t] | (uint64_t)cut[t + 1] << 32);
  }
}

/* The next range [*a, *b) of part t from its front: grain items, or with `half`, half of
 * what is left where that is more (an owner's long runs start few loops); false if none is
 * left. */
static bool nbs__share_front(nbs__share *s, int t, uint32_t grain, bool half, uint32_t *a,
                             uint32_t *b) {
  uint64_t v = atomic_load_explicit(&s->left[t], memory_order_relaxed);
  for (;;) {
    const uint32_t f = (uint32_t)v, e = (uint32_t)(v >> 32);
    if (f >= e) return false;
    uint32_t m = half && (e - f) / 2 > grain ? (e - f) / 2 : grain;
    if (m > e - f) m = e - f;
    if (atomic_compare_exchange_weak_explicit(&s->left[t], &v, v + m, memory_order_relaxed,
                                              memory_order_relaxed)) {
      *a = f;
      *b = f + m;
      return true;
    }
  }
}

/* The last grain items (or fewer) left of part t: false if none is left. */
static bool nbs__share_back_of(nbs__share *s, int t, uint32_t grain, uint32_t *a,
                               uint32_t *b) {
  uint64_t v = atomic_load_explicit(&s->left[t], memory_order_relaxed);
  for (;;) {
    const uint32_t f = (uint32_t)v, e = (uint32_t)(v >> 32);
    if (f >= e) return false;
    const uint32_t m = e - f < grain ? e - f : grain;
    if (atomic_compare_exchange_weak_explicit(&s->left[t], &v, v - ((uint64_t)m << 32),
                                              memory_order_relaxed, memory_order_relaxed)) {
      *a = e - m;
      *b = e;
      return true;
    }
  }
}

/* The last grain items left of the part with the most left: false once none is left of
 * any. */
static bool nbs__share_back(nbs__share *s, uint32_t grain, uint32_t *a, uint32_t *b) {
  for (;;) {
    int v = -1;
    uint32_t most = 0;
    for (int t = 0; t < s->parts; t++) {
      const uint64_t x = atomic_load_explicit(&s->left[t], memory_order_relaxed);
      const uint32_t f = (uint32_t)x, e = (uint32_t)(x >> 32);
      if (e > f && e - f > most) {
        most = e - f;
        v = t;
      }
    }
    if (v < 0) return false;
    if (nbs__share_back_of(s, v, grain, a, b)) return true;
  }
}

/* The next range [*a, *b) for a thread on part t (its own, NBS__PARTS; *stage starts at 0):
 * with `first` (the tests'), the last range of the next part first; then part t from its
 * front (grain items, or half of what is left with `half`); then the last grain items of
 * the part with the most left. *taken says whether the range is another part's. False once
 * none is left of any part. */
static bool nbs__share_next(nbs__share *s, int t, int *stage, uint32_t grain, bool half,
                            uint32_t *a, uint32_t *b, bool *taken) {
  *taken = true;
  if (*stage == 0) {
    *stage = 1;
    if (s->first && nbs__share_back_of(s, (t + 1) % s->parts, grain, a, b)) return true;
  }
  if (*stage == 1) {
    if (nbs__share_front(s, t, grain, half, a, b)) {
      *taken = false;
      return true;
    }
    *stage = 2;
  }
  return nbs__share_back(s, grain, a, b);
}
#endif

/* Whether n packed keys of the digits dg are sorted by the top digit first, and then each
 * bucket in cache (nbs__radix, and the partition, nbs__cs_partition): where there are two
 * digits or more and at least as many keys as the square of the buckets (the buckets'
 * histograms then cost at most one step per key and pass). */
static bool nbs__radix_top_first(int32_t n, nbs__digits dg) {
  return dg.passes >= 2 && (uint64_t)n >= (uint64_t)dg.buckets * dg.buckets;
}

/* The partition's digits (nbs__cs_partition) for n keys of `bits` bits: its top digit, the
 * key's bits from `shift` up, in `buckets` buckets, and the digits below it, `lo`, which each
 * bucket is sorted by in the cache (lo.passes - 1 passes of lo.width bits from the bottom;
 * lo.passes counts the top digit too). They are the radix sort's (nbs__radix_digits), all of
 * one width, unless that leaves the top digit too narrow for the input: the even split puts
 * what the key's bits do not fill in the top digit (30 bits: 8, 8, 8 and 6), and from 3D
 * N = 1.7e7 or so (256 cells per axis) a bucket of its 64 would hold 1.5% of the elements,
 * 1.7 million keys at N = 1e8, far past NBS__RADIX_LOCAL_MAX, and the partition gave way to
 * the sort and the gather. There (or always, with `wide`: NBS_PARTITION=wide, for the tests)
 * the top digit takes as many bits as the keys allow, at most NBS__RADIX_BITS (there must be
 * as many keys as the square of its buckets), and the bits below it as many passes as
 * before, of the width that covers them (3D N = 1e8, 30 bits: 9 and 7, 7, 7, buckets of a
 * layer of cells, 212,000 keys; 2D, 31 bits: 9 and 8, 8, 8). Where the widths do not add
 * up, the last of those passes reaches into the top digit, which every key of a bucket
 * shares: it moves nothing there. By default the top digit is widened only for more than
 * 262,144 keys (the even split leaves it 3 bits at the fewest), and takes 9 bits; with `wide`
 * and few keys it may be narrower than the digits below it. */
typedef struct nbs__cs_pdigits {
  nbs__digits lo;
  int shift;
  size_t buckets;
  bool wide; /* the top digit widened */
} nbs__cs_pdigits;

static nbs__cs_pdigits nbs__cs_part_digits(int32_t n, int bits, bool wide) {
  const nbs__digits dg = nbs__radix_digits(bits);
  nbs__cs_pdigits pd = {dg, (dg.passes - 1) * dg.width, dg.buckets, false};
  if (dg.passes < 2) return pd;
  const int top = bits - pd.shift; /* the bits the even split leaves the top digit */
  int tw = NBS__RADIX_BITS;
  while (tw > top && (uint64_t)n < (uint64_t)1 << (2 * tw)) tw--;
  if (tw > top && (wide || ((uint64_t)n >> top) > NBS__RADIX_LOCAL_MAX)) {
    const int below = dg.passes - 1;
    pd.shift = bits - tw;
    pd.buckets = (size_t)1 << tw;
    /* at most the even split's width: shift is below its (passes - 1) * width */
    pd.lo.width = (pd.shift + below - 1) / below;
    pd.lo.buckets = (size_t)1 << pd.lo.width;
    pd.wide = true;
  }
  return pd;
}

/* Whether the partition of n keys by the digits pd can run: two digits or more, and at least
 * as many keys as the square of its buckets (nbs__radix_top_first's rule, for its top digit). */
static bool nbs__cs_part_top_first(int32_t n, const nbs__cs_pdigits *pd) {
  return pd->lo.passes >= 2 && (uint64_t)n >= (uint64_t)pd->buckets * pd->buckets;
}

/* Whether the partition's largest bucket, `most` of n keys, is sorted in the cache: at most
 * NBS__RADIX_LOCAL_MAX keys, or, where there are more elements than the buckets hold at that,
 * at most 1/128 of them. A larger bucket (3D N = 1e8: 212,000 keys, 10 MB with its
 * coordinates and scratch) is sorted in the last-level cache, not in the core's, and is still
 * faster than the sort and the gather, whose random reads of a 2.4 GB input also miss the TLB
 * (see nbs__cs_partition); a bucket of more than 1/128 of them (a clustered scene) would leave
 * a thread with most of the work, since each bucket is sorted by the thread it starts in. */
static bool nbs__cs_part_fits(int32_t n, uint32_t most) {
  return most <= NBS__RADIX_LOCAL_MAX || most <= (uint32_t)n / 128;
}

/* The second half of a stable counting pass of the digit at `shift` (dg's width) over n keys,
 * sk (and si) to dk (and di), once hist holds each thread's counts (thread t's at
 * t * buckets, of its contiguous part of the input): each thread scatters its part after the
 * parts of the threads before it, bucket by bucket, so that the pass stays stable and its
 * result is the same for any number of threads. A digit shared by every key moves nothing:
 * the pass is skipped and false returned. When `top` is not NULL, the pass is the sort's
 * first one, on its top digit (nbs__radix_top): top[b] receives where bucket b starts
 * (top[buckets] = n), and the pass is skipped, false returned, when a bucket holds more than
 * NBS__RADIX_LOCAL_MAX keys. */
static bool nbs__radix_place(const uint64_t *sk, const int32_t *si, uint64_t *dk, int32_t *di,
                             int32_t n, int shift, nbs__digits dg, uint32_t *hist, int threads,
                             uint32_t *top) {
  const size_t buckets = dg.buckets;
  const uint64_t d0 = (sk[0] >> shift) & (buckets - 1);
  uint64_t same = 0;
  for (int t = 0; t < threads; t++) same += hist[(size_t)t * buckets + d0];
  if (same == (uint64_t)n) return false;
  const uint32_t most = nbs__radix_offsets(hist, buckets, threads, top);
  if (top && most > NBS__RADIX_LOCAL_MAX) return false;
#if defined(_OPENMP)
#pragma omp parallel num_threads(threads) if (threads > 1)
#endif
  NBS__PARTS(t, threads) {
    nbs__radix_scatter(sk, si, dk, di, nbs__chunk(n, t, threads),
                       nbs__chunk(n, t + 1, threads), shift, dg, hist + (size_t)t * buckets);
  }
  return true;
}

/* One stable counting pass of the digit at `shift` (dg's width) over n keys: the counts of
 * each thread's part, then nbs__radix_place (without `top`). */
static bool nbs__radix_pass(const uint64_t *sk, const int32_t *si, uint64_t *dk, int32_t *di,
                            int32_t n, int shift, nbs__digits dg, uint32_t *hist, int threads) {
#if defined(_OPENMP)
#pragma omp parallel num_threads(threads) if (threads > 1)
#endif
  NBS__PARTS(t, threads) {
    nbs__radix_count_ways(sk, nbs__chunk(n, t, threads), nbs__chunk(n, t + 1, threads), shift,
                          dg, hist + (size_t)t * dg.buckets);
  }
  return nbs__radix_place(sk, si, dk, di, n, shift, dg, hist, threads, NULL);
}

/* One digit of `width` bits, for a single pass. */
static nbs__digits nbs__radix_digit(int width) {
  return (nbs__digits){1, width, (size_t)1 << width, width};
}

/* The first pass of the sort by the top digit first (nbs__radix), which also chooses where
 * the top digit starts: at dg's digits, all as wide, the top one whatever bits are left (2D
 * N = 1e6: 25 bits, 9 + 9 + 7), or, where bits / passes rounded down leaves a top digit no
 * wider than dg's, that many bits for each digit below it and the rest on top (9 + 8 + 8
 * there): more buckets for this pass, and smaller ones for the passes in cache. The words'
 * wider top digit is counted (the narrower one's counts are sums of its), and how often it
 * changes from one word to the next, on pairs NBS__RADIX_PAIRS apart: the wider digit is
 * taken where at least half the pairs change (not in cell order) and there are at least
 * NBS__RADIX_WIDE_MIN words (beyond the L2 cache). Why (2D, N = 1e6, timed inside the sort,
 * best of 30 detections): in random order this pass took 2.42 ns per element with 79 buckets
 * filled, 1.45 with 313, the buckets' passes the same (1.66, 1.65); in cell order its scatter
 * took 0.60 with 79 and 0.83 with 313, for reasons not found, and at N = 3e4 in random order
 * (in cache) the wider digit cost the preparation 0.25 ns (2.93 -> 3.18). The random-order
 * gain is this processor's (Zen 5): a test program scattering random digits into B streams,
 * caches cleared before each pass, took 0.9 ns per word at B = 16, 1.1 at 32, 2.3-2.8 at 48
 * to 79, 1.2 at 96 and 0.8-1.2 from 128 to 512. Returns false, having moved nothing, where
 * every word has the same top digit or a bucket holds more than NBS__RADIX_LOCAL_MAX; else
 * top[b] is where bucket b starts (top[buckets] = n), *td the top digit and *lo the digits
 * below it. */
#define NBS__RADIX_PAIRS 64
#define NBS__RADIX_WIDE_MIN ((int32_t)1 << 19)
static bool nbs__radix_top(const uint64_t *sk, uint64_t *dk, int32_t n, int low,
                           nbs__digits dg, uint32_t *hist, int threads, uint32_t *top,
                           nbs__digits *lo, nbs__digits *td) {
  *lo = dg;
  const int lw = dg.bits / dg.passes;
  const bool choice = n >= NBS__RADIX_WIDE_MIN && lw < dg.width &&
                      dg.bits - (dg.passes - 1) * lw <= dg.width;
  if (choice) lo->width = lw;
  *td = nbs__radix_digit(dg.bits - (dg.passes - 1) * lo->width);
  int shift = low + (dg.passes - 1) * lo->width;
  uint64_t changes[NBS__THREADS_MAX];
#if defined(_OPENMP)
#pragma omp parallel num_threads(threads) if (threads > 1)
#endif
  NBS__PARTS(t, threads) {
    const int32_t from = nbs__chunk(n, t, threads), to = nbs__chunk(n, t + 1, threads);
    nbs__radix_count_ways(sk, from, to, shift, *td, hist + (size_t)t * td->buckets);
    uint64_t ch = 0;
    if (choice) {
      const uint64_t mask = td->buckets - 1;
      for (int32_t k = from; k + 1 < to; k += NBS__RADIX_PAIRS) {
        ch += ((sk[k] ^ sk[k + 1]) >> shift & mask) != 0;
      }
    }
    changes[t] = ch;
  }
  uint64_t ch = 0;
  for (int t = 0; t < threads; t++) ch += changes[t];
  if (choice && ch < (uint64_t)n / NBS__RADIX_PAIRS / 2) {
    /* in cell order, or nearly: dg's digits; each thread's counts summed into the narrower
     * digit's, at its place for those */
    const nbs__digits nd = nbs__radix_digit(dg.bits - (dg.passes - 1) * dg.width);
    const int r = td->width - nd.width;
    for (int t = 0; t < threads; t++) {
      uint32_t sum[(size_t)1 << NBS__RADIX_BITS];
      const uint32_t *h = hist + (size_t)t * td->buckets;
      for (size_t b = 0; b < nd.buckets; b++) {
        uint32_t c = 0;
        for (size_t i = b << r; i < (b + 1) << r; i++) c += h[i];
        sum[b] = c;
      }
      memcpy(hist + (size_t)t * nd.buckets, sum, nd.buckets * sizeof *sum);
    }
    lo->width = dg.width;
    *td = nd;
    shift = low + (dg.passes - 1) * dg.width;
  }
  lo->buckets = (size_t)1 << lo->width;
  return nbs__radix_place(sk, NULL, dk, NULL, n, shift, *td, hist, threads, top);
}

/* The digits below the top one of the len packed words at a, which share their top digit,
 * by LSD passes on one thread, the result left at out (a itself, or the bucket's place in
 * the sort's other array). The passes go between out and `other`: a thread's own scratch,
 * or else the bucket's place in the array out is not in. h: a histogram. */
static void nbs__radix_local(uint64_t *a, uint64_t *out, uint64_t *other, int32_t len,
                             int low, nbs__digits dg, uint32_t *h) {
  uint64_t *cur = a;
  /* Two digits below the top one (three passes in all: keys of 19 to 27 bits, 3D and 2D
   * N = 1e6 and 1e7 among them): both counted in one pass over the bucket, a histogram being
   * the same whatever the bucket's order; the counts were half the time of these passes
   * (perf). Preparation, interleaved, medians of 4-8: 3D N = 1e6 8.39-8.53 -> 8.20-8.41 ns
   * per element, 1e7 9.55 -> 9.40, time steps 5.08 -> 4.92 (their sort of the moved
   * elements); 2D 1e6 7.34 -> 7.08. */
  uint32_t h2[2][(size_t)1 << NBS__RADIX_BITS];
  const bool both = dg.passes == 3;
  if (both) {
    /* each digit in two histograms that take the words in turn (see
     * nbs__radix_count_ways), summed into h2 */
    uint32_t h4[2][2][(size_t)1 << NBS__RADIX_BITS];
    const uint64_t mask = dg.buckets - 1;
    const int s1 = low + dg.width;
    for (int i = 0; i < 2; i++) {
      memset(h4[i][0], 0, dg.buckets * sizeof ***h4);
      memset(h4[i][1], 0, dg.buckets * sizeof ***h4);
    }
    int32_t k = 0;
    for (; k + 2 <= len; k += 2) {
      const uint64_t w0 = a[k], w1 = a[k + 1];
      h4[0][0][(w0 >> low) & mask]++;
      h4[0][1][(w0 >> s1) & mask]++;
      h4[1][0][(w1 >> low) & mask]++;
      h4[1][1][(w1 >> s1) & mask]++;
    }
    if (k < len) {
      h4[0][0][(a[k] >> low) & mask]++;
      h4[0][1][(a[k] >> s1) & mask]++;
    }
    for (size_t d = 0; d < dg.buckets; d++) {
      h2[0][d] = h4[0][0][d] + h4[1][0][d];
      h2[1][d] = h4[0][1][d] + h4[1][1][d];
    }
  }
  for (int p = 0; p + 1 < dg.passes; p++) {
    const int shift = low + p * dg.width;
    if (both) {
      h = h2[p];
    } else {
      nbs__radix_count(cur, 0, len, shift, dg, h);
    }
    if (h[(cur[0] >> shift) & (dg.buckets - 1)] == (uint32_t)len) continue; /* shared */
    uint32_t sum = 0;
    for (size_t d = 0; d < dg.buckets; d++) {
      const uint32_t c = h[d];
      h[d] = sum;
      sum += c;
    }
    uint64_t *dst = cur == out ? other : out;
    nbs__radix_scatter(cur, NULL, dst, NULL, 0, len, shift, dg, h);
    cur = dst;
  }
  if (cur != out) memcpy(out, cur, (size_t)len * sizeof *cur);
}

/* Bucket b of the top digit's pass (top[b] .. top[b + 1] of dk) sorted by the digits lo
 * below it into out_k, with the histogram h, through `mine` (a thread's scratch of the
 * largest bucket) or else the other array's place of the bucket. */
static void nbs__radix_bucket(uint64_t *sk, uint64_t *dk, uint64_t *out_k, const uint32_t *top,
                              size_t b, int low, nbs__digits lo, uint32_t *h, uint64_t *mine) {
  if (top[b + 1] == top[b]) return;
  const uint32_t s0 = top[b];
  uint64_t *other = mine ? mine : dk == out_k ? sk + s0 : dk + s0;
  nbs__radix_local(dk + s0, out_k + s0, other, (int32_t)(top[b + 1] - s0), low, lo, h);
}

/* Radix sort of (key, idx) on the digits dg of key from bit `low` on. The keys start in
 * (sk, si) and the sort moves them between it and (dk, di), both of n entries; the result
 * is left in (out_k, out_i), one of the two (copied there if the passes end in the other).
 * si and di are NULL for packed words (the element in the word's `low` bits, below the
 * key): then each pass moves 8 bytes instead of 12. hist holds `threads` histograms. The
 * result is the same for any number of threads, and the same in both of the ways below.
 *
 * Top digit first, where the keys are many. An LSD sort's every pass reads and writes all
 * the keys, at N = 1e6 and beyond from and to memory, not the caches; with two threads the
 * passes shared the machine's memory and did not scale (3D, N = 1e6, two threads: sort 5.9
 * ns per element against 5.0 with one, where the key pass, the gather and the sweep each
 * took half as long). So the first pass scatters the keys by their top digit, stably, into
 * buckets of a few thousand keys (every key of a bucket shares the top digit), and then
 * each bucket is sorted by the digits below it, LSD, on its own: a bucket fits the cache,
 * so those passes do not go to memory, and the threads share the buckets. The passes of a
 * bucket go between its place in the output and a scratch of each thread's own, the same
 * tens of kB for every bucket the thread sorts, which stays in its cache; the bucket's place
 * in the sort's other array, used where the threads' scratches would not fit the y (and z)
 * arrays, left dirty lines to be written back to memory (3D, N = 1e6, one thread: the
 * buckets' passes 3.5 -> 2.3 ns per element; detection, interleaved, min of 6: 32.8 ->
 * 32.0, 2D 19.5 -> 17.3, clustered 40.2 -> 39.4; two threads 18.6 either way: their
 * buckets' passes took 2.7, not faster than one thread's, for reasons not found: not the
 * memory's bandwidth, nor lines moving between the cores). A stable sort by the top digit
 * followed by a stable sort of each bucket by the rest is the stable sort by the whole key:
 * the same result as the LSD sort. It is taken when there are at least as many keys as the
 * square of the buckets (the buckets' histograms then cost at most one step per key and
 * pass), the keys are packed words (unpacked keys come with elements spread over a domain
 * too wide for them, most of whose keys then share a top digit) and no bucket holds more
 * than NBS__RADIX_LOCAL_MAX keys (a clustered scene can put most keys in a few buckets: they
 * would not fit a cache, nor share out among the threads); otherwise the plain LSD sort
 * runs, a pass per digit.
 *
 * A digit shared by every key moves nothing: its pass is skipped. Tried and left out, both
 * slower: counting every digit in the key pass instead of a pass per digit (3D, N = 1e6,
 * key pass 1.2 -> 3.1 ns per element, sort 3.2 -> 2.8); and, to save passes where the
 * domain is huge, sorting the row bits only, then each row by insertion, or by a small LSD
 * when it is long (2D huge domain, N = 1e6, 23.6 -> 25.5 ns per element: the insertion's
 * branches cost more than the two passes); and the top digit always 9 bits wide, the bits
 * below it split evenly (3D N = 1e6, 24 bits: 512 buckets of about 2,000 keys, in L1,
 * instead of 256 of 3,900; 2D 25 bits: 512 instead of 128 buckets, whose 7,800 keys do not
 * fit L1): no faster (interleaved, min of 6, 33.2 / 33.3 and 19.6 / 19.5). On Zen 5 the
 * top digit is the widest where the input is not in cell order (nbs__radix_top). */
static void nbs__radix(uint64_t *sk, int32_t *si, uint64_t *dk, int32_t *di, uint64_t *out_k,
                       int32_t *out_i, int32_t n, int low, nbs__digits dg, uint32_t *hist,
                       int threads, bool first, uint64_t *scratch, size_t scratch_words) {
  (void)first; /* read with OpenMP only */
  if (!si && nbs__radix_top_first(n, dg)) {
    uint32_t top[((size_t)1 << NBS__RADIX_BITS) + 1];
    nbs__digits lo, td; /* the digits below the top one, and the top one */
    if (nbs__radix_top(sk, dk, n, low, dg, hist, threads, top, &lo, &td)) {
      /* a scratch of the largest bucket for each thread, where there is room for it */
      uint32_t most = 0;
      for (size_t b = 0; b < td.buckets; b++) {
        if (top[b + 1] - top[b] > most) most = top[b + 1] - top[b];
      }
      if ((size_t)threads * most > scratch_words) scratch = NULL;
      /* each thread sorts the buckets that start in its part, then takes others' from the
       * back (nbs__share); its histogram and scratch are its own in the team */
#if defined(_OPENMP)
      if (threads > 1) {
        uint32_t cut[NBS__THREADS_MAX + 1];
        for (int t = 0, b = 0; t <= threads; t++) {
          const uint32_t from = t == threads ? (uint32_t)n : (uint32_t)nbs__chunk(n, t, threads);
          while ((size_t)b < td.buckets && top[b] < from) b++;
          cut[t] = (uint32_t)b;
        }
        nbs__share sh;
        nbs__share_init(&sh, threads, cut, first);
#pragma omp parallel num_threads(threads)
        {
          const int me = nbs__thread_num();
          uint32_t *h = hist + (size_t)me * lo.buckets;
          uint64_t *mine = scratch ? scratch + (size_t)me * most : NULL;
          uint32_t a, b;
          bool taken;
          NBS__PARTS(t, threads) {
            for (int stage = 0; nbs__share_next(&sh, t, &stage, 1, false, &a, &b, &taken);) {
              nbs__radix_bucket(sk, dk, out_k, top, a, low, lo, h, mine);
            }
          }
        }
        return;
      }
#endif
      for (size_t b = 0; b < td.buckets; b++) {
        nbs__radix_bucket(sk, dk, out_k, top, b, low, lo, hist, scratch);
      }
      return;
    }
    /* nothing moved: one bucket holds every key, or one bucket too many */
  }
  for (int p = 0; p < dg.passes; p++) {
    if (!nbs__radix_pass(sk, si, dk, di, n, low + p * dg.width, dg, hist, threads)) {
      continue;
    }
    uint64_t *tswap = sk;
    sk = dk;
    dk = tswap;
    int32_t *u = si;
    si = di;
    di = u;
  }
  if (sk != out_k) {
    memcpy(out_k, sk, (size_t)n * sizeof *sk);
    if (si) memcpy(out_i, si, (size_t)n * sizeof *si);
  }
}

/* Where a range of elements puts its pairs: the run's own sink (the first thread, or the
 * only one), or a thread's own list in the context, appended to the run's after the sweep
 * in thread order, so that the output does not depend on the number of threads. */
typedef struct nbs__sink {
  nbs_context *ctx;
  nbs__run *run; /* the run's sink (buf/count/cap mirror run->buf/count/cap), or NULL */
  int thread;    /* otherwise: the context's list of this thread (>= 1) */
  nbs_pair *buf;
  size_t count, cap;
  uint64_t candidates, emitted;
  nbs_status status;
} nbs__sink;

static nbs_status nbs__sink_room(nbs__sink *s, size_t need, bool *room) {
  *room = true;
  if (!s->run) {
    return nbs__thread_pairs_grow(s->ctx, s->thread, s->count + need, &s->buf, &s->cap);
  }
  nbs__run *run = s->run;
  run->count = s->count;
  nbs_status st = nbs__room(run, need, room);
  s->buf = run->buf;
  s->cap = run->cap;
  s->count = run->count;
  return st;
}

/* One pair, when a range found no room (only in the run's sink: callbacks and max_pairs
 * keep the sweep on one thread): at max_pairs, nbs__flush reports NBS_ERR_PAIRS. */
static nbs_status nbs__sink_one(nbs__sink *s, nbs_pair one) {
  bool room;
  NBS__TRY(nbs__sink_room(s, 1, &room));
  if (!room) {
    s->run->count = s->count;
    return nbs__flush(s->run);
  }
  s->buf[s->count++] = one;
  s->emitted++;
  return NBS_OK;
}

/* ---- the block kernels --------------------------------------------------------------
 * The sweep tests a block of up to NBS__CS_LANES consecutive elements of a row (the "i"
 * elements, one per lane) against each element q of a few ranges (the "j" elements): one q
 * against all lanes at once. The ranges come in key order, the last one ending with the
 * block: a q before the block meets every lane, and when the last range holds the block,
 * the block's own 28 pairs follow by rotation (lane l against lane l + k mod 8). A kernel
 * writes the pairs that pass (all of them in candidate mode) in the order (q, lane), then
 * (k, l), whatever the instruction set, so every kernel gives the same bytes. The test is
 * the contract's expression, term for term as in nbs__touch, lane by lane, without fused
 * multiply-adds, so that every algorithm decides every tie the same way. A kernel may write
 * up to NBS__CS_LANES pairs past the ones it keeps; the caller makes room for them. */
#define NBS__CS_LANES 8
/* The most ranges a block meets: four neighbouring rows and its own. */
#define NBS__CS_RANGES 5
/* The most range elements one kernel call meets (nbs__cs_offer slices longer ranges). */
#define NBS__CS_SLICE 256

struct nbs__cs_ranges {
  int count;
  int32_t q0[NBS__CS_RANGES], q1[NBS__CS_RANGES];
  /* places >= 0: the places of the ranges before the block, in order (the last range up to
   * the block only), listed by the AVX-512 sweep as it found the ranges (nbs__cs_list), or
   * by nbs__cs_offer_slices for a slice (3D rows swept element by element list theirs
   * after finding them all); the AVX-512 kernel's steps are then one loop over them. -1: not
   * listed (the other kernels' sweeps, and 2D rows swept element by element, never in 3D);
   * the kernel loops over each range. */
  int32_t places;
  const int32_t *list; /* where places >= 0 */
};
/* Sixteen places, as GCC's vector extension (no target needed: only the AVX-512 sweep
 * lists, and there it is one add and one store). Unsigned lanes (places are below 2^31, so
 * the same values): with signed lanes, GCC 12's check of each lane's add for signed
 * overflow, in the sanitizer build (-fsanitize=address,undefined -fno-sanitize-recover=all,
 * -O2), wrote wrong places to the list, and cellsort with the AVX-512 kernel found wrong
 * contacts there, 14 of the sanitizer suite's 25 tests failing (CI; the same build with
 * -fno-sanitize=signed-integer-overflow, or with unsigned lanes, passes). Unsigned adds are
 * not checked; in the Release build the AVX-512 sweep's code is the same, instruction for
 * instruction. */
typedef uint32_t nbs__cs_v16i __attribute__((vector_size(64)));
/* Appends the places [q0, q1) to the list of t (q1 >= q0; returns t + q1 - q0), written
 * sixteen at a time: up to 15 past the last, where the list has room for them. A list of
 * more than NBS__CS_SLICE places is not used (nbs__cs_offer slices its ranges), so nothing
 * is written past that. */
static inline __attribute__((always_inline)) int32_t nbs__cs_list(int32_t *list, int32_t t,
                                                                  int32_t q0, int32_t q1) {
  if (__builtin_expect(t <= NBS__CS_SLICE, 1)) {
    const nbs__cs_v16i iota = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15};
    nbs__cs_v16i v = iota + (uint32_t)q0;
    __builtin_memcpy(list + t, &v, sizeof v);
    for (int32_t k = 16; __builtin_expect(k < q1 - q0, 0) && t + k <= NBS__CS_SLICE; k += 16) {
      v += 16u;
      __builtin_memcpy(list + t + k, &v, sizeof v);
    }
  }
  return t + (q1 - q0);
}

/* The generic kernel: plain C, one lane after another. */
static inline __attribute__((always_inline)) size_t
nbs__cs_block_body(const nbs__cs *c, int dim, bool radii, bool contacts, int32_t c0, int lanes,
                   const nbs__cs_ranges *rg, nbs_pair *out) {
  const double *X = c->xs, *Y = c->ys, *Z = c->zs, *R = c->rs;
  const int32_t *ids = c->ids;
  const size_t istep = (size_t)c->istep;
  const int32_t imask = (int32_t)c->imask;
  const double d2 = c->d2;
  size_t m = 0;
  /* one pair: lane l against the element at place q */
#define NBS__CS_PAIR(l, q)                                                                    \
  do {                                                                                        \
    const int32_t p = c0 + (l);                                                               \
    double dx = X[p] - X[q], dy = Y[p] - Y[q];                                                \
    double d = dx * dx + dy * dy;                                                             \
    if (dim == 3) {                                                                           \
      double dz = Z[p] - Z[q];                                                                \
      d += dz * dz;                                                                           \
    }                                                                                         \
    double lim = d2;                                                                          \
    if (radii) {                                                                              \
      double rr = R[p] + R[q];                                                                \
      lim = rr * rr;                                                                          \
    }                                                                                         \
    const int32_t ip = ids[(size_t)p * istep] & imask, iq = ids[(size_t)(q)*istep] & imask;   \
    nbs_pair pr;                                                                              \
    pr.i = ip < iq ? ip : iq;                                                                 \
    pr.j = ip < iq ? iq : ip;                                                                 \
    out[m] = pr;                                                                              \
    m += (size_t)(!contacts || d <= lim);                                                     \
  } while (0)
  const int last = rg->count - 1;
  for (int r = 0; r < rg->count; r++) {
    const int32_t q1 = r == last && rg->q1[r] > c0 ? c0 : rg->q1[r];
    for (int32_t q = rg->q0[r]; q < q1; q++) {
      for (int l = 0; l < lanes; l++) NBS__CS_PAIR(l, q);
    }
  }
  /* the block's own pairs, when the last range holds the block (nbs__cs_offer_slices
   * offers it in slices, and the block's own pairs with the last), by rotation: lane l
   * against lane (l + k) mod 8, k = 1 .. 4 */
  const int own = rg->q1[last] > c0 ? NBS__CS_LANES / 2 : 0;
  for (int k = 1; k <= own; k++) {
    for (int l = 0; l < (k == NBS__CS_LANES / 2 ? k : NBS__CS_LANES); l++) {
      const int l2 = (l + k) % NBS__CS_LANES;
      if (l < lanes && l2 < lanes) NBS__CS_PAIR(l, c0 + l2);
    }
  }
#undef NBS__CS_PAIR
  return m;
}

#define NBS__CS_DISPATCH(body, c, ...)                                                         \
  (c->dim == 3 ? (c->rs ? (c->contacts ? body(c, 3, true, true, __VA_ARGS__)                   \
                                       : body(c, 3, true, false, __VA_ARGS__))                 \
                        : (c->contacts ? body(c, 3, false, true, __VA_ARGS__)                  \
                                       : body(c, 3, false, false, __VA_ARGS__)))               \
               : (c->rs ? (c->contacts ? body(c, 2, true, true, __VA_ARGS__)                   \
                                       : body(c, 2, true, false, __VA_ARGS__))                 \
                        : (c->contacts ? body(c, 2, false, true, __VA_ARGS__)                  \
                                       : body(c, 2, false, false, __VA_ARGS__))))

static size_t nbs__cs_block_generic(const nbs__cs *c, int32_t c0, int lanes,
                                    const nbs__cs_ranges *rg, nbs_pair *out) {
  return NBS__CS_DISPATCH(nbs__cs_block_body, c, c0, lanes, rg, out);
}

#if NBS__CS_AVX512
/* The AVX-512 kernel: the block's lanes in one register per coordinate, each q broadcast;
 * the lanes that pass are packed by a compress and stored at once, so the kernel has no
 * branch but the loops'. Chosen at run time when the processor has AVX-512 (F, VL, DQ).
 * Measured on the benchmark machine (AMD EPYC, 3D, N = 1e6), the kernel is about 15 of the
 * sweep's 20 ns per element, at about 5 steps per element; dropping the z term (3 of its 12
 * floating-point operations) saved 3 ns of them. Tried and left out, each slower or no
 * faster: blocks of 4 lanes in 256-bit registers (22 lane tests per element instead of 39,
 * but 25 ns instead of 20), two q per loop step, one kernel call per 16 blocks, and the
 * ranges' positions gathered into one list so that one loop visits them all (again, built
 * without a branch by 16-wide stores: 34.8 / 34.8). Also: the pairs built only for the q
 * that hit (each step stores q and its mask; the hits are expanded after the ranges): the
 * same time (33.2 / 33.2), and the compress stored to memory directly: slower (35.1
 * against 33.4); tried again on Zen 5 after the 32-byte store below, the pairs built only for
 * the q that hit were slower (search 14.4-14.8 -> 15.0-15.3 ns per element, 3D N =
 * 1e6). Where the kernel's time goes, measured by leaving parts out (3D, N = 1e6,
 * detection 34 ns): the steps over the ranges about 12 ns, of which the loops alone (one
 * load per q) about 5.5, the distances on top of them under 1, the pairs' output about 6.
 * Later (interleaved, min of 6, detection in ns per element, 3D N = 1e6 then 2D): leaving
 * q's element out of the pairs (a wrong output, to measure it) saved 1.2 (33.7 -> 31.3);
 * each correct way to save it was slower: the pair left unordered in the steps (one blend
 * for the min and max) and ordered by a vector pass after the ranges, 32.8 -> 33.5 and the
 * same in 2D; q's place in the pair instead of its element, the places then turned into
 * elements after the ranges, by a scalar loop 33.7 -> 35.1 (2D 19.9 -> 20.7), by gathers
 * 33.6 -> 35.1 (19.1 -> 20.7). The sums moved from the adders to the multipliers as
 * fma(a, 1, b), which rounds as a + b does: 33.4 -> 34.0, and the z difference with them
 * 34.8: the adders are not what bounds the steps. The kernel called directly from the sweep
 * compiled for it (a constant, inlined, not a pointer): 33.2 / 33.4; again after the
 * ranges were listed by the sweep (0c29dd2; one form, 3D without radii, inlined into the
 * AVX-512 sweep; interleaved, medians of 5, search ns per element): 11.94 -> 11.61, but the
 * huge domain 16.75 -> 17.26 and sparse 12.29 -> 12.34, for a copy of the sweep per form. */
/* Where the SIMD kernels read q's element, a constant of each of their copies: the idx
 * array (unpacked keys), the low half of a packed word that is the element alone (imask
 * all ones), or one whose low bits hold the element under the key's (ANDed with imask). */
enum { NBS__CS_IDX, NBS__CS_WHOLE, NBS__CS_MASKED };
/* A SIMD kernel's copies: NBS__CS_VARIANTS(pre, attributes, body) makes one function of the
 * body for each form, dimension, radii or not, and contacts or candidates, pre_FORM_dim_
 * radii_contacts, and their table pre_table[form][3D][radii][contacts]; nbs__cs_kernel_of
 * chooses c's once per detection (c->block). Where one function held all 24 copies and
 * chose one at every call, the call saved the choice's branches and half its register
 * saves (3D, N = 1e6, interleaved, medians of 5-8, search in ns per element, the same
 * bytes: 11.83 -> 11.62 and 11.98 -> 11.71; 1e7 12.34 -> 12.12; 1e4 10.52 -> 10.33; sparse
 * 12.09 -> 11.92; clustered 12.05 -> 11.98; huge 16.83 -> 16.97; 2D 4.83 -> 4.75; the
 * AVX2 kernel's, NBS_SIMD=avx2, mixed: 3D 1e6 19.44 -> 19.85 and 19.63 -> 19.96, 1e4
 * 15.18 -> 14.79, 2D 7.23 -> 7.14). */
#define NBS__CS_VARIANT(pre, attr, body, form, dim, radii, contacts)                           \
  attr static size_t pre##_##form##_##dim##_##radii##_##contacts(                             \
      const nbs__cs *c, int32_t c0, int lanes, const nbs__cs_ranges *rg, nbs_pair *out) {     \
    return body(c, dim, radii, contacts, NBS__CS_##form, c0, lanes, rg, out);                 \
  }
#define NBS__CS_VARIANTS_OF(pre, attr, body, form)                                             \
  NBS__CS_VARIANT(pre, attr, body, form, 2, 0, 0)                                              \
  NBS__CS_VARIANT(pre, attr, body, form, 2, 0, 1)                                              \
  NBS__CS_VARIANT(pre, attr, body, form, 2, 1, 0)                                              \
  NBS__CS_VARIANT(pre, attr, body, form, 2, 1, 1)                                              \
  NBS__CS_VARIANT(pre, attr, body, form, 3, 0, 0)                                              \
  NBS__CS_VARIANT(pre, attr, body, form, 3, 0, 1)                                              \
  NBS__CS_VARIANT(pre, attr, body, form, 3, 1, 0)                                              \
  NBS__CS_VARIANT(pre, attr, body, form, 3, 1, 1)
#define NBS__CS_VARIANTS_ROW(pre, form)                                                        \
  {{{pre##_##form##_2_0_0, pre##_##form##_2_0_1}, {pre##_##form##_2_1_0, pre##_##form##_2_1_1}}, \
   {{pre##_##form##_3_0_0, pre##_##form##_3_0_1}, {pre##_##form##_3_1_0, pre##_##form##_3_1_1}}}
#define NBS__CS_VARIANTS(pre, attr, body)                                                      \
  NBS__CS_VARIANTS_OF(pre, attr, body, IDX)                                                    \
  NBS__CS_VARIANTS_OF(pre, attr, body, WHOLE)                                                  \
  NBS__CS_VARIANTS_OF(pre, attr, body, MASKED)                                                 \
  static const nbs__cs_block_fn pre##_table[3][2][2][2] = {                                    \
      NBS__CS_VARIANTS_ROW(pre, IDX), NBS__CS_VARIANTS_ROW(pre, WHOLE),                        \
      NBS__CS_VARIANTS_ROW(pre, MASKED)};
static nbs__cs_block_fn nbs__cs_kernel_of(const nbs__cs_block_fn table[3][2][2][2],
                                          const nbs__cs *c) {
  const int form = c->istep == 1             ? NBS__CS_IDX
                   : c->imask == UINT32_MAX ? NBS__CS_WHOLE
                                            : NBS__CS_MASKED;
  return table[form][c->dim == 3][c->rs != NULL][c->contacts];
}
static inline __attribute__((always_inline)) NBS__CS_AVX512_TARGET size_t
nbs__cs_block512_body(const nbs__cs *c, int dim, bool radii, bool contacts, int form,
                      int32_t c0, int lanes, const nbs__cs_ranges *rg, nbs_pair *out) {
  const double *X = c->xs, *Y = c->ys, *Z = c->zs, *R = c->rs;
  const int32_t *ids = c->ids;
  const bool whole = form != NBS__CS_MASKED;
  const size_t istep = form == NBS__CS_IDX ? 1 : 2;
  const int32_t imask = (int32_t)c->imask;
  const __mmask8 im = (__mmask8)((1u << lanes) - 1);
  /* Lanes past the block hold NaN in x: their distance compares false, so the steps over
   * the ranges need no mask register (GCC 12 reloaded it from the stack at every step). With
   * q's element number ANDed from a broadcast load (one instruction where a scalar load, an
   * AND and a broadcast were three), 20 instructions a step instead of 23: 3D, N = 1e6,
   * interleaved with the build before, min of 8: 33.8 -> 32.8 ns per element (the load alone
   * was within noise); 2D the same within noise. Then two more: q's element read at
   * q * istep with istep a constant of the kernel's copy (form), not a pointer moved by it
   * at every step, and the pairs' place a pointer moved by each step's count, whose store
   * then needs no address of its own (3D, N = 1e6, interleaved with 585a76a, medians of 8:
   * search 14.02 -> 13.39 and 14.34 -> 13.84 ns per element; 1e7 14.53 -> 13.82; 1e4 with
   * four decoys 14.97 -> 14.21; 2D 5.76 -> 5.71 and, the pointer alone, 5.52 -> 5.39). */
  const __m512d PX = _mm512_mask_loadu_pd(_mm512_set1_pd(__builtin_nan("")), im, X + c0);
  const __m512d PY = _mm512_maskz_loadu_pd(im, Y + c0);
  const __m512d PZ = dim == 3 ? _mm512_maskz_loadu_pd(im, Z + c0) : _mm512_setzero_pd();
  const __m512d PR = radii ? _mm512_maskz_loadu_pd(im, R + c0) : _mm512_setzero_pd();
  const __m512d LIM = _mm512_set1_pd(c->d2);
  /* each lane's element twice, {ip, ip}: a pair {min, max} is then one min of all 16 int32
   * and one max of the odd ones, already in nbs_pair's layout */
  const __m512i IP2 = _mm512_and_si512(_mm512_set1_epi32(imask),
      istep == 1 ? _mm512_permutexvar_epi32(
                       _mm512_set_epi32(7, 7, 6, 6, 5, 5, 4, 4, 3, 3, 2, 2, 1, 1, 0, 0),
                       _mm512_castsi256_si512(_mm256_maskz_loadu_epi32(im, ids + c0)))
                 : _mm512_permutexvar_epi32( /* the low halves of 8 packed words */
                       _mm512_set_epi32(14, 14, 12, 12, 10, 10, 8, 8, 6, 6, 4, 4, 2, 2, 0, 0),
                       _mm512_maskz_loadu_epi64(im, ids + 2 * (size_t)c0)));
  const __m512i IMASK = _mm512_set1_epi32(imask);
  nbs_pair *o = out; /* where the next pairs go */
  /* one q against the block's lanes */
#define NBS__CS_STEP512(q)                                                                \
  do {                                                                                        \
    __m512d dx = _mm512_sub_pd(PX, _mm512_set1_pd(X[q]));                                     \
    __m512d dy = _mm512_sub_pd(PY, _mm512_set1_pd(Y[q]));                                     \
    __m512d d = _mm512_add_pd(_mm512_mul_pd(dx, dx), _mm512_mul_pd(dy, dy));                  \
    if (dim == 3) {                                                                           \
      __m512d dz = _mm512_sub_pd(PZ, _mm512_set1_pd(Z[q]));                                   \
      d = _mm512_add_pd(d, _mm512_mul_pd(dz, dz));                                            \
    }                                                                                         \
    __m512d lim = LIM;                                                                        \
    if (radii) {                                                                              \
      __m512d rr = _mm512_add_pd(PR, _mm512_set1_pd(R[q]));                                   \
      lim = _mm512_mul_pd(rr, rr);                                                            \
    }                                                                                         \
    const __mmask8 hit = contacts ? _mm512_cmp_pd_mask(d, lim, _CMP_LE_OQ) : im;              \
    const __m512i IQ =                                                                        \
        whole ? _mm512_set1_epi32(ids[(size_t)(q)*istep])                                     \
              : _mm512_and_si512(                                                             \
                    _mm512_broadcastd_epi32(_mm_cvtsi32_si128(ids[(size_t)(q)*istep])), IMASK); \
    const __m512i pr = _mm512_mask_max_epi32(_mm512_min_epi32(IP2, IQ), 0xAAAA, IP2, IQ);     \
    const __m512i found = _mm512_maskz_compress_epi64(hit, pr);                               \
    const unsigned nfound = (unsigned)__builtin_popcount(hit);                                \
    if (__builtin_expect(nfound > 4, 0)) {                                                    \
      _mm512_storeu_si512((void *)o, found);                                                  \
    } else {                                                                                  \
      _mm256_storeu_si256((__m256i *)(void *)o, _mm512_castsi512_si256(found));               \
    }                                                                                         \
    o += nfound;                                                                              \
  } while (0)
  /* The ranges before the block meet every lane (the last range ends with the block, see
   * nbs__cs_offer). A step stores its pairs, most often none or one, in 32 bytes unless it
   * found more than 4 (a branch almost never taken in contact mode, and always in candidate
   * mode, where every lane passes): a 64-byte store at every step, which crosses a cache
   * line 7 times in 8, cost 2% of the sweep (interleaved, ns per element, one thread,
   * random order; min of 6: 3D N = 1e6 search 15.10 -> 14.76, 2D 5.54 / 5.56, where the
   * kernel is a smaller part; min of 3: 1e7 15.37 -> 14.92, time steps of 1e-3 at 1e6 20.62
   * -> 20.06 in all; the same bytes). 16 bytes unless more than 2 was slower (3D 1e6
   * search 15.1-15.8).
   * The loop over each range ends in an exit the branch predictor can miss, five per block
   * in 3D; a test program of these steps (a block against five ranges of 6-14 places each)
   * took 7.5-7.8 cycles a step, 5.9-6.1 with ranges of 8 places each and 5.3-5.5 with one
   * range of 43. So the ranges' places are written to a list, and the steps are one loop
   * over it: one exit per block instead of five (3D) or two (2D), for a load more a step and
   * the list's stores. First (3ace1a4, 3D only) the kernel wrote the list, sixteen places
   * at a time, before its steps (measured on dc90213, 3D, interleaved with the loops per
   * range, medians of 2-6 processes, search in ns per element, the same bytes): N = 1e6
   * 14.06 -> 13.39 and 14.53 -> 13.71; 1e7 14.54 -> 13.71; 1e5 14.02 -> 13.07; time steps
   * of 1e-3 14.43 -> 13.59; sparse (fraction 0.005) 19.71 -> 17.61; clustered 14.18 ->
   * 13.44; huge 17.31 -> 17.42; 1e4 with four decoys 14.66 -> 13.22, but 1e4 repeated alone
   * 10.74 -> 12.43 (there the branch predictor has learned every exit of the one scene: see
   * nbs_bench --decoys); in 2D it cost more than it saved (1e6 5.70 -> 6.65). Now the
   * AVX-512 sweep writes the list (nbs__cs_list) as it finds each range, where its stores
   * sit among the window searches, which wait on loads, and the kernel only reads it
   * (interleaved with 313d687, medians of 3-6 processes, search in ns per element, the same
   * bytes): 3D N = 1e6 13.04 -> 12.53 and 12.90 -> 12.14; 1e7 13.40 -> 12.69; 1e4 12.34 ->
   * 11.22, with four decoys 13.01 -> 12.06; sparse 13.20 -> 12.74; clustered 12.89 -> 12.49;
   * time steps of 1e-3 13.21 -> 12.80; but huge 16.47 -> 16.81 and 16.44 -> 17.12 (its
   * blocks seldom meet anything and the list is next to never written: the sweep's code is
   * laid out otherwise). 2D: 1e6 5.69 -> 5.07; 1e7 5.51 -> 4.97; 1e4 3.93 -> 3.83; sparse
   * 5.68 -> 5.27; clustered 5.73 -> 5.20; huge 7.03 -> 7.56.
   * The list written after all the ranges were found, just before the kernel, gained less
   * (3D 1e6 12.64 -> 12.45), and written after the neighbouring rows' windows, before the
   * own row's, about half (12.83 -> 12.50), but nothing lost in huge (16.71 -> 16.86);
   * against it, written range by range: 3D 1e6 12.41 -> 11.98, sparse 12.71 -> 12.41, huge
   * 16.12 -> 16.73. The AVX2 kernel, whose step is two halves, keeps a loop per range: with the list
   * (NBS_SIMD=avx2, interleaved, medians of 4) its search took 18.98 -> 18.77 at 3D 1e6 but
   * 14.75 -> 16.14 at 1e4 and 17.20 -> 17.76 in huge, and 2D 7.14 -> 9.14 (and with
   * the list written by the kernel, mixed: 3D 1e6 20.71 -> 21.52, 1e4 with decoys 20.65 ->
   * 19.49).
   * What the exits cost, measured on 585a76a and ff1b1cf by running each of the
   * neighbouring rows' ranges for a fixed number of places (a wrong output, for the timing
   * only; the ranges that are not empty hold 8.65 places on average): 3D N = 1e6, 10 places
   * each, search 14.4-14.8 -> 13.0-13.3 ns per element; 9 places (more steps than the true
   * lengths), with counters in the loop, 14.7-14.8 -> 12.5-13.0; 8 places 11.8-12.0. So the
   * exits cost about 2 ns, some 16 cycles a block (an earlier such test, recorded in
   * bench/README, found no difference: this one does).
   * Other ways around them cost more: a fixed number of steps per range wastes a step for
   * every place it runs past a window (lengths vary by about 3 places), the ranges
   * interleaved two or four at a time likewise (by the longest's excess). Tried and left
   * out: two ranges in one loop, q moved from the first range to the second by a select,
   * not a branch (three exits per block instead of five; the same bytes): search 14.6-15.5
   * -> 15.3-15.7, interleaved, four runs each: four instructions more a step. Also tried
   * and left out: half blocks. Lanes 0-3 and 4-7 each span about 3
   * diameters in x, and of a neighbouring row's window (about 9 places) a q within one edge
   * of one half only is about 4 places either side; so each window was split by two
   * vector counts of its keys, and a step tested one q against lanes 0-3 and another
   * against lanes 4-7 (the q broadcast to each half and the halves joined by an insert),
   * the longer side's rest one q a step: 3D N = 1e6 search 15.7-15.9 -> 23.5-24.1 ns per
   * element (a first version, which also found some pairs twice): three loops per window
   * where there was one, and four more instructions a step. */
  const int last = rg->count - 1;
  /* (in 3D every caller lists: one copy of the steps, not two; a second, for ranges not
   * listed, made the 3D search 0.2-0.9 ns per element slower) */
  if (dim == 3 || rg->places >= 0) {
    /* in locals: read through rg, both were loaded again at every step (the pairs' stores
     * might have changed them, as far as the compiler knows) */
    const int32_t *list = rg->list, places = rg->places;
    for (int32_t k = 0; k < places; k++) {
      const int32_t q = list[k];
      NBS__CS_STEP512(q);
    }
  } else {
    for (int r = 0; r < rg->count; r++) {
      const int32_t q1 = r == last && rg->q1[r] > c0 ? c0 : rg->q1[r];
      for (int32_t q = rg->q0[r]; q < q1; q++) NBS__CS_STEP512(q);
    }
  }
#undef NBS__CS_STEP512
  /* The block's own pairs, by rotation: lane l against lane (l + k) mod 8 for k = 1, 2, 3
   * (every pair whose lanes are 1, 2, 3, 5, 6 or 7 apart, once) and k = 4 for l < 4: 28
   * pairs in 4 steps, where one element of the block against the lanes before it took 7
   * (3D, N = 1e6: sweep 20.2 -> 19.4 ns per element; 2D 6.7 -> 6.6, where the kernel is
   * the smaller part of the sweep). In the order of the generic kernel. The 32-byte store
   * of the steps above was slower here (3D, N = 1e6, search 14.6 -> 15.4 ns per element,
   * interleaved, min of 4), presumably because a rotation, among elements a few diameters
   * apart, finds more than 4 pairs too often for the branch. */
  const __m512i iota = _mm512_set_epi64(7, 6, 5, 4, 3, 2, 1, 0);
  const int own = rg->q1[last] > c0 ? NBS__CS_LANES / 2 : 0;
  for (int k = 1; k <= own; k++) {
    /* lane l is kept when lane (l + k) mod 8 is in the block too */
    unsigned vm = im & ((unsigned)im >> k | (unsigned)im << (NBS__CS_LANES - k));
    if (k == NBS__CS_LANES / 2) vm &= 0x0F;
    if (!vm) break; /* fewer lanes than k + 1: none for larger k either */
    const __m512i rot = _mm512_and_si512(_mm512_add_epi64(iota, _mm512_set1_epi64(k)),
                                         _mm512_set1_epi64(NBS__CS_LANES - 1));
    __m512d dx = _mm512_sub_pd(PX, _mm512_permutexvar_pd(rot, PX));
    __m512d dy = _mm512_sub_pd(PY, _mm512_permutexvar_pd(rot, PY));
    __m512d d = _mm512_add_pd(_mm512_mul_pd(dx, dx), _mm512_mul_pd(dy, dy));
    if (dim == 3) {
      __m512d dz = _mm512_sub_pd(PZ, _mm512_permutexvar_pd(rot, PZ));
      d = _mm512_add_pd(d, _mm512_mul_pd(dz, dz));
    }
    __m512d lim = LIM;
    if (radii) {
      __m512d rr = _mm512_add_pd(PR, _mm512_permutexvar_pd(rot, PR));
      lim = _mm512_mul_pd(rr, rr);
    }
    const __mmask8 keep = (__mmask8)vm;
    const __mmask8 hit = contacts ? _mm512_mask_cmp_pd_mask(keep, d, lim, _CMP_LE_OQ) : keep;
    const __m512i IQ2 = _mm512_permutexvar_epi64(rot, IP2);
    const __m512i pr = _mm512_mask_max_epi32(_mm512_min_epi32(IP2, IQ2), 0xAAAA, IP2, IQ2);
    _mm512_storeu_si512((void *)o, _mm512_maskz_compress_epi64(hit, pr));
    o += (unsigned)__builtin_popcount(hit);
  }
  return (size_t)(o - out);
}

NBS__CS_VARIANTS(nbs__cs_k512, NBS__CS_AVX512_TARGET NBS__CS_PLACED, nbs__cs_block512_body)

/* The AVX2 kernel, for processors without AVX-512: the block's 8 lanes in two registers of
 * 4 per coordinate, the same steps as the AVX-512 kernel, and the pairs that pass packed
 * by a permutation looked up from their 4-bit mask (AVX2 has no compress). Same pairs in
 * the same order as the other kernels: for each q, lanes 0-3 then 4-7; then the rotations,
 * whose partner lanes are read from the block stored twice over (lane l + k at l + k).
 * (The AVX-512 kernel's AND after a broadcast load of q's number was slower here: 3D,
 * N = 1e6, NBS_SIMD=avx2, 41.1 -> 42.1 ns per element.) The three forms of q's element and
 * the pairs' place a pointer, as for the AVX-512 kernel: with NBS_SIMD=avx2, 3D N = 1e6,
 * interleaved with 8851642, medians of 6, search 20.66 -> 19.94 ns per element; 2D 7.79 ->
 * 7.31. In 3D the steps over the ranges only note each q that hit and its mask, and the
 * notes become pairs after them (below). The ids' masked loads: 3D 1e6 search 29.7 ->
 * 29.2 (2D 11.55 -> 11.47). The packing permutations (nbs__pack4, internal.h) serve NBS's
 * AVX2 test too. */
const int32_t nbs__pack4[16][8] = {
    {0, 0, 0, 0, 0, 0, 0, 0}, {0, 1, 0, 0, 0, 0, 0, 0}, {2, 3, 0, 0, 0, 0, 0, 0},
    {0, 1, 2, 3, 0, 0, 0, 0}, {4, 5, 0, 0, 0, 0, 0, 0}, {0, 1, 4, 5, 0, 0, 0, 0},
    {2, 3, 4, 5, 0, 0, 0, 0}, {0, 1, 2, 3, 4, 5, 0, 0}, {6, 7, 0, 0, 0, 0, 0, 0},
    {0, 1, 6, 7, 0, 0, 0, 0}, {2, 3, 6, 7, 0, 0, 0, 0}, {0, 1, 2, 3, 6, 7, 0, 0},
    {4, 5, 6, 7, 0, 0, 0, 0}, {0, 1, 4, 5, 6, 7, 0, 0}, {2, 3, 4, 5, 6, 7, 0, 0},
    {0, 1, 2, 3, 4, 5, 6, 7}};

/* The AVX2 kernel's test of 4 lanes p (coordinates px.., radii pr) against 4 partners q:
 * all ones in the lanes that touch (the generic kernel's operations, in its order). */
static inline __attribute__((always_inline)) NBS__CS_AVX2_TARGET __m256d
nbs__cs_near256(int dim, bool radii, __m256d lim, __m256d px, __m256d py, __m256d pz,
                __m256d pr, __m256d qx, __m256d qy, __m256d qz, __m256d qr) {
  const __m256d dx = _mm256_sub_pd(px, qx), dy = _mm256_sub_pd(py, qy);
  __m256d d = _mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy));
  if (dim == 3) {
    const __m256d dz = _mm256_sub_pd(pz, qz);
    d = _mm256_add_pd(d, _mm256_mul_pd(dz, dz));
  }
  if (radii) {
    const __m256d rr = _mm256_add_pd(pr, qr);
    lim = _mm256_mul_pd(rr, rr);
  }
  return _mm256_cmp_pd(d, lim, _CMP_LE_OQ);
}

static inline __attribute__((always_inline)) NBS__CS_AVX2_TARGET size_t
nbs__cs_block256_body(const nbs__cs *c, int dim, bool radii, bool contacts, int form,
                      int32_t c0, int lanes, const nbs__cs_ranges *rg, nbs_pair *out) {
  const double *X = c->xs, *Y = c->ys, *Z = c->zs, *R = c->rs;
  const int32_t *ids = c->ids;
  const bool whole = form != NBS__CS_MASKED;
  const size_t istep = form == NBS__CS_IDX ? 1 : 2;
  const int32_t imask = (int32_t)c->imask;
  /* the lanes in use, as load masks and as bits */
  const __m256i na = _mm256_set1_epi64x(lanes);
  const __m256i ma = _mm256_cmpgt_epi64(na, _mm256_set_epi64x(3, 2, 1, 0));
  const __m256i mb = _mm256_cmpgt_epi64(na, _mm256_set_epi64x(7, 6, 5, 4));
  const unsigned im = (1u << lanes) - 1, ima = im & 0xF, imb = im >> 4;
  /* The block, twice over: B?[l] and B?[l + 8] hold lane l (0 past the block's lanes). For
   * the steps over the ranges, half a of each coordinate holds lanes 0, 1, 4, 5 and half b
   * lanes 2, 3, 6, 7: one signed pack of the two halves' comparisons (64-bit lanes to
   * 32-bit, within each 128-bit half) then puts the step's 8 results in lane order, read
   * by one movemask. */
  double BX[16], BY[16], BZ[16], BR[16];
  __m256d Xa, Xb, Ya, Yb, Za = _mm256_setzero_pd(), Zb = Za, Ra = Za, Rb = Za;
#define NBS__CS_LOAD256(A)                                                                    \
  do {                                                                                        \
    const __m256d A##0 = _mm256_maskload_pd(A + c0, ma);                                      \
    const __m256d A##1 = _mm256_maskload_pd(A + c0 + 4, mb);                                  \
    _mm256_storeu_pd(B##A, A##0);                                                             \
    _mm256_storeu_pd(B##A + 4, A##1);                                                         \
    _mm256_storeu_pd(B##A + 8, A##0);                                                         \
    _mm256_storeu_pd(B##A + 12, A##1);                                                        \
    A##a = _mm256_permute2f128_pd(A##0, A##1, 0x20);                                          \
    A##b = _mm256_permute2f128_pd(A##0, A##1, 0x31);                                          \
  } while (0)
  NBS__CS_LOAD256(X);
  NBS__CS_LOAD256(Y);
  if (dim == 3) NBS__CS_LOAD256(Z);
  if (radii) NBS__CS_LOAD256(R);
#undef NBS__CS_LOAD256
  /* Each lane's element twice, {ip, ip}, for lanes 0-3 (IP0) and 4-7 (IP1), 0 past the
   * block's lanes, by masked loads, and twice over in BP for the rotations. (Stored lane by
   * lane and read back by a 16-byte load, the load waited for the stores to reach the
   * cache: a forwarding stall, 5% of the kernel's samples at 3D N = 1e6.) */
  __m256i IP0, IP1;
  if (form == NBS__CS_IDX) {
    const __m128i n4 = _mm_set1_epi32(lanes);
    const __m128i m0 = _mm_cmpgt_epi32(n4, _mm_set_epi32(3, 2, 1, 0));
    const __m128i m1 = _mm_cmpgt_epi32(n4, _mm_set_epi32(7, 6, 5, 4));
    const __m128i i0 = _mm_maskload_epi32(ids + c0, m0), i1 = _mm_maskload_epi32(ids + c0 + 4, m1);
    IP0 = _mm256_shuffle_epi32(_mm256_cvtepu32_epi64(i0), 0xA0);
    IP1 = _mm256_shuffle_epi32(_mm256_cvtepu32_epi64(i1), 0xA0);
  } else {
    /* the packed words, whose low halves hold the elements */
    const long long *w = (const long long *)(const void *)(ids + (size_t)c0 * 2);
    IP0 = _mm256_shuffle_epi32(_mm256_maskload_epi64(w, ma), 0xA0);
    IP1 = _mm256_shuffle_epi32(_mm256_maskload_epi64(w + 4, mb), 0xA0);
  }
  if (!whole) {
    IP0 = _mm256_and_si256(IP0, _mm256_set1_epi32(imask));
    IP1 = _mm256_and_si256(IP1, _mm256_set1_epi32(imask));
  }
  long long BP[16];
  _mm256_storeu_si256((__m256i *)(void *)BP, IP0);
  _mm256_storeu_si256((__m256i *)(void *)(BP + 4), IP1);
  _mm256_storeu_si256((__m256i *)(void *)(BP + 8), IP0);
  _mm256_storeu_si256((__m256i *)(void *)(BP + 12), IP1);
  const __m256d LIM = _mm256_set1_pd(c->d2);
  nbs_pair *o = out; /* where the next pairs go */
  /* the pairs of lanes 0-3 (IP = IP0) or 4-7 (IP1) with partners IQ, of the lanes of the
   * bits kh, packed by a permutation and stored at o */
#define NBS__CS_PAIRS256(IP, IQ, kh)                                                          \
  do {                                                                                        \
    const unsigned hit = (kh);                                                                \
    const __m256i pr =                                                                        \
        _mm256_blend_epi32(_mm256_min_epi32(IP, IQ), _mm256_max_epi32(IP, IQ), 0xAA);         \
    const __m256i pk = _mm256_loadu_si256((const __m256i *)(const void *)nbs__pack4[hit]);    \
    _mm256_storeu_si256((__m256i *)(void *)o, _mm256_permutevar8x32_epi32(pr, pk));           \
    o += (unsigned)__builtin_popcount(hit);                                                   \
  } while (0)
  /* The steps over the ranges (before the block, they meet every lane; the last range ends
   * with the block, see nbs__cs_offer) note only each q and its 8 lanes' results, a note
   * kept where one lane or more hit, and the notes become pairs after the ranges (at most
   * NBS__CS_SLICE of them: nbs__cs_offer gives a call no more places): a step without a
   * hit, most of them in contact mode (about
   * 70% in 3D at volume fraction 0.5), then costs no pairs' output, which took half of a
   * step's instructions where the pairs were built at every step. The notes' pairs are the
   * ones the steps found, in the same order (q by q, each q's lanes 0-7). Zen 3 (AVX2
   * only), interleaved with 8acdd9d, min of 3-4 rounds, search in ns per element, the same
   * bytes: 3D N = 1e6 34.0 -> 29.9 (the detection 55.5 -> 52.5), time steps of 1e-3 34.0
   * -> 30.2, sparse 34.9 -> 31.2, clustered 34.6 -> 30.3, huge 11.0 -> 10.9, 1e4 with four
   * decoys 33.6 -> 29.7. A block meets about 35 q in 3D, 8 of them with a hit. In 2D it
   * meets 9, 3.2 with a hit, and the notes were slower (11.6 -> 12.5): the per-block cost
   * of the notes' loop outweighs the steps' savings, so 2D builds the pairs at every step.
   * Tried and left out (min of 4-6, search): the count of notes as a 64-bit index, saving
   * a sign extension a step: no faster; the ranges' places listed by the AVX2 sweep and
   * the steps one loop over them, as for AVX-512: 28.7 -> 28.2 at 1e6 and 29.8 -> 28.8 at
   * 1e4, but the huge domain 11.0 -> 11.6 and time steps 28.7 -> 28.9; each window's next
   * places asked for (prefetched) by the sweep: slower (28.9 -> 30.0); each note's pairs
   * by one 8-lane compress (a table of 256 rows of lane indices, one vpermd of the 8
   * elements, min and max, two unpacks and two stores) instead of the two halves': 28.46
   * against 28.48, no faster; nor in 2D at every step (the two halves' comparisons packed
   * into one mask, its pairs by that compress): 1e6 10.59 against 10.57, 1e4 9.71 -> 9.94.
   * With the notes never turned into pairs (a wrong output, to measure them) the search
   * took 24.0 against 28.8: the notes' loop and the pairs' stores, which go to memory at
   * N = 1e6.
   * What the tests themselves cost (72fa429, Zen 3, wrong outputs, to measure them; search
   * in ns per element, min of 4): with every step's test left out, 3D 28.4 -> 10.9 at N =
   * 1e6 and 27.7 -> 12.5 at 1e4 (whose search costs as much per element: nothing here
   * waits on memory); with half b's tests left out, 3D 27.7 -> 24.5, 2D 10.5 -> 8.8 (1e4
   * 15.2 -> 11.8). A q seldom reaches both halves (a block spans about 8 diameters in x in
   * 3D, 12 in 2D, a q one either side of it), so testing only the halves in reach could
   * save up to those figures; but which q reach which half is a count of each range's keys
   * per half (the windows' own edges, by lanes 3 and 4), and the q of each then a loop or a
   * list of their own, whose order must still come out q by q. Built so (a prototype: each
   * range's two edges counted among its keys, the places of the q that reach half a only,
   * half b only and both listed, a loop over each list, the masks to a byte per place and
   * the pairs from them in place order; the same hashes), the search went from 27.8 to
   * 39.6: the lists and counts came before any test, and cost more than the tests saved.
   * Tried and left out (same figures): the
   * subtractions of dz (or dy and dz) as fused multiply-adds by 1.0, the same roundings,
   * to move them from the two adding pipes to the two multiplying ones: 1e4 27.68 ->
   * 28.17, 1e6 28.15 -> 28.44, no faster (nor is the bound what the pipes give: 20
   * vector operations a step, about 8.5 cycles per step where the pipes need 5); the
   * rotations from k = 2 on skipped, with every one after, where no two lanes k apart lie
   * within `fine` sub-cells (exact, the windows' own criterion): 3D 27.7 -> 28.9, 2D 10.5 ->
   * 11.8 (the lanes' sub-cells stored, then read at offset k across two of the stores,
   * which store forwarding cannot serve), and with rotations 3 and 4 left out whatever the
   * lanes (a wrong output; the check kept at k = 2) 3D 27.8 -> 27.0 only; with the
   * sub-cells' smallest gaps 2, 3 and 4 lanes apart computed from the keys in scalar code
   * (no store forwarding) and the loop run to the last rotation in reach: 3D 27.8 -> 29.8,
   * 2D 10.4 -> 12.6 (the loop's count, 2 to 4, now mispredicted; with every rotation left
   * out, a wrong output, 3D 27.9 -> 25.8 and 2D 10.4 -> 8.8: what the rotations cost); the
   * ranges of long rows listed by the AVX2 sweep, short rows not (the list
   * had cost the huge domain, above): 27.7 -> 28.8. */
  /* the block's lanes 0-3 and 4-7 of each coordinate, X0 and X1 .. */
#define NBS__CS_LANES256()                                                                    \
  const __m256d X0 = _mm256_loadu_pd(BX), X1 = _mm256_loadu_pd(BX + 4);                      \
  const __m256d Y0 = _mm256_loadu_pd(BY), Y1 = _mm256_loadu_pd(BY + 4);                      \
  const __m256d Z0 = dim == 3 ? _mm256_loadu_pd(BZ) : X0;                                     \
  const __m256d Z1 = dim == 3 ? _mm256_loadu_pd(BZ + 4) : X1;                                 \
  const __m256d R0 = radii ? _mm256_loadu_pd(BR) : X0;                                        \
  const __m256d R1 = radii ? _mm256_loadu_pd(BR + 4) : X1
  const int last = rg->count - 1;
  if (dim == 2) {
    NBS__CS_LANES256();
    (void)Z0, (void)Z1;
    for (int r = 0; r < rg->count; r++) {
      const int32_t q1 = r == last && rg->q1[r] > c0 ? c0 : rg->q1[r];
      for (int32_t q = rg->q0[r]; q < q1; q++) {
        const __m256d qx = _mm256_set1_pd(X[q]), qy = _mm256_set1_pd(Y[q]);
        const __m256d qr = radii ? _mm256_set1_pd(R[q]) : qx;
        const __m256i iq = _mm256_set1_epi32(whole ? ids[(size_t)q * istep]
                                                   : ids[(size_t)q * istep] & imask);
        NBS__CS_PAIRS256(IP0, iq,
                         contacts ? (unsigned)_mm256_movemask_pd(nbs__cs_near256(
                                        dim, radii, LIM, X0, Y0, X0, R0, qx, qy, qx, qr)) &
                                        ima
                                  : ima);
        if (imb) {
          NBS__CS_PAIRS256(IP1, iq,
                           contacts ? (unsigned)_mm256_movemask_pd(nbs__cs_near256(
                                          dim, radii, LIM, X1, Y1, X1, R1, qx, qy, qx, qr)) &
                                          imb
                                    : imb);
        }
      }
    }
  } else {
    int32_t nq[NBS__CS_SLICE];
    uint8_t nm[NBS__CS_SLICE];
    int32_t nn = 0;
    for (int r = 0; r < rg->count; r++) {
      const int32_t q1 = r == last && rg->q1[r] > c0 ? c0 : rg->q1[r];
      for (int32_t q = rg->q0[r]; q < q1; q++) {
        const __m256d qx = _mm256_set1_pd(X[q]), qy = _mm256_set1_pd(Y[q]);
        const __m256d qz = _mm256_set1_pd(Z[q]);
        const __m256d qr = radii ? _mm256_set1_pd(R[q]) : qx;
        unsigned hm = 0xFF;
        if (contacts) {
          const __m256d ca = nbs__cs_near256(dim, radii, LIM, Xa, Ya, Za, Ra, qx, qy, qz, qr);
          const __m256d cb = nbs__cs_near256(dim, radii, LIM, Xb, Yb, Zb, Rb, qx, qy, qz, qr);
          hm = (unsigned)_mm256_movemask_ps(_mm256_castsi256_ps(
              _mm256_packs_epi32(_mm256_castpd_si256(ca), _mm256_castpd_si256(cb))));
        }
        nq[nn] = q;
        nm[nn] = (uint8_t)hm;
        nn += hm != 0;
      }
    }
    for (int32_t k = 0; k < nn; k++) {
      const size_t at = (size_t)nq[k] * istep;
      const __m256i iq = _mm256_set1_epi32(whole ? ids[at] : ids[at] & imask);
      const unsigned km = nm[k] & im;
      NBS__CS_PAIRS256(IP0, iq, km & 0xF);
      NBS__CS_PAIRS256(IP1, iq, km >> 4);
    }
  }
  /* the block's own pairs, by rotation, as in the AVX-512 kernel: lanes 0-3 and 4-7
   * against lanes k.. k + 3 and k + 4.. k + 7 */
  const int own = rg->q1[last] > c0 ? NBS__CS_LANES / 2 : 0;
  if (own) {
    NBS__CS_LANES256();
    for (int k = 1; k <= own; k++) {
      unsigned vm = im & (im >> k | im << (NBS__CS_LANES - k));
      if (k == NBS__CS_LANES / 2) vm &= 0x0F;
      if (!vm) break;
      const __m256d qxa = _mm256_loadu_pd(BX + k), qxb = _mm256_loadu_pd(BX + k + 4);
      const __m256d qya = _mm256_loadu_pd(BY + k), qyb = _mm256_loadu_pd(BY + k + 4);
      const __m256d qza = dim == 3 ? _mm256_loadu_pd(BZ + k) : qxa;
      const __m256d qzb = dim == 3 ? _mm256_loadu_pd(BZ + k + 4) : qxb;
      const __m256d qra = radii ? _mm256_loadu_pd(BR + k) : qxa;
      const __m256d qrb = radii ? _mm256_loadu_pd(BR + k + 4) : qxb;
      const __m256i iqa = _mm256_loadu_si256((const __m256i *)(const void *)(BP + k));
      const __m256i iqb = _mm256_loadu_si256((const __m256i *)(const void *)(BP + k + 4));
      unsigned ha = vm & 0xF, hb = vm >> 4;
      if (contacts) {
        ha &= (unsigned)_mm256_movemask_pd(
            nbs__cs_near256(dim, radii, LIM, X0, Y0, Z0, R0, qxa, qya, qza, qra));
        hb &= (unsigned)_mm256_movemask_pd(
            nbs__cs_near256(dim, radii, LIM, X1, Y1, Z1, R1, qxb, qyb, qzb, qrb));
      }
      NBS__CS_PAIRS256(IP0, iqa, ha);
      if (vm >> 4) NBS__CS_PAIRS256(IP1, iqb, hb);
    }
  }
#undef NBS__CS_PAIRS256
#undef NBS__CS_LANES256
  return (size_t)(o - out);
}

NBS__CS_VARIANTS(nbs__cs_k256, NBS__CS_AVX2_TARGET, nbs__cs_block256_body)
#endif

/* The kernel this process uses: AVX-512 where the processor has it, else AVX2, else the
 * generic one. The environment variable NBS_SIMD, read when a context is created, asks for
 * a lesser one, for tests and comparisons: "generic", or "avx2" (where the processor has
 * it). */
int nbs__cellsort_simd(void) {
#if NBS__CS_AVX512
  const char *e = getenv("NBS_SIMD");
  if (e && strcmp(e, "generic") == 0) return NBS__SIMD_GENERIC;
  __builtin_cpu_init();
  const bool avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("popcnt");
  if (e && strcmp(e, "avx2") == 0) return avx2 ? NBS__SIMD_AVX2 : NBS__SIMD_GENERIC;
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
      __builtin_cpu_supports("avx512dq")) {
    return NBS__SIMD_AVX512;
  }
  if (avx2) return NBS__SIMD_AVX2;
#endif
  return NBS__SIMD_GENERIC;
}

/* The input's size (bytes of coordinates and radii) above which cellsort sorts by the
 * partition (nbs__cs_partition) instead of gathering: 1 GiB; from 8 MiB up to it, the
 * context measures which is faster on the machine (nbs__cs_way). It was 32 MiB, about the
 * last-level cache of a server processor, until the gather's prefetches went in two stages
 * (nbs__cs_prefetch); since then the gather wins up to hundreds of MB, and the partition
 * only beyond (interleaved, ns per element, one thread, random order, partition against
 * gather: 3D N = 1e6, 24 MB, 37.9 against 32.5; 1e7, 240 MB, 39.0 / 35.5, two threads 20.9
 * / 19.0, sorted order 37.8 / 32.7; 2e7 43.3 / 41.3; 3e7, 720 MB, 44.0 / 44.0; 1e8, 2.4 GB,
 * 62.2 / 67.1; 2D 1e7, 160 MB, 22.7 / 21.6; 3e7 29.4 / 26.8; 1e8, 1.6 GB, 30.6 / 35.2; on
 * the library of 2026-11-29, before nbs__cs_part_digits, the partition gave way to the sort
 * wherever the even split of the key's bits left its top digit too narrow, 3D from about
 * N = 1.7e7, 30-bit keys: there the figures of "partition" were the sort and the gather's,
 * unless the code of the day differed). Far
 * beyond, the gather's random reads miss the TLB as well as the caches. A constant, not the
 * machine's cache size, so that the path, and so the time, does not depend on what the C
 * library reports (glibc's sysconf gave 320 MiB of L3 on the benchmark machine, which has
 * 32). The environment variable NBS_PARTITION, read when a context is created, says
 * "always" or "never" instead, for tests and comparisons ("wide": always, with the top digit
 * widened wherever the keys allow, nbs__cs_part_digits). */
size_t nbs__cellsort_partition_min(void) {
  const char *e = getenv("NBS_PARTITION");
  if (e && (strcmp(e, "always") == 0 || strcmp(e, "wide") == 0)) return 0;
  if (e && strcmp(e, "never") == 0) return SIZE_MAX;
  return (size_t)1 << 30;
}

/* Whether NBS_PARTITION says "wide" (nbs__cellsort_partition_min). */
bool nbs__cellsort_partition_wide(void) {
  const char *e = getenv("NBS_PARTITION");
  return e && strcmp(e, "wide") == 0;
}

/* Whether a context measures which way its detections from scratch take below that size
 * (nbs__cs_way), and whether its time steps start from the last order or from scratch
 * (nbs__cs_steps_way): unless NBS_PARTITION says "always" or "never" (then every step
 * that can starts from the order), read when the context is created. */
bool nbs__cellsort_tune(void) {
  const char *e = getenv("NBS_PARTITION");
  return !(e && (strcmp(e, "always") == 0 || strcmp(e, "never") == 0));
}

/* NBS_STEAL=first in the environment, read when a context is created: in the work the
 * threads share (nbs__share: the sweep's chunks, the gather, the sort's buckets) each thread
 * first takes the last range of the next thread's part, then does its own, so that the
 * tests see ranges taken from other parts, which otherwise happens only where one thread
 * falls behind. */
bool nbs__cellsort_steal_first(void) {
  const char *e = getenv("NBS_STEAL");
  return e && strcmp(e, "first") == 0;
}

/* Offers the block [c0, c0 + lanes) against its ranges into the sink: in one call of the
 * kernel when they hold at most NBS__CS_SLICE elements and the sink has room, else range by
 * range in slices of at most NBS__CS_SLICE elements (so that the room asked of the sink
 * stays small), and the block's own pairs in a call of their own (the range [c0, c0 +
 * lanes): a kernel gives them all when its last range holds the block); pair by pair, from
 * a call of the kernel per element (or for the block's own pairs), when there is no room (a
 * callback's batch smaller than a slice, or max_pairs in reach). Same pairs, same order. */
static nbs_status nbs__cs_offer_slices(const nbs__cs *c, nbs__sink *s, int32_t c0, int lanes,
                                       const nbs__cs_ranges *rg) {
  int32_t list[NBS__CS_SLICE + 16]; /* each slice's places, listed for any kernel */
  for (int r = 0; r < rg->count; r++) {
    /* the part before the block, then the block alone */
    const bool own = r == rg->count - 1 && rg->q1[r] > c0;
    const int32_t end = own ? c0 : rg->q1[r];
    for (int32_t q0 = rg->q0[r]; q0 < end || (own && q0 == c0);) {
      const bool block = q0 >= c0;
      const int32_t q1 = block ? c0 + lanes : end - q0 > NBS__CS_SLICE ? q0 + NBS__CS_SLICE : end;
      nbs__cs_ranges one = {1, {q0}, {q1}, 0, list};
      one.places = nbs__cs_list(list, 0, q0, block ? c0 : q1);
      const size_t need = block ? (size_t)lanes * (size_t)lanes + NBS__CS_LANES
                                : (size_t)(one.q1[0] - q0) * (size_t)lanes + NBS__CS_LANES;
      bool room = true;
      if (s->cap - s->count < need) NBS__TRY(nbs__sink_room(s, need, &room));
      if (room) {
        const size_t m = c->block(c, c0, lanes, &one, s->buf + s->count);
        s->count += m;
        s->emitted += m;
      } else {
        for (int32_t q = q0; q < one.q1[0]; q++) {
          nbs_pair some[NBS__CS_LANES * NBS__CS_LANES + NBS__CS_LANES];
          nbs__cs_ranges single = {1, {q}, {block ? c0 + lanes : q + 1}, 0, list};
          single.places = nbs__cs_list(list, 0, q, block ? c0 : q + 1);
          size_t k = c->block(c, c0, lanes, &single, some);
          for (size_t u = 0; u < k; u++) NBS__TRY(nbs__sink_one(s, some[u]));
          if (block) break;
        }
      }
      q0 = one.q1[0];
    }
  }
  return NBS_OK;
}

/* The ranges' elements are summed here one range at a time. GCC 12 vectorized the loop,
 * loading q0 and q1 as vectors just after the sweep stored them one by one: a load that
 * store forwarding cannot serve, which waited for the stores to reach the cache at every
 * block (perf: 5.6% of the sweep on the instruction after it). An empty asm that says it
 * may change the sum keeps the loop scalar, each load served by its own store (3D, N = 1e6,
 * interleaved, medians: search 14.5 -> 13.9-14.0 ns per element, time steps 15.1 -> 14.5,
 * 1e7 14.8 -> 14.4, sparse and clustered 0.3 less; 2D the same). Where the ranges are
 * listed (nbs__cs_ranges), the list's length is the sum but for the block's own lanes, and
 * there is no loop (interleaved with the loop, medians of 4-5, search ns per element, the
 * same bytes: 3D N = 1e6 12.41 -> 12.07 and 12.25 -> 11.95, 1e4 11.12 -> 10.61, sparse
 * 12.70 -> 12.26, huge 17.37 -> 17.06; 2D 1e6 5.15 -> 4.97). (Kept by the sweep as it
 * found the ranges, before they were listed, such a sum had cost the huge domain more than
 * it saved: 3D, N = 1e6, min of 6, 33.7 -> 33.2 ns per element, huge 38.8 -> 39.7.) */
#if defined(__GNUC__)
#define NBS__CS_SCALAR(v) __asm__("" : "+r"(v))
#else
#define NBS__CS_SCALAR(v) ((void)0)
#endif
static inline __attribute__((always_inline)) nbs_status
nbs__cs_offer(const nbs__cs *c, nbs__sink *s, int32_t c0, int lanes, const nbs__cs_ranges *rg) {
  size_t total = 0;
  if (rg->places >= 0) {
    total = (size_t)rg->places + (size_t)lanes;
  } else {
    for (int r = 0; r < rg->count; r++) {
      total += (size_t)(rg->q1[r] - rg->q0[r]);
      NBS__CS_SCALAR(total);
    }
  }
  /* the block's own pairs are counted as lanes (lanes - 1) / 2, not lanes * lanes */
  s->candidates += (uint64_t)lanes * total - (uint64_t)lanes * (uint64_t)(lanes + 1) / 2;
  const size_t need = total * (size_t)lanes + NBS__CS_LANES;
  if (total > NBS__CS_SLICE || s->cap - s->count < need) {
    /* The slow path works on a copy, so that the sweep's sink, whose address never
     * escapes, can live in registers. */
    nbs__sink t = *s;
    nbs_status st = nbs__cs_offer_slices(c, &t, c0, lanes, rg);
    *s = t;
    return st;
  }
  const size_t m = c->block(c, c0, lanes, rg, s->buf + s->count);
  s->count += m;
  s->emitted += m;
  return NBS_OK;
}

/* Window edges. An edge q moves forwards while key[q] < bound (or <= bound). Edges move by
 * a few places per block, in no pattern a branch predictor learns, and each step of a plain
 * loop waits for the load before it. So sixteen keys are compared at once, without a branch
 * (the keys are sorted: the count of those that pass is the step), and only a step of
 * sixteen loops. The key array has NBS__CS_PAD entries of UINT64_MAX after the end, never
 * below a bound. A counter returns how many of key[0..16) pass. */
typedef int32_t (*nbs__cs_count_fn)(const uint64_t *key, uint64_t bound);

static inline int32_t nbs__cs_below(const uint64_t *key, uint64_t bound) {
  int32_t n = 0;
  for (int i = 0; i < NBS__CS_PAD; i++) n += key[i] < bound;
  return n;
}
static inline int32_t nbs__cs_upto(const uint64_t *key, uint64_t bound) {
  int32_t n = 0;
  for (int i = 0; i < NBS__CS_PAD; i++) n += key[i] <= bound;
  return n;
}
#if NBS__CS_AVX512
static inline NBS__CS_AVX512_TARGET int32_t nbs__cs_below512(const uint64_t *key, uint64_t bound) {
  const __m512i b = _mm512_set1_epi64((long long)bound);
  const unsigned m0 = _mm512_cmplt_epu64_mask(_mm512_loadu_si512((const void *)key), b);
  const unsigned m1 = _mm512_cmplt_epu64_mask(_mm512_loadu_si512((const void *)(key + 8)), b);
  return __builtin_popcount(m0 | m1 << 8);
}
static inline NBS__CS_AVX512_TARGET int32_t nbs__cs_upto512(const uint64_t *key, uint64_t bound) {
  const __m512i b = _mm512_set1_epi64((long long)bound);
  const unsigned m0 = _mm512_cmple_epu64_mask(_mm512_loadu_si512((const void *)key), b);
  const unsigned m1 = _mm512_cmple_epu64_mask(_mm512_loadu_si512((const void *)(key + 8)), b);
  return __builtin_popcount(m0 | m1 << 8);
}
#endif

#if NBS__CS_AVX512
/* With AVX2: signed compares of 4 keys at a time, keys and bound with the sign bit flipped.
 * nbs__cs_count4 counts the keys of key[0..4) above b (as flipped), or below it. */
static inline NBS__CS_AVX2_TARGET int32_t nbs__cs_count4(const uint64_t *key, __m256i b,
                                                         bool above) {
  const __m256i sign = _mm256_set1_epi64x(INT64_MIN);
  const __m256i k =
      _mm256_xor_si256(_mm256_loadu_si256((const __m256i *)(const void *)key), sign);
  const __m256i gt = above ? _mm256_cmpgt_epi64(k, b) : _mm256_cmpgt_epi64(b, k);
  return __builtin_popcount((unsigned)_mm256_movemask_pd(_mm256_castsi256_pd(gt)));
}
static inline NBS__CS_AVX2_TARGET int32_t nbs__cs_below256(const uint64_t *key, uint64_t bound) {
  const __m256i b = _mm256_set1_epi64x((long long)(bound ^ ((uint64_t)1 << 63)));
  int32_t n = 0;
  for (int i = 0; i < NBS__CS_PAD; i += 4) n += nbs__cs_count4(key + i, b, false);
  return n;
}
static inline NBS__CS_AVX2_TARGET int32_t nbs__cs_upto256(const uint64_t *key, uint64_t bound) {
  const __m256i b = _mm256_set1_epi64x((long long)(bound ^ ((uint64_t)1 << 63)));
  int32_t above = 0;
  for (int i = 0; i < NBS__CS_PAD; i += 4) above += nbs__cs_count4(key + i, b, true);
  return NBS__CS_PAD - above;
}
#endif

#define NBS__CS_ADVANCE(key, q, count, bound)                                                 \
  do {                                                                                        \
    int32_t nbs__step;                                                                        \
    do {                                                                                      \
      nbs__step = count((key) + (q), (bound));                                                \
      (q) += nbs__step;                                                                       \
    } while (nbs__step == NBS__CS_PAD);                                                       \
  } while (0)

/* A picker: to list[t ..], the places from + i (i < 16, in order) whose keys key[from + i]
 * lie in a row of [rlo, rlo + rspan] (the key's bits from kx on) and at an x sub-cell of
 * [xl, xl + xspan] (its bits from ks on, masked by mx); returns t + how many. A 3D short
 * row's element takes its candidates so with AVX-512 (nbs__cs_sweep3_body: the sweeps of
 * the other kernels, whose kernels loop over ranges, not lists, pass NULL and never call
 * it). The list has room for sixteen places past t (the vector store writes them all). */
typedef int32_t (*nbs__cs_pick_fn)(const uint64_t *key, int32_t from, int kx, int ks,
                                   uint64_t mx, uint64_t rlo, uint64_t rspan, uint64_t xl,
                                   uint64_t xspan, int32_t *list, int32_t t);
#if NBS__CS_AVX512
static inline NBS__CS_AVX512_TARGET int32_t nbs__cs_pick512(const uint64_t *key, int32_t from,
                                                            int kx, int ks, uint64_t mx,
                                                            uint64_t rlo, uint64_t rspan,
                                                            uint64_t xl, uint64_t xspan,
                                                            int32_t *list, int32_t t) {
  const __m128i sr = _mm_cvtsi32_si128(kx), sx = _mm_cvtsi32_si128(ks);
  const __m512i R = _mm512_set1_epi64((long long)rlo), RS = _mm512_set1_epi64((long long)rspan);
  const __m512i XL = _mm512_set1_epi64((long long)xl), XS = _mm512_set1_epi64((long long)xspan);
  const __m512i MX = _mm512_set1_epi64((long long)mx);
  unsigned m = 0;
  for (int h = 0; h < 2; h++) {
    const __m512i k = _mm512_loadu_si512((const void *)(key + from + 8 * h));
    const __mmask8 in_row = _mm512_cmple_epu64_mask(_mm512_sub_epi64(_mm512_srl_epi64(k, sr), R), RS);
    const __m512i xk = _mm512_and_si512(_mm512_srl_epi64(k, sx), MX);
    const __mmask8 in_x = _mm512_mask_cmple_epu64_mask(in_row, _mm512_sub_epi64(xk, XL), XS);
    m |= (unsigned)in_x << (8 * h);
  }
  if (!m) return t; /* the most common case in a sparse domain, and predicted so */
  const __m512i iota = _mm512_set_epi32(15, 14, 13, 12, 11, 10, 9, 8, 7, 6, 5, 4, 3, 2, 1, 0);
  const __m512i at = _mm512_add_epi32(iota, _mm512_set1_epi32(from));
  _mm512_storeu_si512((void *)(list + t), _mm512_maskz_compress_epi32((__mmask16)m, at));
  return t + __builtin_popcount(m);
}
#endif

/* The lower bound of `k` in key[0, hi). */
static int32_t nbs__cs_lower(const uint64_t *key, int32_t hi, uint64_t k) {
  int32_t lo = 0;
  while (lo < hi) {
    int32_t m = lo + (hi - lo) / 2;
    if (key[m] < k) lo = m + 1;
    else hi = m;
  }
  return lo;
}

/* The sweep's own rows at place q, asked for ahead of their use (see nbs__cs_row_blocks):
 * the key, the coordinates, the radius and (unpacked keys) the element. */
static inline __attribute__((always_inline)) void nbs__cs_ask_own(const nbs__cs *c, int32_t q) {
  __builtin_prefetch(c->key + q);
  __builtin_prefetch(c->xs + q);
  __builtin_prefetch(c->ys + q);
  if (c->dim == 3) __builtin_prefetch(c->zs + q);
  if (c->rs) __builtin_prefetch(c->rs + q);
  if (c->istep == 1) __builtin_prefetch(c->ids + q); /* unpacked keys */
}

/* The three counts of nbs__cs_back among the eight keys k8[0 .. 8), one load for all three:
 * c[0] from lb on, c[1] above hb, c[2] from own on. */
typedef void (*nbs__cs_back8_fn)(const uint64_t *k8, uint64_t own, uint64_t lb, uint64_t hb,
                                 int32_t c[3]);
#if NBS__CS_AVX512
static inline NBS__CS_AVX512_TARGET void nbs__cs_back8_512(const uint64_t *k8, uint64_t own,
                                                           uint64_t lb, uint64_t hb,
                                                           int32_t c[3]) {
  const __m512i k = _mm512_loadu_si512((const void *)k8);
  c[0] = __builtin_popcount(_mm512_cmpge_epu64_mask(k, _mm512_set1_epi64((long long)lb)));
  c[1] = __builtin_popcount(_mm512_cmpgt_epu64_mask(k, _mm512_set1_epi64((long long)hb)));
  c[2] = __builtin_popcount(_mm512_cmpge_epu64_mask(k, _mm512_set1_epi64((long long)own)));
}
/* With AVX2: the eight keys as two registers, sign bits flipped for signed compares
 * (nbs__cs_count4). */
static inline NBS__CS_AVX2_TARGET void nbs__cs_back8_256(const uint64_t *k8, uint64_t own,
                                                         uint64_t lb, uint64_t hb, int32_t c[3]) {
  const uint64_t sign = (uint64_t)1 << 63;
  const __m256i l = _mm256_set1_epi64x((long long)(lb ^ sign));
  const __m256i h = _mm256_set1_epi64x((long long)(hb ^ sign));
  const __m256i o = _mm256_set1_epi64x((long long)(own ^ sign));
  c[0] = 8 - nbs__cs_count4(k8, l, false) - nbs__cs_count4(k8 + 4, l, false);
  c[1] = nbs__cs_count4(k8, h, true) + nbs__cs_count4(k8 + 4, h, true);
  c[2] = 8 - nbs__cs_count4(k8, o, false) - nbs__cs_count4(k8 + 4, o, false);
}
#endif

/* A short row's element p (2D and 3D, swept element by element): how many of the places
 * just before p hold keys from lb on (*c1), above hb (*c2), and from own on (*c3): the row
 * before it in its layer (2D: the row below), x - fine .. x + fine (lb .. hb, where `before`
 * says there is such a row), and its own row from x - fine on (own); c1 >= c2 >= c3. Counted
 * among the sixteen keys before p, or found by search where those are all in reach or p
 * has fewer before it. The AVX-512 and AVX2 sweeps count among the eight keys before p
 * first (back8: one load, or two, for the three counts), and go on as above only where all
 * eight are in reach: a sparse domain's element has a key or two in reach, and the two
 * loads and six compares of sixteen keys were a fifth of its sweep (2D huge domain, N =
 * 1e6, interleaved, min of 5: search 8.90 -> 7.24 ns per element, 2D spacing S/D 100 and
 * 200 at 1e5 8.97 -> 8.20 and 8.95 -> 8.05; AVX2 huge 9.41 -> 8.82; uniform and 3D the
 * same). */
static inline __attribute__((always_inline)) void
nbs__cs_back(const uint64_t *key, int32_t p, uint64_t own, uint64_t lb, uint64_t hb,
             bool before, nbs__cs_count_fn below, nbs__cs_count_fn upto,
             nbs__cs_back8_fn back8, int32_t *c1, int32_t *c2, int32_t *c3) {
  if (back8 && p >= 8) {
    int32_t c[3];
    back8(key + p - 8, own, lb, hb, c);
    if ((before ? c[0] : c[2]) < 8) {
      *c3 = c[2];
      *c1 = before ? c[0] : c[2];
      *c2 = before ? c[1] : c[2];
      return;
    }
  }
  if (p >= NBS__CS_PAD) {
    const uint64_t *kb = key + p - NBS__CS_PAD;
    *c3 = NBS__CS_PAD - below(kb, own);
    *c1 = *c2 = *c3;
    if (before) {
      *c1 = NBS__CS_PAD - below(kb, lb);
      *c2 = NBS__CS_PAD - upto(kb, hb);
    }
  } else {
    *c1 = NBS__CS_PAD; /* the search below */
  }
  if (*c1 == NBS__CS_PAD) {
    *c3 = p - nbs__cs_lower(key, p, own);
    *c1 = *c2 = *c3;
    if (before) {
      *c1 = p - nbs__cs_lower(key, p, lb);
      *c2 = p - nbs__cs_lower(key, p, hb + 1); /* hb < own: no overflow */
    }
  }
}

/* The blocks of the row [a, b) of the cell order, a row that starts at row_a <= a (a is
 * row_a, or a block of the row where a thread's range starts; see nbs__cs_thread_start).
 * Each row is cut into blocks of NBS__CS_LANES consecutive elements. A block meets itself,
 * the elements before it in its own row within one cell edge in x of its first element,
 * and a window of each of the `rows` neighbouring rows of the half mask: the elements
 * within one cell edge in x either side of the block. Neighbouring row r's keys start at
 * base[r]; its window starts at q0[r] = q1[r] (q0[r] < 0: no such row). On the x axis the
 * key counts sub-cells of edge / fine (8 unless the key needs the bits), so these windows
 * hug the block. Every window only moves forwards, so finding them costs O(1) per block
 * and row; the kernel then tests one window element against the whole block at once.
 * Finding the windows takes about a third of the sweep, and does not overlap the kernel
 * (3D, N = 1e6, Zen 5: the sweep without the kernel 4.6 ns per element, with the kernel
 * called twice 25.2, once 14.9). Tried and left out: each block's windows found one block
 * ahead, before the kernel of the block before, so that the processor could run the two
 * side by side: no faster (search 14.8-15.1 against 14.9-15.4, interleaved, min of 4).
 * Where `listed` (the AVX-512 sweep), the ranges' places are also written to a list as they
 * are found, which the kernel's steps loop over (nbs__cs_ranges, nbs__cs_list). */
static inline __attribute__((always_inline)) nbs_status
nbs__cs_row_blocks(const nbs__cs *c, nbs__sink *s, int32_t row_a, int32_t a, int32_t b,
                   int rows, const uint64_t *base, int32_t *q0, int32_t *q1,
                   nbs__cs_count_fn below, nbs__cs_count_fn upto, bool listed) {
  /* key[q] >> ks is element q's key; a bound b on keys is b << ks on the words (below), or
   * b << ks | low (up to) */
  const uint64_t *key = c->key;
  const int ks = c->ks;
  const uint64_t low = ((uint64_t)1 << ks) - 1, mx = ((uint64_t)1 << c->bx) - 1;
  const uint64_t fine = c->fine;
  nbs_status st = NBS_OK;
  int32_t w = row_a;
  int32_t list[NBS__CS_SLICE + 16]; /* the block's places, where listed (nbs__cs_ranges) */
  for (int32_t c0 = a; c0 < b && st == NBS_OK; c0 += NBS__CS_LANES) {
    const int lanes = b - c0 < NBS__CS_LANES ? (int)(b - c0) : NBS__CS_LANES;
    /* The sweep's own rows are its one stream of memory not read before: the gather (or
     * the start from the last order) wrote them, and at scale they have left the caches
     * since; the windows of the neighbouring rows read what the own rows read a row or a
     * layer before. Asked for NBS__CS_SWEEP_AHEAD places ahead, which the processor's
     * prefetchers, following some twenty streams, did not do as well (3D, N = 1e6, one
     * thread: sweep 19.8 -> 18.2 ns per element; 1e7: 21.9 -> 18.9; 2D 1e6: 7.2 -> 6.3;
     * asking for the windows' streams too gained nothing). */
    nbs__cs_ask_own(c, c0 + NBS__CS_SWEEP_AHEAD < c->n ? c0 + NBS__CS_SWEEP_AHEAD : c0);
    const uint64_t k0 = key[c0] >> ks;
    const uint64_t fa = k0 & mx, fb = (key[c0 + lanes - 1] >> ks) & mx;
    nbs__cs_ranges rg;
    rg.count = 0;
    int32_t places = 0;
    /* each neighbouring row: a window of fa - fine .. fb + fine (a loop, not unrolled: with
     * 3D's four rows a constant, GCC unrolled it, and the detection was 3-5% slower) */
#pragma GCC unroll 1
    for (int r = 0; r < rows; r++) {
      if (q0[r] < 0) continue;
      const uint64_t lo = base[r] + (fa > fine ? fa - fine : 0);
      const uint64_t hi = base[r] + (mx - fb > fine ? fb + fine : mx);
      /* both stop at a at the latest: key[a] > base + mx. Each edge moves from where it
       * was, so that the two are independent chains of loads (q1 >= q0 all the same: the
       * first key above hi is not before the first key from lo on); a sparse row's blocks
       * wait for one edge at a time instead of two (2D huge domain, N = 1e6: sweep 14.3 ->
       * 13.0 ns per element) */
      NBS__CS_ADVANCE(key, q0[r], below, lo << ks);
      NBS__CS_ADVANCE(key, q1[r], upto, hi << ks | low);
      rg.q0[rg.count] = q0[r];
      rg.q1[rg.count] = q1[r];
      rg.count += q1[r] > q0[r];
      /* listed here, among the window searches (see the AVX-512 kernel) */
      if (listed) places = nbs__cs_list(list, places, q0[r], q1[r]);
    }
    /* own row: the elements before the block from fa - fine on (none before a row's first
     * block: no search there, which spares sparse scenes, whose rows hold one element or
     * two, a load and compare per row: huge domain, N = 1e6, sweep 13.5 -> 12.6 ns per
     * element in 2D, 16.7 -> 15.7 in 3D), and the block itself */
    if (c0 > row_a) NBS__CS_ADVANCE(key, w, below, (k0 - (fa < fine ? fa : fine)) << ks);
    rg.q0[rg.count] = w;
    rg.q1[rg.count] = c0 + lanes;
    rg.count++;
    /* nothing in reach (sparse rows): no neighbouring window, nothing before the block
     * within one edge in x, and the block's own elements more than one edge apart (keys
     * more than `fine` apart, the windows' own criterion): no candidate, no kernel call (2D
     * huge domain, N = 1e6, where a quarter of the rows hold two elements or more: sweep 16
     * -> 15 ns per element; 3D: 19 -> 17.5) */
    if (rg.count == 1 && w == c0) {
      int l = 1;
      while (l < lanes && ((key[c0 + l] >> ks) & mx) - ((key[c0 + l - 1] >> ks) & mx) > fine) l++;
      if (l == lanes) continue;
    }
    /* the own row's places before the block; those of the block are its rotations */
    rg.places = listed ? nbs__cs_list(list, places, w, c0) : -1;
    rg.list = list;
    st = nbs__cs_offer(c, s, c0, lanes, &rg);
  }
  return st;
}

/* A 3D row of fewer elements than this is swept element by element (nbs__cs_sweep3_body);
 * at most NBS__CS_PAD + 1, for the padding after the keys. */
#define NBS__CS_SHORT3 4

/* 3D: sweeps the places [from, to) of the cell order (from and to at rows' starts or at
 * blocks of a long row: nbs__cs_thread_start), with the four neighbouring rows of the half
 * mask, (dy, dz) = (-1, -1) (0, -1) (1, -1) (-1, 0) in key order.
 * A row of NBS__CS_SHORT3 elements or more is swept by its blocks (nbs__cs_row_blocks). A
 * shorter one, element by element, as in 2D (nbs__cs_sweep2_body): element p meets the
 * elements before it in its own row within one cell edge in x, those of the row before it
 * in its layer within one edge either side (both among the sixteen keys before p, or found
 * by search further back), and those of the three rows of the layer below, (y - 1 .. y + 1,
 * z - 1), within one edge either side. Those three rows are consecutive in key order, so
 * one cursor, moved forwards to the first key from the start of row (y - 1, z - 1) on,
 * finds all three windows among the sixteen keys from it (a search from the cursor where
 * they reach further). Nothing else is carried from one element to the next. Where both
 * sides lie among their sixteen keys, the AVX-512 sweep picks the keys in the windows from
 * each sixteen at once, their row and their x tested side by side, and compresses their
 * places into the kernel's list (nbs__cs_pick512); the other sweeps count each window's
 * edges among those keys (below, upto), as the AVX-512 one does elsewhere.
 * Why: in a sparse domain most rows hold a few elements, and a row swept by blocks waited
 * on finding its end, the cursor of each of its four neighbouring rows and each row's
 * window, one after the other, and most of those rows were empty; and a block's windows
 * span all its elements' x, most of a sparse row, so the kernel met elements out of reach
 * of every lane. Measured: see the file's comment, step 4. Rows of 4 or more stay with
 * blocks: from 5, 6 or 8 the benchmarks' sparse scene (fraction 0.005, rows of about 4.5
 * elements) was no faster, from 8 slower (search 18.8 -> 21.1 ns per element); and with
 * the windows' edges counted, not picked, so too from 4 (18.8 / 19.3) and 6 (19 -> 31). */
static inline __attribute__((always_inline)) nbs_status
nbs__cs_sweep3_body(const nbs__cs *c, nbs__sink *s, int32_t from, int32_t to,
                    nbs__cs_count_fn below, nbs__cs_count_fn upto, nbs__cs_back8_fn back8,
                    nbs__cs_pick_fn pick, bool listed) {
  nbs_status st = NBS_OK;
  const uint64_t *key = c->key;
  const int bx = c->bx, by = c->by, ks = c->ks, kx = bx + ks;
  const uint64_t my = ((uint64_t)1 << by) - 1;
  const uint64_t low = ((uint64_t)1 << ks) - 1, mx = ((uint64_t)1 << bx) - 1;
  const uint64_t fine = c->fine;
  const int64_t ny = c->ny;
  static const int row_dy[4] = {-1, 0, 1, -1}, row_dz[4] = {-1, -1, -1, 0};
  int32_t cur[4] = {-1, -1, -1, -1};
  /* where the last row's window in the row below it (dy = +1, dz = -1) ended (-1: none,
   * or the last row was short) */
  int32_t lq1 = -1;
  /* the last row begun, and its first place (-1: none yet in this range) */
  int32_t prev_a = -1;
  uint64_t prev_row = 0;
  /* the short rows' cursor in the layer below (-1: none yet in this range) */
  int32_t sc = -1;
  int32_t list[NBS__CS_SLICE + 16]; /* a short row's element's places, where listed */
  int32_t p = from;
  while (p < to && st == NBS_OK) {
    const uint64_t k = key[p] >> ks, row = k >> bx;
    const bool first = p == 0 || key[p - 1] >> kx != row;
    /* a thread's range that starts inside a row starts at one of its blocks, so the row is
     * a long one */
    const bool inside = p == from && !first;
    const int64_t iy = (int64_t)(row & my), iz = (int64_t)(row >> by);
    if ((first && key[p + NBS__CS_SHORT3 - 1] >> kx == row) || inside) {
      /* a long row: by blocks. Its start: p, unless a thread's range starts inside the row */
      const int32_t a = p;
      const int32_t a0 = inside ? nbs__cs_lower(key, a, row << kx) : a;
      /* its end: a loop by key, from the last place known to be in it (a 3D key may have
       * 64 bits, so the padding after the keys may be in the last row); it stops at `to` at
       * the latest */
      int32_t b = inside ? a + 1 : a + NBS__CS_SHORT3;
      if (b > to) b = to;
      while (b < to && key[b] >> kx == row) b++;
      /* the neighbouring rows: their first element (or -1: empty or outside) */
      uint64_t base[4];
      int32_t q0[4], q1[4];
      /* Row y, right after row y - 1 in its layer: its cursors at rows y - 1 and y of the
       * layer below are those row y - 1 had there, and the one at y + 1 starts where row
       * y - 1's window in row y ended, a few places before it. Each cursor moved from its
       * own place went over a whole row of the layer below for every row swept, sixteen keys
       * a step, each step waiting for the one before (3D, N = 1e6: search 15.4 -> 14.6 ns
       * per element). Tried first: each cursor from the furthest of the places known to lie
       * before its row, chosen for every row: the huge domain's search, whose rows seldom
       * follow one another, 16.1 -> 26.7. Selected without a branch (with one, the sparse
       * scene's search took 0.4 ns more). A short row before sets all three cursors to its
       * own, which lies before each of them. */
      {
        const bool next = (prev_a >= 0) & (row == prev_row + 1) & (row >> by == prev_row >> by);
        const int32_t c1 = cur[1], c2 = cur[2], l2 = lq1 > c2 ? lq1 : c2;
        cur[0] = next ? c1 : cur[0];
        cur[1] = next ? c2 : c1;
        cur[2] = next ? l2 : c2;
      }
      /* The three rows of the layer below, (y - 1, z - 1) to (y + 1, z - 1), are consecutive
       * in key order: where the first key from the first of them on lies past the third, all
       * three are empty, and one cursor's step finds it, where each row's took its own (and
       * its own check of what it found). A sparse scene's rows find them so nearly always; a
       * crowded one's seldom, at the cost of one more step per row of many elements (3D,
       * N = 1e6, one thread, interleaved, medians of 5, search in ns per element: huge domain
       * 15.32 -> 10.02, two threads 7.95 -> 5.25; uniform 13.81 / 13.63, sparse 14.29 /
       * 14.35, clustered 13.75 / 13.86; the same bytes). */
      int r0 = 0;
      if (iz >= 1 && iy >= 1 && iy + 1 < ny && cur[0] >= 0) {
        const uint64_t trow = (uint64_t)(iz - 1) << by | (uint64_t)(iy - 1);
        int32_t q = cur[0];
        NBS__CS_ADVANCE(key, q, below, trow << bx << ks);
        cur[0] = q;
        if (key[q] >> kx > trow + 2) {
          cur[1] = cur[2] = q;
          q0[0] = q0[1] = q0[2] = -1;
          r0 = 3;
        }
      }
      for (int r = r0; r < 4; r++) {
        q0[r] = -1;
        const int64_t y = iy + row_dy[r], z = iz + row_dz[r];
        if (y < 0 || y >= ny || z < 0) continue;
        const uint64_t trow = (uint64_t)z << by | (uint64_t)y;
        base[r] = trow << bx;
        int32_t q = cur[r];
        if (row_dz[r] == 0 && prev_a >= 0) {
          /* the row before in the same layer: the last row begun, if it is that row (else
           * the row is empty, and its window starts at a, whose keys are above it) */
          q = prev_row == trow ? prev_a : a;
        } else {
          /* first use: search, then forwards */
          if (q < 0) q = nbs__cs_lower(key, a, base[r] << ks);
          /* stops at a at the latest: its row > trow */
          NBS__CS_ADVANCE(key, q, below, base[r] << ks);
          cur[r] = q;
        }
        /* most of a sparse scene's neighbouring rows are empty, and the branch costs less
         * than the empty windows */
        if (key[q] >> kx == trow) q0[r] = q1[r] = q;
      }
      /* A row of one element whose four neighbouring rows are all empty (q0 < 0 in each:
       * their AND is negative) has nothing in reach: no call. nbs__cs_row_blocks finds the
       * same (its "nothing in reach" test), but only after its prefetches and set-up, at
       * every one of the huge domain's rows, most of which hold one element alone
       * (interleaved, medians, ns per element, the same bytes and candidates: 3D huge
       * domain, N = 1e6, search 17.25 -> 12.99, time steps 28.0 -> 23.9 in all, two threads
       * 16.2 -> 14.1; AVX2 17.86 -> 13.92, generic 21.89 -> 16.48; uniform, sparse and
       * clustered within noise). */
      if (b - a0 > 1 || (q0[0] & q0[1] & q0[2] & q0[3]) >= 0) {
        st = nbs__cs_row_blocks(c, s, a0, a, b, 4, base, q0, q1, below, upto, listed);
      }
      lq1 = q0[2] >= 0 ? q1[2] : -1;
      /* the short rows' cursor: the first place from row (y - 1, z - 1) on (or an older
       * one), which lies before the first of any later row's three rows below */
      sc = cur[0] > sc ? cur[0] : sc;
      prev_row = row;
      prev_a = a0;
      p = b;
      continue;
    }
    /* a short row: element p alone */
    prev_row = first ? row : prev_row;
    prev_a = first ? p : prev_a;
    if ((p & (NBS__CS_LANES - 1)) == 0 && p + NBS__CS_SWEEP_AHEAD < c->n) {
      nbs__cs_ask_own(c, p + NBS__CS_SWEEP_AHEAD);
    }
    const uint64_t x = k & mx;
    const uint64_t xl = x > fine ? x - fine : 0, xh = mx - x > fine ? x + fine : mx;
    /* The layer below: rows y0 = y - 1 .. y1 = y + 1 of z - 1 where they exist, their
     * windows x - fine .. x + fine, found from the cursor at the first key from row y0's
     * start on (not from its window's: where y0 is the row's own y, y = 0, the window of a
     * later element of the layer's next row starts further back in that row). */
    const int64_t y0 = iy >= 1 ? iy - 1 : iy, y1 = iy + 1 < ny ? iy + 1 : iy;
    const uint64_t lrow = (uint64_t)(iz - 1) << by;
    const uint64_t hi1 = ((lrow | (uint64_t)y1) << bx | xh) << ks | low;
    int32_t q = p;
    if (iz >= 1) {
      const uint64_t r0 = (lrow | (uint64_t)y0) << bx << ks;
      q = sc;
      if (q < 0) q = nbs__cs_lower(key, p, r0);
      NBS__CS_ADVANCE(key, q, below, r0); /* stops at p at the latest */
      sc = q;
      /* the rows below of a long row to come lie at or after it: its cursors */
      cur[0] = cur[1] = cur[2] = q;
      lq1 = -1;
    }
    /* anything from the first window on up to the last (below: key[q] is p's, in the
     * layer, past hi1, where there is no layer below), and all of it among the sixteen keys
     * from q */
    const bool down = iz >= 1 && key[q] <= hi1;
    const bool down_near = iz < 1 || key[q + NBS__CS_PAD - 1] > hi1;
    /* The layer's own rows: the row before (y - 1), x - fine .. x + fine (a word above `hb`
     * is past it), and the own row from x - fine on; anything in reach (the key before p),
     * and all of it among the sixteen keys before p. */
    const uint64_t own = (row << bx | xl) << ks;
    const uint64_t lb = ((row - 1) << bx | xl) << ks, hb = ((row - 1) << bx | xh) << ks | low;
    const uint64_t first_in = iy >= 1 ? lb : own;
    const bool back = p > 0 && key[p - 1] >= first_in;
    if (!down && !back) {
      p++;
      continue;
    }
    nbs__cs_ranges rg;
    rg.count = 0;
    rg.places = -1;
    rg.list = list;
    if (pick && down_near && p >= NBS__CS_PAD && key[p - NBS__CS_PAD] < first_in &&
        s->cap - s->count >= 2 * NBS__CS_PAD + 1 + NBS__CS_LANES) {
      /* With AVX-512 (the only sweep with a picker, and `listed`), where all of it lies
       * among those sixteen keys each side: the places of the keys in the windows, picked
       * from each sixteen at once (their row in range, their x in the window), in key
       * order, the list the kernel loops over; the one range that holds p tells the kernel
       * where the element is (the same pairs in the same order as from the ranges, below). */
      int32_t places = 0;
      if (down) places = pick(key, q, kx, ks, mx, lrow | (uint64_t)y0, (uint64_t)(y1 - y0), xl,
                              xh - xl, list, places);
      if (back) places = pick(key, p - NBS__CS_PAD, kx, ks, mx, iy >= 1 ? row - 1 : row,
                              iy >= 1 ? 1 : 0, xl, xh - xl, list, places);
      if (places > 0) {
        rg.places = places;
        rg.q0[0] = p;
        rg.q1[0] = p + 1;
        rg.count = 1;
        st = nbs__cs_offer(c, s, p, 1, &rg);
      }
      p++;
      continue;
    }
    if (down) {
      const bool near = down_near;
      for (int64_t y = y0; y <= y1; y++) {
        const uint64_t lo = ((lrow | (uint64_t)y) << bx | xl) << ks;
        const uint64_t hi = ((lrow | (uint64_t)y) << bx | xh) << ks | low;
        int32_t e0, e1;
        if (near) {
          e0 = q + below(key + q, lo);
          e1 = q + upto(key + q, hi);
        } else {
          e0 = q;
          NBS__CS_ADVANCE(key, e0, below, lo);
          e1 = e0;
          NBS__CS_ADVANCE(key, e1, upto, hi);
        }
        rg.q0[rg.count] = e0;
        rg.q1[rg.count] = e1;
        rg.count += e1 > e0;
      }
    }
    /* The places before p: from p - c1 on, keys from lb on; from p - c2, above hb; from
     * p - c3, in reach in the own row (c1 >= c2 >= c3: lb <= hb < own) */
    int32_t c1 = 0, c2 = 0, c3 = 0;
    if (back) nbs__cs_back(key, p, own, lb, hb, iy >= 1, below, upto, back8, &c1, &c2, &c3);
    rg.q0[rg.count] = p - c1;
    rg.q1[rg.count] = p - c2;
    rg.count += c1 > c2;
    rg.q0[rg.count] = p - c3;
    rg.q1[rg.count] = p + 1;
    if (rg.count > 0 || c3 > 0) {
      rg.count++;
      if (listed) {
        /* the places before p, for the AVX-512 kernel, which in 3D loops over a list */
        int32_t places = 0;
        for (int r = 0; r < rg.count; r++) {
          places = nbs__cs_list(list, places, rg.q0[r], r == rg.count - 1 ? p : rg.q1[r]);
        }
        rg.places = places;
      }
      st = nbs__cs_offer(c, s, p, 1, &rg);
    }
    p++;
  }
  return st;
}

/* A 2D row of fewer elements than this is swept element by element (nbs__cs_sweep2_body);
 * at most NBS__CS_PAD + 1, for the padding after the keys. */
#define NBS__CS_SHORT 4

/* 2D: sweeps the places [from, to) of the cell order (from and to at rows' starts or at
 * blocks of a long row: nbs__cs_thread_start), with the one neighbouring row of the half
 * mask, the row below (dy = -1).
 * A row of NBS__CS_SHORT elements or more is swept by its blocks (nbs__cs_row_blocks). A
 * shorter one, element by element: element p meets the elements before it in its own row
 * within one cell edge in x (sub-cells x - fine .. x), and those of the row below within one
 * edge either side (x - fine .. x + fine). All of them lie in the cell order between the
 * first key from (row - 1, x - fine) on and p, so three counts of the sixteen keys before p
 * find both ranges, with no search and no state carried from one element to the next;
 * further back (more than sixteen keys in reach) a binary search does.
 * Why: a sparse domain's rows hold an element or two (2D huge domain, 1e12 cells for 1e6
 * elements: 0.63 rows per element), and a row cost about 13 ns in blocks: finding its end,
 * the row below and the windows, each waiting on the one before. Element by element, the
 * counts of an element do not wait on those of the one before. */
static inline __attribute__((always_inline)) nbs_status
nbs__cs_sweep2_body(const nbs__cs *c, nbs__sink *s, int32_t from, int32_t to,
                    nbs__cs_count_fn below, nbs__cs_count_fn upto, nbs__cs_back8_fn back8,
                    bool listed) {
  nbs_status st = NBS_OK;
  const uint64_t *key = c->key;
  const int bx = c->bx, ks = c->ks, kx = bx + ks;
  const uint64_t low = ((uint64_t)1 << ks) - 1, mx = ((uint64_t)1 << bx) - 1;
  const uint64_t rowlow = ((uint64_t)1 << kx) - 1;
  const uint64_t fine = c->fine;
  /* the last row begun, and its first place (-1: none yet in this range) */
  uint64_t last_row = 0;
  int32_t last_a = -1;
  int32_t p = from;
  while (p < to && st == NBS_OK) {
    const uint64_t k = key[p] >> ks, row = k >> bx, x = k & mx;
    /* a 2D key has at most 63 bits, so the padding (all ones) after the keys is in no
     * row, and a key past `to` is in a later row, or in a long row that a thread's range
     * ends inside (its blocks are cut at `to` below) */
    const bool first = p == 0 || key[p - 1] >> kx != row;
    /* a thread's range that starts inside a row starts at one of its blocks, so the row is
     * a long one */
    const bool inside = p == from && !first;
    if ((first && key[p + NBS__CS_SHORT - 1] >> kx == row) || inside) {
      /* a long row: by blocks. Its end, sixteen keys at a time (a loop by key
       * mispredicts its exit once per row). The row below (row = iy in 2D): the last row
       * begun, if it is that row, else empty, its window starting at p (whose keys are
       * above it); a range's first row searches. */
      const int32_t a0 = inside ? nbs__cs_lower(key, p, row << kx) : p;
      int32_t b = inside ? p + 1 : p + NBS__CS_SHORT;
      NBS__CS_ADVANCE(key, b, upto, row << kx | rowlow);
      if (b > to) b = to; /* a thread's range that ends inside the row */
      uint64_t base[1] = {0};
      int32_t q0[1] = {-1}, q1[1] = {-1};
      if (row > 0) {
        base[0] = (row - 1) << bx;
        const int32_t q = last_a < 0            ? nbs__cs_lower(key, p, base[0] << ks)
                          : last_row == row - 1 ? last_a
                                                : p;
        q0[0] = q1[0] = q;
      }
      st = nbs__cs_row_blocks(c, s, a0, p, b, 1, base, q0, q1, below, upto, listed);
      last_row = row;
      last_a = a0;
      p = b;
      continue;
    }
    last_row = first ? row : last_row;
    last_a = first ? p : last_a;
    if ((p & (NBS__CS_LANES - 1)) == 0 && p + NBS__CS_SWEEP_AHEAD < c->n) {
      nbs__cs_ask_own(c, p + NBS__CS_SWEEP_AHEAD);
    }
    /* bounds on the words: the own row from x - fine on; the row below, x - fine .. x +
     * fine (a word above `hb` is past it) */
    const uint64_t xl = x > fine ? x - fine : 0, xh = mx - x > fine ? x + fine : mx;
    const uint64_t own = (row << bx | xl) << ks;
    const uint64_t lb = ((row - 1) << bx | xl) << ks, hb = ((row - 1) << bx | xh) << ks | low;
    /* the places before p: from p - c1 on, keys from lb on; from p - c2, above hb; from
     * p - c3, in reach in the own row (c1 >= c2 >= c3: lb <= hb < own) */
    int32_t c1, c2, c3;
    nbs__cs_back(key, p, own, lb, hb, row > 0, below, upto, back8, &c1, &c2, &c3);
    if (c1 > c2 || c3 > 0) {
      nbs__cs_ranges rg;
      rg.q0[0] = p - c1;
      rg.q1[0] = p - c2;
      rg.count = c1 > c2;
      rg.q0[rg.count] = p - c3;
      rg.q1[rg.count] = p + 1;
      rg.count++;
      rg.places = -1;
      st = nbs__cs_offer(c, s, p, 1, &rg);
    }
    p++;
  }
  return st;
}

/* The sweep of the places [from, to) of the cell order, into `out`: 2D or 3D. */
static inline __attribute__((always_inline)) nbs_status
nbs__cs_sweep_body(const nbs__cs *c, nbs__sink *out, int32_t from, int32_t to,
                   nbs__cs_count_fn below, nbs__cs_count_fn upto, nbs__cs_back8_fn back8,
                   nbs__cs_pick_fn pick, bool listed) {
  nbs__sink local = *out; /* kept in registers, written back at the end */
  const nbs_status st =
      c->dim == 2 ? nbs__cs_sweep2_body(c, &local, from, to, below, upto, back8, listed)
                  : nbs__cs_sweep3_body(c, &local, from, to, below, upto, back8, pick, listed);
  *out = local;
  return st;
}

/* The sweep, compiled once per kernel: with the plain counters, and for AVX-512 and AVX2
 * with their vector ones (the function pointers are constants, so the compiler inlines
 * them); for AVX-512, the ranges' places listed (`listed`, see nbs__cs_ranges). */
static nbs_status nbs__cs_sweep_generic(const nbs__cs *c, nbs__sink *out, int32_t from,
                                        int32_t to) {
  return nbs__cs_sweep_body(c, out, from, to, nbs__cs_below, nbs__cs_upto, NULL, NULL, false);
}
#if NBS__CS_AVX512
NBS__CS_AVX512_TARGET NBS__CS_HOT
static nbs_status nbs__cs_sweep_avx512(const nbs__cs *c, nbs__sink *out, int32_t from, int32_t to) {
  return nbs__cs_sweep_body(c, out, from, to, nbs__cs_below512, nbs__cs_upto512,
                            nbs__cs_back8_512, nbs__cs_pick512, true);
}
NBS__CS_AVX2_TARGET
static nbs_status nbs__cs_sweep_avx2(const nbs__cs *c, nbs__sink *out, int32_t from, int32_t to) {
  return nbs__cs_sweep_body(c, out, from, to, nbs__cs_below256, nbs__cs_upto256,
                            nbs__cs_back8_256, NULL, false);
}
#endif

static nbs_status nbs__cs_sweep(const nbs__cs *c, nbs__sink *out, int32_t from, int32_t to) {
#if NBS__CS_AVX512
  if (c->run->ctx->simd == NBS__SIMD_AVX512) return nbs__cs_sweep_avx512(c, out, from, to);
  if (c->run->ctx->simd == NBS__SIMD_AVX2) return nbs__cs_sweep_avx2(c, out, from, to);
#endif
  return nbs__cs_sweep_generic(c, out, from, to);
}

/* Where a chunk's pairs lie: sinks[sink].buf + at, count of them (offsets, not pointers:
 * a sink's list may move as it grows). */
typedef struct nbs__cs_seg {
  int32_t sink;
  size_t at, count;
} nbs__cs_seg;

/* The most chunks of a threaded sweep (nbs__cs_sweep_parts), all parts together. */
#define NBS__CS_SEGS 256

#if defined(_OPENMP)
/* Where the part of the sweep that would start at place p starts: at p's row's start, or,
 * in a row longer than a block, at the last of the row's blocks that starts at or before p
 * (blocks of NBS__CS_LANES places from the row's start). The blocks are those of one
 * thread, and so are the pairs, in their order: a thread that starts inside a row finds the
 * row's start, its own window and the neighbouring rows' by search (a 2D row it starts
 * inside is long: nbs__cs_sweep2_body sweeps it by blocks). Parts cut at rows' starts only
 * left a scene of few, long rows to one thread: a 2D strip two diameters wide has three or
 * four rows along its length (N = 1e6, the scene `slab`, interleaved, min of 5: one thread
 * 14.5 ns per element, two 12.97 -> 10.79, 1.12x -> 1.34x; a uniform square and cube the
 * same, 9.41 and 9.59, 18.10 and 18.14). Tried and left out: the key pass, the gather and
 * the buckets' sorts taken by the threads a part at a time rather than a fixed half each
 * (schedule(dynamic); perf showed one core slower than the other at times): the same or
 * slower (square 9.81, cube 18.08, strip 10.73). */
static int32_t nbs__cs_thread_start(const nbs__cs *c, int32_t p) {
  if (p <= 0 || p >= c->n) return p;
  const int kx = c->bx + c->ks;
  const int32_t a = nbs__cs_lower(c->key, p, c->key[p] >> kx << kx);
  return a + (p - a) / NBS__CS_LANES * NBS__CS_LANES;
}

/* The most chunks of a part of the threaded sweep, and the fewest places of a chunk (each
 * chunk's start costs a search of the rows' windows, as a thread's does). */
#define NBS__CS_CHUNKS 32
#define NBS__CS_CHUNK_MIN 8192

/* Chunks [k, k + many), the places [bound[k], bound[k + many]), swept into sinks[sink];
 * where their pairs lie to seg[k] (seg[k + 1 ..] hold none). False if the sink failed (no
 * memory for its list). */
static bool nbs__cs_sweep_chunk(const nbs__cs *c, nbs__sink *sinks, int32_t sink,
                                const int32_t *bound, int k, int many, nbs__cs_seg *seg) {
  nbs__sink *s = &sinks[sink];
  const size_t at = s->count;
  if (bound[k] < bound[k + many]) s->status = nbs__cs_sweep(c, s, bound[k], bound[k + many]);
  for (int j = 0; j < many; j++) {
    seg[k + j].sink = sink;
    seg[k + j].at = at;
    seg[k + j].count = j == 0 ? s->count - at : 0;
  }
  return s->status == NBS_OK;
}

/* The sweep with threads. The cell order is cut into `threads` parts of about equal places
 * (at nbs__cs_thread_start's places), and each part into chunks the same way; part t is
 * thread t's (NBS__PARTS). A thread sweeps its part's chunks from the front, then takes
 * chunks from the back of the part with the most chunks left, until none is left
 * (nbs__share): where one core runs slower than the other (on this machine's virtual
 * processors, by up to a half at times: the same detection pinned to each, taskset), the
 * faster one takes on part of the slower one's share, where the even halves waited for the
 * slower one. Each chunk's
 * pairs go to the list of the part's owner (the run's own list for part 0), or, taken from
 * another part, to the taker's (thread 0's: sinks[threads]), and segs says where: the
 * pairs are the same in the same order whoever sweeps a chunk, since chunks are cut where
 * threads' ranges were. The run's list holds part 0's first chunks in place; the segments
 * of the rest, in order, are compacted to the front of segs, and their number returned.
 * Measured (N = 1e6, two threads, interleaved with the even halves, medians of 4, ns per
 * element, the same hashes): idle, 3D 15.22 / 15.30 (search 7.66 / 7.79), 2D 8.90 / 8.67;
 * with a busy loop pinned to the second core (taskset -c 1), 3D 28.06 -> 25.28 (search
 * 15.72 -> 9.87), 2D 17.01 -> 15.74; on a spell of this machine whose second core ran the
 * detection 1.45x slower than the first (no load of ours), 3D 22.3 -> 19.1-19.9 (search
 * 12.1-12.6 -> 9.1-10.1, min of 4). Chunks of one per claim from the front cost the
 * search 7% idle (3D 7.41 -> 7.92, 2D 2.95 -> 3.18): the owner claims half of what is left.
 * Tried and left out: the gather's loop by chunks of 16,384 (schedule(dynamic)): idle the
 * same in 3D (15.57 / 15.59) and 2D 0.3 ns slower, on the slower spell 0.9 faster. */
static int nbs__cs_sweep_parts(const nbs__cs *c, nbs__sink *sinks, int threads,
                               nbs__cs_seg *segs) {
  nbs_context *ctx = c->run->ctx;
  int stolen = 0;
  const int32_t n = c->n;
  int chunks = n / threads / NBS__CS_CHUNK_MIN;
  if (chunks > NBS__CS_SEGS / threads) chunks = NBS__CS_SEGS / threads;
  if (chunks > NBS__CS_CHUNKS) chunks = NBS__CS_CHUNKS;
  if (chunks < 1) chunks = 1;
  const int total = threads * chunks;
  int32_t bound[NBS__CS_SEGS + 1];
  for (int k = 0; k <= total; k++) bound[k] = nbs__cs_thread_start(c, nbs__chunk(n, k, total));
  uint32_t cut[NBS__THREADS_MAX + 1];
  for (int t = 0; t <= threads; t++) cut[t] = (uint32_t)(t * chunks);
  nbs__share sh;
  nbs__share_init(&sh, threads, cut, ctx->cs_steal_first);
  memset(segs, 0, (size_t)total * sizeof *segs); /* a failed sweep leaves chunks undone */
#pragma omp parallel num_threads(threads) reduction(+ : stolen)
  {
    bool failed = false;
    const int me = nbs__thread_num();
    const int32_t mine = me == 0 ? threads : me; /* the list of the chunks it takes */
    uint32_t a, b;
    bool taken;
    NBS__PARTS(t, threads) {
      for (int stage = 0; !failed && nbs__share_next(&sh, t, &stage, 1, true, &a, &b, &taken);) {
        failed = !nbs__cs_sweep_chunk(c, sinks, taken ? mine : t, bound, (int)a, (int)(b - a),
                                      segs);
        stolen += taken;
      }
    }
  }
  ctx->cs_stolen = stolen;
  int m = 0;
  for (int k = 0; k < total; k++) {
    if (segs[k].sink != 0 && segs[k].count > 0) segs[m++] = segs[k];
  }
  return m;
}
#endif

/* Whether an element of the input x may lie across two cache lines: 24 bytes in 3D, 16 in
 * 2D off a 16-byte boundary. */
static inline bool nbs__cs_ends(const double *x, int dim) {
  return dim == 3 || (uintptr_t)x % 16 != 0;
}

/* The gather's prefetches for element `far` (NBS__CS_AHEAD places ahead: into L2, locality
 * 1, which on this processor does not hold an L1 miss buffer while memory answers) and
 * element `near` (NBS__CS_NEAR ahead: into L1, from L2 by then), both ends of each (in 3D a
 * quarter of the elements straddle two lines), and their radii. Measured (one thread,
 * random order, interleaved, min of 4, ns per element) against one prefetch into L1 128
 * places ahead: N = 1e6 3D 37.5 -> 32.7, 2D 21.2 -> 18.8, two threads 3D 19.4 -> 18.0,
 * sparse 46.4 -> 41.4; N = 1e4, where nothing waits on memory, 24.5 -> 25.5 (since then
 * inputs of at most NBS__CS_PREFETCH_MIN are gathered without prefetches); time steps
 * (the warm pass, whose input the step has just written) the same, 32.3 and 32.8. A
 * random gather alone (1e6 elements of 24 bytes, a test program) went from 9.1 to 4.5 ns
 * per element; distances 128-512 and 16-48 were all within noise.
 * The far end only where an element may straddle two lines (nbs__cs_ends): in 3D, and in 2D
 * where the input is not on a 16-byte boundary; in 2D on one, each element lies in one line
 * and the second prefetch only cost (2D, N = 1e6, interleaved, min of 8, two runs: 18.9-19.5
 * -> 18.6-18.9 ns per element, time steps of 1e-3 14.5-14.9 -> 13.9-14.1; 3D the same code,
 * 32.6 / 32.6).
 * always_inline: GCC 12 treats a function of nothing but prefetches as having no effect,
 * and as a plain static inline one this was removed from the gather whole. */
static inline __attribute__((always_inline)) void
nbs__cs_prefetch(const double *x, const double *r, int dim, bool ends, int32_t far,
                 int32_t near) {
  __builtin_prefetch(x + (size_t)far * (size_t)dim, 0, 1);
  if (ends) __builtin_prefetch(x + (size_t)far * (size_t)dim + (dim - 1), 0, 1);
  __builtin_prefetch(x + (size_t)near * (size_t)dim);
  if (ends) __builtin_prefetch(x + (size_t)near * (size_t)dim + (dim - 1));
  if (r) {
    __builtin_prefetch(r + far, 0, 1);
    __builtin_prefetch(r + near);
  }
}

/* How a cell key is made from an element's coordinates: (iz, iy, x sub-cell), iz highest,
 * where the key's x, y and z are the coordinates c[0], c[1], c[2] (see nbs__cellsort: the
 * rows lie along the axis with the most cells). x counts sub-cells: (x - lo) * (fine /
 * edge), the same roundings as nbs__cell's (the scaling by a power of two is exact), so the
 * argument of input.c holds with windows of `fine` sub-cells: |dx| <= edge(1 - margin)
 * stays within them. */
typedef struct nbs__cs_keying {
  const nbs__grid *g; /* its axes in the key's order */
  double lo_x, inv_fine;
  int c[3];        /* the coordinate of the key's x, y and z */
  int dim, sy, sz; /* where iy and iz start in the key */
} nbs__cs_keying;

static inline uint64_t nbs__cs_cellkey(const nbs__cs_keying *kg, const double *xk) {
  const uint64_t ix = (uint64_t)((xk[kg->c[0]] - kg->lo_x) * kg->inv_fine);
  const uint64_t iy = (uint64_t)nbs__cell_of(kg->g, xk[kg->c[1]], 1);
  const uint64_t iz = kg->dim == 3 ? (uint64_t)nbs__cell_of(kg->g, xk[kg->c[2]], 2) : 0;
  return iz << kg->sz | iy << kg->sy | ix;
}

/* The changed lanes ne (a bit per lane) of the keys kk of elements e, e + 1, ...: each one's
 * old word keys[e + l] << 32 | (e + l) to r, its new one to s (*m of them so far), and
 * keys[e + l] the new key; false past `share` of them. The SIMD key passes' common tail
 * (nbs__cs_note8, nbs__cs_changed256_body). */
static inline bool nbs__cs_note_lanes(const uint32_t *kk, unsigned ne, uint32_t *keys, int32_t e,
                                      uint64_t *r, uint64_t *s, int64_t *m, int64_t share) {
  for (; ne; ne &= ne - 1) {
    const int l = __builtin_ctz(ne);
    if (*m == share) return false;
    r[*m] = (uint64_t)keys[e + l] << 32 | (uint64_t)(e + l);
    s[(*m)++] = (uint64_t)kk[l] << 32 | (uint64_t)(e + l);
    keys[e + l] = kk[l];
  }
  return true;
}

#if NBS__CS_AVX512
/* nbs__cs_cellkey for 8 consecutive elements at once (AVX-512: F, DQ), the same operations
 * in the same order (a subtraction, a multiplication, a truncation: the same keys bit for
 * bit). The 8 elements' coordinates, 3 (2D: 2) registers as they lie in the input, are
 * sorted out by two permutations per key axis (2D: one). */
typedef struct nbs__cs_keys8 {
  __m512i i1[3], i2[3]; /* per key axis: from the first two registers, then the third */
  __m512d lo[3], inv[3];
  __m128i sy, sz;
} nbs__cs_keys8;

static inline NBS__CS_AVX512_TARGET void nbs__cs_keys8_init(nbs__cs_keys8 *v,
                                                          const nbs__cs_keying *kg) {
  const int dim = kg->dim;
  for (int a = 0; a < dim; a++) {
    int64_t i1[8], i2[8];
    for (int j = 0; j < 8; j++) {
      const int at = dim * j + kg->c[a]; /* the place of element j's coordinate */
      i1[j] = at < 16 ? at : 0;
      i2[j] = at < 16 ? j : 8 + (at - 16);
    }
    v->i1[a] = _mm512_loadu_si512((const void *)i1);
    v->i2[a] = _mm512_loadu_si512((const void *)i2);
    v->lo[a] = _mm512_set1_pd(a == 0 ? kg->lo_x : kg->g->lo[a]);
    v->inv[a] = _mm512_set1_pd(a == 0 ? kg->inv_fine : kg->g->inv_edge);
  }
  v->sy = _mm_cvtsi32_si128(kg->sy);
  v->sz = _mm_cvtsi32_si128(kg->sz);
}

/* The 8 elements' coordinates of each key axis (c) and their cell positions (t: x in
 * sub-cells), before truncation, for the elements whose coordinates start at x8. */
static inline __attribute__((always_inline)) NBS__CS_AVX512_TARGET void
nbs__cs_pos8(const nbs__cs_keys8 *v, const double *x8, int dim, __m512d c[3], __m512d t[3]) {
  const __m512d r0 = _mm512_loadu_pd(x8), r1 = _mm512_loadu_pd(x8 + 8);
  for (int a = 0; a < dim; a++) {
    c[a] = _mm512_permutex2var_pd(r0, v->i1[a], r1);
    if (dim == 3) c[a] = _mm512_permutex2var_pd(c[a], v->i2[a], _mm512_loadu_pd(x8 + 16));
    t[a] = _mm512_mul_pd(_mm512_sub_pd(c[a], v->lo[a]), v->inv[a]);
  }
}

/* The keys of those positions. */
static inline __attribute__((always_inline)) NBS__CS_AVX512_TARGET __m512i
nbs__cs_key8_of(const nbs__cs_keys8 *v, const __m512d t[3], int dim) {
  const __m512i ix = _mm512_cvttpd_epu64(t[0]);
  const __m512i iy = _mm512_cvtepi32_epi64(_mm512_cvttpd_epi32(t[1]));
  __m512i k = _mm512_or_si512(ix, _mm512_sll_epi64(iy, v->sy));
  if (dim == 3) {
    const __m512i iz = _mm512_cvtepi32_epi64(_mm512_cvttpd_epi32(t[2]));
    k = _mm512_or_si512(k, _mm512_sll_epi64(iz, v->sz));
  }
  return k;
}

/* The 8 keys k of elements e, e + 1, ... against keys[]: each changed one's old word to r,
 * its new one to s (m of them so far), and keys[] updated; false past `share` of them. */
static inline __attribute__((always_inline)) NBS__CS_AVX512_TARGET bool
nbs__cs_note8(__m256i k, uint32_t *keys, int32_t e, uint64_t *r, uint64_t *s, int64_t *m,
              int64_t share) {
  unsigned ne = _mm256_cmpneq_epi32_mask(k, _mm256_loadu_si256((const void *)(keys + e)));
  if (ne == 0) return true;
  uint32_t kk[8];
  _mm256_storeu_si256((void *)kk, k);
  return nbs__cs_note_lanes(kk, ne, keys, e, r, s, m, share);
}

#endif

/* Step 1 of nbs__cs_rekey for the elements [from, to), the m changed keys before them
 * already found: each element's key again, against keys[e]; a changed one's old word to r,
 * its new one to s, and keys[e] the new key. Returns the number of changed keys, or -1 past
 * `share` of them. In a time step it reads the input in place of input.c's pass
 * (nbs__cellsort_step), with the last detection's keying, which this detection's may not
 * be: an element may lie outside that keying's box (below its origin, or past the bits of a
 * key's field), or a coordinate may not be finite. Each element's cell positions are
 * therefore checked to lie in the box before they become integers (a conversion out of
 * range is undefined in C); the first that does not stops the pass (NBS__CS_OUT). With the
 * detection's own keying every element lies in its box. Meanwhile it measures the
 * coordinates' bounding box, as input.c's pass does, into box. */
#define NBS__CS_OUT (-2)
/* The partition's counts of the keys' top digit (key >> shift & mask) into h, where the
 * pass over the input that makes the words makes them instead (nbs__cellsort_fresh). */
typedef struct nbs__cs_tally {
  uint32_t *h;
  int shift;
  uint64_t mask;
} nbs__cs_tally;
typedef struct nbs__cs_box {
  double lo[3], hi[3];
} nbs__cs_box;

/* A box that holds nothing yet. */
static void nbs__cs_box_clear(nbs__cs_box *box) {
  for (int a = 0; a < 3; a++) {
    box->lo[a] = DBL_MAX;
    box->hi[a] = -DBL_MAX;
  }
}

/* The box of the threads' boxes, to lo and hi (0 past dim). */
static void nbs__cs_boxes_join(const nbs__cs_box *boxes, int threads, int dim, double lo[3],
                               double hi[3]) {
  for (int a = 0; a < 3; a++) {
    lo[a] = a < dim ? boxes[0].lo[a] : 0.0;
    hi[a] = a < dim ? boxes[0].hi[a] : 0.0;
    for (int t = 1; t < threads && a < dim; t++) {
      if (boxes[t].lo[a] < lo[a]) lo[a] = boxes[t].lo[a];
      if (boxes[t].hi[a] > hi[a]) hi[a] = boxes[t].hi[a];
    }
  }
}

/* The keying's box for packed words key << eb | element: how far each of the key's fields
 * reaches (x in sub-cells; the top field as far as a key of 63 - eb bits, 31 with eb = 32, the
 * words' high half, and a cell of at most 2^31, an int32's). */
static void nbs__cs_box_limits(const nbs__cs_keying *kg, int eb, double lim[3]) {
  const int top = kg->dim == 3 ? kg->sz : kg->sy;
  const int tb = 63 - eb - top < 31 ? 63 - eb - top : 31; /* the top field's bits */
  lim[0] = ldexp(1.0, kg->sy);
  lim[1] = kg->dim == 3 ? ldexp(1.0, kg->sz - kg->sy) : ldexp(1.0, tb);
  lim[2] = ldexp(1.0, tb);
}

/* The keying's box and the terms of its keys, for the passes that check each element in
 * it (nbs__cs_key_boxed). */
typedef struct nbs__cs_check {
  double lim[3], lo[3], inv[3];
  int shift[3];
} nbs__cs_check;

static nbs__cs_check nbs__cs_check_of(const nbs__cs_keying *kg, int eb) {
  nbs__cs_check ck;
  nbs__cs_box_limits(kg, eb, ck.lim);
  const double lo[3] = {kg->lo_x, kg->g->lo[1], kg->g->lo[2]};
  const double inv[3] = {kg->inv_fine, kg->g->inv_edge, kg->g->inv_edge};
  const int shift[3] = {0, kg->sy, kg->sz};
  for (int a = 0; a < 3; a++) {
    ck.lo[a] = lo[a];
    ck.inv[a] = inv[a];
    ck.shift[a] = shift[a];
  }
  return ck;
}

/* The key of the element at xk, as nbs__cs_cellkey computes it, to *k, and its coordinates
 * into box; false if it lies outside the keying's box, or a coordinate is not finite. */
static inline bool nbs__cs_key_boxed(const nbs__cs_keying *kg, const nbs__cs_check *ck,
                                     const double *xk, int dim, nbs__cs_box *box, uint64_t *k) {
  uint64_t key = 0;
  for (int a = 0; a < dim; a++) {
    const double v = xk[kg->c[a]];
    const double t = (v - ck->lo[a]) * ck->inv[a]; /* as nbs__cs_cellkey and nbs__cell_of */
    if (!(t >= 0.0 && t < ck->lim[a])) return false; /* NaN too */
    key |= (uint64_t)t << ck->shift[a];
    const int c = kg->c[a];
    if (v < box->lo[c]) box->lo[c] = v;
    if (v > box->hi[c]) box->hi[c] = v;
  }
  *k = key;
  return true;
}

static inline int64_t nbs__cs_changed(const nbs__cs_keying *kg, const double *x, int dim,
                                          int32_t from, int32_t to, uint32_t *keys,
                                          uint64_t *r, uint64_t *s, int64_t m, int64_t share,
                                          nbs__cs_box *box) {
  const nbs__cs_check ck = nbs__cs_check_of(kg, 32); /* the time steps' keys: eb = 32 */
  for (int32_t e = from; e < to; e++) {
    uint64_t k;
    if (!nbs__cs_key_boxed(kg, &ck, x + (size_t)e * (size_t)dim, dim, box, &k)) {
      return NBS__CS_OUT;
    }
    if ((uint32_t)k != keys[e]) {
      if (m == share) return -1;
      r[m] = (uint64_t)keys[e] << 32 | (uint64_t)e;
      s[m++] = k << 32 | (uint64_t)e;
      keys[e] = (uint32_t)k;
    }
  }
  return m;
}

#if NBS__CS_AVX512
/* nbs__cs_key_boxed for 8 elements at a time: their box so far, per lane. */
typedef struct nbs__cs_box8 {
  __m512d lim[3], lo[3], hi[3];
} nbs__cs_box8;

static inline __attribute__((always_inline)) NBS__CS_AVX512_TARGET void
nbs__cs_box8_init(nbs__cs_box8 *b, const nbs__cs_keying *kg, int eb) {
  double lim[3];
  nbs__cs_box_limits(kg, eb, lim);
  for (int a = 0; a < 3; a++) {
    b->lim[a] = _mm512_set1_pd(lim[a]);
    b->lo[a] = _mm512_set1_pd(DBL_MAX);
    b->hi[a] = _mm512_set1_pd(-DBL_MAX);
  }
}

/* The 8 elements at x8: their cell positions to t (as nbs__cs_pos8), their coordinates
 * into the box; false if one lies outside the keying's box, or a coordinate is not
 * finite. */
static inline __attribute__((always_inline)) NBS__CS_AVX512_TARGET bool
nbs__cs_box8_pos(nbs__cs_box8 *b, const nbs__cs_keys8 *v, const double *x8, int dim,
                 __m512d t[3]) {
  __m512d c[3];
  nbs__cs_pos8(v, x8, dim, c, t);
  __mmask8 in = 0xFF;
  for (int a = 0; a < dim; a++) {
    in &= _mm512_cmp_pd_mask(t[a], _mm512_setzero_pd(), _CMP_GE_OQ) &
          _mm512_cmp_pd_mask(t[a], b->lim[a], _CMP_LT_OQ); /* NaN fails both */
    b->lo[a] = _mm512_min_pd(b->lo[a], c[a]);
    b->hi[a] = _mm512_max_pd(b->hi[a], c[a]);
  }
  return in == 0xFF;
}

/* The lanes' box into box. */
static inline __attribute__((always_inline)) NBS__CS_AVX512_TARGET void
nbs__cs_box8_done(const nbs__cs_box8 *b, const nbs__cs_keying *kg, int dim, nbs__cs_box *box) {
  for (int a = 0; a < dim; a++) {
    const int ca = kg->c[a];
    const double l = _mm512_reduce_min_pd(b->lo[a]), h = _mm512_reduce_max_pd(b->hi[a]);
    if (l < box->lo[ca]) box->lo[ca] = l;
    if (h > box->hi[ca]) box->hi[ca] = h;
  }
}
#endif

#if NBS__CS_AVX512
/* The same 8 elements at a time, the keys as nbs__cs_key8 computes them. */
static inline __attribute__((always_inline)) NBS__CS_AVX512_TARGET int64_t
nbs__cs_changed512_body(const nbs__cs_keying *kg, const double *x, int dim, int32_t from,
                            int32_t to, uint32_t *keys, uint64_t *r, uint64_t *s,
                            int64_t share, nbs__cs_box *box) {
  nbs__cs_keys8 v;
  nbs__cs_keys8_init(&v, kg);
  nbs__cs_box8 b;
  nbs__cs_box8_init(&b, kg, 32);
  int64_t m = 0;
  int32_t e = from;
  for (; to - e >= 8; e += 8) {
    __m512d t[3];
    if (!nbs__cs_box8_pos(&b, &v, x + (size_t)e * (size_t)dim, dim, t)) return NBS__CS_OUT;
    const __m256i k = _mm512_cvtepi64_epi32(nbs__cs_key8_of(&v, t, dim));
    if (!nbs__cs_note8(k, keys, e, r, s, &m, share)) return -1;
  }
  nbs__cs_box8_done(&b, kg, dim, box);
  return nbs__cs_changed(kg, x, dim, e, to, keys, r, s, m, share, box);
}

NBS__CS_AVX512_TARGET
static int64_t nbs__cs_changed512(const nbs__cs_keying *kg, const double *x, int32_t from,
                                      int32_t to, uint32_t *keys, uint64_t *r, uint64_t *s,
                                      int64_t share, nbs__cs_box *box) {
  if (kg->dim == 3) {
    return nbs__cs_changed512_body(kg, x, 3, from, to, keys, r, s, share, box);
  }
  return nbs__cs_changed512_body(kg, x, 2, from, to, keys, r, s, share, box);
}
#endif

/* Step 1 of a sort from scratch (the packed words key << eb | e of the elements [from,
 * to)) in input.c's place, before the grid is known (nbs__cellsort_fresh): with a keying
 * guessed from a sample, each element checked to lie in that keying's box, as
 * nbs__cs_changed checks it, and the coordinates' bounding box measured into box. False at
 * the first element outside the box, or with a coordinate that is not finite. With a tally
 * (ty, not NULL), the partition's first pass instead: each key's top digit counted into
 * ty->h, which holds the counts so far, and no words written (nbs__cs_partition). */
static bool nbs__cs_words_boxed(const nbs__cs_keying *kg, const double *x, int dim, int32_t from,
                                int32_t to, int eb, uint64_t *k0, nbs__cs_box *box,
                                const nbs__cs_tally *ty) {
  const nbs__cs_check ck = nbs__cs_check_of(kg, eb);
  for (int32_t e = from; e < to; e++) {
    uint64_t k;
    if (!nbs__cs_key_boxed(kg, &ck, x + (size_t)e * (size_t)dim, dim, box, &k)) return false;
    if (ty) {
      ty->h[(k >> ty->shift) & ty->mask]++;
    } else {
      k0[e] = k << eb | (uint64_t)e;
    }
  }
  return true;
}

#if NBS__CS_AVX512
/* The same 8 elements at a time, the keys as nbs__cs_key8 computes them; with `boxed`
 * false, the words alone, unchecked (step 1 after input.c's pass: nbs__cs_words512). */
static inline __attribute__((always_inline)) NBS__CS_AVX512_TARGET bool
nbs__cs_words512_body(const nbs__cs_keying *kg, const double *x, int dim, int32_t from,
                      int32_t to, int eb, uint64_t *k0, bool boxed, nbs__cs_box *box,
                      const nbs__cs_tally *ty) {
  nbs__cs_keys8 v;
  nbs__cs_keys8_init(&v, kg);
  nbs__cs_box8 b;
  if (boxed) nbs__cs_box8_init(&b, kg, eb);
  const __m128i sh = _mm_cvtsi32_si128(eb);
  const __m512i eight = _mm512_set1_epi64(8);
  __m512i ks = _mm512_add_epi64(_mm512_set_epi64(7, 6, 5, 4, 3, 2, 1, 0), _mm512_set1_epi64(from));
  int32_t e = from;
  for (; to - e >= 8; e += 8) {
    const double *x8 = x + (size_t)e * (size_t)dim;
    __m512d c[3], t[3];
    if (boxed) {
      if (!nbs__cs_box8_pos(&b, &v, x8, dim, t)) return false;
    } else {
      nbs__cs_pos8(&v, x8, dim, c, t);
    }
    const __m512i key = nbs__cs_key8_of(&v, t, dim);
    if (ty) {
      uint64_t d[8];
      _mm512_storeu_si512((void *)d, _mm512_srli_epi64(key, (unsigned)ty->shift));
      for (int l = 0; l < 8; l++) ty->h[d[l] & ty->mask]++;
      continue;
    }
    _mm512_storeu_si512((void *)(k0 + e), _mm512_or_si512(_mm512_sll_epi64(key, sh), ks));
    ks = _mm512_add_epi64(ks, eight);
  }
  if (!boxed) {
    for (; e < to; e++) k0[e] = nbs__cs_cellkey(kg, x + (size_t)e * (size_t)dim) << eb | (uint64_t)e;
    return true;
  }
  nbs__cs_box8_done(&b, kg, dim, box);
  return nbs__cs_words_boxed(kg, x, dim, e, to, eb, k0, box, ty);
}

/* The packed words key << eb | k of the elements [from, to), 8 at a time. */
NBS__CS_AVX512_TARGET
static void nbs__cs_words512(const nbs__cs_keying *kg, const double *x, int32_t from, int32_t to,
                             int eb, uint64_t *k0) {
  if (kg->dim == 3) nbs__cs_words512_body(kg, x, 3, from, to, eb, k0, false, NULL, NULL);
  else nbs__cs_words512_body(kg, x, 2, from, to, eb, k0, false, NULL, NULL);
}

NBS__CS_AVX512_TARGET
static bool nbs__cs_words_boxed512(const nbs__cs_keying *kg, const double *x, int32_t from,
                                   int32_t to, int eb, uint64_t *k0, nbs__cs_box *box,
                                   const nbs__cs_tally *ty) {
  if (kg->dim == 3) return nbs__cs_words512_body(kg, x, 3, from, to, eb, k0, true, box, ty);
  return nbs__cs_words512_body(kg, x, 2, from, to, eb, k0, true, box, ty);
}
#endif

#if NBS__CS_AVX512
/* The key passes 4 elements at a time with AVX2, for processors without AVX-512 (Zen 3,
 * where the scalar passes were a tenth of a detection: `perf record`, 3D N = 1e6, random
 * order; after, 3.6%: Zen 3, N = 1e6, interleaved with fa75d1d, min of 6-8 rounds, 3D from
 * scratch 60.3 -> 56.3 ns per element, time steps of 1e-3 49.1 -> 45.6, 2D 32.4 -> 29.1,
 * the same hashes). The same operations in the same order as nbs__cs_key_boxed and
 * nbs__cs_cellkey (a subtraction, a multiplication, a truncation), so the same keys bit for
 * bit; but AVX2
 * truncates a double to an int32 only, so these passes run where every field of the key
 * is below 2^31 (nbs__cs_fits4: the keying's box checked first, in the boxed passes, keeps
 * each position t below its field's limit), and the scalar ones elsewhere. The 4 elements'
 * coordinates, 12 doubles (2D: 8) as they lie in the input, are loaded by halves, two
 * elements' worth per register, and sorted out by one shuffle per axis. */
typedef struct nbs__cs_keys4 {
  __m256d lo[3], inv[3], lim[3];
  __m128i sy, sz;
} nbs__cs_keys4;

/* Whether the keying's fields all lie below 2^31: in the boxed passes their limits
 * (nbs__cs_box_limits), which each position is checked against; in the unchecked pass
 * (after input.c's, every element on the grid) the x sub-cells' field, where the others
 * are the grid's cells, below 2^31 (an int32's, as nbs__cell_of makes them). */
static bool nbs__cs_fits4(const nbs__cs_keying *kg, int eb, bool boxed) {
  if (!boxed) return kg->sy <= 31;
  double lim[3];
  nbs__cs_box_limits(kg, eb, lim);
  for (int a = 0; a < kg->dim; a++) {
    if (!(lim[a] <= 2147483648.0)) return false;
  }
  return true;
}

static inline NBS__CS_AVX2_TARGET void nbs__cs_keys4_init(nbs__cs_keys4 *v,
                                                        const nbs__cs_keying *kg, int eb) {
  double lim[3];
  nbs__cs_box_limits(kg, eb, lim);
  for (int a = 0; a < 3; a++) {
    v->lo[a] = _mm256_set1_pd(a == 0 ? kg->lo_x : kg->g->lo[a]);
    v->inv[a] = _mm256_set1_pd(a == 0 ? kg->inv_fine : kg->g->inv_edge);
    v->lim[a] = _mm256_set1_pd(lim[a]);
  }
  v->sy = _mm_cvtsi32_si128(kg->sy);
  v->sz = _mm_cvtsi32_si128(kg->sz);
}

/* The 4 elements' coordinates at x4, by element axis (p[0] x, p[1] y, p[2] z). */
static inline __attribute__((always_inline)) NBS__CS_AVX2_TARGET void
nbs__cs_load4(const double *x4, int dim, __m256d p[3]) {
  if (dim == 3) {
    /* x0 y0 | x2 y2, z0 x1 | z2 x3, y1 z1 | y3 z3 */
    const __m256d a = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(x4)),
                                           _mm_loadu_pd(x4 + 6), 1);
    const __m256d b = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(x4 + 2)),
                                           _mm_loadu_pd(x4 + 8), 1);
    const __m256d c = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(x4 + 4)),
                                           _mm_loadu_pd(x4 + 10), 1);
    p[0] = _mm256_shuffle_pd(a, b, 0xA);
    p[1] = _mm256_shuffle_pd(a, c, 0x5);
    p[2] = _mm256_shuffle_pd(b, c, 0xA);
  } else {
    /* x0 y0 | x2 y2, x1 y1 | x3 y3 */
    const __m256d a = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(x4)),
                                           _mm_loadu_pd(x4 + 4), 1);
    const __m256d b = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(x4 + 2)),
                                           _mm_loadu_pd(x4 + 6), 1);
    p[0] = _mm256_unpacklo_pd(a, b);
    p[1] = _mm256_unpackhi_pd(a, b);
  }
}

/* The 4 elements' keys (64-bit lanes) from their coordinates by key axis (c); with `check`,
 * false if one lies outside the keying's box or a coordinate is not finite. */
static inline __attribute__((always_inline)) NBS__CS_AVX2_TARGET bool
nbs__cs_key4_of(const nbs__cs_keys4 *v, const __m256d c[3], int dim, bool check, __m256i *key) {
  __m256d in = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
  __m256i k = _mm256_setzero_si256();
  for (int a = 0; a < dim; a++) {
    const __m256d t = _mm256_mul_pd(_mm256_sub_pd(c[a], v->lo[a]), v->inv[a]);
    if (check) {
      /* NaN fails both */
      in = _mm256_and_pd(in, _mm256_and_pd(_mm256_cmp_pd(t, _mm256_setzero_pd(), _CMP_GE_OQ),
                                           _mm256_cmp_pd(t, v->lim[a], _CMP_LT_OQ)));
    }
    const __m256i i = _mm256_cvtepu32_epi64(_mm256_cvttpd_epi32(t));
    k = a == 0 ? i : _mm256_or_si256(k, _mm256_sll_epi64(i, a == 1 ? v->sy : v->sz));
  }
  *key = k;
  return !check || _mm256_movemask_pd(in) == 0xF;
}

/* The lanes' boxes (lo, hi by key axis) into box. */
static inline __attribute__((always_inline)) NBS__CS_AVX2_TARGET void
nbs__cs_box4_done(const __m256d lo[3], const __m256d hi[3], const nbs__cs_keying *kg, int dim,
                  nbs__cs_box *box) {
  for (int a = 0; a < dim; a++) {
    double l[4], h[4];
    _mm256_storeu_pd(l, lo[a]);
    _mm256_storeu_pd(h, hi[a]);
    const int ca = kg->c[a];
    for (int j = 0; j < 4; j++) {
      if (l[j] < box->lo[ca]) box->lo[ca] = l[j];
      if (h[j] > box->hi[ca]) box->hi[ca] = h[j];
    }
  }
}

/* nbs__cs_words_boxed, and with `boxed` false the words alone, unchecked (nbs__cs_words256),
 * 4 elements at a time: their box so far per lane. */
static inline __attribute__((always_inline)) NBS__CS_AVX2_TARGET bool
nbs__cs_words256_body(const nbs__cs_keying *kg, const double *x, int dim, int32_t from,
                      int32_t to, int eb, uint64_t *k0, bool boxed, nbs__cs_box *box,
                      const nbs__cs_tally *ty) {
  nbs__cs_keys4 v;
  nbs__cs_keys4_init(&v, kg, eb);
  __m256d lo[3], hi[3];
  for (int a = 0; a < 3; a++) {
    lo[a] = _mm256_set1_pd(DBL_MAX);
    hi[a] = _mm256_set1_pd(-DBL_MAX);
  }
  const __m128i sh = _mm_cvtsi32_si128(eb);
  const __m128i tsh = _mm_cvtsi32_si128(ty ? ty->shift : 0);
  const __m256i four = _mm256_set1_epi64x(4);
  __m256i ks = _mm256_add_epi64(_mm256_set_epi64x(3, 2, 1, 0), _mm256_set1_epi64x(from));
  int32_t e = from;
  for (; to - e >= 4; e += 4) {
    __m256d p[3], c[3];
    nbs__cs_load4(x + (size_t)e * (size_t)dim, dim, p);
    for (int a = 0; a < dim; a++) c[a] = p[kg->c[a]];
    __m256i key;
    if (!nbs__cs_key4_of(&v, c, dim, boxed, &key)) return false;
    if (boxed) {
      for (int a = 0; a < dim; a++) {
        lo[a] = _mm256_min_pd(lo[a], c[a]);
        hi[a] = _mm256_max_pd(hi[a], c[a]);
      }
    }
    if (ty) {
      uint64_t d[4];
      _mm256_storeu_si256((void *)d, _mm256_srl_epi64(key, tsh));
      for (int l = 0; l < 4; l++) ty->h[d[l] & ty->mask]++;
      continue;
    }
    _mm256_storeu_si256((void *)(k0 + e), _mm256_or_si256(_mm256_sll_epi64(key, sh), ks));
    ks = _mm256_add_epi64(ks, four);
  }
  if (!boxed) {
    for (; e < to; e++) k0[e] = nbs__cs_cellkey(kg, x + (size_t)e * (size_t)dim) << eb | (uint64_t)e;
    return true;
  }
  nbs__cs_box4_done(lo, hi, kg, dim, box);
  return nbs__cs_words_boxed(kg, x, dim, e, to, eb, k0, box, ty);
}

/* The packed words key << eb | k of the elements [from, to), 4 at a time where the
 * keying's fields fit (nbs__cs_fits4). */
NBS__CS_AVX2_TARGET
static void nbs__cs_words256(const nbs__cs_keying *kg, const double *x, int32_t from, int32_t to,
                             int eb, uint64_t *k0) {
  if (kg->dim == 3) nbs__cs_words256_body(kg, x, 3, from, to, eb, k0, false, NULL, NULL);
  else nbs__cs_words256_body(kg, x, 2, from, to, eb, k0, false, NULL, NULL);
}

NBS__CS_AVX2_TARGET
static bool nbs__cs_words_boxed256(const nbs__cs_keying *kg, const double *x, int32_t from,
                                   int32_t to, int eb, uint64_t *k0, nbs__cs_box *box,
                                   const nbs__cs_tally *ty) {
  if (kg->dim == 3) return nbs__cs_words256_body(kg, x, 3, from, to, eb, k0, true, box, ty);
  return nbs__cs_words256_body(kg, x, 2, from, to, eb, k0, true, box, ty);
}
/* nbs__cs_changed 4 elements at a time (the time steps' keys: eb = 32, where the keys fit
 * 31 bits and nbs__cs_fits4 holds), each lane's key against keys[]. */
static inline __attribute__((always_inline)) NBS__CS_AVX2_TARGET int64_t
nbs__cs_changed256_body(const nbs__cs_keying *kg, const double *x, int dim, int32_t from,
                        int32_t to, uint32_t *keys, uint64_t *r, uint64_t *s, int64_t share,
                        nbs__cs_box *box) {
  nbs__cs_keys4 v;
  nbs__cs_keys4_init(&v, kg, 32);
  __m256d lo[3], hi[3];
  for (int a = 0; a < 3; a++) {
    lo[a] = _mm256_set1_pd(DBL_MAX);
    hi[a] = _mm256_set1_pd(-DBL_MAX);
  }
  const __m256i low = _mm256_set_epi32(7, 5, 3, 1, 6, 4, 2, 0); /* each lane's low half */
  int64_t m = 0;
  int32_t e = from;
  for (; to - e >= 4; e += 4) {
    __m256d p[3], c[3];
    nbs__cs_load4(x + (size_t)e * (size_t)dim, dim, p);
    for (int a = 0; a < dim; a++) c[a] = p[kg->c[a]];
    __m256i key;
    if (!nbs__cs_key4_of(&v, c, dim, true, &key)) return NBS__CS_OUT;
    for (int a = 0; a < dim; a++) {
      lo[a] = _mm256_min_pd(lo[a], c[a]);
      hi[a] = _mm256_max_pd(hi[a], c[a]);
    }
    const __m128i k = _mm256_castsi256_si128(_mm256_permutevar8x32_epi32(key, low));
    const __m128i old = _mm_loadu_si128((const void *)(keys + e));
    unsigned ne = ~(unsigned)_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(k, old))) & 0xFu;
    if (ne == 0) continue;
    uint32_t kk[4];
    _mm_storeu_si128((void *)kk, k);
    if (!nbs__cs_note_lanes(kk, ne, keys, e, r, s, &m, share)) return -1;
  }
  nbs__cs_box4_done(lo, hi, kg, dim, box);
  return nbs__cs_changed(kg, x, dim, e, to, keys, r, s, m, share, box);
}

NBS__CS_AVX2_TARGET
static int64_t nbs__cs_changed256(const nbs__cs_keying *kg, const double *x, int32_t from,
                                  int32_t to, uint32_t *keys, uint64_t *r, uint64_t *s,
                                  int64_t share, nbs__cs_box *box) {
  if (kg->dim == 3) return nbs__cs_changed256_body(kg, x, 3, from, to, keys, r, s, share, box);
  return nbs__cs_changed256_body(kg, x, 2, from, to, keys, r, s, share, box);
}
#endif

/* The bytes of the input's coordinates and radii, which choose the gather's path
 * (NBS__CS_PREFETCH_MIN, nbs__cellsort_partition_min). */
static size_t nbs__input_bytes(int32_t n, int dim, bool radii) {
  return (size_t)n * (size_t)(dim + (radii ? 1 : 0)) * sizeof(double);
}
static size_t nbs__cs_input_bytes(const nbs__cs *c) {
  return nbs__input_bytes(c->n, c->dim, c->rs != NULL);
}

/* Which way a detection from scratch of run's input, on `threads` threads, takes: 1 the sort
 * and the gather (steps 1-3), 2 the partition (nbs__cs_partition; it needs packed keys, and
 * gives way to the sort and the gather where it cannot run). Chosen once per detection
 * (run->cs_way), before nbs__cellsort_fresh's pass, which only the first way uses.
 *  - Up to NBS__CS_TUNE_MIN bytes of input (coordinates and radii), the gather: its reads at
 *    random hit the caches.
 *  - Beyond cs_part_min (1 GiB, or what NBS_PARTITION says), the partition.
 *  - Between, measured. Which way is faster there depends on the machine, not on the
 *    input: the gather waits on memory once per element, at random, the partition streams
 *    the input and writes whole lines past the caches. 3D, N = 1e6 (24 MB), random order,
 *    one thread, ns per element, sort and gather against partition: on the AMD EPYC
 *    instances (Zen 5), where a random read of memory costs about 5 ns in a stream of them
 *    (bench/floor.c), 32.5 against 37.9 (see nbs__cellsort_partition_min); on an Intel Xeon
 *    guest (Sapphire Rapids class, 2026-11-28) whose random reads cost 17-20 ns in a stream
 *    (12 lines in flight at 200 ns; its last-level cache gave nothing beyond 2 MiB), and a
 *    plain store that misses about 12 ns per element in a scatter, 75.3-78.5 against
 *    62.3-66.0 (interleaved, four rounds; the same bytes). So the context times its first
 *    detections from scratch, NBS__CS_TUNE_TRIES of each way, the sort and the gather first
 *    (not the first in a work block just allocated, whose pages it faults in: nbs__detect;
 *    each from the detection's start to its search, the input's pass included: the
 *    partition has input.c's pass, the other way nbs__cellsort_fresh's), and takes the
 *    faster way from then on, for inputs of the class it measured (the dimension, the
 *    threads and the power of two of the bytes; another class measures again). A try costs
 *    at most the difference between the two ways, once; the output is the same bytes either
 *    way (test_determinism). */
#define NBS__CS_TUNE_MIN ((size_t)8 << 20)
#define NBS__CS_TUNE_TRIES 2

/* The class of run's input for a nbs__tune: the dimension, the threads and the power of two
 * of its bytes. */
static int nbs__tune_class_of(const nbs__run *run, int threads, size_t bytes) {
  return run->dim | threads << 2 | nbs__bits((uint64_t)bytes) << 10;
}

/* t measures class cls: its measurements start again where they were of another class. */
static void nbs__tune_class(nbs__tune *t, int cls) {
  if (cls == t->cls) return;
  t->cls = cls;
  t->tries[0] = t->tries[1] = 0;
  t->best[0] = t->best[1] = 0.0;
}

/* Whether t has timed both ways enough to choose. */
static bool nbs__tune_done(const nbs__tune *t) {
  return t->tries[0] >= NBS__CS_TUNE_TRIES && t->tries[1] >= NBS__CS_TUNE_TRIES;
}

/* Whether way 1 is the faster (once nbs__tune_done). */
static bool nbs__tune_second(const nbs__tune *t) { return t->best[1] < t->best[0]; }

/* The way to try next: the one tried fewer times, way 0 first. */
static int nbs__tune_next(const nbs__tune *t) { return t->tries[0] <= t->tries[1] ? 0 : 1; }

/* A try of way w took `per` seconds per element. */
static void nbs__tune_record(nbs__tune *t, int w, double per) {
  if (t->tries[w] == 0 || per < t->best[w]) t->best[w] = per;
  t->tries[w]++;
}

static int nbs__cs_way(nbs__run *run, int threads) {
  if (run->cs_way) return run->cs_way;
  nbs_context *ctx = run->ctx;
  const size_t bytes = nbs__input_bytes(run->n, run->dim, run->r != NULL);
  int way = 1;
  if (bytes > ctx->cs_part_min) {
    way = 2;
  } else if (ctx->cs_tune && bytes > NBS__CS_TUNE_MIN) {
    nbs__tune *t = &ctx->cs_ways;
    nbs__tune_class(t, nbs__tune_class_of(run, threads, bytes));
    if (nbs__tune_done(t)) {
      way = nbs__tune_second(t) ? 2 : 1;
    } else {
      way = 1 + nbs__tune_next(t);
      run->cs_try = true;
    }
  }
  run->cs_way = (int8_t)way;
  return way;
}

void nbs__cellsort_tried(nbs_context *ctx, const nbs__run *run, double seconds) {
  if (run->n <= 0) return;
  const double per = seconds / (double)run->n;
  /* a time step's try (nbs__cs_steps_way): one from the order counts only where it
   * started from it (not where too many elements had moved), and either only where cellsort
   * ran (auto may have chosen another algorithm) */
  if (run->cs_step_try && run->ran == NBS_CELLSORT &&
      (run->cs_step_try == 2 || run->reused_order)) {
    nbs__tune_record(&ctx->cs_steps, run->cs_step_try - 1, per);
  }
  if (!run->cs_tried) return; /* started from the last order: no try of the way */
  /* the partition that could not run is never taken for this class */
  nbs__tune_record(&ctx->cs_ways, run->cs_tried == 1 ? 0 : 1,
                   run->cs_tried == 3 ? DBL_MAX : per);
}

/* Place p of the cell order (xs, ys, zs, rs) takes element e's coordinates (and radius)
 * from the input (x, r): the gather, the time-step pass and merge. The arrays come as
 * arguments, so that the loops that call it hold them in locals: read through c at every
 * element, the time-step pass took 1 ns per element more (3D and 2D, N = 1e6, steps of
 * 1e-3; the gathers 0.3-0.9 ns, see nbs__cs_gather). nbs__cs_take: the same with c's
 * arrays, for the merge's takes of the changed elements (nbs__cs_warm_merge), where that
 * cost does not show. */
static inline void nbs__cs_place(double *xs, double *ys, double *zs, double *rs, const double *x,
                                 const double *r, int dim, int32_t p, int32_t e) {
  const double *xk = x + (size_t)e * (size_t)dim;
  xs[p] = xk[0];
  ys[p] = xk[1];
  if (dim == 3) zs[p] = xk[2];
  if (rs) rs[p] = r[e];
}
static inline void nbs__cs_take(const nbs__cs *c, const nbs__run *run, int32_t p, int32_t e) {
  nbs__cs_place(c->xs, c->ys, c->zs, c->rs, run->x, run->r, c->dim, p, e);
}

/* result = the first i of [floor, top) for which below(i) is false (top if none), where
 * below(i) is true up to some i and false from it on: galloping down from top (1, 2, 4 ...
 * places), then bisection, so that it takes few steps when the answer is near top, as it is
 * for each word of a merge from the end (nbs__cs_core). */
#define NBS__CS_GALLOP(result, floor, top, below)                                            \
  do {                                                                                        \
    int32_t nbs__hi = (top), nbs__lo = (floor);                                               \
    for (int32_t nbs__step = 1;; nbs__step *= 2) {                                            \
      if (nbs__hi - nbs__step < (floor)) break;                                               \
      if (below(nbs__hi - nbs__step)) {                                                       \
        nbs__lo = nbs__hi - nbs__step + 1;                                                    \
        break;                                                                                \
      }                                                                                       \
      nbs__hi -= nbs__step;                                                                   \
      if (nbs__step > INT32_MAX / 2) break;                                                   \
    }                                                                                         \
    while (nbs__lo < nbs__hi) {                                                               \
      const int32_t nbs__mid = nbs__lo + (nbs__hi - nbs__lo) / 2;                             \
      if (below(nbs__mid)) nbs__lo = nbs__mid + 1;                                            \
      else nbs__hi = nbs__mid;                                                                \
    }                                                                                         \
    (result) = nbs__lo;                                                                       \
  } while (0)

/* Moves the places [a, b) of the cell order (word, coordinates, radius) by d places. */
static void nbs__cs_shift(const nbs__cs *c, int32_t a, int32_t b, int32_t d) {
  if (b - a <= 8) { /* most runs: a loop, not five calls (memmove's direction: d's) */
    for (int32_t i = 0; i < b - a; i++) {
      const int32_t q = d < 0 ? a + i : b - 1 - i;
      c->key[q + d] = c->key[q];
      c->xs[q + d] = c->xs[q];
      c->ys[q + d] = c->ys[q];
      if (c->dim == 3) c->zs[q + d] = c->zs[q];
      if (c->rs) c->rs[q + d] = c->rs[q];
    }
    return;
  }
  const size_t len = (size_t)(b - a);
  const size_t to = (size_t)((int64_t)a + d);
  memmove(c->key + to, c->key + a, len * sizeof *c->key);
  memmove(c->xs + to, c->xs + a, len * sizeof *c->xs);
  memmove(c->ys + to, c->ys + a, len * sizeof *c->ys);
  if (c->dim == 3) memmove(c->zs + to, c->zs + a, len * sizeof *c->zs);
  if (c->rs) memmove(c->rs + to, c->rs + a, len * sizeof *c->rs);
}

/* The warm start's merge, in place: the m elements whose words changed leave the places
 * P[0 .. m) (ascending) of the last order, and their new words S[0 .. m) (sorted) go in
 * among the words kept. A kept word at place p ends up d(p) = #{j: S[j] < key[p]} -
 * #{i: P[i] < p} places away, and d changes only at the P and at the places I[j] where the
 * S would go in the last order (the lower bound of S[j] in key[]: all words differ), so the
 * kept words move in at most 2m + 1 runs of one d each, most of them 0 where the elements
 * moved little (a word taken out and put back a few places on). Final places keep the kept
 * words' order, so a word moved down (d < 0) only lands on a place whose word moved down
 * before it, or was taken out: the runs with d < 0 move in ascending order, those with d >
 * 0 in descending order, and neither lands on a place the other reads. S[j] then takes its
 * place, I[j] - #{i: P[i] < I[j]} + j, its coordinates read from the input. The result is
 * the merge by word: the order a sort from scratch gives. Where the elements moved little,
 * only the few words between an element's old and new places move; the merge before (all
 * the kept elements after the first taken out moved down during the check, then up by runs
 * from the end, several threads sharing it) moved every element past the first change
 * twice. Measured (time steps of D diameters per axis, nbs_bench --move D, one thread,
 * interleaved, min of 3-4, preparation in ns per element, the same hashes): D = 1e-4, 2D
 * huge 6.43 -> 3.92; D = 1e-3, 2D sparse (fraction 0.5, 1,443 elements re-sorted) 6.38 ->
 * 5.29, huge 7.12 -> 5.67, clustered 6.50 -> 5.34, 3D huge 11.22 -> 8.30, two threads 2D
 * sparse 4.25 -> 3.34; D = 1e-2, 3D huge 12.67 -> 11.80, 2D huge 8.91 -> 8.48, but 2D sparse
 * 7.41 -> 8.55 and clustered 7.46 -> 8.29: there 15,000 elements re-sorted, a sixth of
 * them a row away (1,250 places in those crowded rows), so that most words move, in many
 * runs, and after the chunks' pass, out of the caches. I (m int32) is scratch. */
static void nbs__cs_warm_merge(const nbs__cs *c, const nbs__run *run, const uint64_t *S,
                               const int32_t *P, int32_t *I, int64_t m) {
  const int32_t n = c->n;
  const int dim = c->dim;
  const uint64_t emask = c->imask;
  const uint64_t *key = c->key;
  const double *x = run->x, *r = run->r;
  /* I[j]: galloping up from I[j - 1] (S is sorted), then bisection */
  for (int64_t j = 0, at = 0; j < m; j++) {
    int64_t step = 1, hi = at;
    while (hi < n && key[hi] < S[j]) {
      at = hi + 1;
      hi += step;
      step *= 2;
    }
    if (hi > n) hi = n;
    at += nbs__cs_lower(key + at, (int32_t)(hi - at), S[j]);
    I[j] = (int32_t)at;
  }
  /* the runs with d < 0, ascending: d(p) = #{I[j] <= p} - #{P[i] < p} */
  int64_t ir = 0, is = 0;
  int32_t d = 0;
  for (int32_t p = 0; p < n;) {
    while (is < m && I[is] <= p) {
      d++;
      is++;
    }
    if (ir < m && P[ir] == p) { /* taken out: the places after it are one closer */
      d--;
      ir++;
      p++;
      continue;
    }
    int32_t e = n;
    if (ir < m && P[ir] < e) e = P[ir];
    if (is < m && I[is] < e) e = I[is];
    if (d < 0) nbs__cs_shift(c, p, e, d);
    p = e;
  }
  /* the runs with d > 0, descending: d(p) = #{P[i] >= p} - #{I[j] > p} */
  ir = m - 1;
  is = m - 1;
  int32_t np = 0, ni = 0;
  for (int32_t p = n - 1; p >= 0;) {
    while (is >= 0 && I[is] > p) {
      ni++;
      is--;
    }
    if (ir >= 0 && P[ir] == p) {
      np++;
      ir--;
      p--;
      continue;
    }
    int32_t lo = 0; /* the run is [lo, p] */
    if (ir >= 0 && P[ir] + 1 > lo) lo = P[ir] + 1;
    if (is >= 0 && I[is] > lo) lo = I[is];
    if (np - ni > 0) nbs__cs_shift(c, lo, p + 1, np - ni);
    p = lo - 1;
  }
  /* the new words in their places */
  int64_t below = 0; /* #{P[i] < I[j]} */
  for (int64_t j = 0; j < m; j++) {
    while (below < m && P[below] < I[j]) below++;
    if (j + 8 < m) { /* the elements taken out are few and anywhere: ask ahead */
      const size_t ea = (size_t)(S[j + 8] & emask) * (size_t)dim;
      __builtin_prefetch(x + ea);
      __builtin_prefetch(x + ea + (dim - 1));
      if (r) __builtin_prefetch(r + (S[j + 8] & emask));
    }
    const int32_t q = (int32_t)(I[j] - below + j);
    c->key[q] = S[j];
    nbs__cs_take(c, run, q, (int32_t)(S[j] & emask));
  }
}

/* The warm start: at most this share (1 / it) of the elements may change place. */
#define NBS__CS_WARM_SHARE 16

/* The words of the places [from, to) of the gathered coordinates cs[] (x, y, z), keyed as
 * nbs__cs_cellkey keys the input (the same values: copies), each with the element of the last
 * order's word key[p], to out[0 ..]. */
static void nbs__cs_words_at(const nbs__cs_keying *kg, const double *const cs[3], int dim,
                             const uint64_t *key, uint64_t emask, int eb, int32_t from,
                             int32_t to, uint64_t *out) {
  for (int32_t p = from; p < to; p++) {
    const double xk[3] = {cs[0][p], cs[1][p], dim == 3 ? cs[2][p] : 0.0};
    out[p - from] = nbs__cs_cellkey(kg, xk) << eb | (key[p] & emask);
  }
}

#if NBS__CS_AVX512
/* The same 8 places at a time, the keys as nbs__cs_key8_of computes them (the input's
 * coordinates are copies, side by side already: no permutation). */
static inline __attribute__((always_inline)) NBS__CS_AVX512_TARGET void
nbs__cs_words_at512_body(const nbs__cs_keying *kg, const double *const cs[3], int dim,
                         const uint64_t *key, uint64_t emask, int eb, int32_t from, int32_t to,
                         uint64_t *out) {
  nbs__cs_keys8 v;
  nbs__cs_keys8_init(&v, kg);
  const __m128i sh = _mm_cvtsi32_si128(eb);
  const __m512i em = _mm512_set1_epi64((long long)emask);
  const double *ca[3] = {cs[kg->c[0]], cs[kg->c[1]], dim == 3 ? cs[kg->c[2]] : NULL};
  int32_t p = from;
  for (; to - p >= 8; p += 8) {
    __m512d t[3];
    for (int a = 0; a < dim; a++) {
      t[a] = _mm512_mul_pd(_mm512_sub_pd(_mm512_loadu_pd(ca[a] + p), v.lo[a]), v.inv[a]);
    }
    const __m512i e = _mm512_and_si512(_mm512_loadu_si512((const void *)(key + p)), em);
    const __m512i w = _mm512_or_si512(_mm512_sll_epi64(nbs__cs_key8_of(&v, t, dim), sh), e);
    _mm512_storeu_si512((void *)(out + (p - from)), w);
  }
  nbs__cs_words_at(kg, cs, dim, key, emask, eb, p, to, out + (p - from));
}

NBS__CS_AVX512_TARGET
static void nbs__cs_words_at512(const nbs__cs_keying *kg, const double *const cs[3], int dim,
                                const uint64_t *key, uint64_t emask, int eb, int32_t from,
                                int32_t to, uint64_t *out) {
  if (dim == 3) nbs__cs_words_at512_body(kg, cs, 3, key, emask, eb, from, to, out);
  else nbs__cs_words_at512_body(kg, cs, 2, key, emask, eb, from, to, out);
}
#endif

/* The warm start's chunk: places a chunk of the last order at a time (NBS__CS_WARM_CHUNK),
 * whose coordinates are then still in the L1 cache for the check of their words. */
#define NBS__CS_WARM_CHUNK 512

/* Starts from the last detection's cell order (nbs_detect's "time steps") where the words'
 * low half is not the element alone (eb < 32; else nbs__cs_rekey, below, which is faster).
 * key[] holds it as packed words, sorted, of the same n elements. One pass places the
 * elements' coordinates in that order, as the gather does, a chunk at a time, and computes
 * the chunk's new words from those copies while they are in the L1 cache (8 at a time with
 * AVX-512); a chunk whose words all stand is done. An element whose word changed (it moved
 * to another x sub-cell, row or layer) has its place and its new word noted in `spare`.
 * When none changed, that is all: the sort and the gather are skipped (the figures are in
 * the file comment). Otherwise the new words are sorted (the radix sort, in spare) and
 * merged in place of the old (nbs__cs_warm_merge). Sorted by the whole word (key, then
 * element), the result is the order a sort from scratch gives, whose stable passes leave
 * equal keys in element order: the same pairs in the same order.
 * Returns false, the arrays then holding nothing of use, when more than n /
 * NBS__CS_WARM_SHARE elements changed place (the pass stops there: an input that is not a
 * later state of the same elements stops it within the first sixteenth); the caller sorts
 * from scratch. With several threads each takes a contiguous part and its own share of
 * spare, and the parts' notes are closed up before the merge, which one thread does (it
 * moves few words where the elements moved little). spare is the idx array (4 n bytes),
 * which packed words leave unused; this uses 3.5 n / NBS__CS_WARM_SHARE words of it: the
 * new words, the radix sort's scratch, the places (int32) and the merge's insertion places
 * (int32). */
static bool nbs__cs_warm(const nbs__cs *c, const nbs__run *run, const nbs__cs_keying *kg,
                         int eb, int bits, uint64_t *spare, uint32_t *hist, int threads,
                         int64_t *moved) {
  const int32_t n = c->n;
  const int dim = c->dim;
  const uint64_t emask = c->imask;
  const int64_t limit = n / NBS__CS_WARM_SHARE, share = limit / threads;
  uint64_t *key = c->key;
  double *xs = c->xs, *ys = c->ys, *zs = c->zs, *rs = c->rs;
  const double *x = run->x, *r = run->r;
  const bool ask = nbs__cs_input_bytes(c) > NBS__CS_PREFETCH_MIN; /* see the gather */
  const bool ends = nbs__cs_ends(x, dim);
#if NBS__CS_AVX512
  const bool v512 = run->ctx->simd == NBS__SIMD_AVX512;
#endif
  /* spare: the new words [0, limit), the sort's scratch [limit, 2 limit), the places taken
   * out (int32) from 2 limit, then their insertion places (int32) from 3 limit */
  int32_t *places = (int32_t *)(void *)(spare + 2 * limit);
  int32_t *ins = (int32_t *)(void *)(spare + 3 * limit);
  /* zeroed for GCC 12, which without OpenMP takes out[0] for unset after the pass */
  int64_t out[NBS__THREADS_MAX] = {0};
  bool over = false;
#if defined(_OPENMP)
#pragma omp parallel num_threads(threads) if (threads > 1) reduction(|| : over)
#endif
  NBS__PARTS(t, threads) {
    const int32_t from = nbs__chunk(n, t, threads), to = nbs__chunk(n, t + 1, threads);
    const double *const cs[3] = {xs, ys, zs};
    uint64_t *mine = spare + (size_t)t * (size_t)share;
    int32_t *mine_at = places + (size_t)t * (size_t)share;
    uint64_t words[NBS__CS_WARM_CHUNK];
    int64_t m = 0;
    for (int32_t a = from; a < to && !over; a += NBS__CS_WARM_CHUNK) {
      const int32_t b = to - a > NBS__CS_WARM_CHUNK ? a + NBS__CS_WARM_CHUNK : to;
      /* the chunk's coordinates, in place, as the gather places them; key[pa] is still the
       * last order's word, within this thread's part (the next thread's rewrites its own) */
      for (int32_t p = a; p < b; p++) {
        if (ask) {
          const int32_t pa = p + NBS__CS_AHEAD < to ? p + NBS__CS_AHEAD : p;
          const int32_t pn = p + NBS__CS_NEAR < to ? p + NBS__CS_NEAR : p;
          nbs__cs_prefetch(x, rs ? r : NULL, dim, ends, (int32_t)(key[pa] & emask),
                           (int32_t)(key[pn] & emask));
        }
        nbs__cs_place(xs, ys, zs, rs, x, r, dim, p, (int32_t)(key[p] & emask));
      }
      /* their words now */
#if NBS__CS_AVX512
      if (v512) {
        nbs__cs_words_at512(kg, cs, dim, key, emask, eb, a, b, words);
      } else
#endif
      {
        nbs__cs_words_at(kg, cs, dim, key, emask, eb, a, b, words);
      }
      if (memcmp(words, key + a, (size_t)(b - a) * sizeof *key) == 0) continue;
      /* the places whose word changed, and their new words */
      for (int32_t p = a; p < b; p++) {
        const uint64_t w = words[p - a];
        if (w == key[p]) continue;
        if (m == share) {
          over = true;
          break;
        }
        mine_at[m] = p;
        mine[m++] = w;
      }
    }
    out[t] = m;
    if (over) break;
  }
  *moved = 0;
  if (over) return false;
  int64_t m = 0;
  for (int t = 0; t < threads; t++) m += out[t];
  if (m == 0) return true;

  /* the parts' words and places together, in place order */
  int64_t j = out[0];
  for (int t = 1; t < threads; t++) {
    memmove(spare + j, spare + (size_t)t * (size_t)share, (size_t)out[t] * sizeof *spare);
    memmove(places + j, places + (size_t)t * (size_t)share, (size_t)out[t] * sizeof *places);
    j += out[t];
  }
  nbs__radix(spare, NULL, spare + limit, NULL, spare, NULL, (int32_t)m, 0,
             nbs__radix_digits(bits + eb), hist, 1, false, NULL, 0);
  nbs__cs_warm_merge(c, run, spare, places, ins, m);
  *moved = m;
  return true;
}

/* The large inputs' gather of the places [from, to), prefetching ahead (to n: the places
 * past `to` are read by whoever gathers them). */
static void nbs__cs_gather_range(const nbs__cs *c, const nbs__run *run, bool ends,
                                 int32_t from, int32_t to) {
  const int32_t n = c->n;
  const int dim = c->dim;
  const double *x = run->x;
  const uint64_t emask = c->imask;
  const bool packed = c->idx == NULL;
  /* the arrays in restrict locals, as in the small inputs' gather: read through c at every
   * element, this loop took 0.3-0.9 ns per element more (3D, Zen 5, interleaved, min of 4:
   * N = 1e7 26.43 -> 25.83, 1e6 23.95 -> 23.66; 2D 1e6 12.77 / 12.69). Tried and left out:
   * the coordinates put 8 at a time in a line of each array with a streaming store (the
   * line is then not read from memory before it is written): N = 1e6 the same (prepare 9.4-
   * 9.5 against 9.6-9.8 ns per element, three runs), 1e7 0.2-0.6 less (10.0-10.6 against
   * 10.5-11.2, six runs), too little for a loop of its own per dimension, radii and thread
   * count. */
  double *restrict xs = c->xs, *restrict ys = c->ys, *restrict zs = c->zs;
  double *restrict rs = c->rs;
  const double *r = run->r;
  const uint64_t *restrict kr = c->key;
  const int32_t *restrict idx = c->idx;
  for (int32_t p = from; p < to; p++) {
    /* ask for the elements a few iterations ahead: the reads are random */
    const int32_t pa = p + NBS__CS_AHEAD < n ? p + NBS__CS_AHEAD : p;
    const int32_t pn = p + NBS__CS_NEAR < n ? p + NBS__CS_NEAR : p;
    nbs__cs_prefetch(x, r, dim, ends, packed ? (int32_t)(kr[pa] & emask) : idx[pa],
                     packed ? (int32_t)(kr[pn] & emask) : idx[pn]);
    nbs__cs_place(xs, ys, zs, rs, x, r, dim, p, packed ? (int32_t)(kr[p] & emask) : idx[p]);
  }
}

/* The fewest places a thread takes from another's part of the gather (nbs__share). */
#define NBS__CS_GATHER_GRAIN 16384

/* Step 3, the gather: place p of the cell order takes the coordinates (and radius) of the
 * element of word p, from key[] (idx[] for unpacked keys); or, where src is not NULL, of
 * src[p], which is copied to key[p] (src may be the x coordinates' array: place p reads
 * src[p] before it writes xs[p]). Where the input is small, in a loop of its own without
 * the prefetches (a branch on it in the one loop, or a function inlined twice with it a
 * constant, which OpenMP outlines once, took 24.0-24.3 ns per element against 23.3 at 3D
 * N = 1e4). */
static void nbs__cs_gather(const nbs__cs *c, const nbs__run *run, const uint64_t *src,
                           int threads) {
  const int32_t n = c->n;
  const int dim = c->dim;
  const double *x = run->x;
  const bool ends = nbs__cs_ends(x, dim);
  const uint64_t emask = c->imask;
  const bool packed = c->idx == NULL;
  uint64_t *key = c->key;
  const bool small = nbs__cs_input_bytes(c) <= NBS__CS_PREFETCH_MIN;
  if (small && src) { /* no restrict: src may be xs */
    double *xs = c->xs, *ys = c->ys, *zs = c->zs, *rs = c->rs;
    const double *r = run->r;
#if defined(_OPENMP)
#pragma omp parallel for num_threads(threads) schedule(static) if (threads > 1)
#endif
    for (int32_t p = 0; p < n; p++) {
      const uint64_t w = src[p];
      key[p] = w;
      nbs__cs_place(xs, ys, zs, rs, x, r, dim, p, (int32_t)(w & emask));
    }
    return;
  }
  if (small) {
    double *restrict xs = c->xs, *restrict ys = c->ys, *restrict zs = c->zs;
    double *restrict rs = c->rs;
    const double *r = run->r;
    const uint64_t *restrict kr = key;
#if defined(_OPENMP)
#pragma omp parallel for num_threads(threads) schedule(static) if (threads > 1)
#endif
    for (int32_t p = 0; p < n; p++) {
      nbs__cs_place(xs, ys, zs, rs, x, r, dim, p, packed ? (int32_t)(kr[p] & emask) : c->idx[p]);
    }
    return;
  }
  if (src) {
    /* each part asks for words of its own only: the next part's may be coordinates */
#if defined(_OPENMP)
#pragma omp parallel num_threads(threads) if (threads > 1)
#endif
    NBS__PARTS(t, threads) {
      const int32_t from = nbs__chunk(n, t, threads), to = nbs__chunk(n, t + 1, threads);
      /* the arrays in locals (see below: steps of 1e-3, N = 1e6, interleaved, min of 4, 3D
       * 20.78 -> 20.38 ns per element, 2D 9.30 -> 9.12; 1e7 the same); not restrict: src
       * may lie in xs */
      double *xs = c->xs, *ys = c->ys, *zs = c->zs, *rs = c->rs;
      const double *r = run->r;
      for (int32_t p = from; p < to; p++) {
        const int32_t pa = p + NBS__CS_AHEAD < to ? p + NBS__CS_AHEAD : p;
        const int32_t pn = p + NBS__CS_NEAR < to ? p + NBS__CS_NEAR : p;
        nbs__cs_prefetch(x, r, dim, ends, (int32_t)(src[pa] & emask), (int32_t)(src[pn] & emask));
        const uint64_t w = src[p];
        key[p] = w;
        nbs__cs_place(xs, ys, zs, rs, x, r, dim, p, (int32_t)(w & emask));
      }
    }
    return;
  }
#if defined(_OPENMP)
  if (threads > 1) { /* halves, the rest taken from the back by the thread done first */
    uint32_t cut[NBS__THREADS_MAX + 1];
    for (int t = 0; t <= threads; t++) cut[t] = (uint32_t)nbs__chunk(n, t, threads);
    nbs__share sh;
    nbs__share_init(&sh, threads, cut, run->ctx->cs_steal_first);
#pragma omp parallel num_threads(threads)
    {
      uint32_t a, b;
      bool taken;
      NBS__PARTS(t, threads) {
        for (int stage = 0;
             nbs__share_next(&sh, t, &stage, NBS__CS_GATHER_GRAIN, true, &a, &b, &taken);) {
          nbs__cs_gather_range(c, run, ends, (int32_t)a, (int32_t)b);
        }
      }
    }
    return;
  }
#endif
  nbs__cs_gather_range(c, run, ends, 0, n);
}

/* keys[e] = the key of element e in the order of key[], whose words' low half is the
 * element alone: where the last detection did not leave them (a detection from scratch),
 * for nbs__cs_rekey. A scatter, about a nanosecond per element at N = 1e6, paid by the
 * first start from an order, not by every detection from scratch (there, as a store
 * beside each word of the key pass, 0.3 ns of every detection). */
static void nbs__cs_keys_of(const nbs__cs *c, uint32_t *keys, int threads) {
  const int32_t n = c->n;
  const uint64_t *key = c->key;
  (void)threads; /* without OpenMP */
#if defined(_OPENMP)
#pragma omp parallel for num_threads(threads) schedule(static) if (threads > 1)
#endif
  for (int32_t p = 0; p < n; p++) keys[(uint32_t)key[p]] = (uint32_t)(key[p] >> 32);
}

/* The start from the last order where its words' low half is the element alone and the
 * idx array holds each element's key of that order (ctx->cs_keys): the elements whose key
 * changed are found by one pass over the input in element order, reading and writing
 * idx[e] beside it, not in the last order (a random read of each element); only their words
 * are sorted and merged into the last order's, 8 bytes per element; and the coordinates are
 * then gathered once, in the new order, as from scratch. nbs__cs_warm instead reads the
 * elements in the last order, and its merge moves every element's word and coordinates
 * after the first taken out: in 3D that cost what the sort from scratch does.
 *   1. each element's key again; where it differs from idx[e], the element's old word
 *      (idx[e] << 32 | e) goes to R, its new one to S, and idx[e] takes the new key;
 *   2. R and S sorted (the radix sort, by the whole word);
 *   3. key[] without R, merged with S, into M: in T parts, part t from the last order's
 *      words [n t / T, n (t + 1) / T), with the words of R and S between the first of them
 *      and the next part's first (found by bisection);
 *   4. the gather from M, each word copied to key[] as it is read.
 * Sorted by the whole word, the result is the order of a sort from scratch, as for
 * nbs__cs_warm. Scratch: M in the x coordinates' array, R, S and the sort's scratch in the
 * y coordinates' (3 n / NBS__CS_WARM_SHARE words of n), each read before the gather writes
 * it. Returns false, having written nothing the caller needs, when more than n /
 * NBS__CS_WARM_SHARE keys changed. */
/* Step 1 of nbs__cs_rekey over all n elements, in `threads` parts, with keying kg: the
 * changed elements' old words to R and new ones to S (each part its share of n /
 * NBS__CS_WARM_SHARE, then closed up), their number returned, or -1 past that many, or
 * NBS__CS_OUT (nbs__cs_changed); the coordinates' bounding box to lo, hi. */
static int64_t nbs__cs_changes(const nbs__run *run, const nbs__cs_keying *kg, uint32_t *keys,
                               uint64_t *R, int threads, double lo[3], double hi[3]) {
  const int32_t n = run->n;
  const int dim = run->dim;
  const int64_t limit = n / NBS__CS_WARM_SHARE, share = limit / threads;
  uint64_t *S = R + limit;
  const double *x = run->x;
  int64_t out[NBS__THREADS_MAX] = {0}; /* zeroed for GCC 12 without OpenMP, as in nbs__cs_warm */
  nbs__cs_box boxes[NBS__THREADS_MAX];
  bool over = false, outside = false;
#if defined(_OPENMP)
#pragma omp parallel num_threads(threads) if (threads > 1) reduction(|| : over, outside)
#endif
  NBS__PARTS(t, threads) {
    const int32_t from = nbs__chunk(n, t, threads), to = nbs__chunk(n, t + 1, threads);
    const nbs__grid g = *kg->g; /* locals, in registers (see nbs__cs_core_split) */
    nbs__cs_keying kl = *kg;
    kl.g = &g;
    nbs__cs_box *box = &boxes[t];
    nbs__cs_box_clear(box);
    uint64_t *r = R + (size_t)t * (size_t)share, *s = S + (size_t)t * (size_t)share;
    int64_t m;
    /* with AVX-512, 8 at a time: 3D steps of 1e-3 29.3-29.8 -> 29.1-29.4, 2D 15.6 -> 15.2 */
#if NBS__CS_AVX512
    if (run->ctx->simd == NBS__SIMD_AVX512) {
      m = nbs__cs_changed512(&kl, x, from, to, keys, r, s, share, box);
    } else if (run->ctx->simd == NBS__SIMD_AVX2 && nbs__cs_fits4(&kl, 32, true)) {
      m = nbs__cs_changed256(&kl, x, from, to, keys, r, s, share, box);
    } else
#endif
    {
      m = nbs__cs_changed(&kl, x, dim, from, to, keys, r, s, 0, share, box);
    }
    if (m == -1) over = true;
    if (m == NBS__CS_OUT) outside = true;
    out[t] = m < 0 ? 0 : m;
  }
  if (outside) return NBS__CS_OUT;
  if (over) return -1;
  int64_t m = out[0];
  for (int t = 1; t < threads; t++) {
    memmove(R + m, R + (size_t)t * (size_t)share, (size_t)out[t] * sizeof *R);
    memmove(S + m, S + (size_t)t * (size_t)share, (size_t)out[t] * sizeof *S);
    m += out[t];
  }
  nbs__cs_boxes_join(boxes, threads, dim, lo, hi);
  return m;
}

static void nbs__cs_rekey_merge(const nbs__cs *c, const nbs__run *run, int64_t m,
                                uint32_t *hist, int threads);
static bool nbs__cs_rekey(const nbs__cs *c, const nbs__run *run, const nbs__cs_keying *kg,
                          uint32_t *keys, uint32_t *hist, int threads, int64_t *moved) {
  double lo[3], hi[3]; /* the grid's box already (input.c's pass): not used */
  const int64_t m = nbs__cs_changes(run, kg, keys, (uint64_t *)(void *)c->ys, threads, lo, hi);
  *moved = m < 0 ? 0 : m;
  if (m < 0) return false; /* past n / 16 (or, which this keying rules out, outside) */
  nbs__cs_rekey_merge(c, run, m, hist, threads);
  return true;
}

/* Steps 2-4 of nbs__cs_rekey, for the m changed elements whose old and new words step 1
 * left in R and S (the ys region, see there). */
static void nbs__cs_rekey_merge(const nbs__cs *c, const nbs__run *run, int64_t m,
                                uint32_t *hist, int threads) {
  const int32_t n = c->n;
  const int64_t limit = n / NBS__CS_WARM_SHARE;
  uint64_t *key = c->key;
  uint64_t *M = (uint64_t *)(void *)c->xs, *R = (uint64_t *)(void *)c->ys, *S = R + limit;
  uint64_t *scratch = S + limit;
  if (m == 0) {
    nbs__cs_gather(c, run, NULL, threads);
    return;
  }
  /* 2: by the whole word, not by this detection's key bits: the old words' keys fit the last
   * detection's cells, which may have needed more bits (a layer more, say) than these */
  const nbs__digits dg = nbs__radix_digits(63);
  nbs__radix(R, NULL, scratch, NULL, R, NULL, (int32_t)m, 0, dg, hist, 1, false, NULL, 0);
  nbs__radix(S, NULL, scratch, NULL, S, NULL, (int32_t)m, 0, dg, hist, 1, false, NULL, 0);
  /* 3 */
  int32_t ib[NBS__THREADS_MAX + 1];
  int64_t rb[NBS__THREADS_MAX + 1], sb[NBS__THREADS_MAX + 1];
  for (int t = 0; t <= threads; t++) {
    /* the first part takes the words of S below key[0] too, the last those above key[n - 1] */
    ib[t] = nbs__chunk(n, t, threads);
    rb[t] = t == 0 ? 0 : t == threads ? m : nbs__cs_lower(R, (int32_t)m, key[ib[t]]);
    sb[t] = t == 0 ? 0 : t == threads ? m : nbs__cs_lower(S, (int32_t)m, key[ib[t]]);
  }
#if defined(_OPENMP)
#pragma omp parallel num_threads(threads) if (threads > 1)
#endif
  NBS__PARTS(t, threads) {
    int64_t r = rb[t], s = sb[t], p = ib[t] - rb[t] + sb[t];
    const int64_t r1 = rb[t + 1], s1 = sb[t + 1];
    uint64_t nr = r < r1 ? R[r] : UINT64_MAX, ns = s < s1 ? S[s] : UINT64_MAX;
    for (int32_t i = ib[t]; i < ib[t + 1]; i++) {
      const uint64_t w = key[i];
      if (w == nr) { /* taken out */
        r++;
        nr = r < r1 ? R[r] : UINT64_MAX;
        continue;
      }
      while (ns < w) {
        M[p++] = ns;
        s++;
        ns = s < s1 ? S[s] : UINT64_MAX;
      }
      M[p++] = w;
    }
    while (s < s1) M[p++] = S[s++];
  }
  /* 4 */
  nbs__cs_gather(c, run, M, threads);
}

/* Step b of nbs__cs_core for the elements [f, to): each one's key computed again
 * (nbs__cs_cellkey); the core's words to A, the outliers to key[] and idx[], both from
 * their start (packed keys, idx NULL: the outliers' words to key[]). The keying and its
 * grid are copied to locals, which stay in registers (dim a constant where this is inlined):
 * read through pointers in the OpenMP region's own code, the pass took twice as long. */
static inline __attribute__((always_inline)) void
nbs__cs_core_split(const nbs__cs_keying *kg, const double *restrict x, int dim, int32_t f,
                   int32_t to, const uint64_t lo[3], const int cw[3], int eb,
                   uint64_t *restrict A, uint64_t *restrict key, int32_t *restrict idx,
                   int32_t *n_core, int32_t *n_out) {
  const nbs__grid g = *kg->g;
  nbs__cs_keying k1 = *kg;
  k1.g = &g;
  k1.dim = dim;
  const int sy = k1.sy, sz = k1.sz, c0 = cw[0], c1 = cw[1];
  const uint64_t mx = ((uint64_t)1 << sy) - 1, my = ((uint64_t)1 << (sz - sy)) - 1;
  const uint64_t l0 = lo[0], l1 = lo[1], l2 = lo[2];
  const uint64_t s0 = (uint64_t)1 << cw[0], s1 = (uint64_t)1 << cw[1], s2 = (uint64_t)1 << cw[2];
  int32_t cc = 0, oc = 0;
  for (int32_t k = f; k < to; k++) {
    const uint64_t kk = nbs__cs_cellkey(&k1, x + (size_t)k * (size_t)dim);
    const uint64_t ox = (kk & mx) - l0, oy = ((kk >> sy) & my) - l1;
    const uint64_t oz = dim == 3 ? (kk >> sz) - l2 : 0;
    if (ox < s0 && oy < s1 && oz < s2) {
      A[cc++] = ((oz << c1 | oy) << c0 | ox) << eb | (uint64_t)k;
    } else if (idx) {
      key[oc] = kk;
      idx[oc++] = k;
    } else {
      key[oc++] = kk << eb | (uint64_t)k; /* packed keys: the outlier's word */
    }
  }
  *n_core = cc;
  *n_out = oc;
}

#if NBS__CS_AVX512
/* The crowded core's box (corner lo, sides of cw bits in each field of the whole key) in
 * AVX-512 registers, for 8 keys at a time: nbs__cs_core8_in. */
typedef struct nbs__cs_core8 {
  __m512i mx, my, l0, l1, l2, s0, s1, s2;
  __m128i shy, shz, sc0, sc1;
} nbs__cs_core8;

static inline __attribute__((always_inline)) NBS__CS_AVX512_TARGET void
nbs__cs_core8_init(nbs__cs_core8 *b, const nbs__cs_keying *kg, const uint64_t lo[3],
                  const int cw[3]) {
  const int sy = kg->sy, sz = kg->sz;
  b->mx = _mm512_set1_epi64((int64_t)(((uint64_t)1 << sy) - 1));
  b->my = _mm512_set1_epi64((int64_t)(((uint64_t)1 << (sz - sy)) - 1));
  b->l0 = _mm512_set1_epi64((int64_t)lo[0]);
  b->l1 = _mm512_set1_epi64((int64_t)lo[1]);
  b->l2 = _mm512_set1_epi64((int64_t)lo[2]);
  b->s0 = _mm512_set1_epi64((int64_t)((uint64_t)1 << cw[0]));
  b->s1 = _mm512_set1_epi64((int64_t)((uint64_t)1 << cw[1]));
  b->s2 = _mm512_set1_epi64((int64_t)((uint64_t)1 << cw[2]));
  b->shy = _mm_cvtsi32_si128(sy);
  b->shz = _mm_cvtsi32_si128(sz);
  b->sc0 = _mm_cvtsi32_si128(cw[0]);
  b->sc1 = _mm_cvtsi32_si128(cw[1]);
}

/* Which of the 8 whole keys kk lie in the box (the mask), and each one's key relative to the
 * box's corner (*rel; the lanes outside it hold no key). */
static inline __attribute__((always_inline)) NBS__CS_AVX512_TARGET __mmask8
nbs__cs_core8_in(const nbs__cs_core8 *b, __m512i kk, int dim, __m512i *rel) {
  const __m512i ox = _mm512_sub_epi64(_mm512_and_si512(kk, b->mx), b->l0);
  const __m512i oy =
      _mm512_sub_epi64(_mm512_and_si512(_mm512_srl_epi64(kk, b->shy), b->my), b->l1);
  __mmask8 in = _mm512_cmplt_epu64_mask(ox, b->s0) & _mm512_cmplt_epu64_mask(oy, b->s1);
  __m512i w = oy;
  if (dim == 3) {
    const __m512i oz = _mm512_sub_epi64(_mm512_srl_epi64(kk, b->shz), b->l2);
    in &= _mm512_cmplt_epu64_mask(oz, b->s2);
    w = _mm512_or_si512(_mm512_sll_epi64(oz, b->sc1), oy);
  }
  *rel = _mm512_or_si512(_mm512_sll_epi64(w, b->sc0), ox);
  return in;
}

/* The 8 elements at x8 (dim constant where this is inlined): their coordinates to c[], in the
 * key's order of the axes (c[a] the caller's coordinate kg->c[a], as nbs__cs_pos8 gives
 * them), their whole keys to *kk (nbs__cs_key8_of), and which of them lie in the core box
 * (the mask), with their keys relative to it to *rel (nbs__cs_core8_in). */
static inline __attribute__((always_inline)) NBS__CS_AVX512_TARGET __mmask8
nbs__cs_core8_next(const nbs__cs_keys8 *v, const nbs__cs_core8 *b, const double *x8, int dim,
                   __m512d c[3], __m512i *kk, __m512i *rel) {
  __m512d t[3];
  nbs__cs_pos8(v, x8, dim, c, t);
  *kk = nbs__cs_key8_of(v, t, dim);
  return nbs__cs_core8_in(b, *kk, dim, rel);
}

/* nbs__cs_core_split 8 elements at a time (AVX-512: F, DQ, VL), the keys as nbs__cs_key8_of
 * computes them (the same keys bit for bit): each lane's offsets from the core box's corner
 * compared with its sides at once, and the lanes in the box and the others each packed by a
 * compress and stored whole (8 words, of which the next store overwrites those past the
 * count: a store stays within [f, to) as long as 8 elements remain). The same words in the
 * same order as the scalar loop, which does the last few elements. Against the scalar loop
 * (3D, N = 1e6, one thread, interleaved, medians of 5, preparation in ns per element, the
 * same hashes): sparse 14.21 -> 11.94, clustered 14.16 -> 11.90, two threads sparse 9.73 ->
 * 7.89; perf: the split 11.3% -> 2.9% of the sparse scene's detection. */
static inline __attribute__((always_inline)) NBS__CS_AVX512_TARGET void
nbs__cs_core_split512_body(const nbs__cs_keying *kg, const double *restrict x, int dim,
                           int32_t f, int32_t to, const uint64_t lo[3], const int cw[3], int eb,
                           uint64_t *restrict A, uint64_t *restrict key, int32_t *restrict idx,
                           int32_t *n_core, int32_t *n_out) {
  nbs__cs_keys8 v;
  nbs__cs_keys8_init(&v, kg);
  nbs__cs_core8 bx;
  nbs__cs_core8_init(&bx, kg, lo, cw);
  const __m128i seb = _mm_cvtsi32_si128(eb);
  const __m512i eight = _mm512_set1_epi64(8);
  __m512i es = _mm512_add_epi64(_mm512_set_epi64(7, 6, 5, 4, 3, 2, 1, 0), _mm512_set1_epi64(f));
  int32_t cc = 0, oc = 0, e = f;
  for (; to - e >= 8; e += 8) {
    __m512d c[3];
    __m512i kk, w;
    const __mmask8 in = nbs__cs_core8_next(&v, &bx, x + (size_t)e * (size_t)dim, dim, c, &kk, &w);
    w = _mm512_or_si512(_mm512_sll_epi64(w, seb), es);
    _mm512_storeu_si512((void *)(A + cc), _mm512_maskz_compress_epi64(in, w));
    cc += __builtin_popcount(in);
    const __mmask8 out = (__mmask8)~in;
    if (out) {
      /* the outliers' keys and elements, or (packed keys) their words */
      const __m512i ov = idx ? kk : _mm512_or_si512(_mm512_sll_epi64(kk, seb), es);
      _mm512_storeu_si512((void *)(key + oc), _mm512_maskz_compress_epi64(out, ov));
      if (idx) {
        _mm256_storeu_si256((void *)(idx + oc),
                            _mm512_cvtepi64_epi32(_mm512_maskz_compress_epi64(out, es)));
      }
      oc += __builtin_popcount(out);
    }
    es = _mm512_add_epi64(es, eight);
  }
  int32_t tc = 0, to_ = 0;
  nbs__cs_core_split(kg, x, dim, e, to, lo, cw, eb, A + cc, key + oc, idx ? idx + oc : NULL,
                     &tc, &to_);
  *n_core = cc + tc;
  *n_out = oc + to_;
}

NBS__CS_AVX512_TARGET
static void nbs__cs_core_split512(const nbs__cs_keying *kg, const double *x, int32_t f,
                                  int32_t to, const uint64_t lo[3], const int cw[3], int eb,
                                  uint64_t *A, uint64_t *key, int32_t *idx, int32_t *n_core,
                                  int32_t *n_out) {
  if (kg->dim == 3) {
    nbs__cs_core_split512_body(kg, x, 3, f, to, lo, cw, eb, A, key, idx, n_core, n_out);
  } else {
    nbs__cs_core_split512_body(kg, x, 2, f, to, lo, cw, eb, A, key, idx, n_core, n_out);
  }
}
#endif

/* Bins per axis of nbs__cs_core's histograms: at most 2^12. */
#define NBS__CS_CORE_BINS 12

/* Step a of nbs__cs_core (and of nbs__cs_core_part): the crowded core's box, its corner lo
 * and its sides' bits cw in each field of the whole key (bits of them in all, returned), from
 * a sample of the elements; the coordinate arrays are its scratch. */
static int nbs__cs_core_box(const nbs__cs *c, const nbs__run *run, const nbs__cs_keying *kg,
                            int bits, uint64_t lo[3], int cw[3]) {
  const int32_t n = c->n;
  const int dim = c->dim;
  const double *x = run->x;
  /* the key's fields: x sub-cell, iy, iz; where each starts and its bits */
  const int at[3] = {0, kg->sy, kg->sz};
  const int wd[3] = {c->bx, c->by, dim == 3 ? bits - c->bx - c->by : 0};
  uint64_t mask[3] = {0, 0, 0};
  /* a. the histograms of a sample, every stride-th element (about 2^13 of them), in the
   * coordinate arrays: at most 2^12 bins per axis, and at most n / 2, so that they and the
   * sample's keys after them take at most 2 dim n + 8 n bytes of the arrays' 8 dim n */
  int hb = 0;
  while (hb < NBS__CS_CORE_BINS && ((int64_t)2 << hb) <= (int64_t)n) hb++;
  for (int a = 0; a < dim; a++) mask[a] = ((uint64_t)1 << wd[a]) - 1; /* at most 33 bits */
  uint32_t *hall = (uint32_t *)(void *)c->xs;
  const int32_t stride = n >> 13 > 0 ? n >> 13 : 1;
  const int64_t m = ((int64_t)n + stride - 1) / stride; /* the sample's size */
  const int64_t need = m - m / (16 * dim);
  /* the sample's keys, after the histograms */
  uint64_t *sample = (uint64_t *)(void *)(hall + ((size_t)dim << hb));
  /* each axis's window [lo, lo + span) of its field: the whole field, then the fewest bins
   * that hold `need` of the sample, then within those the bins, finer, from the first to the
   * last that hold any of it */
  uint64_t span[3] = {1, 1, 1}, lo0[3] = {0, 0, 0};
  for (int a = 0; a < 3; a++) lo[a] = 0;
  for (int a = 0; a < dim; a++) span[a] = (uint64_t)1 << wd[a];
  for (int round = 0; round < 2; round++) {
    if (round == 1) memcpy(lo0, lo, 3 * sizeof *lo);
    int sh[3] = {0, 0, 0};
    size_t bins[3] = {1, 1, 1};
    for (int a = 0; a < dim; a++) {
      const int w = nbs__bits(span[a]);
      sh[a] = w > hb ? w - hb : 0;
      bins[a] = (size_t)((span[a] - 1) >> sh[a]) + 1; /* at most 2^hb */
    }
    memset(hall, 0, ((size_t)dim << hb) * sizeof *hall);
    for (int64_t k = 0, s = 0; k < n; k += stride, s++) {
      uint64_t kk;
      if (round == 0) {
        /* the sample's reads are far apart: ask for them ahead */
        if (k + 16 * (int64_t)stride < n) {
          __builtin_prefetch(x + (size_t)(k + 16 * (int64_t)stride) * (size_t)dim);
        }
        kk = nbs__cs_cellkey(kg, x + (size_t)k * (size_t)dim);
        sample[s] = kk;
      } else {
        kk = sample[s];
      }
      for (int a = 0; a < dim; a++) {
        const uint64_t v = ((kk >> at[a]) & mask[a]) - lo[a];
        if (v < span[a]) hall[((size_t)a << hb) + (v >> sh[a])]++;
      }
    }
    for (int a = 0; a < dim; a++) {
      const uint32_t *h = hall + ((size_t)a << hb);
      /* need, then all of the sample within the window */
      int64_t want = need;
      if (round == 1) {
        want = 0;
        for (size_t b = 0; b < bins[a]; b++) want += h[b];
      }
      size_t b0 = 0, best0 = 0, best = bins[a];
      int64_t sum = 0;
      for (size_t b1 = 0; b1 < bins[a]; b1++) {
        sum += h[b1];
        while (b0 < b1 && sum - h[b0] >= want) sum -= h[b0++];
        if (sum >= want && b1 - b0 + 1 < best) {
          best = b1 - b0 + 1;
          best0 = b0;
        }
      }
      const uint64_t l = (uint64_t)best0 << sh[a], w = (uint64_t)best << sh[a];
      lo[a] += l;
      span[a] = w < span[a] - l ? w : span[a] - l;
    }
  }
  /* the box's sides are powers of two: their room beyond the window, half of it below, as
   * far as the first round's window (elements beyond the sample's lowest are not left out
   * for that; those the first round left out stay out) */
  int cb = 0;
  for (int a = 0; a < 3; a++) cw[a] = 0;
  for (int a = 0; a < dim; a++) {
    cw[a] = nbs__bits(span[a]);
    const uint64_t below = (((uint64_t)1 << cw[a]) - span[a]) / 2;
    lo[a] -= below < lo[a] - lo0[a] ? below : lo[a] - lo0[a];
    cb += cw[a];
  }
  return cb;
}

/* Steps 1 and 2 where the keys do not fit a word with the element but those of a crowded
 * core would: a few elements far out (the sparse scene's 0.1% a million diameters away, the
 * clustered scene's 1%) stretch the grid until its keys need 60 bits, unpacked, while the
 * rest sit in a box whose keys need 30. Sorting them all by the whole key took 7-8 LSD
 * passes of 12 bytes per element, each to and from memory (3D sparse, N = 1e6: a third of
 * the detection's time). So:
 *   a. a histogram per axis of where a sample of the elements lies (every stride-th, about
 *      2^13 of them; 2^12 bins at most), and on each axis the fewest consecutive bins that
 *      hold all but 1 / (16 dim) of the sample; then a histogram within those bins, in bins
 *      as fine as 2^12 of them allow, and the bins from the first to the last that hold any
 *      of the sample: the core box, its sides rounded up to powers of two, as long as the
 *      bits its keys need allow. (With the first histogram alone, whose bins are hundreds
 *      of cells wide where the far elements stretch the grid, the sparse scene's core of
 *      100 cells a side took a bin or two on each axis: 28 bits where 24 do, which cost the
 *      sort its top digit in cache, four passes to and from memory instead);
 *   b. the core's elements as packed words (the key relative to the core box's corner, and
 *      the element), the others (the outliers) as (key, element), at the start of key[] and
 *      idx[] (nbs__cs_core_split); then each group's parts of the threads joined up;
 *   c. the outliers sorted by their whole key (a plain LSD sort: they are few), then the
 *      core's words as any packed words (nbs__radix: the top digit first, the rest in cache);
 *   d. the two merged, from the end, into key[] and idx[], each core word's key put back in
 *      the whole grid's terms (adding the corner's offset to each field keeps the order).
 * The result is that of the sort by the whole key: the order of (key, element), since both
 * sorts are stable and both groups come to them in element order, and no core element
 * shares a key with an outlier (which group an element is in follows from its key). The
 * sample only chooses the box: any box gives the same result, a bad one only more outliers.
 * Measured (3D, N = 1e6, one thread, interleaved, min of 5 processes, ns per element): the
 * sparse scene 46.5 -> 41.4 and the clustered one 39.4 -> 34.8, with uniform at 31.2 in the
 * same run; two threads (min of 4) 32.7 -> 23.9 and 27.2 -> 21.6, though the sample and the
 * merge run on one; sparse at N = 1e7 50.4 -> 43.0. Then the second histogram, the sample
 * of 2^13 where it was 2^16 (its reads are far apart, and they took 1-2 ns per element of
 * the detection) and the merge a run at a time (below), interleaved, min of 5: sparse 44.0
 * -> 39.3, clustered 39.4 -> 37.0; two threads 23.5 -> 21.0 and 21.6 -> 20.0; the same
 * bytes.
 * Packed keys too (c->idx NULL: the whole keys share a word with the element), where they take
 * four passes or more and the core's would save two (2D sparse and clustered, N = 1e6: 43
 * bits, five passes, against the core's 23, three); the outliers are then packed words, and so
 * is the merge's output, the words of the sort by the whole word (the time steps start from
 * them as from any). First tried with the split a scalar loop: no faster (2D sparse 23.2 /
 * 23.2, clustered 23.6 / 23.2: the split and the merge cost what the two passes did). With the
 * split of nbs__cs_core_split512 (interleaved, medians of 6, preparation in ns per element, the
 * same hashes): 2D sparse 12.27 -> 10.18, clustered 11.39 -> 10.50, two threads sparse 9.51 ->
 * 7.02; time steps (which start from the last order) and the huge domain (whose core is the
 * whole domain: no two passes saved, the sample only) the same. Returns false, having written
 * nothing the caller needs, where the core's keys would not fit a word with the element
 * either, or, for packed keys, would not save two passes.
 * Scratch: the coordinate arrays (the histograms, the core's words and the bucket scratch,
 * the outliers at their end). */
static bool nbs__cs_core(const nbs__cs *c, const nbs__run *run, const nbs__cs_keying *kg,
                         int eb, int bits, uint32_t *hist, int threads) {
  const int32_t n = c->n;
  const int dim = c->dim;
  const double *x = run->x;
  uint64_t *key = c->key;
  int32_t *idx = c->idx;
  const bool packed = idx == NULL; /* the whole keys share a word with the element too */
  const int at[3] = {0, kg->sy, kg->sz};
  uint64_t lo[3];
  int cw[3];
  const int cb = nbs__cs_core_box(c, run, kg, bits, lo, cw);
  if (cb + eb > 63) return false;
  /* packed keys: only where the core's keys save two passes or more (the split and the merge
   * cost about what a pass in the cache does) */
  if (packed && nbs__radix_digits(cb).passes + 2 > nbs__radix_digits(bits).passes) return false;
  /* b. the core's words at the start of each thread's part of the coordinate arrays, the
   * outliers at the start of its part of key[] and idx[] */
  uint64_t *A = (uint64_t *)(void *)c->xs;
  int32_t from[NBS__THREADS_MAX + 1], nc[NBS__THREADS_MAX], no[NBS__THREADS_MAX];
  for (int t = 0; t <= threads; t++) from[t] = nbs__chunk(n, t, threads);
#if defined(_OPENMP)
#pragma omp parallel num_threads(threads) if (threads > 1)
#endif
  NBS__PARTS(t, threads) {
    const int32_t f = from[t], to = from[t + 1];
    int32_t *oi = packed ? NULL : idx + f; /* the outliers' elements (packed: in their words) */
#if NBS__CS_AVX512
    if (run->ctx->simd == NBS__SIMD_AVX512) {
      nbs__cs_core_split512(kg, x, f, to, lo, cw, eb, A + f, key + f, oi, &nc[t], &no[t]);
    } else
#endif
    if (dim == 3) {
      nbs__cs_core_split(kg, x, 3, f, to, lo, cw, eb, A + f, key + f, oi, &nc[t], &no[t]);
    } else {
      nbs__cs_core_split(kg, x, 2, f, to, lo, cw, eb, A + f, key + f, oi, &nc[t], &no[t]);
    }
  }
  /* the outliers together, and the core's words together, each in element order: the radix
   * sort is stable and sorts by the key's bits alone, so that words of one key keep the
   * order they come in (with one thread nothing moves) */
  int32_t NO = 0, NC = 0;
  for (int t = 0; t < threads; t++) {
    if (NO != from[t] && no[t] > 0) {
      memmove(key + NO, key + from[t], (size_t)no[t] * sizeof *key);
      if (!packed) memmove(idx + NO, idx + from[t], (size_t)no[t] * sizeof *idx);
    }
    if (NC != from[t] && nc[t] > 0) memmove(A + NC, A + from[t], (size_t)nc[t] * sizeof *A);
    NO += no[t];
    NC += nc[t];
  }
  /* c. the outliers, sorted to the end of the coordinate arrays; then the core */
  const size_t W = (size_t)n * (size_t)dim;
  uint64_t *tk = A + W - ((size_t)NO + (packed ? 0 : ((size_t)NO + 1) / 2));
  int32_t *ti = packed ? NULL : (int32_t *)(void *)(tk + NO);
  if (NO > 0) {
    nbs__radix(key, idx, tk, ti, tk, ti, NO, packed ? eb : 0, nbs__radix_digits(bits), hist,
               1, false, NULL, 0);
  }
  if (NC > 0) {
    nbs__radix(A, NULL, key, NULL, key, NULL, NC, eb, nbs__radix_digits(cb), hist, threads,
               run->ctx->cs_steal_first, A + NC, (size_t)(tk - (A + NC)));
  }
  /* d. the merge, from the end, a run at a time: outlier j goes after the core words whose
   * keys are below its own (a_j of them, found by galloping down from a_(j+1), then
   * bisection), and the run of core words between it and outlier j + 1 moves up by j + 1
   * places, each word put back in the whole grid's terms. A run moves eight words at a time,
   * all eight read before any is written, so that a move by fewer places than eight reads
   * each word before it is overwritten (a core word only moves up), with no branch per word
   * (against word by word, with a branch on which of the two came next: 3D, N = 1e6,
   * interleaved, min of 6, sparse 40.0 -> 39.5 ns per element, clustered 37.1 -> 36.7). */
  const uint64_t em = ((uint64_t)1 << eb) - 1;
  const int s1 = at[1], s2 = at[2], c0 = cw[0], c01 = cw[0] + cw[1];
  const uint64_t m0 = ((uint64_t)1 << cw[0]) - 1, m1 = ((uint64_t)1 << cw[1]) - 1;
#define NBS__CS_WHOLE(w)                                                                       \
  ((((w) >> eb >> c01) + lo[2]) << s2 | ((((w) >> eb >> c0) & m1) + lo[1]) << s1 |               \
   ((((w) >> eb) & m0) + lo[0]))
  /* core word w to place p: its key in the whole grid's terms, and its element (packed keys:
   * the word of the two) */
#define NBS__CS_BACK(p, w)                                                                     \
  do {                                                                                        \
    if (packed) {                                                                             \
      key[p] = NBS__CS_WHOLE(w) << eb | ((w) & em);                                           \
    } else {                                                                                  \
      idx[p] = (int32_t)((w) & em);                                                           \
      key[p] = NBS__CS_WHOLE(w);                                                              \
    }                                                                                         \
  } while (0)
  int32_t r = NC; /* the core words below outlier j + 1 */
  for (int32_t j = NO - 1; j >= 0; j--) {
    const uint64_t o = packed ? tk[j] >> eb : tk[j]; /* its key */
    /* the core words above o: [lo_, r) */
    int32_t lo_;
#define NBS__CS_BELOW(i) (NBS__CS_WHOLE(key[i]) < o)
    NBS__CS_GALLOP(lo_, 0, r, NBS__CS_BELOW);
#undef NBS__CS_BELOW
    const int32_t by = j + 1;
    int32_t q = r;
    while (q - lo_ >= 8) {
      q -= 8;
      uint64_t w[8];
      for (int l = 0; l < 8; l++) w[l] = key[q + l];
      for (int l = 0; l < 8; l++) NBS__CS_BACK(q + by + l, w[l]);
    }
    while (q > lo_) {
      q--;
      const uint64_t w = key[q];
      NBS__CS_BACK(q + by, w);
    }
    if (packed) {
      key[lo_ + j] = tk[j];
    } else {
      key[lo_ + j] = o;
      idx[lo_ + j] = ti[j];
    }
    r = lo_;
  }
  const int32_t i = r - 1;
  /* the core words below the last outlier: in place */
#if defined(_OPENMP)
#pragma omp parallel for num_threads(threads) schedule(static) if (threads > 1)
#endif
  for (int32_t q = 0; q <= i; q++) {
    const uint64_t w = key[q];
    NBS__CS_BACK(q, w);
  }
#undef NBS__CS_BACK
#undef NBS__CS_WHOLE
  run->ctx->cs_outliers = NO;
  return true;
}

/* ---- the partition: the sort and the gather at once, where the input is large ---------- */

/* Entries of 8 bytes in a cache line. */
#define NBS__CS_LINE 8

/* The 64 bytes at src to dst (both on a 64-byte boundary), past the caches where the
 * processor can (a streaming store: the line is written whole, not read first). Tried and
 * left out: plain stores, so that the buckets' pass would find the lines in the cache (the
 * Intel guest's L3 holds 105 MB, the arrays of N = 1e6 24 to 40): each line was read first,
 * and the preparation lost (2026-11-29, N = 1e6, NBS_PARTITION=always, interleaved, min of
 * 4, ns per element, the same hashes): 2D uniform 23.2 -> 31.7, 3D uniform 24.2 -> 36.5, 3D
 * sparse 38.0 -> 55.1. */
static inline void nbs__cs_stream(void *dst, const void *src) {
#if NBS__CS_AVX512
  __m128i *d = (__m128i *)dst;
  const __m128i *s = (const __m128i *)src;
  _mm_stream_si128(d, _mm_load_si128(s));
  _mm_stream_si128(d + 1, _mm_load_si128(s + 1));
  _mm_stream_si128(d + 2, _mm_load_si128(s + 2));
  _mm_stream_si128(d + 3, _mm_load_si128(s + 3));
#else
  memcpy(dst, src, 64);
#endif
}

/* The arrays a partition writes: the words and each coordinate array (and the radii), in
 * their order in a bucket's line buffer. */
typedef struct nbs__cs_dst {
  uint64_t *key;
  double *a[4];
  int S; /* coordinate arrays: dim, + 1 with radii */
} nbs__cs_dst;

/* The arrays of c a partition writes. */
static nbs__cs_dst nbs__cs_dst_of(const nbs__cs *c) {
  nbs__cs_dst d;
  d.key = c->key;
  d.a[0] = c->xs;
  d.a[1] = c->ys;
  d.a[2] = c->dim == 3 ? c->zs : c->rs;
  d.a[3] = c->dim == 3 ? c->rs : NULL;
  d.S = c->dim + (c->rs != NULL ? 1 : 0);
  return d;
}

/* Places [from, to) of the line buffers wl (words) and cl (coordinates) to their places in
 * the arrays, one by one: a line not wholly the thread's own. */
static inline __attribute__((always_inline)) void
nbs__cs_put(const nbs__cs_dst *d, const uint64_t *wl, const double *cl, uint32_t from,
            uint32_t to) {
  for (uint32_t q = from; q < to; q++) {
    d->key[q] = wl[q % NBS__CS_LINE];
    for (int s = 0; s < d->S; s++) d->a[s][q] = cl[s * NBS__CS_LINE + q % NBS__CS_LINE];
  }
}

/* The crowded core's box of a partition (nbs__cs_core_part): its corner and the bits of its
 * sides in each field of the whole key (x sub-cell, iy, iz), and the whole keys of its
 * lowest and highest corners. */
typedef struct nbs__cs_corebox {
  uint64_t lo[3];
  int cw[3];
  int pad; /* the relative keys' shift up, so that the partition's top digit is whole */
  uint64_t wmin, wmax;
  /* the partition's buckets: the whole key of each one's lowest place (b >= 1), and the
   * outliers between wmin and wmax counted in the bucket whose keys' range they fall in */
  const uint64_t *bound;
  int buckets;
  uint32_t *between;
} nbs__cs_corebox;

/* Whether whole key kk (fields at 0, sy, sz) lies in box b; if so *rel is its key relative to
 * the box's corner, the fields packed in cw's bits (nbs__cs_core_split's words' keys), shifted
 * up by b->pad. */
static inline __attribute__((always_inline)) bool
nbs__cs_in_core(const nbs__cs_corebox *b, int sy, int sz, int dim, uint64_t kk, uint64_t *rel) {
  const uint64_t ox = (kk & (((uint64_t)1 << sy) - 1)) - b->lo[0];
  const uint64_t oy = ((kk >> sy) & (((uint64_t)1 << (sz - sy)) - 1)) - b->lo[1];
  const uint64_t oz = dim == 3 ? (kk >> sz) - b->lo[2] : 0;
  if ((ox >> b->cw[0]) | (oy >> b->cw[1]) | (oz >> b->cw[2])) return false;
  *rel = ((oz << b->cw[1] | oy) << b->cw[0] | ox) << b->pad;
  return true;
}

/* The whole key of the key rel relative to box b, shifted up by b->pad (the inverse of
 * nbs__cs_in_core: adding the corner to each field keeps the keys' order). */
static inline uint64_t nbs__cs_core_whole(const nbs__cs_corebox *b, int sy, int sz, uint64_t rel) {
  const int c0 = b->cw[0], c01 = b->cw[0] + b->cw[1];
  rel >>= b->pad;
  const uint64_t m0 = ((uint64_t)1 << c0) - 1, m1 = ((uint64_t)1 << b->cw[1]) - 1;
  return ((rel >> c01) + b->lo[2]) << sz | (((rel >> c0) & m1) + b->lo[1]) << sy |
         ((rel & m0) + b->lo[0]);
}

/* The highest value of each field of a whole key of `bits` bits, its fields at 0, sy, sz. */
static void nbs__cs_field_max(int sy, int sz, int bits, uint64_t fmax[3]) {
  fmax[0] = ((uint64_t)1 << sy) - 1;
  fmax[1] = ((uint64_t)1 << (sz - sy)) - 1;
  fmax[2] = bits > sz ? ((uint64_t)1 << (bits - sz)) - 1 : 0;
}

/* The lowest whole key, at or after the key rel relative to box b (shifted up by b->pad) in
 * the order of the box's keys, whose fields lie within their ranges in the whole key (x below
 * 2^sy, y below 2^(sz - sy), z below 2^(bits - sz)); UINT64_MAX where there is none. The box's
 * sides are powers of two and may pass the grid's fields (a window near the top of a field
 * rounded up), where nbs__cs_core_whole's fields would spill into the next: no element lies
 * there, but a bucket's lowest key or the box's highest may. A position past x's range
 * continues at the next row of the box, one past y's at the next layer. */
static uint64_t nbs__cs_core_first(const nbs__cs_corebox *b, int sy, int sz, int bits,
                                   uint64_t rel) {
  rel >>= b->pad;
  const uint64_t m0 = ((uint64_t)1 << b->cw[0]) - 1, m1 = ((uint64_t)1 << b->cw[1]) - 1;
  uint64_t ox = rel & m0, oy = (rel >> b->cw[0]) & m1, oz = rel >> (b->cw[0] + b->cw[1]);
  uint64_t fmax[3];
  nbs__cs_field_max(sy, sz, bits, fmax);
  if (b->lo[0] + ox > fmax[0]) {
    ox = 0;
    oy++;
  }
  if (oy > m1 || b->lo[1] + oy > fmax[1]) {
    ox = 0;
    oy = 0;
    oz++;
  }
  if (oz >> b->cw[2] || b->lo[2] + oz > fmax[2]) return UINT64_MAX;
  return (b->lo[2] + oz) << sz | (b->lo[1] + oy) << sy | (b->lo[0] + ox);
}

/* Outlier kk (a whole key outside box b) counted in o[]: o[0] where its key is below the
 * box's lowest, o[2] above its highest, else o[1] and b->between[u], u the bucket whose range
 * holds it: the number of buckets past the first whose lowest key is below it (no core key is
 * equal to it). */
static inline void nbs__cs_core_outlier(const nbs__cs_corebox *b, uint64_t kk, int32_t o[3]) {
  if (kk < b->wmin) {
    o[0]++;
  } else if (kk > b->wmax) {
    o[2]++;
  } else {
    int lo_ = 1, hi = b->buckets;
    while (lo_ < hi) {
      const int m = lo_ + (hi - lo_) / 2;
      if (b->bound[m] < kk) lo_ = m + 1;
      else hi = m;
    }
#if defined(_OPENMP)
#pragma omp atomic
#endif
    b->between[lo_ - 1]++;
    o[1]++;
  }
}

/* The counts of the keys' top digit (at kshift, dmask) of the elements [f, to), into h.
 * With a core box (nbs__cs_core_part; NULL where this is inlined for the whole keys), the
 * digit of the key relative to it, for the elements in it; the others (outliers) counted in
 * out[] (nbs__cs_core_outlier). Added to h and out, which the caller clears. */
static inline __attribute__((always_inline)) void
nbs__cs_part_count(const nbs__cs_keying *kg, const double *restrict x, int dim, int32_t f,
                   int32_t to, int kshift, uint64_t dmask, uint32_t *restrict h,
                   const nbs__cs_corebox *core, int32_t out[3]) {
  const nbs__grid g = *kg->g;
  nbs__cs_keying k1 = *kg;
  k1.g = &g;
  k1.dim = dim;
  nbs__cs_corebox box;
  if (core) box = *core;
  for (int32_t k = f; k < to; k++) {
    uint64_t kk = nbs__cs_cellkey(&k1, x + (size_t)k * (size_t)dim);
    if (core && !nbs__cs_in_core(&box, k1.sy, k1.sz, dim, kk, &kk)) {
      nbs__cs_core_outlier(&box, kk, out);
      continue;
    }
    h[(kk >> kshift) & dmask]++;
  }
}

#if NBS__CS_AVX512
/* nbs__cs_part_count with a core box, 8 elements at a time (AVX-512), the keys as
 * nbs__cs_key8_of computes them (the same bit for bit): each lane's offsets from the box's
 * corner compared with its sides at once, the digits of the lanes in the box counted one by
 * one, the outliers (few) classified by the scalar loop's rule; the last few elements by the
 * scalar loop. Against the scalar loop (N = 1e6, one thread, NBS_PARTITION=always,
 * interleaved, min of 8, preparation in ns per element, the same hashes): 3D sparse 41.1 ->
 * 36.7, clustered 36.6 -> 32.1, 2D sparse 37.7 -> 34.7. */
static inline __attribute__((always_inline)) NBS__CS_AVX512_TARGET void
nbs__cs_core_count512_body(const nbs__cs_keying *kg, const double *restrict x, int dim,
                           int32_t f, int32_t to, int kshift, uint64_t dmask,
                           uint32_t *restrict h, const nbs__cs_corebox *core, int32_t out[3]) {
  nbs__cs_keys8 v;
  nbs__cs_keys8_init(&v, kg);
  const nbs__cs_corebox box = *core;
  nbs__cs_core8 bx;
  nbs__cs_core8_init(&bx, kg, box.lo, box.cw);
  const __m128i sdig = _mm_cvtsi32_si128(kshift - box.pad);
  const __m512i dm = _mm512_set1_epi64((int64_t)dmask);
  int32_t e = f;
  for (; to - e >= 8; e += 8) {
    __m512d c[3];
    __m512i kk, w;
    const __mmask8 in = nbs__cs_core8_next(&v, &bx, x + (size_t)e * (size_t)dim, dim, c, &kk, &w);
    /* the digit of (relative key << pad) at kshift: the relative key's at kshift - pad */
    uint64_t dg[8];
    _mm512_storeu_si512((void *)dg, _mm512_and_si512(_mm512_srl_epi64(w, sdig), dm));
    if (in == 0xff) {
      for (int l = 0; l < 8; l++) h[dg[l]]++;
      continue;
    }
    uint64_t kl[8];
    _mm512_storeu_si512((void *)kl, kk);
    for (int l = 0; l < 8; l++) {
      if (in >> l & 1) {
        h[dg[l]]++;
      } else {
        nbs__cs_core_outlier(&box, kl[l], out);
      }
    }
  }
  nbs__cs_part_count(kg, x, dim, e, to, kshift, dmask, h, core, out);
}

NBS__CS_AVX512_TARGET
static void nbs__cs_core_count512(const nbs__cs_keying *kg, const double *x, int32_t f,
                                  int32_t to, int kshift, uint64_t dmask, uint32_t *h,
                                  const nbs__cs_corebox *core, int32_t out[3]) {
  if (kg->dim == 3) {
    nbs__cs_core_count512_body(kg, x, 3, f, to, kshift, dmask, h, core, out);
  } else {
    nbs__cs_core_count512_body(kg, x, 2, f, to, kshift, dmask, h, core, out);
  }
}
#endif

/* One element to bucket b of a partition's scatter: its word w and coordinates (x0, x1, x2)
 * and radius (r0) to the next place of the bucket's line buffers, and the lines to the arrays
 * when full: a line wholly this thread's (from start[b] on) with streaming stores, one that
 * holds places of another entry by entry. */
static inline __attribute__((always_inline)) void
nbs__cs_part_put(const nbs__cs_dst *d, int dim, bool radii, size_t b, uint64_t w, double x0,
                 double x1, double x2, double r0, uint32_t *restrict h,
                 const uint32_t *restrict start, uint64_t *restrict wb) {
  const int S = dim + (radii ? 1 : 0);
  const uint32_t pos = h[b]++;
  const uint32_t s = pos % NBS__CS_LINE;
  uint64_t *wl = wb + b * (size_t)(S + 1) * NBS__CS_LINE;
  double *cl = (double *)(void *)(wl + NBS__CS_LINE);
  wl[s] = w;
  cl[s] = x0;
  cl[NBS__CS_LINE + s] = x1;
  if (dim == 3) cl[2 * NBS__CS_LINE + s] = x2;
  if (radii) cl[dim * NBS__CS_LINE + s] = r0;
  if (s == NBS__CS_LINE - 1) {
    const uint32_t l0 = pos - (NBS__CS_LINE - 1);
    if (l0 >= start[b]) {
      nbs__cs_stream(d->key + l0, wl);
      nbs__cs_stream(d->a[0] + l0, cl);
      nbs__cs_stream(d->a[1] + l0, cl + NBS__CS_LINE);
      if (dim == 3) nbs__cs_stream(d->a[2] + l0, cl + 2 * NBS__CS_LINE);
      if (radii) nbs__cs_stream(d->a[dim == 3 ? 3 : 2] + l0, cl + dim * NBS__CS_LINE);
    } else {
      nbs__cs_put(d, wl, cl, start[b], pos + 1);
    }
  }
}

/* The elements [f, to) to their buckets: element k's word (key << eb | k), coordinates (and
 * radius) to place h[b]++ of the arrays, b its key's top digit (with a core box, the key
 * relative to it, and the outliers' whole keys and elements to ok[] and oe[] instead). Each bucket gathers a line
 * of each array in the buffer wb (per bucket, a line of 8 entries of its words, then one of
 * each coordinate array) and writes it whole when it is full; start[b] is the bucket's first
 * place of this thread, and a line that holds places of another (its first, and its last)
 * is written entry by entry. dim and radii are constants where this is inlined. */
static inline __attribute__((always_inline)) void
nbs__cs_part_scatter(const nbs__cs_keying *kg, const double *restrict x,
                     const double *restrict r, int dim, bool radii, int32_t f, int32_t to,
                     int eb, int kshift, uint64_t dmask, uint32_t *restrict h,
                     const uint32_t *restrict start, uint64_t *restrict wb,
                     const nbs__cs_dst *d, const nbs__cs_corebox *core,
                     uint64_t *restrict ok, int32_t *restrict oe) {
  const nbs__grid g = *kg->g;
  nbs__cs_keying k1 = *kg;
  k1.g = &g;
  k1.dim = dim;
  const int S = dim + (radii ? 1 : 0);
  nbs__cs_corebox box;
  if (core) box = *core;
  int32_t o = 0;
  for (int32_t k = f; k < to; k++) {
    const double *xk = x + (size_t)k * (size_t)dim;
    uint64_t kk = nbs__cs_cellkey(&k1, xk);
    if (core && !nbs__cs_in_core(&box, k1.sy, k1.sz, dim, kk, &kk)) {
      ok[o] = kk; /* an outlier: its whole key and element, in element order */
      oe[o++] = k;
      continue;
    }
    nbs__cs_part_put(d, dim, radii, (size_t)((kk >> kshift) & dmask), kk << eb | (uint64_t)k,
                     xk[0], xk[1], dim == 3 ? xk[2] : 0.0, radii ? r[k] : 0.0, h, start, wb);
  }
  /* each bucket's last line, as far as it is filled */
  for (size_t b = 0; b <= dmask; b++) {
    uint32_t l0 = h[b] - h[b] % NBS__CS_LINE;
    if (l0 < start[b]) l0 = start[b];
    uint64_t *wl = wb + b * (size_t)(S + 1) * NBS__CS_LINE;
    nbs__cs_put(d, wl, (double *)(void *)(wl + NBS__CS_LINE), l0, h[b]);
  }
#if NBS__CS_AVX512
  _mm_sfence(); /* the streaming stores, before another thread reads them */
#endif
}

#if NBS__CS_AVX512
/* nbs__cs_part_scatter with a core box (not NULL), 8 elements at a time (AVX-512): the keys
 * as nbs__cs_key8_of computes them (the same bit for bit), the relative keys and which lanes
 * are in the box (nbs__cs_core8_in),
 * the words and digits of the 8 at once; each lane then to its bucket's line buffers
 * (nbs__cs_part_put), an outlier to the list, in element order; the last few elements, and
 * the buckets' last lines, by the scalar loop. Against the scalar loop (3D sparse, N = 1e6,
 * one thread, NBS_PARTITION=always, interleaved, min of 8): preparation 40.4 -> 35.8 ns per
 * element, the same hashes (2D sparse 33.5 / 32.7). */
static inline __attribute__((always_inline)) NBS__CS_AVX512_TARGET void
nbs__cs_part_scatter512_body(const nbs__cs_keying *kg, const double *restrict x,
                             const double *restrict r, int dim, bool radii, int32_t f,
                             int32_t to, int eb, int kshift, uint64_t dmask,
                             uint32_t *restrict h, const uint32_t *restrict start,
                             uint64_t *restrict wb, const nbs__cs_dst *d,
                             const nbs__cs_corebox *core, uint64_t *restrict ok,
                             int32_t *restrict oe) {
  nbs__cs_keys8 v;
  nbs__cs_keys8_init(&v, kg);
  const nbs__cs_corebox box = *core;
  nbs__cs_core8 bx;
  nbs__cs_core8_init(&bx, kg, box.lo, box.cw);
  const __m128i spad = _mm_cvtsi32_si128(box.pad);
  const __m128i seb = _mm_cvtsi32_si128(eb), sdig = _mm_cvtsi32_si128(kshift);
  const __m512i dm = _mm512_set1_epi64((int64_t)dmask), eight = _mm512_set1_epi64(8);
  __m512i es = _mm512_add_epi64(_mm512_set_epi64(7, 6, 5, 4, 3, 2, 1, 0), _mm512_set1_epi64(f));
  int32_t o = 0, e = f;
  for (; to - e >= 8; e += 8) {
    __m512d c[3];
    __m512i kk, rel;
    const __mmask8 in =
        nbs__cs_core8_next(&v, &bx, x + (size_t)e * (size_t)dim, dim, c, &kk, &rel);
    uint64_t kl[8];
    _mm512_storeu_si512((void *)kl, kk);
    rel = _mm512_sll_epi64(rel, spad);
    uint64_t wv[8], dv[8];
    double cv[3][8];
    _mm512_storeu_si512((void *)wv, _mm512_or_si512(_mm512_sll_epi64(rel, seb), es));
    _mm512_storeu_si512((void *)dv, _mm512_and_si512(_mm512_srl_epi64(rel, sdig), dm));
    /* c[] holds the key's axes: key axis a is the caller's coordinate kg->c[a] (the rows
     * lie along the axis with the most cells), and the arrays keep the caller's order */
    for (int a = 0; a < dim; a++) _mm512_storeu_pd(cv[kg->c[a]], c[a]);
    for (int l = 0; l < 8; l++) {
      if (!(in >> l & 1)) {
        ok[o] = kl[l];
        oe[o++] = e + l;
        continue;
      }
      nbs__cs_part_put(d, dim, radii, (size_t)dv[l], wv[l], cv[0][l], cv[1][l],
                       dim == 3 ? cv[2][l] : 0.0, radii ? r[e + l] : 0.0, h, start, wb);
    }
    es = _mm512_add_epi64(es, eight);
  }
  nbs__cs_part_scatter(kg, x, r, dim, radii, e, to, eb, kshift, dmask, h, start, wb, d, core,
                       ok + o, oe + o);
}

/* nbs__cs_part_scatter512_body with dim and radii constants, for nbs__cs_core_part (core not
 * NULL). With the whole keys (nbs__cs_partition, core NULL), where the keys cost less than
 * the in-box test and the relative key, it gained nothing over the scalar loop (3D and 2D
 * uniform, N = 1e6, interleaved, min of 8, preparation 21.9 / 22.6 and 21.2 / 22.4 ns per
 * element): what it saved on the keys, the stores to S + 1 lines per element lost. There
 * the keys 8 at a time gain with one store per element (nbs__cs_part_rec512). */
NBS__CS_AVX512_TARGET
static void nbs__cs_part_scatter512(const nbs__cs_keying *kg, const double *x, const double *r,
                                    int32_t f, int32_t to, int eb, int kshift, uint64_t dmask,
                                    uint32_t *h, const uint32_t *start, uint64_t *wb,
                                    const nbs__cs_dst *d, const nbs__cs_corebox *core,
                                    uint64_t *ok, int32_t *oe) {
#define NBS__CS_SC(D, R, C)                                                                     \
  nbs__cs_part_scatter512_body(kg, x, r, D, R, f, to, eb, kshift, dmask, h, start, wb, d, C, ok, \
                               oe)
  const bool radii = r != NULL;
  if (kg->dim == 3 && radii) NBS__CS_SC(3, true, core);
  else if (kg->dim == 3) NBS__CS_SC(3, false, core);
  else if (radii) NBS__CS_SC(2, true, core);
  else NBS__CS_SC(2, false, core);
#undef NBS__CS_SC
}
#endif

/* Whether a partition's scatter (nbs__cs_partition) puts each element in its bucket's buffer
 * as one record (nbs__cs_part_rec512): with AVX-512, where its coordinates (and radius) and
 * word fit the record's 4 lanes (3D, 2D with radii or without). */
static bool nbs__cs_part_recs(const nbs_context *ctx, int S) {
#if NBS__CS_AVX512
  return ctx->simd == NBS__SIMD_AVX512 && S <= 3;
#else
  (void)ctx;
  (void)S;
  return false;
#endif
}

/* The bytes of a thread's line buffers of a partition's scatter: a line of 8 entries per
 * bucket and array (the words', then each coordinate array's), or with records
 * (nbs__cs_part_recs) 8 records of 32 bytes per bucket. */
static size_t nbs__cs_part_wbytes(size_t buckets, int S, bool recs) {
  return buckets * (size_t)(recs ? 4 : 1 + S) * NBS__CS_LINE * sizeof(uint64_t);
}

#if NBS__CS_AVX512
/* Places [from, to) of a bucket's records bl (nbs__cs_part_rec512) to their places in the
 * arrays, one by one: a line not wholly the thread's own. */
static inline __attribute__((always_inline)) void
nbs__cs_put_recs(const nbs__cs_dst *d, int S, const double *bl, uint32_t from, uint32_t to) {
  for (uint32_t q = from; q < to; q++) {
    const double *rec = bl + 4 * (q % NBS__CS_LINE);
    memcpy(&d->key[q], rec + 3, sizeof *d->key);
    for (int s = 0; s < S; s++) d->a[s][q] = rec[s];
  }
}

/* Element k (coordinates at xk, word w) to place h[b]++ of bucket b as a record of its buffer
 * (nbs__cs_part_rec512_body), and the bucket's 8 records, when they are in, to a line of each
 * array. The record's coordinates come from one unmasked load of 4 lanes, the next element's
 * first ones in the lanes past them (`whole`: there is a next element), overwritten by the
 * radius and the word: a masked load, where a lane masked out lay past a cache line, cost
 * 1.3-1.5 ns per element more (Zen 5, a loop of this scatter alone, N = 1e6 and 1e7). */
static inline __attribute__((always_inline)) NBS__CS_AVX512_TARGET void
nbs__cs_rec_put(const nbs__cs_dst *d, int dim, bool radii, bool whole, const double *xk,
                const double *rk, uint64_t w, size_t b, uint32_t *restrict h,
                const uint32_t *restrict start, double *restrict wb) {
  const int S = dim + (radii ? 1 : 0);
  const uint32_t pos = h[b]++;
  const uint32_t s = pos % NBS__CS_LINE;
  double *bl = wb + b * 4 * NBS__CS_LINE;
  __m256d v = whole ? _mm256_loadu_pd(xk) : _mm256_maskz_loadu_pd(dim == 3 ? 0x7 : 0x3, xk);
  if (radii) v = _mm256_mask_broadcastsd_pd(v, 0x4, _mm_load_sd(rk));
  const __m256i vw = _mm256_mask_set1_epi64(_mm256_castpd_si256(v), 0x8, (long long)w);
  _mm256_store_si256((__m256i *)(void *)(bl + 4 * s), vw);
  if (s < NBS__CS_LINE - 1) return;
  const uint32_t l0 = pos - (NBS__CS_LINE - 1);
  if (l0 < start[b]) {
    nbs__cs_put_recs(d, S, bl, start[b], pos + 1);
    return;
  }
  /* lanes 0 and 1 of records 0-3, then of records 4-7 (u0, u1); lanes 2 and 3 (u2, u3) */
  const __m512i lo = _mm512_set_epi64(13, 9, 5, 1, 12, 8, 4, 0);
  const __m512i hi = _mm512_set_epi64(15, 11, 7, 3, 14, 10, 6, 2);
  const __m512d r0 = _mm512_load_pd(bl), r1 = _mm512_load_pd(bl + 8);
  const __m512d r2 = _mm512_load_pd(bl + 16), r3 = _mm512_load_pd(bl + 24);
  const __m512d u0 = _mm512_permutex2var_pd(r0, lo, r1), u1 = _mm512_permutex2var_pd(r2, lo, r3);
  const __m512d u2 = _mm512_permutex2var_pd(r0, hi, r1), u3 = _mm512_permutex2var_pd(r2, hi, r3);
  _mm512_stream_pd(d->a[0] + l0, _mm512_shuffle_f64x2(u0, u1, 0x44));
  _mm512_stream_pd(d->a[1] + l0, _mm512_shuffle_f64x2(u0, u1, 0xee));
  if (S == 3) _mm512_stream_pd(d->a[2] + l0, _mm512_shuffle_f64x2(u2, u3, 0x44));
  _mm512_stream_pd((double *)(void *)(d->key + l0), _mm512_shuffle_f64x2(u2, u3, 0xee));
}

/* nbs__cs_part_scatter without a core box (nbs__cs_partition's whole keys), where each
 * element's numbers and word make a record of 4 lanes (nbs__cs_part_recs): the element's
 * coordinates (and radius) in lanes 0 to S - 1, its word in lane 3, put in its bucket's
 * buffer of 8 records with one store; when the 8 are in, they are turned into a line of each
 * array (two permutes a line) and written whole with streaming stores, as
 * nbs__cs_part_put's lines are (nbs__cs_rec_put). The keys 8 at a time (nbs__cs_key8_of, the
 * same bit for bit). The same bytes in the same places as the scalar scatter, which stores
 * each element to S + 1 lines of its bucket's buffer (of 512 buckets: 128 kB in 3D, far
 * past L1) and computes its key alone. n: the elements of the input.
 * Measured against the scalar scatter (Zen 5, uniform, fraction 0.5, random order, one
 * thread, NBS_PARTITION=always, interleaved, min of 6 processes, preparation in ns per
 * element; the same hashes): 3D N = 1e7 13.30 -> 12.03, 1e6 12.65 -> 11.26; 2D 1e7 10.76 ->
 * 10.02, 1e6 10.46 -> 9.79. What is left is not the buffers': a loop of this scatter alone
 * (keys given, 512 buckets) took 4.8-5.3 ns per element at N = 1e6-1e7 and 2.2-3.2 at 1e5,
 * where its streaming stores alone, round robin into 2048 streams, ran at 24 GB/s (1.3 ns
 * for the 32 bytes of an element). */
static inline __attribute__((always_inline)) NBS__CS_AVX512_TARGET void
nbs__cs_part_rec512_body(const nbs__cs_keying *kg, const double *restrict x,
                         const double *restrict r, int dim, bool radii, int32_t n, int32_t f,
                         int32_t to, int eb, int kshift, uint64_t dmask, uint32_t *restrict h,
                         const uint32_t *restrict start, double *restrict wb,
                         const nbs__cs_dst *d) {
  const int S = dim + (radii ? 1 : 0);
  nbs__cs_keys8 v8;
  nbs__cs_keys8_init(&v8, kg);
  const __m128i seb = _mm_cvtsi32_si128(eb), sdig = _mm_cvtsi32_si128(kshift);
  const __m512i dm = _mm512_set1_epi64((int64_t)dmask), eight = _mm512_set1_epi64(8);
  __m512i es = _mm512_add_epi64(_mm512_set_epi64(7, 6, 5, 4, 3, 2, 1, 0), _mm512_set1_epi64(f));
  int32_t k = f;
  for (; to - k >= 8; k += 8) {
    const double *x8 = x + (size_t)k * (size_t)dim;
    __m512d c8[3], t8[3];
    nbs__cs_pos8(&v8, x8, dim, c8, t8);
    const __m512i kk = nbs__cs_key8_of(&v8, t8, dim);
    uint64_t wv[8], dv[8];
    _mm512_storeu_si512((void *)wv, _mm512_or_si512(_mm512_sll_epi64(kk, seb), es));
    _mm512_storeu_si512((void *)dv, _mm512_and_si512(_mm512_srl_epi64(kk, sdig), dm));
    es = _mm512_add_epi64(es, eight);
    for (int l = 0; l < 8; l++) {
      nbs__cs_rec_put(d, dim, radii, k + l + 1 < n, x8 + l * dim, radii ? r + k + l : NULL,
                      wv[l], (size_t)dv[l], h, start, wb);
    }
  }
  const nbs__grid g = *kg->g;
  nbs__cs_keying k1 = *kg;
  k1.g = &g;
  k1.dim = dim;
  for (; k < to; k++) {
    const double *xk = x + (size_t)k * (size_t)dim;
    const uint64_t kk = nbs__cs_cellkey(&k1, xk);
    nbs__cs_rec_put(d, dim, radii, k + 1 < n, xk, radii ? r + k : NULL, kk << eb | (uint64_t)k,
                    (size_t)((kk >> kshift) & dmask), h, start, wb);
  }
  /* each bucket's last line, as far as it is filled */
  for (size_t b = 0; b <= dmask; b++) {
    uint32_t l0 = h[b] - h[b] % NBS__CS_LINE;
    if (l0 < start[b]) l0 = start[b];
    nbs__cs_put_recs(d, S, wb + b * 4 * NBS__CS_LINE, l0, h[b]);
  }
  _mm_sfence(); /* the streaming stores, before another thread reads them */
}

/* nbs__cs_part_rec512_body with dim and radii constants. */
NBS__CS_AVX512_TARGET
static void nbs__cs_part_rec512(const nbs__cs_keying *kg, const double *x, const double *r,
                                int32_t n, int32_t f, int32_t to, int eb, int kshift,
                                uint64_t dmask, uint32_t *h, const uint32_t *start,
                                uint64_t *wb, const nbs__cs_dst *d) {
#define NBS__CS_REC(D, R, RR)                                                                  \
  nbs__cs_part_rec512_body(kg, x, RR, D, R, n, f, to, eb, kshift, dmask, h, start,             \
                           (double *)(void *)wb, d)
  if (kg->dim == 3) NBS__CS_REC(3, false, NULL);
  else if (r) NBS__CS_REC(2, true, r);
  else NBS__CS_REC(2, false, NULL);
#undef NBS__CS_REC
}
#endif

/* Bucket [s0, s0 + len) of the partition, whose words and coordinates lie in element order,
 * put in cell order in the cache: each word's element bits give way to its place in the
 * bucket (the element to gid[]), the words are sorted by the digits below the top one
 * (nbs__radix_local, with `other` for scratch), the elements go back into the words and each
 * one's new place to rank[], and each coordinate array is permuted after them through
 * `other`: read in order (it comes from memory), each entry written to its rank (in the
 * cache); reading it at random instead took a fifth longer (3D, N = 1e7, perf).
 * Tried and left out (Intel Xeon guest, NBS_PARTITION=always, interleaved with the build
 * before, preparation in ns per element, medians of 8-12 processes; the same bytes):
 *  - the coordinates carried through the two passes with the words, in place of the
 *    elements' places, their ranks and the permutation (S + 1 arrays scattered per pass
 *    where the permutation scatters S once): 2D N = 1e6 24.3 -> 22.9, but 3D 24.9 -> 26.4,
 *    1e7 3D 37.0 -> 51.5 (buckets of 20,000 elements, 1.3 MB with their scratch), 2D 35.8
 *    -> 34.9 (min 29.3 -> 33.9); it also needs (1 + S) 8 bytes of scratch per element of
 *    the largest bucket, 16 now, which test_determinism's 3D strip with three threads then
 *    lacks;
 *  - the next bucket's lines asked for (prefetched) while this one is sorted, a line per 8
 *    entries of each array in step with this bucket's loops over the same array: 2D 1e6
 *    31.4 -> 31.9, 3D 35.4 -> 34.4, 1e7 2D 27.8 -> 30.6, 3D 36.6 -> 33.3: no gain beyond
 *    the noise (the processor's own prefetcher follows these streams). */
static void nbs__cs_part_bucket(const nbs__cs_dst *d, uint32_t s0, int32_t len, int eb,
                                nbs__digits dg, uint32_t *h, uint64_t *other, int32_t *gid,
                                int32_t *rank) {
  const uint64_t em = ((uint64_t)1 << eb) - 1;
  uint64_t *w = d->key + s0;
  for (int32_t q = 0; q < len; q++) {
    gid[q] = (int32_t)(w[q] & em);
    w[q] = (w[q] & ~em) | (uint64_t)q;
  }
  nbs__radix_local(w, w, other, len, eb, dg, h);
  for (int32_t p = 0; p < len; p++) {
    const int32_t q = (int32_t)(w[p] & em);
    rank[q] = p;
    w[p] = (w[p] & ~em) | (uint64_t)gid[q];
  }
  double *t = (double *)(void *)other;
  for (int s = 0; s < d->S; s++) {
    double *a = d->a[s] + s0;
    for (int32_t q = 0; q < len; q++) t[rank[q]] = a[q];
    memcpy(a, t, (size_t)len * sizeof *t);
  }
}

/* A thread's scatter of a partition, the elements [f, to) (nbs__cs_part_scatter, with dim,
 * radii and whether there is a core box constants; with a core box and AVX-512,
 * nbs__cs_part_scatter512): h its counts' places, wb its line buffers. */
static void nbs__cs_part_thread(const nbs__cs_keying *kg, const nbs__run *run,
                                const nbs__cs_dst *d, int32_t f, int32_t to, int eb, int kshift,
                                uint64_t dmask, uint32_t *h, uint64_t *wb,
                                const nbs__cs_corebox *core, uint64_t *ok, int32_t *oe) {
  uint32_t start[(size_t)1 << NBS__RADIX_BITS];
  memcpy(start, h, (size_t)(dmask + 1) * sizeof *h);
  const double *x = run->x, *r = run->r;
  const int dim = kg->dim;
  const bool radii = r != NULL;
#if NBS__CS_AVX512
  if (core && run->ctx->simd == NBS__SIMD_AVX512) {
    nbs__cs_part_scatter512(kg, x, r, f, to, eb, kshift, dmask, h, start, wb, d, core, ok, oe);
    return;
  }
  if (!core && nbs__cs_part_recs(run->ctx, d->S)) {
    nbs__cs_part_rec512(kg, x, r, run->n, f, to, eb, kshift, dmask, h, start, wb, d);
    return;
  }
#endif
#define NBS__CS_SCATTER(C, K, E)                                                                \
  do {                                                                                        \
    if (dim == 3 && radii) {                                                                  \
      nbs__cs_part_scatter(kg, x, r, 3, true, f, to, eb, kshift, dmask, h, start, wb, d, C, K, E); \
    } else if (dim == 3) {                                                                    \
      nbs__cs_part_scatter(kg, x, r, 3, false, f, to, eb, kshift, dmask, h, start, wb, d, C, K,  \
                           E);                                                                \
    } else if (radii) {                                                                       \
      nbs__cs_part_scatter(kg, x, r, 2, true, f, to, eb, kshift, dmask, h, start, wb, d, C, K, E); \
    } else {                                                                                  \
      nbs__cs_part_scatter(kg, x, r, 2, false, f, to, eb, kshift, dmask, h, start, wb, d, C, K,  \
                           E);                                                                \
    }                                                                                         \
  } while (0)
  if (core) {
    NBS__CS_SCATTER(core, ok, oe);
  } else {
    NBS__CS_SCATTER(NULL, NULL, NULL);
  }
#undef NBS__CS_SCATTER
}

/* A thread's counts of a partition, the elements [f, to), into h (its dmask + 1 counts,
 * cleared first): the top digits (at kshift) of their keys (nbs__cs_part_count; with a core
 * box, of the keys relative to it, the outliers counted in out[], cleared first too, and with
 * AVX-512 by nbs__cs_core_count512). */
static void nbs__cs_part_counts(const nbs__cs_keying *kg, const nbs__run *run, int32_t f,
                                int32_t to, int kshift, uint64_t dmask, uint32_t *h,
                                const nbs__cs_corebox *core, int32_t out[3]) {
  const double *x = run->x;
  memset(h, 0, (size_t)(dmask + 1) * sizeof *h);
  if (core) {
    memset(out, 0, 3 * sizeof *out);
#if NBS__CS_AVX512
    if (run->ctx->simd == NBS__SIMD_AVX512) {
      nbs__cs_core_count512(kg, x, f, to, kshift, dmask, h, core, out);
    } else
#endif
    if (kg->dim == 3) {
      nbs__cs_part_count(kg, x, 3, f, to, kshift, dmask, h, core, out);
    } else {
      nbs__cs_part_count(kg, x, 2, f, to, kshift, dmask, h, core, out);
    }
  } else if (kg->dim == 3) {
    nbs__cs_part_count(kg, x, 3, f, to, kshift, dmask, h, NULL, NULL);
  } else {
    nbs__cs_part_count(kg, x, 2, f, to, kshift, dmask, h, NULL, NULL);
  }
}

static void nbs__cs_core_merge(const nbs__cs *c, const nbs__run *run, const nbs__cs_corebox *b,
                               const nbs__cs_keying *kg, int eb, int32_t s0, int32_t len,
                               const int32_t *oe, int32_t u);

/* A partition's last step for part t of `threads` (of the places [0, n)): each bucket that
 * starts in it (top[b], of the B buckets) put in order in the cache (nbs__cs_part_bucket,
 * with h the thread's counts and `scratch` its scratch for a bucket: the words' sort and the
 * coordinates' permutation, `most` entries of 8 bytes, then the elements and their ranks, 4
 * bytes each); with a core box, each bucket's outliers between (core->between[b] of them,
 * their places at its end, their elements oe[mfrom[b] ...] in order) then merged into it
 * (nbs__cs_core_merge). */
static void nbs__cs_part_buckets(const nbs__cs *c, const nbs__run *run, const nbs__cs_dst *d,
                                 int t, int threads, const uint32_t *top, size_t B, int eb,
                                 nbs__digits dg, uint32_t *h, uint32_t most, char *scratch,
                                 const nbs__cs_corebox *core, const nbs__cs_keying *kg,
                                 const uint32_t *mfrom, const int32_t *oe) {
  const uint32_t from = (uint32_t)nbs__chunk(c->n, t, threads);
  const uint32_t end = (uint32_t)nbs__chunk(c->n, t + 1, threads);
  uint64_t *other = (uint64_t *)(void *)scratch;
  int32_t *gid = (int32_t *)(void *)(other + most), *rank = gid + most;
  for (size_t b = 0; b < B; b++) {
    if (top[b] < from || top[b] >= end || top[b + 1] == top[b]) continue;
    const uint32_t u = core ? core->between[b] : 0;
    const int32_t len = (int32_t)(top[b + 1] - top[b] - u);
    if (len > 0) nbs__cs_part_bucket(d, top[b], len, eb, dg, h, other, gid, rank);
    if (u > 0) {
      nbs__cs_core_merge(c, run, core, kg, eb, (int32_t)top[b], len, oe + mfrom[b], (int32_t)u);
    }
  }
}

/* Steps 1-3 at once, for packed keys, where the input is larger than 1 GiB
 * (nbs__cellsort_partition_min), or the context has timed it faster (nbs__cs_way): the keys'
 * top digit counted (a pass over the input, in order, computing each key:
 * nbs__cellsort_fresh's, which validates the input too, where the context holds its work
 * block and the keying it guessed holds, `counted`; else one of its own), each element's
 * word and coordinates (and radius) moved to its top digit's bucket (a second such pass,
 * nbs__cs_part_scatter), and each bucket put in order in the cache (nbs__cs_part_bucket).
 * The result is that of the sort and the gather, byte for byte: the partition is stable
 * (each thread takes a contiguous part of the input and writes after the threads before it
 * in each bucket), and so is the bucket's sort.
 * Why. The gather reads each element's coordinates at random from the caller's array; where
 * that array is far larger than the caches every read waits on memory, and the gather grew
 * from 2.6 ns per element at N = 1e4 to 15 at 1e7 (3D, perf), the largest part of the
 * detection's growth with N. The partition reads the input in order instead, and writes
 * whole lines: the plain scatter into 4 or 5 arrays per bucket had lost to the gather (see
 * the file comment), since each element's write to each array fetched its line from memory
 * first; here each bucket gathers a line of each array in a buffer and writes it whole with
 * a streaming store, which does not read it. Measured (N = 1e7, random order, one thread,
 * interleaved, min of 4 processes, ns per element, NBS_PARTITION=never against the
 * default): 3D 40.9 -> 39.2, 2D 25.1 -> 22.6; perf, 3D: count 2.0, scatter 8.7, buckets 8.2
 * (their sort 2.8), against keys 2.3, top digit's pass 2.5, buckets' sort 3.0, gather 15.1.
 * The buckets' pass waits on memory too (it reads back what the scatter wrote past the
 * caches), and it is why the gain is not larger. Below the threshold it loses: N = 5e5 in
 * 3D (12 MB) 33.7 -> 36.7, 2D 3e5 16.2 -> 21.7; at 1e6, about even (3D 39.2 -> 38.0, 2D
 * 22.7 -> 22.0, two threads 19.3 -> 19.7 and 11.2 -> 11.3, min of 3). Those figures are
 * from before the gather's two-stage prefetches, which made it lose up to hundreds of MB
 * (see nbs__cellsort_partition_min, which now sets the threshold at 1 GiB).
 * spare (spare_bytes of it): the idx array, unused by packed keys: each thread's line
 * buffers (a line per bucket and array: 160 kB for 512 buckets in 3D with radii), then its
 * scratch for a bucket (16 bytes per element of the largest). Returns false, having written
 * nothing the caller needs, where the keys need one digit, are fewer than the square of the
 * buckets, or have a bucket larger than NBS__RADIX_LOCAL_MAX (a sheet whose elements share
 * the top digit), or where the buffers or the scratch do not fit spare; the caller then
 * sorts and gathers. */
static bool nbs__cs_partition(const nbs__cs *c, const nbs__run *run, const nbs__cs_keying *kg,
                              int eb, nbs__digits dg, uint32_t *hist, bool counted, int threads,
                              char *spare, size_t spare_bytes) {
  const int32_t n = c->n;
  const nbs__cs_pdigits pd = nbs__cs_part_digits(n, dg.bits, run->ctx->cs_part_wide);
  const size_t B = pd.buckets;
  const nbs__cs_dst d = nbs__cs_dst_of(c);
  const size_t wc = nbs__cs_part_wbytes(B, d.S, nbs__cs_part_recs(run->ctx, d.S));
  if (!nbs__cs_part_top_first(n, &pd) || (size_t)threads * wc > spare_bytes) return false;
  const int kshift = pd.shift;
  const uint64_t dmask = B - 1;
  uint32_t top[((size_t)1 << NBS__RADIX_BITS) + 1];
  uint32_t most = 0;
  size_t per = 0;
  bool fits = true;
  /* one region: the counts, then (one thread) where each thread's part of each bucket
   * starts, then the scatter, which the buckets' sizes may call off */
#if defined(_OPENMP)
#pragma omp parallel num_threads(threads) if (threads > 1)
#endif
  {
    NBS__PARTS(t, threads) {
      /* (where `counted`, nbs__cellsort_fresh's pass counted them, with this keying and
       * these parts) */
      if (!counted) {
        nbs__cs_part_counts(kg, run, nbs__chunk(n, t, threads), nbs__chunk(n, t + 1, threads),
                            kshift, dmask, hist + (size_t)t * B, NULL, NULL);
      }
    }
#if defined(_OPENMP)
#pragma omp barrier
#pragma omp single
#endif
    {
      most = nbs__radix_offsets(hist, B, threads, top);
      /* each part's scratch for a bucket: the words' sort and the coordinates' permutation
       * (8 bytes per entry), the elements and their ranks (4 each), on a line's boundary */
      per = ((size_t)most * 16 + 63) & ~(size_t)63;
      fits = nbs__cs_part_fits(n, most) && (size_t)threads * per <= spare_bytes;
    }
    if (fits) {
      NBS__PARTS(t, threads) {
        const int32_t f = nbs__chunk(n, t, threads), to = nbs__chunk(n, t + 1, threads);
        nbs__cs_part_thread(kg, run, &d, f, to, eb, kshift, dmask, hist + (size_t)t * B,
                            (uint64_t *)(void *)(spare + (size_t)t * wc), NULL, NULL, NULL);
      }
      /* then each part's buckets (those that start in it) are sorted */
#if defined(_OPENMP)
#pragma omp barrier
#endif
      /* each thread's histogram for its buckets' sorts: pd.lo's digits, which may be wider
       * than the top one where that is widened for few keys (NBS_PARTITION=wide), so at a
       * stride of the widest digit (hist holds that many per thread), not of B (a finding of
       * fuzz_partition: two threads' histograms overlapped) */
      NBS__PARTS(t, threads) {
        nbs__cs_part_buckets(c, run, &d, t, threads, top, B, eb, pd.lo,
                             hist + (size_t)t * ((size_t)1 << NBS__RADIX_BITS), most,
                             spare + (size_t)t * per, NULL, kg, NULL, NULL);
      }
    }
  }
  run->ctx->cs_part_widened = fits && pd.wide;
  return fits;
}

/* An outlier's element in its place of the order while the core's words are being made
 * (nbs__cs_core_part): marked by the top bit, which no core word has (its key relative to the
 * core's box and its element take at most 62 bits). */
#define NBS__CS_OUTLIER ((uint64_t)1 << 63)

/* Place p of the order, a core word (the key relative to box b, shifted up by b->pad, << eb |
 * element) or an outlier's marked element, in the whole grid's terms: the whole key (the
 * outlier's computed again, as the count computed it) << eb | element where the keys are
 * packed; else the key, and the element to idx[]. */
static inline __attribute__((always_inline)) void
nbs__cs_core_back(const nbs__cs *c, const nbs__run *run, const nbs__cs_corebox *b,
                  const nbs__cs_keying *kg, int eb, int32_t p) {
  const uint64_t w = c->key[p], e = w & (((uint64_t)1 << eb) - 1);
  const uint64_t whole = w & NBS__CS_OUTLIER
                             ? nbs__cs_cellkey(kg, run->x + (size_t)e * (size_t)c->dim)
                             : nbs__cs_core_whole(b, kg->sy, kg->sz, w >> eb);
  if (c->idx) {
    c->key[p] = whole;
    c->idx[p] = (int32_t)e;
  } else {
    c->key[p] = whole << eb | e;
  }
}

/* The outliers of a bucket whose keys fall in its range (u of them, their elements oe[], in
 * order), merged into its core words [s0, s0 + len), in order, from the end, in the cache:
 * outlier j goes after the core words whose whole keys are below its own (found by galloping
 * down), and the run of core words between it and outlier j + 1 moves up by j + 1 places with
 * their coordinates (nbs__cs_shift); the outlier's place takes its marked element and its
 * coordinates (and radius) from the input. */
static void nbs__cs_core_merge(const nbs__cs *c, const nbs__run *run, const nbs__cs_corebox *b,
                               const nbs__cs_keying *kg, int eb, int32_t s0, int32_t len,
                               const int32_t *oe, int32_t u) {
  const uint64_t *w = c->key + s0;
  int32_t r = len;
  for (int32_t j = u - 1; j >= 0; j--) {
    const int32_t e = oe[j];
    const uint64_t o = nbs__cs_cellkey(kg, run->x + (size_t)e * (size_t)c->dim);
    int32_t lo_;
#define NBS__CS_BELOW(i) (nbs__cs_core_whole(b, kg->sy, kg->sz, w[i] >> eb) < o)
    NBS__CS_GALLOP(lo_, 0, r, NBS__CS_BELOW);
#undef NBS__CS_BELOW
    if (r > lo_) nbs__cs_shift(c, s0 + lo_, s0 + r, j + 1);
    c->key[s0 + lo_ + j] = NBS__CS_OUTLIER | (uint64_t)e;
    nbs__cs_take(c, run, s0 + lo_ + j, e);
    r = lo_;
  }
}

/* Steps 1-3 at once for the keys nbs__cs_core sorts by their crowded core (a few elements far
 * out stretch the grid until its keys need 60 bits, unpacked: the sparse and clustered scenes
 * of the benchmarks), where the context has timed the partition faster than the sort and the
 * gather (nbs__cs_way): nbs__cs_partition's partition of the core's elements, by their keys
 * relative to the core's box, with the outliers put in their places apart.
 *   a. the core's box, from a sample (nbs__cs_core_box); the relative keys shifted up so that
 *      the top digit is whole (29 bits in 4 digits of 8: a top digit of 5 bits made 32
 *      buckets, too large for the cache; 2D sparse, N = 1e6); the whole key of each bucket's
 *      lowest place;
 *   b. a pass over the input (nbs__cs_part_count): the core keys' top digits counted, and
 *      the outliers, by whether their keys are below the box's lowest (they come before every
 *      core element in the order), above its highest (after every one), or between (a side of
 *      the box cuts a layer of cells: they come among the core's elements of one bucket, that
 *      whose range holds the key, and are counted in it);
 *   c. the places: the outliers below first, then each bucket's core elements and the
 *      outliers between in its range, then the outliers above. Each core element's word (its
 *      relative key << eb | element) and coordinates to its bucket, in whole lines, each
 *      outlier's whole key and element to a list (nbs__cs_part_scatter);
 *   d. the outliers sorted by (key, element) (a plain LSD sort: they are few); those below
 *      and above to their places, marked (NBS__CS_OUTLIER), with their coordinates;
 *   e. each bucket put in order in the cache (nbs__cs_part_bucket), and its outliers between
 *      merged into it there (nbs__cs_core_merge);
 *   f. each place put in the whole grid's terms (nbs__cs_core_back), one pass in order.
 * The result is that of the sort by the whole key and the gather, byte for byte: the
 * partition, the buckets' sorts and the outliers' sort are stable, and no core element shares
 * a key with an outlier. Where the sort and the gather read each element's coordinates at
 * random (on the Intel guest, 20 ns each at N = 1e6 in 3D: bench/floor.c), this reads the
 * input in order, twice. Measured there (2026-11-29, N = 1e6, one thread,
 * NBS_PARTITION=always against never, interleaved, min of 8, ns per element, preparation /
 * detection, the same hashes): 3D sparse 45.5 / 82.0 -> 35.8 / 71.4, clustered 40.4 / 70.1
 * -> 32.4 / 62.9; 2D sparse 50.0 / 62.3 -> 33.4 / 44.6, clustered 35.6 / 49.5 -> 33.4 /
 * 47.8. Not measured on the AMD instances, whose random reads cost a quarter as much: there
 * the context's timing (nbs__cs_way) chooses.
 * Memory: none beyond the work block. spare (the idx array, which unpacked keys fill only in
 * f.) holds the scatter's line buffers, then the buckets' scratch, and at its end the
 * outliers' list and its sort's copy (24 bytes per outlier). Returns false, having written
 * nothing the caller needs, where nbs__cs_core would not sort by the core (the core's keys
 * would not fit a word with the element and the mark), where packed whole keys would take no
 * more digits than the core's (the huge domain, whose core is all of it: nbs__cs_partition
 * does as well), where the partition would not (too few elements for the digits, a bucket too
 * large: nbs__cs_part_fits), or where the buffers and the outliers' list do not fit spare.
 * Where the even split's top digit would leave its buckets too large (3D clustered N = 1e8, a
 * core of 30 bits), the top digit is widened as nbs__cs_partition's (nbs__cs_part_digits). A
 * sparse domain's core at N = 1e8 (fraction 0.005, 2188 cells per axis) takes 37 bits, which
 * with the element's 27 do not fit a word: that detection still sorts and gathers. */
static bool nbs__cs_core_part(const nbs__cs *c, const nbs__run *run, const nbs__cs_keying *kg,
                              int eb, int bits, uint32_t *hist, int threads, char *spare,
                              size_t spare_bytes) {
  const int32_t n = c->n;
  /* a */
  nbs__cs_corebox box;
  const int cb = nbs__cs_core_box(c, run, kg, bits, box.lo, box.cw);
  if (cb + eb > 63) return false;
  const nbs__digits dg0 = nbs__radix_digits(cb);
  if (!c->idx && dg0.passes >= nbs__radix_digits(bits).passes) return false;
  /* The digits: the even split's, the relative keys shifted up by pad so that the top digit
   * is whole (30 bits: by 2, four digits of 8); or, where that top digit's buckets would be
   * too large for a cache, a top digit widened as the whole keys' partition widens its own
   * (nbs__cs_part_digits: 3D clustered N = 1e8, a core of 30 bits, 9 and 7, 7, 7; unshifted,
   * pad 0). Until then the core's partition gave way there to the sort and the gather, as the
   * whole keys' had. */
  const nbs__cs_pdigits pd = nbs__cs_part_digits(n, cb, run->ctx->cs_part_wide);
  if (!nbs__cs_part_top_first(n, &pd)) return false;
  box.pad = pd.wide ? 0 : dg0.passes * dg0.width - cb;
  if (cb + box.pad + eb > 62) return false;
  /* the whole keys of the box's lowest and highest positions within the fields' ranges
   * (nbs__cs_core_first), and of each bucket's lowest: no core key lies outside them */
  box.wmin = nbs__cs_core_whole(&box, kg->sy, kg->sz, 0);
  {
    uint64_t hi[3], fmax[3];
    nbs__cs_field_max(kg->sy, kg->sz, bits, fmax);
    for (int a = 0; a < 3; a++) {
      hi[a] = box.lo[a] + (((uint64_t)1 << box.cw[a]) - 1);
      if (hi[a] > fmax[a]) hi[a] = fmax[a];
    }
    box.wmax = hi[2] << kg->sz | hi[1] << kg->sy | hi[0];
  }
  /* (unwidened, pd.shift is the even split's, (passes - 1) * width, on the padded keys) */
  const size_t B = pd.buckets;
  const int kshift = pd.shift;
  const uint64_t dmask = B - 1;
  uint64_t bound[(size_t)1 << NBS__RADIX_BITS];
  uint32_t between[(size_t)1 << NBS__RADIX_BITS], mfrom[((size_t)1 << NBS__RADIX_BITS) + 1];
  /* (Of the two, only the box's highest key changes the output when taken past the fields:
   * test_determinism core_partition, scene 11. A bucket's lowest taken past them spills a
   * field into the next, so it is below the true one (the next row or layer of the box) and
   * above every key of the buckets before; the keys between the two are outliers that come
   * after the buckets before and before this one's core keys, wherever they are counted, so
   * counted in this bucket and not the one before they land in the same places. The fields'
   * ranges are kept for the bounds too, so that each is a key the order can hold.) */
  for (size_t b = 0; b < B; b++) {
    bound[b] = nbs__cs_core_first(&box, kg->sy, kg->sz, bits, (uint64_t)b << kshift);
    between[b] = 0;
  }
  box.bound = bound;
  box.buckets = (int)B;
  box.between = between;
  const nbs__cs_dst d = nbs__cs_dst_of(c);
  const size_t wc = nbs__cs_part_wbytes(B, d.S, false); /* a line per array: nbs__cs_part_put */
  uint32_t top[((size_t)1 << NBS__RADIX_BITS) + 1];
  int32_t out[NBS__THREADS_MAX][3], ofrom[NBS__THREADS_MAX + 1];
  int32_t below = 0, mid = 0, above = 0;
  uint32_t most = 0;
  size_t per = 0;
  bool fits = true;
  uint64_t *ok = NULL;
  int32_t *oe = NULL, *se = NULL;
#if defined(_OPENMP)
#pragma omp parallel num_threads(threads) if (threads > 1)
#endif
  {
    /* b */
    NBS__PARTS(t, threads) {
      nbs__cs_part_counts(kg, run, nbs__chunk(n, t, threads), nbs__chunk(n, t + 1, threads),
                          kshift, dmask, hist + (size_t)t * B, &box, out[t]);
    }
#if defined(_OPENMP)
#pragma omp barrier
#pragma omp single
#endif
    {
      /* c. the places */
      ofrom[0] = 0;
      for (int t = 0; t < threads; t++) {
        below += out[t][0];
        mid += out[t][1];
        above += out[t][2];
        ofrom[t + 1] = ofrom[t] + out[t][0] + out[t][1] + out[t][2];
      }
      most = nbs__radix_offsets(hist, B, threads, top);
      uint32_t add = (uint32_t)below;
      mfrom[0] = 0;
      for (size_t b = 0; b < B; b++) {
        for (int t = 0; t < threads; t++) hist[(size_t)t * B + b] += add;
        top[b] += add;
        add += between[b];
        mfrom[b + 1] = mfrom[b] + between[b];
      }
      top[B] += add;
      per = ((size_t)most * 16 + 63) & ~(size_t)63;
      /* the outliers' list at spare's end: keys and elements, then the sort's copy */
      const size_t no = (size_t)ofrom[threads], list = no * 24 + 64;
      const size_t R = list <= spare_bytes ? (spare_bytes - list) & ~(size_t)63 : 0;
      fits = list <= spare_bytes && nbs__cs_part_fits(n, most) &&
             (size_t)threads * wc <= R && (size_t)threads * per <= R;
      ok = (uint64_t *)(void *)(spare + R);
      oe = (int32_t *)(void *)(ok + no);
    }
    if (fits) {
      NBS__PARTS(t, threads) {
        const int32_t f = nbs__chunk(n, t, threads), to = nbs__chunk(n, t + 1, threads);
        nbs__cs_part_thread(kg, run, &d, f, to, eb, kshift, dmask, hist + (size_t)t * B,
                            (uint64_t *)(void *)(spare + (size_t)t * wc), &box, ok + ofrom[t],
                            oe + ofrom[t]);
      }
#if defined(_OPENMP)
#pragma omp barrier
#pragma omp single
#endif
      {
        /* d */
        const int32_t no = below + mid + above;
        uint64_t *sk = (uint64_t *)(void *)(oe + no + (no & 1));
        se = (int32_t *)(void *)(sk + no);
        if (no > 0) {
          nbs__radix(ok, oe, sk, se, sk, se, no, 0, nbs__radix_digits(bits), hist, 1, false,
                     NULL, 0);
        }
        for (int32_t j = 0; j < below; j++) {
          c->key[j] = NBS__CS_OUTLIER | (uint64_t)se[j];
          nbs__cs_take(c, run, j, se[j]);
        }
        for (int32_t j = 0; j < above; j++) {
          const int32_t p = n - above + j, e = se[below + mid + j];
          c->key[p] = NBS__CS_OUTLIER | (uint64_t)e;
          nbs__cs_take(c, run, p, e);
        }
      }
      /* e (each thread's histogram at the widest digit's stride, as in nbs__cs_partition:
       * a widened top digit may be narrower than those below it) */
      NBS__PARTS(t, threads) {
        nbs__cs_part_buckets(c, run, &d, t, threads, top, B, eb, pd.lo,
                             hist + (size_t)t * ((size_t)1 << NBS__RADIX_BITS), most,
                             spare + (size_t)t * per, &box, kg, mfrom, se + below);
      }
    }
  }
  run->ctx->cs_part_widened = fits && pd.wide;
  if (!fits) return false;
  /* f */
#if defined(_OPENMP)
#pragma omp parallel for num_threads(threads) schedule(static) if (threads > 1)
#endif
  for (int32_t p = 0; p < n; p++) nbs__cs_core_back(c, run, &box, kg, eb, p);
  run->ctx->cs_outliers = below + mid + above;
  return true;
}

/* Where step 1 (the keys in element order) puts them, for a sort of `bits` key bits: the
 * sort's scratch is the coordinate array xs, not yet filled (8 or 12 of its >= 16 bytes per
 * element), and the passes alternate between it and key[]; with an odd number of them the
 * keys start in the scratch, so that they end in key[] without a copy (unless a pass is
 * skipped). */
static uint64_t *nbs__cs_step1_at(uint64_t *key, double *xs, int bits) {
  return nbs__radix_digits(bits).passes % 2 == 1 ? (uint64_t *)(void *)xs : key;
}

static bool nbs__cs_kept_same(const nbs__cs_kept *kp, const nbs__cs_keying *kg);

/* From scratch: 1. the keys in element order, 2. their radix sort, 3. the gather of the
 * coordinates (and radii) in cell order. */
static void nbs__cs_sort_gather(const nbs__cs *c, nbs__run *run, const nbs__cs_keying *kg,
                                bool packed, int eb, int bits, bool words, uint32_t *hist,
                                int threads, char *spare, size_t spare_bytes) {
  const int32_t n = c->n;
  const size_t nn = (size_t)n;
  const int dim = c->dim;
  const double *x = run->x;
  const nbs__digits dg = nbs__radix_digits(bits);
  /* the sort's scratch: the coordinate arrays (nbs__cs_step1_at) */
  uint64_t *tk = (uint64_t *)(void *)c->xs;
  int32_t *ti = packed ? NULL : (int32_t *)(void *)(c->xs + nn);
  uint64_t *k0 = nbs__cs_step1_at(c->key, c->xs, bits);
  const bool odd = k0 == tk;
  uint64_t *k1 = odd ? c->key : tk;
  int32_t *i0 = odd ? ti : c->idx, *i1 = odd ? c->idx : ti;
  /* 1-3 at once, where the input is larger than 1 GiB, or the context has measured the
   * partition faster (nbs__cs_way) */
  /* 1-2 by the crowded core's keys, where they fit a word with the element and the whole
   * keys do not, or where the whole keys do but take four passes or more and the core's two
   * fewer (not where nbs__cellsort_fresh has made the words already) */
  const bool core = !packed || (!words && dg.passes >= 4);
  const bool part = nbs__cs_way(run, threads) == 2;
  /* 1-3 at once, where the context has measured the partition faster (nbs__cs_way): by the
   * crowded core's keys, or by the whole keys (where they are packed, and also where the
   * input is larger than 1 GiB) */
  bool parted = part && core &&
                nbs__cs_core_part(c, run, kg, eb, bits, hist, threads, spare, spare_bytes);
  const bool counted = part && !parted && run->precounts && eb == run->pre_eb &&
                       bits == run->pre_bits && nbs__cs_kept_same(&run->pre, kg);
  if (part && !parted && packed) {
    parted = nbs__cs_partition(c, run, kg, eb, dg, hist, counted, threads, spare, spare_bytes);
    if (parted) run->ctx->cs_fresh_words = counted;
  }
  run->ctx->cs_partitioned = parted;
  if (run->cs_try) run->cs_tried = (int8_t)(parted ? 2 : part ? 3 : 1);
  if (parted) return;
  /* else: */
  if (!core || !nbs__cs_core(c, run, kg, eb, bits, hist, threads)) {
    /* 1. keys (the grid in locals; with the small inputs' gather's locals below, 3D N = 1e6
     * 33.8 -> 33.5 ns per element, 1e4 23.2 -> 23.0-23.2, 2D 1e4 11.8 -> 11.4, interleaved,
     * min of 4-6; the same loops written out for each dimension, with it a constant, were
     * no faster, 33.3 / 33.5 and 22.95 / 23.15) */
    const nbs__grid g = *kg->g;
    nbs__cs_keying kl = *kg;
    kl.g = &g;
    /* with AVX-512, 8 elements at a time (nbs__cs_words512: 3D, N = 1e6, interleaved, min
     * of 8-10, 33.4-33.9 -> 32.6-33.1 ns per element, 2D 20.0-20.4 -> 18.6-18.9; the same
     * bytes) */
    if (words) {
      /* step 1 is done: nbs__cellsort_fresh wrote the words to k0 */
    } else if (packed && run->ctx->simd == NBS__SIMD_AVX512) {
#if NBS__CS_AVX512
#if defined(_OPENMP)
#pragma omp parallel num_threads(threads) if (threads > 1)
#endif
      NBS__PARTS(t, threads) {
        const int32_t f = nbs__chunk(n, t, threads), to = nbs__chunk(n, t + 1, threads);
        nbs__cs_words512(&kl, x, f, to, eb, k0);
      }
#endif
    } else if (packed && run->ctx->simd == NBS__SIMD_AVX2 && nbs__cs_fits4(&kl, eb, false)) {
#if NBS__CS_AVX512
#if defined(_OPENMP)
#pragma omp parallel num_threads(threads) if (threads > 1)
#endif
      NBS__PARTS(t, threads) {
        const int32_t f = nbs__chunk(n, t, threads), to = nbs__chunk(n, t + 1, threads);
        nbs__cs_words256(&kl, x, f, to, eb, k0);
      }
#endif
    } else {
#if defined(_OPENMP)
#pragma omp parallel for num_threads(threads) schedule(static) if (threads > 1)
#endif
      for (int32_t k = 0; k < n; k++) {
        const uint64_t w = nbs__cs_cellkey(&kl, x + (size_t)k * (size_t)dim);
        if (packed) {
          k0[k] = w << eb | (uint64_t)k;
        } else {
          k0[k] = w;
          i0[k] = k;
        }
      }
    }
    /* 2. sort */
    /* the buckets' scratch: the y (and z) coordinates' arrays, not yet filled either */
    nbs__radix(k0, i0, k1, i1, c->key, c->idx, n, c->ks, dg, hist, threads,
               run->ctx->cs_steal_first, (uint64_t *)(void *)c->ys, nn * (size_t)(dim - 1));
  }
  /* 3. gather */
  nbs__cs_gather(c, run, NULL, threads);
}

bool nbs__cellsort_fits(const nbs__grid *g) {
  if (!g->fits) return false;
  int bits = 0;
  for (int a = 0; a < g->dim; a++) bits += nbs__bits((uint64_t)g->n[a]);
  return bits <= 64;
}

/* cellsort's grid: on each axis the origin is moved down from the lowest coordinate lo to
 * the point of the lattice (k + f) e below it, less one edge (e the cell edge, f = 0.381966,
 * the golden section: far from 0, 1/2 and other simple fractions, where the lowest
 * coordinate of a scene often lies, at a wall or a radius from it). The cells, and so the
 * keys, then stay where they are from step to step: the start from the last order compares
 * words, and with the origin at the lowest element a step of that one element would move
 * every cell and change every key. The origin is a function of this
 * detection's input alone (not of the context's history), so that a detection from the
 * last order and one from scratch cut the same cells: elements on cell faces must fall on
 * the same side in both (fuzz_detect found an origin kept from an earlier step to give
 * another order). It moves, and every key with it, only when lo crosses a lattice point.
 * The grid is kept only when its cells need the same bits in all as input.c's, so that it
 * never changes whether the key fits or is packed; otherwise, and where the lattice point
 * cannot be computed exactly enough (|lo| huge next to e), the grid stays as input.c made
 * it. input.c's rounding argument holds for any origin at or below the lowest coordinate. */
static void nbs__cs_anchor(nbs__grid *g) {
  if (!g->fits || !(g->inv_edge > 0.0)) return;
  nbs__grid a = *g;
  const double e = g->edge;
  int before = 0, after = 0;
  for (int ax = 0; ax < g->dim; ax++) {
    const double f = 0.381966;
    const double lo = (floor(g->lo[ax] * g->inv_edge - f) - 1.0 + f) * e;
    if (!(lo <= g->lo[ax] && g->lo[ax] - lo < 3.0 * e)) return;
    const double top = (g->hi[ax] - lo) * g->inv_edge;
    if (!(top < (double)NBS__AXIS_MAX)) return;
    a.lo[ax] = lo;
    a.n[ax] = (int64_t)top + 1;
    before += nbs__bits((uint64_t)g->n[ax]);
    after += nbs__bits((uint64_t)a.n[ax]);
  }
  if (after == before) *g = a;
}

/* The work block's layout, from a 64-byte boundary within the block (nbs__cs_base):
 * key[n + pad] | idx[n; used by unpacked keys only, and as scratch] | xs, ys[, zs], each
 * n rounded up to 8 | rs[the same, with radii] | hist[threads * 2^9], each part on a 64-byte
 * boundary, so that place p of key[] and of every coordinate array lie at the same place of
 * a cache line (the partition's whole lines, nbs__cs_partition). The same for packed and
 * unpacked keys, so that a scene that spreads out never makes a detection allocate. at[]
 * receives where idx, xs, rs and hist start, *stride the coordinate arrays' length; the total,
 * with the 64 bytes the boundary may need, is returned. */
static size_t nbs__cs_layout(int dim, int32_t n, bool radii, int threads, size_t at[4],
                             size_t *stride) {
  const size_t nn = (size_t)n, line = 64, ns = (nn + 7) & ~(size_t)7;
  at[0] = ((nn + NBS__CS_PAD) * sizeof(uint64_t) + line - 1) & ~(line - 1);
  at[1] = at[0] + ((nn * sizeof(int32_t) + line - 1) & ~(line - 1));
  at[2] = at[1] + ns * (size_t)dim * sizeof(double);
  at[3] = at[2] + (radii ? ns * sizeof(double) : 0);
  *stride = ns;
  return at[3] + (size_t)threads * ((size_t)1 << NBS__RADIX_BITS) * sizeof(uint32_t) + line;
}

/* The first 64-byte boundary of the work block. */
static char *nbs__cs_base(char *work) {
  return work + ((64 - (uintptr_t)work % 64) % 64);
}

size_t nbs__cellsort_bytes(int dim, int32_t n, bool radii, int threads) {
  size_t at[4], stride;
  return nbs__cs_layout(dim, n, radii, threads, at, &stride);
}

/* Below this many elements per thread, one thread is faster. */
#define NBS__CS_MIN_PER_THREAD 20000

/* The chunks' pairs that are not in place (segs[0 .. nsegs), in order, `more` pairs in all)
 * copied to dst one after the other, each thread copying an equal share of them: one thread
 * alone could not keep the machine's memory busy (3D, N = 1e6, two threads: 0.55 -> 0.30 ns
 * per element). */
static void nbs__cs_append(nbs_pair *dst, const nbs__sink *sinks, const nbs__cs_seg *segs,
                           int nsegs, int threads, size_t more) {
#if defined(_OPENMP)
#pragma omp parallel num_threads(threads)
#endif
  NBS__PARTS(t, threads) {
    const size_t a = more * (size_t)t / (size_t)threads;
    const size_t b = more * (size_t)(t + 1) / (size_t)threads;
    size_t at = 0; /* where segment k starts in dst */
    for (int k = 0; k < nsegs && at < b; k++) {
      const size_t s0 = at > a ? at : a;
      const size_t s1 = at + segs[k].count < b ? at + segs[k].count : b;
      if (s0 < s1) {
        memcpy(dst + s0, sinks[segs[k].sink].buf + segs[k].at + (s0 - at),
               (s1 - s0) * sizeof *dst);
      }
      at += segs[k].count;
    }
  }
}

/* The threads a cellsort detection of run uses. */
static int nbs__cs_threads(const nbs__run *run) {
  /* callbacks and max_pairs need the pairs in one stream */
  if (run->callback || run->ctx->max_pairs) return 1;
  return nbs__threads(run->ctx, run->n / NBS__CS_MIN_PER_THREAD);
}

/* Whether keying kg is the one the context kept (nbs_context.cs_kept): the same keys. */
static bool nbs__cs_kept_same(const nbs__cs_kept *kp, const nbs__cs_keying *kg) {
  /* (sz, where iz starts, is that of a 2D key's top field's end: not in its keys) */
  bool same = kp->dim == kg->dim && kp->sy == kg->sy && (kg->dim == 2 || kp->sz == kg->sz) &&
              kp->lo_x == kg->lo_x && kp->inv_fine == kg->inv_fine &&
              kp->g.inv_edge == kg->g->inv_edge;
  for (int a = 0; a < kg->dim; a++) same = same && kp->c[a] == kg->c[a];
  for (int a = 1; a < kg->dim; a++) same = same && kp->g.lo[a] == kg->g->lo[a];
  return same;
}

/* The keying kg as the context keeps it. */
static nbs__cs_kept nbs__cs_kept_of(const nbs__cs_keying *kg) {
  nbs__cs_kept kp;
  memset(&kp, 0, sizeof kp);
  kp.g = *kg->g;
  kp.lo_x = kg->lo_x;
  kp.inv_fine = kg->inv_fine;
  for (int a = 0; a < 3; a++) kp.c[a] = kg->c[a];
  kp.dim = kg->dim;
  kp.sy = kg->sy;
  kp.sz = kg->sz;
  return kp;
}

/* Time steps read the input once. A step of nbs__cs_rekey read it twice: input.c's pass
 * (every number finite, and the bounding box, from which the grid), then step 1 of
 * nbs__cs_rekey (each element's key against keys[e]), both in element order, one after the
 * other. Here, where the context holds an order to start from with its keys (cs_keys) and
 * the keying that made them (cs_kept), step 1 runs first, with that keying, and measures
 * the bounding box as it goes; the grid follows from the box as input.c's would, and where
 * this detection's keying comes out the same (nbs__cellsort, nbs__cs_kept_same; as it does
 * but where the elements' box has crossed a cell edge's lattice line or a power of two of
 * cells), its keys are those step 1 would have computed, and nbs__cellsort goes on from
 * step 2. Where it does not, the keys are dropped (cs_keys) and the detection sorts from
 * scratch, as it would have once nbs__cs_rekey had found too many keys changed. The pass
 * stops at the first element outside the keying's box, or with a coordinate that is not
 * finite (nbs__cs_changed): the caller then runs input.c's pass, which names a bad
 * number as it always does. Radii, where given, are read after it by input.c's pass of
 * them, whose largest the grid needs too (a bad one: input.c's passes then run again, to
 * name it as they always do).
 * Measured (steps of 1e-3, one thread, interleaved with the build before, min of 8-12, ns
 * per element, the same hashes): 3D N = 1e6 28.65 -> 27.07, 28.66 -> 27.80 and 28.36 ->
 * 27.80 in three runs, two threads 15.10 -> 14.63, N = 1e5 22.87 -> 22.46; 2D N = 1e6
 * 14.00 / 13.98 and 13.69 / 13.78, no faster: by perf the pass saves its 0.5 ns there too,
 * and the merge and the gather after it take about as much more (not understood). With
 * radii (the scene `wide`, 3D N = 1e6) 49.36 -> 48.46. */
/* Whether a time step starts from the last order or sorts from scratch, where a detection
 * from scratch takes the partition (nbs__cs_way: inputs over cs_part_min, 1 GiB, or of a
 * class the context measured the partition faster for; elsewhere the step is the faster).
 * A step from the order replaces the key pass and the sort by a pass like it and a merge of
 * the few elements that changed cells, but still gathers every coordinate at random
 * (nbs__cs_rekey); from scratch, the partition reads the input in order. Which is faster
 * depends on the machine and on the size: on the Zen 4 instance (3D, random order, steps of
 * 1e-3 diameters, one thread, ns per element) N = 1e8 (2.4 GB, where the gather misses the
 * TLB at every element) 53.8-67.5 from the order against 43.4-44.8 from scratch (at N = 3e7,
 * 720 MB, where the sort and the gather are the way from scratch there, steps 29.0-31.3
 * against 39.9-42.8). So where cs_tune, a context times its first steps of a class
 * (dimension, threads and the power of two of the input's bytes, as nbs__cs_way),
 * NBS__CS_TUNE_TRIES from the order and as many from scratch, alternating, each from the
 * detection's start to its search, and takes the faster from then on: run->fresh, set here,
 * makes a detection one from scratch. A start from the order right after a detection from
 * scratch writes the order's keys first (nbs__cs_keys_of), which a step does not: it is not
 * timed. A try costs at most the difference between the two ways, once; the output is the
 * same bytes either way (test_determinism tuned_steps). */
static void nbs__cs_steps_way(nbs__run *run) {
  nbs_context *ctx = run->ctx;
  const int32_t n = run->n;
  if (!ctx->cs_tune || run->fresh) return;
  /* an order this detection would start from (nbs__cellsort, step 0) */
  if (ctx->work_kind != NBS__WORK_CELLSORT || ctx->cs_order_n != n || ctx->cs_warm_wait > 0) {
    return;
  }
  const size_t bytes = nbs__input_bytes(n, run->dim, run->r != NULL);
  if (bytes <= NBS__CS_TUNE_MIN) return;
  const int cls = nbs__tune_class_of(run, nbs__cs_threads(run), bytes);
  /* only where a detection from scratch partitions (nbs__cs_way: by size, or as measured):
   * a step replaces the sort and the gather's key pass and sort by a pass and a merge, and
   * keeps the gather, so it is never slower than they are */
  const nbs__tune *ways = &ctx->cs_ways;
  if (bytes <= ctx->cs_part_min &&
      !(cls == ways->cls && nbs__tune_done(ways) && nbs__tune_second(ways))) {
    return;
  }
  nbs__tune *t = &ctx->cs_steps;
  nbs__tune_class(t, cls);
  if (nbs__tune_done(t)) {
    run->fresh = nbs__tune_second(t);
  } else if (nbs__tune_next(t) == 0) {
    /* from the order, timed where it has its keys (or needs none: nbs__cs_warm) */
    if (ctx->cs_order_eb != 32 || ctx->cs_keys) run->cs_step_try = 1;
  } else {
    run->fresh = true;
    run->cs_step_try = 2;
  }
}

bool nbs__cellsort_step(nbs__run *run, const nbs_input *in, nbs_algorithm asked) {
  nbs_context *ctx = run->ctx;
  const int32_t n = run->n;
  const int dim = run->dim;
  run->stepped = false;
  run->step_over = false;
  if (n < 2 || (asked != NBS_AUTO && asked != NBS_CELLSORT)) return false;
  nbs__cs_steps_way(run); /* may make this detection one from scratch (run->fresh) */
  if (run->fresh) return false;
  if (!ctx->cs_kept_ok || !ctx->cs_keys || ctx->cs_warm_wait > 0 ||
      ctx->work_kind != NBS__WORK_CELLSORT || ctx->cs_order_n != n || ctx->cs_order_eb != 32 ||
      ctx->cs_kept.dim != dim) {
    return false;
  }
  const int threads = nbs__cs_threads(run);
  size_t at[4], stride;
  if (nbs__cs_layout(dim, n, run->r != NULL, threads, at, &stride) > ctx->work_size) {
    return false;
  }
  char *w = nbs__cs_base(ctx->work);
  const nbs__cs_kept *kp = &ctx->cs_kept;
  nbs__cs_keying kg;
  kg.g = &kp->g;
  kg.lo_x = kp->lo_x;
  kg.inv_fine = kp->inv_fine;
  for (int a = 0; a < 3; a++) kg.c[a] = kp->c[a];
  kg.dim = dim;
  kg.sy = kp->sy;
  kg.sz = kp->sz;
  double lo[3], hi[3];
  const int64_t m = nbs__cs_changes(run, &kg, (uint32_t *)(void *)(w + at[0]),
                                    (uint64_t *)(void *)((double *)(void *)(w + at[1]) + stride),
                                    threads, lo, hi);
  if (m < 0) {
    ctx->cs_keys = false; /* some were rewritten */
    run->step_over = m == -1; /* nbs__cellsort counts it as a start that failed */
    return false;
  }
  /* the radii, where given, by input.c's pass of them: their largest sizes the cells */
  double rmax = 0.5 * in->diameter;
  if (run->r && !nbs__radii_max(run, &rmax)) {
    ctx->cs_keys = false; /* input.c's passes name the bad radius */
    return false;
  }
  nbs__grid_measured(run, lo, hi, rmax);
  /* some keys are this step's: not the order's until nbs__cellsort has used them (an error
   * before it, or another algorithm, leaves them unused) */
  ctx->cs_keys = false;
  run->stepped = true;
  run->step_moved = m;
  return true;
}

/* cellsort's grid and key for a grid measured by input.c (or a guess of it: nbs__cellsort_fresh),
 * worked out the same way for both. */
typedef struct nbs__cs_plan {
  int kc[3];    /* the caller's axis of the key's x, y and z */
  nbs__grid g;  /* the grid with its axes in the key's order, anchored (nbs__cs_anchor) */
  int bx, by, bz; /* the key's fields: x in sub-cells, y and z in cells */
  int fine_bits;  /* sub-cells per edge on x: 2^fine_bits */
  int eb;         /* a packed word is key << eb | element */
  int bits;       /* bx + by + bz */
  bool packed;    /* key and element share a word */
} nbs__cs_plan;

/* The plan of `grid`; false where an axis has too many cells (p->g.fits false) or the key
 * would not fit 64 bits (p->bits its cells' bits). */
static bool nbs__cs_plan_of(const nbs__grid *grid, int dim, int32_t n, nbs__cs_plan *p) {
  /* the grid with its axes in the key's order: the rows (the key's x) along the axis with
   * the most cells, where it has at least twice as many as x (nbs__axis_order). A scene thin
   * in x (a wall, a column) would otherwise make rows of an element or two, and the sweep's
   * time would go to finding rows and windows, not to testing pairs. */
  nbs__axis_order(dim, grid->n, 0, p->kc);
  p->g = nbs__grid_reorder(grid, p->kc);
  const nbs__grid *g = &p->g;
  if (!g->fits) return false;
  int by = nbs__bits((uint64_t)g->n[1]), bz = nbs__bits((uint64_t)(dim == 3 ? g->n[2] : 1));
  int bx = nbs__bits((uint64_t)g->n[0]), fine_bits = NBS__CS_FINE_BITS;
  /* the packed cell key (iz, iy, x sub-cell) must fit 64 bits */
  if (!nbs__cellsort_fits(g)) {
    p->bits = bx + by + bz;
    return false;
  }
  nbs__cs_anchor(&p->g); /* the same bits: it still fits */
  /* The key shares its word with the element when both fit, key << eb | element with eb
   * the bits of n - 1: the sort then moves 8 bytes per element and pass instead of 12, and
   * the sweep reads one array for both. At most 63 bits in all, so that the padding after
   * the end (all ones) stays above every bound "up to a key". The x sub-cells give up bits
   * for it (a sparse domain, where they matter little, is where the cells need many).
   * Where the whole key fits 31 bits (every uniform scene of the benchmarks, up to N = 1e8
   * in 3D), eb is 32: the low half of the word is then the element alone, and the AVX-512
   * kernel reads it without a mask (one instruction of its 20 per step: 3D, N = 1e6,
   * interleaved, min of 4-5, 34.3 -> 33.5 ns per element, time steps of 1e-3 35.1 -> 34.4;
   * 2D the same, 20.4 / 20.6, where the kernel is a smaller part). The sort's digits are
   * the key's either way; a start from the last order needs the same eb (cs_order_eb). */
  const int cell_bits = bx + by + bz;
  p->eb = cell_bits + NBS__CS_FINE_BITS <= 31 ? 32 : nbs__bits((uint64_t)n);
  p->packed = cell_bits + p->eb <= 63;
  const int spare = p->packed ? 63 - p->eb - cell_bits : 64 - cell_bits;
  if (fine_bits > spare) fine_bits = spare;
  p->fine_bits = fine_bits;
  p->bx = bx + fine_bits;
  p->by = by;
  p->bz = bz;
  p->bits = p->bx + by + bz;
  return true;
}

/* The keying of a plan (kg->g points into it). */
static nbs__cs_keying nbs__cs_keying_of(const nbs__cs_plan *p, int dim) {
  nbs__cs_keying kg;
  kg.g = &p->g;
  kg.lo_x = p->g.lo[0];
  kg.inv_fine = p->g.inv_edge * (double)((uint64_t)1 << p->fine_bits);
  for (int a = 0; a < 3; a++) kg.c[a] = p->kc[a];
  kg.dim = dim;
  kg.sy = p->bx;
  kg.sz = p->bx + p->by;
  return kg;
}

/* The elements a detection from scratch needs for its input pass to be cellsort's
 * (nbs__cellsort_fresh): below, the sample is a large part of the input. */
#define NBS__CS_FRESH_MIN 4096
/* The elements of that guess's sample, evenly spaced in the input. */
#define NBS__CS_FRESH_SAMPLE 1024

/* The plan of the box of s elements evenly spaced in run's input (its grid as
 * nbs__grid_measured makes it from a box, with the cells' largest radius rmax), for
 * nbs__cellsort_fresh: false where a coordinate of them is not finite (input.c's pass names
 * it), or the plan's keys do not share a word with the element (unpacked keys: input.c's pass
 * and step 1 as they were). */
static bool nbs__cs_guess(const nbs__run *run, int64_t s, double rmax, nbs__cs_plan *plan) {
  const int dim = run->dim;
  double lo[3] = {0.0, 0.0, 0.0}, hi[3] = {0.0, 0.0, 0.0};
  for (int a = 0; a < dim; a++) {
    lo[a] = DBL_MAX;
    hi[a] = -DBL_MAX;
  }
  for (int64_t i = 0; i < s; i++) {
    const double *p = run->x + (size_t)(i * run->n / s) * (size_t)dim;
    for (int a = 0; a < dim; a++) {
      if (!isfinite(p[a])) return false;
      if (p[a] < lo[a]) lo[a] = p[a];
      if (p[a] > hi[a]) hi[a] = p[a];
    }
  }
  nbs__run guess = *run;
  nbs__grid_measured(&guess, lo, hi, rmax);
  return nbs__cs_plan_of(&guess.grid, dim, run->n, plan) && plan->packed;
}

/* A detection from scratch reads the input twice before it sorts: input.c's pass (every
 * number finite, and the bounding box, from which the grid), then step 1 (each element's
 * key), both in element order. Here step 1 runs first, in input.c's place, with a keying
 * worked out from the bounding box of a sample of the elements (NBS__CS_FRESH_SAMPLE, evenly
 * spaced), and measures the whole box as it goes, as the time steps' pass does
 * (nbs__cellsort_step). The keying depends on the box only through the lattice point below
 * its lowest corner (nbs__cs_anchor), the bits of its cells on each axis and which axis has
 * the most: a sample of a thousand elements almost always lands on the same ones (a uniform
 * scene: every time), and where it does not, nbs__cellsort finds the keying different
 * (run->pre) and computes the keys again, as it would have. The pass stops at the first
 * element outside the guessed keying's box, or with a coordinate that is not finite; the
 * caller then runs input.c's pass, which names a bad number as it always does. So the
 * pairs, their order and the errors are those of input.c's pass and step 1.
 * Taken only where the context holds a work block large enough and free of another
 * algorithm's state (a first detection has none: nothing is allocated before the grid is
 * known), where the detection sorts from scratch (def.fresh, no order of this n, or one it
 * would not start from: the starts paused after failing, or the time-step pass having found
 * too many elements moved; the words overwrite the order), and where the guess's keys are
 * packed and the input is below the partition's size (the paths of nbs__cs_sort_gather that
 * begin with step 1 as it is). Packed with fewer than 32 bits for the element too (keys of
 * more than 31 bits, a sparse domain: the huge one of the benchmarks, whose keys take 43
 * bits; the keying's box then reaches as far as a key of 63 - eb bits, nbs__cs_box_limits):
 * interleaved, medians of 6, 3D N = 1e6, input and preparation 15.61 -> 15.24 ns per
 * element, the same hashes (the guess's sample, 16 elements per cell of the longest axis,
 * costs about what the pass saves beyond it).
 * Where the guess fails, the pass costs about what input.c's does, plus the words it wrote
 * for nothing; that happens most where the elements thin out towards the domain's edges, so
 * that the sample's lowest element lies cells above the lowest (a uniform scene whose
 * elements each step moved up to D / 2 at random: the sample's guess failed at every step).
 * Measured (one thread, random order, fraction 0.5, interleaved with the build before,
 * median of 4-12 processes each the minimum of 5 detections, ns per element, the same
 * hashes): 3D N = 1e6 24.79 -> 23.27 and 25.91 -> 25.20 (two runs; the sort after it took
 * 1.4-1.7 less, more than the keys' pass: the input is read once, while it is in the
 * caches), 1e7 26.56 -> 25.33, 1e4 (with 4 decoys) 18.70 -> 18.63; 2D 1e6 14.46 -> 14.09;
 * time steps (which do not take it) the same; one context detecting three unrelated scenes
 * of 1e6 elements in turn, without def.fresh (the starts from the order fail and pause),
 * 26.8-27.8 -> 26.0-26.2 (medians of 30 detections, three processes each). The sample:
 * 1,024 elements, or 16 per cell
 * of the longest axis where that is more (a quarter of N at most); 2D N = 1e6 took the
 * guessed keys only with it (1,253 cells per axis). */
bool nbs__cellsort_fresh(nbs__run *run, const nbs_input *in, nbs_algorithm asked) {
  nbs_context *ctx = run->ctx;
  const int32_t n = run->n;
  const int dim = run->dim;
  run->prewords = false;
  if (n < NBS__CS_FRESH_MIN || (asked != NBS_AUTO && asked != NBS_CELLSORT)) return false;
  if (ctx->work_kind != NBS__WORK_CELLSORT && ctx->work_kind != NBS__WORK_NONE) return false;
  /* The block holds the last detection's order of this n: taken only where this detection
   * would not start from it either, its starts being paused (cs_warm_wait) or the time-step
   * pass having found too many elements moved (step_over); nbs__cellsort then counts the
   * pause, or the failed start, as it would have (run->order_dropped). */
  const bool order = ctx->work_kind == NBS__WORK_CELLSORT && ctx->cs_order_n == n;
  if (order && !run->fresh && !run->step_over && ctx->cs_warm_wait == 0) return false;
  const int threads = nbs__cs_threads(run);
  size_t at[4], stride;
  if (nbs__cs_layout(dim, n, run->r != NULL, threads, at, &stride) > ctx->work_size) {
    return false;
  }
  /* the radii, where given, by input.c's pass of them: their largest sizes the cells */
  double rmax = 0.5 * in->diameter;
  if (run->r && !nbs__radii_max(run, &rmax)) return false; /* input.c's passes name it */

  /* the guess: the plan of a sample's box */
  nbs__cs_plan plan;
  if (!nbs__cs_guess(run, NBS__CS_FRESH_SAMPLE, rmax, &plan)) return false;
  /* s elements spread evenly over an axis of C cells leave about C / s cells between the
   * lowest of them and the lowest element: a sample of 16 C, so that the two share a
   * lattice point more than 9 times in 10 (2D, N = 1e6: 1,253 cells, a sample of 20,048),
   * but of at most N / 16, a part of the pass it is to save */
  int64_t more = NBS__CS_FRESH_SAMPLE, cells = 0;
  for (int a = 0; a < dim; a++) {
    if (16 * plan.g.n[a] > more) more = 16 * plan.g.n[a];
    if (plan.g.n[a] > cells) cells = plan.g.n[a];
  }
  if (more > n / 16) more = n / 16;
  /* fewer than the cells of an axis: the sample's lowest element lies a cell or more above
   * the lowest, most often past a lattice point, and the pass would be lost (a domain spread
   * thin: 2D, N = 1e6 over 1e12 cells, 1e6 cells per axis for a sample of 62,500, where the
   * pass stopped at every detection, input 0.68 -> 1.50 ns per element; 3D, 1e4 cells per
   * axis, the guess held at 9 detections of 10) */
  if (more < cells) return false;
  if (more > NBS__CS_FRESH_SAMPLE && !nbs__cs_guess(run, more, rmax, &plan)) return false;
  const nbs__cs_keying kg = nbs__cs_keying_of(&plan, dim);
  /* where the partition is to run (nbs__cs_way), the pass counts its top digits instead of
   * making the words: the partition's own first pass over the input, which read it all a
   * second time, is saved (the Intel guest, N = 1e6, one thread, random order, eight rounds
   * interleaved with 85a4f1d, input and preparation in ns per element, medians: 3D 41.4 ->
   * 35.4, 2D 43.0 -> 35.8 of five; two threads, 3D preparation 19.9-21.9 -> 16.6-18.7; the
   * same bytes) */
  const nbs__cs_pdigits pd = nbs__cs_part_digits(n, plan.bits, ctx->cs_part_wide);
  const bool tally =
      plan.packed && nbs__cs_way(run, threads) == 2 && nbs__cs_part_top_first(n, &pd);

  /* step 1 where nbs__cs_sort_gather puts it; the order the block held is gone */
  run->order_dropped = order && !run->fresh;
  run->dropped_eb = ctx->cs_order_eb;
  ctx->cs_order_n = 0;
  ctx->cs_kept_ok = false;
  ctx->cs_keys = false;
  char *w = nbs__cs_base(ctx->work);
  uint64_t *k0 = nbs__cs_step1_at((uint64_t *)(void *)w, (double *)(void *)(w + at[1]),
                                  plan.bits);
  uint32_t *hist = (uint32_t *)(void *)(w + at[3]); /* nbs__cellsort's */
  nbs__cs_box boxes[NBS__THREADS_MAX];
  bool outside = false;
  const double *x = run->x;
#if defined(_OPENMP)
#pragma omp parallel num_threads(threads) if (threads > 1) reduction(|| : outside)
#endif
  NBS__PARTS(t, threads) {
    const int32_t from = nbs__chunk(n, t, threads), to = nbs__chunk(n, t + 1, threads);
    const nbs__grid g = *kg.g; /* locals, in registers (see nbs__cs_core_split) */
    nbs__cs_keying kl = kg;
    kl.g = &g;
    nbs__cs_box *box = &boxes[t];
    nbs__cs_box_clear(box);
    nbs__cs_tally ty = {hist + (size_t)t * pd.buckets, pd.shift, pd.buckets - 1};
    if (tally) memset(ty.h, 0, pd.buckets * sizeof *ty.h);
    bool in_box;
#if NBS__CS_AVX512
    if (ctx->simd == NBS__SIMD_AVX512) {
      in_box = nbs__cs_words_boxed512(&kl, x, from, to, plan.eb, k0, box, tally ? &ty : NULL);
    } else if (ctx->simd == NBS__SIMD_AVX2 && nbs__cs_fits4(&kl, plan.eb, true)) {
      in_box = nbs__cs_words_boxed256(&kl, x, from, to, plan.eb, k0, box, tally ? &ty : NULL);
    } else
#endif
    {
      in_box = nbs__cs_words_boxed(&kl, x, dim, from, to, plan.eb, k0, box, tally ? &ty : NULL);
    }
    if (!in_box) outside = true;
  }
  if (outside) return false;
  double lo[3], hi[3];
  nbs__cs_boxes_join(boxes, threads, dim, lo, hi);
  nbs__grid_measured(run, lo, hi, rmax);
  /* the keying the words were made with, for nbs__cellsort to compare with its own */
  run->pre = nbs__cs_kept_of(&kg);
  run->pre_bits = plan.bits;
  run->pre_eb = plan.eb;
  run->prewords = !tally;
  run->precounts = tally;
  return true;
}

nbs_status nbs__cellsort(nbs__run *run) {
  nbs_context *ctx = run->ctx;
  const int dim = run->dim;
  const int32_t n = run->n;
  run->ran = NBS_CELLSORT;
  run->compressed = false;
  nbs__cs_plan plan;
  const bool planned = nbs__cs_plan_of(&run->grid, dim, n, &plan);
  const int *kc = plan.kc;
  for (int a = 0; a < 3; a++) ctx->axes[a] = (int8_t)kc[a];
  if (!planned && !plan.g.fits) {
    return nbs__fail(ctx, NBS_ERR_EXTENT, -1,
                     "cellsort: the domain spans more than %lld cells on an axis; use 'auto'",
                     (long long)NBS__AXIS_MAX);
  }
  if (!planned) {
    return nbs__fail(ctx, NBS_ERR_EXTENT, -1,
                     "cellsort: %lld x %lld x %lld cells need a %d-bit key; use 'auto'",
                     (long long)run->grid.n[0], (long long)run->grid.n[1],
                     (long long)(dim == 3 ? run->grid.n[2] : 1), plan.bits);
  }
  const nbs__grid *g = &plan.g;
  const int64_t nx = g->n[0], ny = g->n[1], nz = dim == 3 ? g->n[2] : 1;
  const int eb = plan.eb, bx = plan.bx, by = plan.by, bits = plan.bits;
  const int fine_bits = plan.fine_bits;
  const bool packed = plan.packed;
  run->cells[2] = 1;
  for (int a = 0; a < dim; a++) run->cells[kc[a]] = g->n[a];

  const size_t nn = (size_t)n;
  const int threads = nbs__cs_threads(run);
  size_t at[4], stride;
  const size_t bytes = nbs__cs_layout(dim, n, run->r != NULL, threads, at, &stride);
  NBS__TRY(nbs__work_reserve(ctx, bytes));
  /* the last detection's cell order, when it is there (a new block holds none) */
  const bool had_order = (ctx->work_kind == NBS__WORK_CELLSORT && ctx->cs_order_n == n &&
                          ctx->cs_order_eb == eb) ||
                         (run->order_dropped && run->dropped_eb == eb);
  ctx->work_kind = NBS__WORK_CELLSORT;
  ctx->cs_order_n = 0; /* no order until this detection's is complete */
  ctx->cs_kept_ok = false;
  ctx->cs_outliers = -1;
  ctx->cs_partitioned = false;
  ctx->cs_part_widened = false;
  char *w = nbs__cs_base(ctx->work);
  nbs__cs c;
  c.run = run;
  c.dim = dim;
  c.n = n;
  c.key = (uint64_t *)(void *)w;
  c.idx = packed ? NULL : (int32_t *)(void *)(w + at[0]);
  /* the low half of a packed word: the first int32 of it on a little-endian machine */
  c.ids = packed ? (const int32_t *)(const void *)c.key + (NBS__BIG_ENDIAN ? 1 : 0) : c.idx;
  c.istep = packed ? 2 : 1;
  c.xs = (double *)(void *)(w + at[1]);
  c.ys = c.xs + stride;
  c.zs = dim == 3 ? c.ys + stride : NULL;
  c.rs = run->r ? (double *)(void *)(w + at[2]) : NULL;
  c.d2 = run->d2;
  c.contacts = run->mode == NBS_MODE_CONTACTS;
  c.block = nbs__cs_block_generic;
  c.nx = nx;
  c.ny = ny;
  c.nz = nz;
  c.bx = bx;
  c.by = by;
  c.fine = (uint64_t)1 << fine_bits;
  c.ks = packed ? eb : 0;
  c.imask = packed ? (uint32_t)(((uint64_t)1 << eb) - 1) : UINT32_MAX;
#if NBS__CS_AVX512
  /* the SIMD kernel's copy for c (the form needs imask) */
  if (ctx->simd == NBS__SIMD_AVX512) c.block = nbs__cs_kernel_of(nbs__cs_k512_table, &c);
  if (ctx->simd == NBS__SIMD_AVX2) c.block = nbs__cs_kernel_of(nbs__cs_k256_table, &c);
#endif
  run->work_bytes = bytes;

  const nbs__cs_keying kg = nbs__cs_keying_of(&plan, dim);
  uint32_t *hist = (uint32_t *)(void *)(w + at[3]);

  /* 0. from the last detection's order, when the elements have moved little since */
  bool warm = false;
  const bool keys = ctx->cs_keys;
  ctx->cs_keys = false; /* until this detection has written them */
  if (run->stepped) {
    /* step 1 is done (nbs__cellsort_step), with the last keying: its keys stand if this
     * detection's keying is the same; else they are dropped, and the sort is from scratch */
    if (had_order && packed && eb == 32 && nbs__cs_kept_same(&ctx->cs_kept, &kg)) {
      run->moved = run->step_moved;
      nbs__cs_rekey_merge(&c, run, run->moved, hist, threads);
      warm = true;
      ctx->cs_keys = true;
      ctx->cs_stepped = true;
      ctx->cs_warm_fails = 0;
    }
  } else if (had_order && packed && !run->fresh) {
    if (ctx->cs_warm_wait > 0) {
      ctx->cs_warm_wait--;
    } else {
      if (run->step_over) {
        /* nbs__cellsort_step found too many keys changed: the same start, tried already */
      } else if (eb == 32) {
        uint32_t *ek = (uint32_t *)(void *)(w + at[0]);
        if (!keys) nbs__cs_keys_of(&c, ek, threads);
        warm = nbs__cs_rekey(&c, run, &kg, ek, hist, threads, &run->moved);
        ctx->cs_keys = warm;
      } else {
        warm = nbs__cs_warm(&c, run, &kg, eb, bits, (uint64_t *)(void *)(w + at[0]), hist,
                            threads, &run->moved);
      }
      if (!warm && ctx->cs_warm_fails < 6) ctx->cs_warm_fails++;
      if (warm) ctx->cs_warm_fails = 0;
      ctx->cs_warm_wait = warm ? 0 : 1 << ctx->cs_warm_fails;
    }
  }
  run->reused_order = warm;
  if (!warm) {
    run->moved = 0;
    /* step 1 done by nbs__cellsort_fresh, where it guessed this keying */
    const bool words = run->prewords && packed && eb == run->pre_eb && bits == run->pre_bits &&
                       nbs__cs_kept_same(&run->pre, &kg);
    ctx->cs_fresh_words = words;
    nbs__cs_sort_gather(&c, run, &kg, packed, eb, bits, words, hist, threads, w + at[0],
                        at[1] - at[0]);
  }
  for (size_t t = nn; t < nn + NBS__CS_PAD; t++) c.key[t] = UINT64_MAX;
  if (packed) {
    ctx->cs_order_n = n;
    ctx->cs_order_eb = eb;
  }
  if (packed && eb == 32) {
    ctx->cs_kept = nbs__cs_kept_of(&kg);
    ctx->cs_kept_ok = true;
  }

  /* 4. sweep: in one range, or by threads in parts of chunks (nbs__cs_sweep_parts) */
  nbs__search_begins(run);
  nbs__sink sinks[NBS__THREADS_MAX + 1]; /* each part's; [threads]: thread 0's steals */
  for (int t = 0; t <= threads; t++) {
    memset(&sinks[t], 0, sizeof sinks[t]);
    sinks[t].ctx = ctx;
    sinks[t].thread = t == threads ? 0 : t;
    if (t == 0) {
      sinks[t].run = run;
      sinks[t].buf = run->buf;
      sinks[t].count = run->count;
      sinks[t].cap = run->cap;
    } else {
      sinks[t].buf = ctx->tpairs[sinks[t].thread];
      sinks[t].cap = ctx->tcap[sinks[t].thread];
    }
  }
  nbs__cs_seg segs[NBS__CS_SEGS];
  int nsegs = 0;
  ctx->cs_stolen = 0;
  if (threads == 1) {
    sinks[0].status = nbs__cs_sweep(&c, &sinks[0], 0, n);
  } else {
#if defined(_OPENMP)
    nsegs = nbs__cs_sweep_parts(&c, sinks, threads, segs);
#endif
  }
  /* the run's sink holds part 0's first chunks in place; the other chunks follow in order */
  run->count = sinks[0].count;
  nbs_status st = sinks[0].status;
  for (int t = 0; t <= threads; t++) {
    run->candidates += sinks[t].candidates;
    run->emitted += sinks[t].emitted;
    if (st == NBS_OK) st = sinks[t].status;
  }
  if (st == NBS_ERR_NOMEM && !ctx->error[0]) {
    st = nbs__fail(ctx, NBS_ERR_NOMEM, -1, "cannot grow a thread's pair list");
  }
  size_t more = 0;
  for (int k = 0; k < nsegs; k++) more += segs[k].count;
  if (st == NBS_OK && more > 0) {
    /* threads > 1 only without callbacks and max_pairs: room is always made */
    st = nbs__room_whole(run, more);
    if (st == NBS_OK) {
      nbs__cs_append(run->buf + run->count, sinks, segs, nsegs, threads, more);
      run->count += more;
    }
  }
  return st;
}
