/*
 * nbs: contact detection for discrete element simulations.
 *
 * The library finds every pair of elements whose bounding circles (2D) or spheres (3D)
 * touch, with the family of algorithms of chapter 3 of A. Munjiza, "The Combined
 * Finite-Discrete Element Method" (Wiley 2004): direct checking, screening (direct
 * mapping), sorting and Munjiza-NBS.
 *
 * Use:
 *   nbs_context *ctx;
 *   nbs_context_def cdef = nbs_default_context_def();
 *   if (nbs_context_create(&cdef, &ctx) != NBS_OK) ...          once
 *   nbs_input in = {.dim = 3, .n = n, .coords = xyz, .diameter = d};
 *   nbs_detect_def ddef = nbs_default_detect_def();
 *   nbs_status s = nbs_detect(ctx, &in, &ddef);                   every time step
 *   size_t count; const nbs_pair *pairs = nbs_pairs(ctx, &count);
 *   nbs_context_destroy(ctx);
 *
 * Contract, the same for every algorithm:
 *   contact means |xi - xj|^2 <= (ri + rj)^2 evaluated in double (touching counts; with one
 *   diameter D for all elements the right-hand side is D^2); every contacting pair is
 *   reported exactly once as (i, j) with i < j. The order of the pairs depends on the
 *   algorithm; sorted with nbs_sort_pairs(), the lists of all algorithms are identical.
 *
 * Threading: a context is used by one thread at a time; distinct contexts are independent.
 * Nothing in the library aborts or exits on user input: every public function that can
 * fail returns an nbs_status.
 */
#ifndef NBS_NBS_H
#define NBS_NBS_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#if defined(_WIN32) && defined(NBS_SHARED_BUILD)
#define NBS_API __declspec(dllexport)
#elif defined(__GNUC__)
#define NBS_API __attribute__((visibility("default")))
#else
#define NBS_API
#endif

#define NBS_VERSION_MAJOR 0
#define NBS_VERSION_MINOR 1
#define NBS_VERSION_PATCH 0
#define NBS_VERSION_STRING "0.1.0"

/* The version the library was built as ("0.1.0"); may differ from the header's when linked
 * against another build. */
NBS_API const char *nbs_version(void);

/* ---------------------------------------------------------------------------------------
 * Status codes. One list, so that the enum, the names and the messages never disagree.
 * X(ENUM, value, "name", "message")
 */
#define NBS_STATUS_LIST(X)                                                                   \
  X(NBS_OK, 0, "ok", "success")                                                               \
  X(NBS_ERR_NULL, 1, "null", "a required pointer argument is NULL")                           \
  X(NBS_ERR_DIM, 2, "dim", "the dimension must be 2 or 3")                                    \
  X(NBS_ERR_COUNT, 3, "count", "the number of elements must satisfy 0 <= n < 2^31")           \
  X(NBS_ERR_COORD, 4, "coord", "a coordinate is NaN or infinite")                             \
  X(NBS_ERR_RADIUS, 5, "radius", "a radius or diameter is not a finite number > 0")           \
  X(NBS_ERR_ALGORITHM, 6, "algorithm", "unknown algorithm")                                   \
  X(NBS_ERR_MODE, 7, "mode", "unknown detection mode")                                        \
  X(NBS_ERR_BUDGET, 8, "budget", "the cell array would exceed the memory budget")             \
  X(NBS_ERR_EXTENT, 9, "extent",                                                              \
    "the domain spans more cells on an axis than this algorithm can index; use 'auto'")      \
  X(NBS_ERR_NOMEM, 10, "nomem", "memory allocation failed")                                   \
  X(NBS_ERR_PAIRS, 11, "pairs", "the number of pairs exceeds what the pair buffer can hold")  \
  X(NBS_ERR_STOPPED, 12, "stopped", "the pair callback asked to stop")                        \
  X(NBS_ERR_ARGUMENT, 13, "argument", "an argument is out of its documented range")        \
  X(NBS_ERR_BUSY, 14, "busy",                                                                 \
    "the context is in a detection: a pair callback called back into it")

typedef enum nbs_status {
#define NBS_X_ENUM(e, v, name, msg) e = v,
  NBS_STATUS_LIST(NBS_X_ENUM)
#undef NBS_X_ENUM
} nbs_status;

