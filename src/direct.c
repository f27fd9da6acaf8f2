/*
 * Direct checking (section 3.2): every pair is tested. CPU time grows as N^2 and no memory
 * is needed. It is the reference every other algorithm is tested against, and auto's
 * choice for a handful of elements. In candidate mode every pair is a candidate.
 */
#include "internal.h"

nbs_status nbs__direct(nbs__run *run) {
  run->ran = NBS_DIRECT;
  run->work_bytes = 0;
  run->compressed = false;
  run->cells[0] = run->cells[1] = run->cells[2] = 0;
  const int32_t n = run->n;
  nbs__search_begins(run);
  for (int32_t i = 0; i < n; i++) {
    for (int32_t j = i + 1; j < n; j++) NBS__TRY(nbs__offer(run, i, j));
  }
  return NBS_OK;
}