/* Short stable name of a status ("nomem"); "unknown" for a value not in the list. */
NBS_API const char *nbs_status_name(nbs_status status);
/* One-sentence description of a status; never NULL. */
NBS_API const char *nbs_status_message(nbs_status status);

/* ---------------------------------------------------------------------------------------
 * Algorithms, chosen by value or by name.
 */
typedef enum nbs_algorithm {
  NBS_AUTO = 0,      /* the library's choice; succeeds for every finite input */
  NBS_DIRECT = 1,    /* every pair, O(N^2): the reference */
  NBS_SCREENING = 2, /* direct mapping onto a cell array, O(N) time, O(cells) memory */
  NBS_SORTING = 3,   /* cells sorted by the book's midpoint sort, O(N log N), 3N/4N ints */
  NBS_NBS = 4,       /* Munjiza-NBS, O(N) time, O(N + nx + ny + nz) memory */
  NBS_CELLSORT = 5,  /* beyond the book: radix-sorted cells, cache-friendly, O(N) memory */
  NBS_ALGORITHM_COUNT
} nbs_algorithm;

/* "auto", "direct", "screening", "sorting", "nbs", "cellsort"; NULL for a value out of range. */
NBS_API const char *nbs_algorithm_name(nbs_algorithm algorithm);
/* Parses one of the names above. NBS_ERR_NULL, NBS_ERR_ALGORITHM. */
NBS_API nbs_status nbs_algorithm_from_name(const char *name, nbs_algorithm *out);

typedef enum nbs_mode {
  NBS_MODE_CONTACTS = 0,  /* pairs that pass the distance test */
  NBS_MODE_CANDIDATES = 1 /* every pair the algorithm's cell mask yields (a superset) */
} nbs_mode;

/* ---------------------------------------------------------------------------------------
 * Memory. The library allocates only through this allocator and counts what it holds.
 * alloc returns NULL on failure (the library then returns NBS_ERR_NOMEM, leaks nothing and
 * leaves the context usable). free receives the size that was asked of alloc, and is
 * never called with NULL. Memory from alloc must be aligned for any C object (like malloc).
 * realloc is optional (NULL: the library allocates, copies and frees); like C's realloc
 * it returns NULL and leaves the block as it was on failure. The pair buffer grows with it,
 * which for large buffers avoids holding the old and the new one at once (glibc remaps).
 * A detection with threads may call these from its OpenMP threads, one call at a time.
 */
typedef struct nbs_allocator {
  void *(*alloc)(void *opaque, size_t size);
  void (*free)(void *opaque, void *ptr, size_t size);
  void *opaque;
  void *(*realloc)(void *opaque, void *ptr, size_t old_size, size_t new_size);
} nbs_allocator;

typedef struct nbs_context_def {
  /* alloc and free NULL (the default): malloc, realloc and free. alloc and free are set
   * both or neither; realloc only with them. */
  nbs_allocator allocator;
  /* Largest number of bytes that arrays indexed by cell may take: screening's head array
   * (one int per cell) and NBS's per-axis head arrays with their records of started
   * lists (one int per head, about). A detection that would pass it
   * returns NBS_ERR_BUDGET before allocating. Default NBS_DEFAULT_CELL_BUDGET. */
  size_t cell_budget;
  /* Largest number of pairs the context's pair buffer may hold; a detection that finds
   * more returns NBS_ERR_PAIRS (with the count so far in nbs_last_stats). 0 means no
   * limit beyond allocation failure. Default 0. It does not apply to detections with a
   * callback, whose pairs the context does not hold. */
  size_t max_pairs;
  /* Threads for the algorithms that use them (cellsort, and so auto): 0 (the default) for
   * OpenMP's default (OMP_NUM_THREADS, or the cores), 1 for none. The pairs are the same,
   * in the same order, for any number, and whatever OpenMP gives of them: a detection
   * called from inside the caller's own parallel region (a context per thread) uses one
   * thread there unless nesting is on, and OMP_THREAD_LIMIT or OMP_DYNAMIC may give it fewer
   * than asked. Ignored when the library is built without OpenMP. */
  int threads;
} nbs_context_def;

#define NBS_DEFAULT_CELL_BUDGET ((size_t)1 << 30)

NBS_API nbs_context_def nbs_default_context_def(void);

typedef struct nbs_context nbs_context;

/* Creates a context. def may be NULL for the defaults. On failure *out is NULL.
 * NBS_ERR_NULL (out), NBS_ERR_ARGUMENT (only one allocator function set, or threads < 0),
 * NBS_ERR_NOMEM. */
NBS_API nbs_status nbs_context_create(const nbs_context_def *def, nbs_context **out);
/* Frees everything the context holds. NULL is allowed. */
NBS_API void nbs_context_destroy(nbs_context *ctx);

/* Bytes the library holds now for this context (the context itself, work arrays and the
 * pair buffer), and the largest that figure has been since creation. */
NBS_API size_t nbs_context_bytes(const nbs_context *ctx);
NBS_API size_t nbs_context_peak_bytes(const nbs_context *ctx);

/* Grows the context ahead of time so that detections of up to n elements with up to
 * pairs pairs allocate nothing for their elements or pairs (cell arrays still follow the
 * domain's extent). With threads, each of the context's threads gets a list of `pairs` as
 * well (cellsort's threads stage their pairs in lists of their own, and a thread may find
 * all of them): 8 * pairs bytes for the buffer and as much again per thread.
 * NBS_ERR_NULL, NBS_ERR_COUNT, NBS_ERR_NOMEM, NBS_ERR_BUSY. */
NBS_API nbs_status nbs_context_reserve(nbs_context *ctx, int64_t n, size_t pairs);

/* The message of the last failed call on this context, with detail where there is one
 * ("element 17: coordinate 1 is NaN"); "" after a success. Valid until the next call. */
NBS_API const char *nbs_context_error(const nbs_context *ctx);
/* The element named by the last error, or -1 when the error names none. */
NBS_API int64_t nbs_context_error_element(const nbs_context *ctx);

/* ---------------------------------------------------------------------------------------
 * Detection.
 */
typedef struct nbs_input {
  int dim;              /* 2 or 3 */
  int64_t n;            /* number of elements, 0 <= n < 2^31 */
  const double *coords; /* n * dim centre coordinates, interleaved: x0 y0 [z0] x1 y1 ... */
  const double *radii;  /* n radii, or NULL: then every element has diameter `diameter` */
  double diameter;      /* the common bounding diameter, used when radii is NULL */
} nbs_input;

typedef struct nbs_pair {
  int32_t i, j; /* i < j, 0-based element indices */
} nbs_pair;

/* Receives pairs in batches. Return 0 to continue, non-zero to stop the detection (it then
 * returns NBS_ERR_STOPPED). The batch is valid only during the call. The callback may use
 * other contexts freely; on the detecting context, nbs_detect and nbs_context_reserve return
 * NBS_ERR_BUSY (changing nothing), nbs_pairs gives no pairs, and nbs_context_destroy must not
 * be called. The input's coordinates and radii must stay as they are until nbs_detect
 * returns: some algorithms read them again after a batch. */
typedef int (*nbs_pair_fn)(void *user, const nbs_pair *pairs, size_t count);

typedef struct nbs_detect_def {
  nbs_algorithm algorithm; /* default NBS_AUTO */
  nbs_mode mode;           /* default NBS_MODE_CONTACTS */
  nbs_pair_fn callback;    /* NULL (default): pairs go to the context's buffer */
  void *user;              /* passed to callback */
  int sorted;              /* 1: sort the buffer's pairs by i, then j, in place (the same list
                            * for every algorithm and thread count); ignored with a callback */
  int fresh;               /* 1: cellsort sorts from scratch even when the context holds the
                            * cell order of a last detection of the same n (see below) */
} nbs_detect_def;

NBS_API nbs_detect_def nbs_default_detect_def(void);

/* Finds the pairs of `in`. def may be NULL for the defaults.
 * Time steps: cellsort (and auto, when it runs cellsort) keeps the cell order it sorted the
 * elements into. The next detection of the same n computes each element's cell again, and
 * when they have moved little since (a time step) it re-sorts only the few that changed
 * place and merges them into that order, instead of sorting all of them. The pairs and their order are exactly those of a
 * detection from scratch; only the time differs. Inputs that are not a later state of the
 * same elements are recognised early and sorted from scratch. def.fresh = 1 turns it off.
 * Where a detection from scratch would read the input in order rather than at random (over
 * 1 GiB of input, or where the context has measured that faster), the context times its
 * first few steps both ways, from the order and from scratch, and takes the faster from then
 * on (the same pairs either way: from scratch wins at 10^8 spheres on the benchmark
 * machine); nbs_stats.reused_order says which a detection took.
 * Without a callback the pairs replace the context's buffer (nbs_pairs); with one they are
 * delivered in batches and the buffer is left empty. After a first detection, a detection
 * with the same or a smaller n (and a domain of no more cells per axis) allocates nothing,
 * unless it finds more pairs than the buffer has held before, or, with NBS, its two fullest
 * neighbouring layers (2D: rows) hold more elements than its layer block has room for: the
 * first detection's two fullest and four standard deviations of that count more (in 3D with
 * a block over 512 KiB, likewise its fullest layer for the copy its rows are laid out
 * through), which a simulation's steps stay within unless its elements crowd into fewer
 * layers. With threads
 * (cellsort, and auto), each thread stages its pairs in a list of its own, which grows (by
 * half again) when the thread finds more than it has room for: the threads share the work
 * by the cores' speeds, so their shares move from step to step, and such steps come, more
 * rarely as the lists grow. nbs_context_reserve with the pairs makes every list hold them
 * all: then none comes.
 * Errors: NBS_ERR_NULL, NBS_ERR_DIM, NBS_ERR_COUNT, NBS_ERR_COORD, NBS_ERR_RADIUS,
 * NBS_ERR_ALGORITHM, NBS_ERR_MODE, NBS_ERR_BUDGET, NBS_ERR_EXTENT, NBS_ERR_NOMEM,
 * NBS_ERR_PAIRS, NBS_ERR_STOPPED, NBS_ERR_BUSY (called from this detection's own callback).
 * After an error the buffer holds no valid pairs and the context remains usable. */
NBS_API nbs_status nbs_detect(nbs_context *ctx, const nbs_input *in, const nbs_detect_def *def);

/* The pairs of the last successful detection (NULL and 0 when there are none). */
NBS_API const nbs_pair *nbs_pairs(const nbs_context *ctx, size_t *count);

typedef struct nbs_stats {
  nbs_algorithm algorithm; /* the algorithm that ran (never NBS_AUTO) */
  nbs_mode mode;
  int dim;
  int64_t n;
  uint64_t pairs;      /* pairs reported (contacts, or candidates in candidate mode) */
  uint64_t candidates; /* pairs the cell mask yielded before the distance test */
  double cell_size;    /* edge of a cell (0 for direct) */
  int64_t cells[3];    /* cells per axis (sorting's compressed axes: distinct cell
                        * coordinates; nbs's folded axes: lists per axis) */
  int compressed;      /* 1 if the axes were compressed (sorting) or folded (nbs) because
                        * the grid was too large */
  size_t work_bytes;   /* bytes of the algorithm's arrays during this detection */
  size_t pair_bytes;   /* bytes of the pair buffer */
  int reused_order;    /* 1 if cellsort started from the last detection's cell order */
  int64_t moved;       /* then: elements that changed place in it and were sorted again */
  /* Where the time went (wall clock, seconds; four reads of a monotonic clock per
   * detection, about 0.1 microseconds on a current x86 Linux machine). What is
   * not in the input or the search is the algorithm's preparation: putting every element
   * in its cells, lists or order (cellsort's keys, sort and gather; sorting's sort;
   * screening's and nbs's first lists), and with def.sorted the pairs' sort. */
  double seconds;        /* the whole detection, from the call to its return */
  double seconds_input;  /* validating the input and measuring its bounds (in a cellsort
                          * time step, and in a cellsort detection from scratch once the
                          * context holds its work arrays, the one pass that also computes
                          * the keys) */
  double seconds_search; /* testing candidates and handing out pairs: from the moment the
                          * algorithm has every element in place to its end */
} nbs_stats;

/* Statistics of the last detection (also after NBS_ERR_PAIRS: pairs then counts what was
 * found before the limit). NBS_ERR_NULL. */
NBS_API nbs_status nbs_last_stats(const nbs_context *ctx, nbs_stats *out);

/* Sorts pairs by i, then j, in place, without allocating. NULL with count 0 is allowed. */
NBS_API void nbs_sort_pairs(nbs_pair *pairs, size_t count);

#ifdef __cplusplus
}
#endif

#endif /* NBS_NBS_H */
