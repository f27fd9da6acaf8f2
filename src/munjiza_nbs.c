/*
 * Munjiza-NBS contact detection ("No Binary Search"; book section 3.8 for 2D, section 3.10
 * for 3D and its generalisation, pp. 103-128).
 *
 * Elements are mapped onto cells of edge d >= the largest diameter (the book's
 * integerisation, eq. 3.26; grid.edge here), so that only elements in the same or in
 * neighbouring cells can touch. Instead of an array of cells (screening, whose memory grows
 * with the number of cells) NBS keeps one level of singly connected lists per axis, built and
 * torn down per detection:
 *
 *   2D:  y-lists B[ny] + Y[N]            one list per row of cells (stored as runs, below)
 *        x-lists A[2][nx] + X[M]         one list per cell of the central row (set 0) and of
 *                                        the row below it (set 1)
 *   3D:  z-lists C[nz] + Z[N]            one list per layer (stored as runs, below)
 *        y-lists B[2][ny] + Y[M]         rows of the central layer (set 0), of the layer
 *                                        below it (set 1)
 *        x-lists A[2][nx] + X[M]         cells of the central row (set 0), of its neighbour
 *                                        rows (set 1, eqs. 3.78-3.79)
 *
 * A list is found non-empty by looping over the elements of the list one level up, never by
 * looping over cells, and each list is removed by resetting only the heads the elements that
 * built it touched. Time is therefore proportional to N whatever the packing density and the
 * extent of the domain (eqs. 3.63-3.64). Memory is ny + 2nx + N integers in 2D and
 * nz + 2ny + 2nx + N in 3D, and a block of M <= N entries of 32 bytes in 2D, 36 in 3D
 * (below), where eq. 3.65 has ny + 2nx + 2N integers and eq. 3.80 nz + 2ny + 2nx + 3N; plus
 * the records described below (ny + 2nx in 2D, nz + 2ny + 2nx in 3D) and a count per row
 * (2D) or layer (3D); in 3D, where the input is over 32 MiB, 3N doubles more (4N with
 * radii: the elements in layer order, below).
 *
 * Deviations from the book's text, all of them representation only:
 *  - 0-based element indices, and the end of a list is NBS__EMPTY (-1);
 *  - each head array is padded by one cell on each side, so that a cell coordinate i is
 *    stored at index i + 1 and i - 1, i + 1 are always valid indices;
 *  - a list is marked "old" by storing -2 - head (nbs__mark) instead of adding 2N, which
 *    would overflow int32 for large N; a marked head read as a neighbour goes through
 *    nbs__unmark. Lists of set 1 are never marked. A layer (3D) or row (2D), whose list is
 *    a run (below), is marked in its count instead: CN[iz] = ~CN[iz], which keeps the count
 *    (step 4 of the layer above still needs it) and is negative;
 *  - records of started heads (RB0, RB1 of at most ny entries, RA0, RA1 of at most nx, RC of at
 *    most nz, or ny in 2D): a push that starts a list (its head was empty) also notes the head's
 *    index. The removal of a set of lists (3D steps 9, 10, 11 and the z-lists; the 2D removal of
 *    x-lists) resets the heads its record names instead of walking the lists or the elements a
 *    second time to recompute them (the same heads: exactly those the elements touched). In 3D,
 *    step 5's loop over the central layer, which finds each row "new" at its first element in layer
 *    order, runs over RB0: step 3 walks the same layer in the same order and notes each row at the
 *    same first element, so the central rows come in the book's order without a second walk of the
 *    layer (the rows are still found by the loop over the elements of the layer, step 3's).
 *    Likewise step 2's loop over the elements runs over RC, the layers in the order step 1 met
 *    their first elements, and so does the pass that sizes the layer block: two passes over
 *    the coordinates (step 1, the second for the runs below) where there were four;
 *  - walks of independent lists go side by side (3D: the central row and its four
 *    neighbouring rows in steps 6 and 7, and the four neighbour lists of a central cell). In
 *    random element order every step of a list is a cache miss; walked side by side the
 *    misses overlap. The rows of steps 6-7 link entries of the block, which at N = 1e7 (3 MB)
 *    is larger than the core's cache; walked one after the other every step waited on the
 *    one before; where the block is larger than 1 MiB, each of those walks also asks for
 *    the entry 8 places further down its list (NBS__NBS_AHEAD);
 *  - runs (beyond the book, for time). A layer's z-list (2D: a row's y-list) is stored as
 *    the run of its elements in the order the book's list links them, the last pushed
 *    first, and its head C[iz] is where the run starts in Z (nbs__nbs_body's step 1: a
 *    count, then a second pass over the coordinates that puts each element at the end of
 *    its layer's run still free: a counting sort by layer). The lists hold the same
 *    elements in the same order, in the same N ints; only their links are implicit: the
 *    next of the run's j-th element is its (j+1)-th. Why: steps 3-4 walk every layer
 *    once, and in random element order each step of a linked walk waited on memory twice,
 *    for the link and then for the element's coordinates, one after the other; 8 lists per
 *    layer walked side by side (this deviation's predecessor) kept only 8-16 such chains in
 *    flight, and perf found a quarter of the detection's time (3D, N = 1e7) on the links'
 *    loads. A run gives the elements ahead of the walk, so their coordinates are asked for
 *    64 places ahead (nbs__nbs_run) and the walk runs at the pace of the memory, not of its
 *    latency. Measured (Zen 4, random order, one thread, interleaved, min / median of 5
 *    processes of three detections (thirty at N = 1e4), ns per element, 8 (3D) or 32 (2D)
 *    linked lists per layer against runs): 3D N = 1e4 71.6 / 71.9 -> 70.7 / 72.8, 1e6
 *    107.2 / 119.1 -> 93.6 / 125.5, 1e7 126.2 / 139.3 -> 100.5 / 123.4; 1e6 sparse
 *    (fraction 0.005) 62.0 -> 47.9, clustered 100.7 -> 88.2, huge 110.8 -> 45.7, cell
 *    order 78.1 -> 71.9; 2D 1e4 30.6 -> 30.1, 1e6 59.2 -> 50.7, 1e7 58.7 -> 57.2. The
 *    second pass over the coordinates and its scatter into the runs cost 0.5-3 ns per
 *    element of preparation (2D 1e7, 4,500 rows: 3.0 -> 6.1). The order of the pairs differs
 *    from the linked lists' (this and the chains and gathered candidates below make it
 *    differ from the book's plain rendering, the same from run to run);
 *  - the elements in layer order (beyond the book, for time; 3D, where the input's
 *    coordinates and radii are over NBS__NBS_ORDER_MIN, 32 MiB: N > 1.4e6 without radii).
 *    Step 1's second pass, as it puts element k at its place p in its layer's run, copies
 *    its coordinates (and radius) to XS[p] too (ctx->nbs_order, 24 bytes per element, 32
 *    with radii), and steps 3-4 read a run's coordinates from there, in order. Why: even
 *    asked for 64 places ahead, each read of a run in the input is a miss of the caches and
 *    of the TLB (a run's elements lie 5 kB apart in 240 MB at N = 1e7, each on its own 4 kB
 *    page), and steps 3-4 went from 15.5 cycles per element at 1e4 to about 65 at 1e7
 *    (rdtsc); the copy is one pass in element order that writes into a few hundred streams.
 *    Measured (Zen 4, random order, one thread, interleaved, min / median of 4 processes of
 *    three detections, ns per element): N = 1e7 101.0 / 104.4 -> 87.6 / 88.3 (preparation
 *    3.6 -> 6.7, search 95.7 -> 79.5), within 1.3x of N = 1e4 (69.4-70.4, unchanged); 3e6
 *    88.6 / 89.2 -> 86.4 / 88.6; at 1e6, 24 MB, where the input's lines come from L3, even
 *    (88.3 -> 89.1, a prototype), and it is not done. The same pairs in the same order. In
 *    2D it lost (1e7, 4,000 rows: 59.3 -> 57.5 at best, preparation 6.7 -> 12.9: the scatter
 *    into that many rows costs what the walks save) and is not done; nor with the copy on
 *    2 MiB pages (madvise(MADV_HUGEPAGE), Zen 4, 1e7, 6 processes interleaved, min /
 *    median: 57.5 / 59.1 without the copy, 58.3 / 60.5 with it, 57.5 / 59.4 with it on huge
 *    pages; preparation 5.9 -> 12.3 -> 12.7, search 51.1 -> 44.6 -> 44.0: the scatter does
 *    not wait on the TLB; 3D's copy on huge pages likewise, 87.4 / 91.2 -> 89.3 / 91.4);
 *    nor did a copy into 256 bands of 16 rows, each element's number beside its
 *    coordinates and the rows' runs the places in their bands, so that a row's walk reads
 *    within 640 kB (1e7, interleaved, min / median of 4: 65.6 / 78.2 -> 69.0 / 78.1, search
 *    56.3 / 70.2 -> 51.3 / 58.8, preparation 7.1 / 8.5 -> 15.9 / 18.3; the same pairs in the
 *    same order). Nor, in 3D,
 *    the copy written with streaming stores, 8 elements of a layer gathered in a buffer
 *    and stored as a whole where they lie in its run, so that the lines are not read
 *    before they are written (1e7, min / median of 4, preparation 8.4 / 10.2 -> 9.9 /
 *    11.3, the same pairs; the array was not aligned to 64 bytes, so a group's end lines were
 *    written in part: aligned, it was not tried).
 *    NBS_NBS_ORDER=always or never, read when a context is created, overrides the size,
 *    for the tests and for comparisons;
 *  - 3D: the layer block. Steps 3 and 4 copy each element they meet (coordinates, radius,
 *    number) into the next entry of a block that holds the central layer and the layer
 *    below it, and the y- and x-lists link entries of the block instead of elements
 *    (nbs__nbs_block, below, says why). The lists hold the same elements; the pairs are
 *    stored under the elements' numbers. The block has as many entries M as
 *    the largest layer and the one below it hold together: step 1 counts each layer's
 *    elements (CN[nz]), and the largest sum is taken before step 2. An entry is 32 bytes,
 *    coordinates, x-link and number together, so that a candidate costs one cache line,
 *    not three;
 *  - 3D: chains of layers. Step 2 makes the layer of the first element of a new z-list
 *    central, as the book says; when steps 5-11 are done with it, the layer above it, if
 *    it is new and not empty, is made central next, and so on up, until a layer above is
 *    empty or old (the order of the central layers is the only change: each is central
 *    once, with the same neighbouring layer). The neighbouring layer of each layer of a
 *    chain after the first is the layer just done, whose elements are already in the
 *    block: step 4 pushes those entries onto the y-lists of set 1 instead of walking its
 *    z-lists again, and only the new central layer is walked, into the entries after them
 *    (the block is a ring; the two layers never hold more than M entries together). In
 *    random element order the walks of steps 3-4 are the misses that remain, and this
 *    halves them: a uniform scene is one or two chains. Rows chain the same way in step 5:
 *    after a central row, the row above it, if new and not empty, so that the rows two
 *    central rows share are still in the core's cache (at N = 1e7 a layer block is 3 MB);
 *  - 2D, the same representation one level down (one body, nbs__nbs_body, runs both): the y-lists
 *    are runs (above) and counted (CN[ny], RC), the central row and the row below it are
 *    copied into a block (entries without a y-link) as they are walked, straight onto the x-lists
 *    of sets 0 and 1 (whose links are the entries'; no X[N]), the central row is the ring's range
 *    it was copied to, and rows chain upwards as layers do. Memory: ny + 2nx + N ints and the
 *    block, where eq. 3.65 has 2N; measured (N = 1e6, random order, interleaved, min of 3) 123 ->
 *    66 ns per element, sorted 57 -> 44, work bytes 8.03 -> 4.13 MB;
 *  - both: the candidates of a central cell. The four neighbour lists are walked side by side
 *    (an entry before the block's first, its sentinel, links to NBS__EMPTY, so that an
 *    ended walk stays ended without a branch); the entries met are gathered, and each
 *    element of the cell is tested against them in a loop that stores every pair and keeps
 *    it by counting it only when the elements touch: no branch per candidate for the
 *    processor to mispredict (about 1 in 6 candidates touches, in no pattern). With
 *    AVX-512, in 3D and with radii, the candidates' coordinates are copied side by side as
 *    they are gathered and tested eight at a time (nbs__nbs_test512), in the same order;
 *    with AVX2 only, four at a time (nbs__nbs_test256);
 *
 *
 * Folded axes (beyond the book, for memory). The heads follow the extent of the domain on
 * each axis, not its elements: a million elements in a box with a thousand more a million
 * cells away would need 2e6 heads per list set per axis, 84 bytes per element in 3D where
 * the box alone needs 4.7; a million elements spread thin over 1e12 cells in 2D need 28 MB
 * of heads where a crowded million needs 8. When the heads and records would take more
 * than half as many ints as there are elements, nbs__nbs_fold folds axes: cell c goes on
 * list c mod m (an AND: m is a power of two >= 4), and the neighbours of list i are i - 1
 * and i + 1 mod m (nbs__nbs_near), so that list m - 1 is next to list 0. Nothing else
 * changes: the lists are built, walked and removed as the book says. Every pair of
 * neighbouring cells still lands on neighbouring lists, exactly once (the offsets -1, 0, +1
 * stay distinct mod m >= 3, so no pair is reached by two cells of the mask), and cells that
 * share a list but are m or more apart only add candidates, which the distance test
 * rejects. How many lists, measured on up to 1024 elements spread evenly over the input:
 *  - each axis covers its core (the cells from the 2% to the 98% point of the sample) and
 *    a little more, rounded up, so that the cells of a crowded box never share a list and
 *    only the elements outside it can fall on its lists;
 *  - where those cells are still more than a budget, the elements are sparse or spread
 *    thin, and x and y (in 3D; in 2D both) are scaled down to about the budget: 1.5 N
 *    cells in 2D (about the cells of N elements crowded at fraction 0.5, so the heads take
 *    no more than theirs and a list holds about as many elements; y rounded up, so that
 *    rows are not overlaid more than scaling asks (their two fullest neighbours size the
 *    block), and x down by as much more: a single scaled axis is rounded down), 64 N in 3D
 *    (where the links and the layer block outweigh the heads; rounded up);
 *  - scaling overlays cells far apart, which could pile elements onto a few lists where
 *    they are not spread (a sheet, a lattice of the lists' period): the scaled axes are
 *    doubled until the sample's pairs that share a list estimate no more than twice the
 *    grid's own crowding plus 4 elements per list.
 * An unfolded grid runs a copy of the steps compiled without the folding arithmetic
 * (nbs__nbs_axes.fold is a constant in each). Measured when folding came (N = 1e6, bench
 * scenes, work bytes against a crowded uniform scene's 4.72 MB in 3D and 8.03 MB in 2D): 3D
 * sparse 84.2 -> 4.18 MB, clustered 8.78 -> 4.73, huge 4.41 (not folded); 2D sparse 48.2 ->
 * 8.02, clustered 33.1 -> 8.02, huge 28.0 -> 8.02. The price is in 2D sparse scenes, whose
 * lists now hold as many elements as crowded ones: as fast as a crowded scene, where the
 * unfolded lists of a sparse one were about twice as fast. (With 2D's block, below, the
 * crowded 2D scene holds 4.13 MB, and sparse, clustered, huge 4.10, 4.12, 4.10.)
 *
 * The order of the axes (beyond the book, for memory and time). The book nests its lists
 * x in y in z (2D: x in y), and the layer block holds the largest layer and the one below
 * it. On a flat scene, a bed of spheres two diameters deep on a floor, the layers along z
 * are two, and the block held all N elements: 40 bytes per element where a crowded cube
 * needs 4.7, and time went up with it (the block far out of cache). So the outer axis (the
 * layers' in 3D, the rows' in 2D) is the one with the most lists, where it has at least
 * twice as many as the book's z (2D: y); the other axes keep their order (nbs__axis_order,
 * after the fold). A cube, whose axes hold about as many lists each, keeps the book's
 * order exactly. Only which coordinate each list level reads changes (nbs__nbs_axes.at):
 * the elements, in the block too, keep the caller's coordinates, so the distance test
 * rounds as direct's. Measured (N = 1e6, one thread, interleaved, min of 3, ns per element
 * and work bytes; the scene `slab`, and its coordinates turned for the others): 3D slab
 * 209 -> 86 ns and 40.0 -> 4.15 MB; a rod 4 diameters thick along x 363 -> 188 ns and 44.2
 * -> 7.14 MB, as along z before; 2D strip two diameters wide 215 -> 174 ns and 44.4 -> 10.3
 * MB. A strip stays dearer than a crowded square (57 ns, 4.13 MB): its rows, each a cell
 * of the long axis, hold an element or two, so its heads are about N / 2 rows of 3 ints,
 * and walking a row of two waits on memory without another walk beside it.
 *
 * Rows together (beyond the book, for time; 3D). Steps 3-4 copy a layer's elements into
 * the block in the order its z-lists meet them: in random element order a row's hundred
 * entries (N = 1e6) lie anywhere among the layer's ten thousand, and steps 6-10, which walk
 * each row five times and read the candidates of 13 cells from five rows, miss L1 at nearly
 * every entry, and past a core's L2 (N = 1e7: 3.3 MB of block) miss that too. Where the block
 * is over 512 KiB (N of about 7e5 and up at fraction 0.5), each layer, once its elements are
 * in the block and on its y-lists, is laid out again row by row (nbs__nbs_rows: the rows'
 * counts, then the entries through a copy of the layer to their rows' places, then the
 * y-lists through them), unless a sample of its neighbouring entries finds it nearly so
 * already (elements in cell order). The y-lists hold the same entries, only their places
 * in the block change, and the walks of steps 6-7 no longer need their look-ahead. The copy
 * is the price: the fullest layer's entries (32 bytes each, 40 with radii) and their slack,
 * 5.08 MB of work at N = 1e6 where the block alone held 4.75 (7%), 44.9 MB at 1e7 against
 * 43.4. Measured (Zen 4, 3D, fraction 0.5, random order, one thread, interleaved, min /
 * median of 6-8 processes of three detections, ns per element): N = 1e6 113.5 / 138.6 ->
 * 107.8 / 133.4, 1e7 125.2 / 132.1 -> 109.1 / 127.1; the clustered scene at 1e6 (one core
 * busy beside it) 143.9 / 149.2 -> 106.3 / 131.3, quiet 123.7 / 142.6 -> 112.7 / 118.7; cell
 * order at 1e6, every layer left as it is, 82.3 / 89.7 -> 79.2 / 102.2 (the same pairs in
 * the same order: the sample's cost, within the noise); below 512 KiB unchanged (N = 1e4,
 * always put in rows: 75.0 -> 79.5; 1e5 even). NBS_NBS_ROWS=always or never, read when a
 * context is created, overrides the size, for the tests and for comparisons.
 * Tried and left out (Zen 4, random order, one thread, interleaved, min of 2-5 processes of
 * three detections, ns per element, in a slow spell of the machine; db5e4c0 against each):
 *  - in 2D, each row's entries laid out by their cells the same way: N = 1e4 30.6 -> 35.1,
 *    1e6 69.0-69.7 -> 71.5-73.0, 1e7 65.4-68.7 -> 72.6-73.1, an input in row order at 1e7
 *    49.0 -> 52.9;
 *  - with the elements in layer order, each layer taken from XS straight to its rows'
 *    places (a pass that counts the rows, then each element to its row's next place: no
 *    copy to K->se and back; the same pairs in the same order): N = 1e7 89.9-93.7 ->
 *    91.1-91.3, 3e6 87.5 -> 91.6;
 *  - the rows laid out in increasing y, not in the order the walk meets them (1e7, the
 *    input in layer order, 88.8 -> 94.6);
 *  - each row's entries in x order too, by a counting sort of each row through the x-list
 *    heads after the rows (1e7, the input in layer order, 84.1 -> 85.6; random 86.2 -> 90.0),
 *    or of the whole layer by cell in the rows' one scatter (88.0 -> 93.4; random 93.2 ->
 *    90.8), or by x and then by row, two stable scatters through K->se (random 99.6 ->
 *    108.8, min of 6): perf puts the sort at 7-10 ns per element, about what the walks and
 *    the cell checks save; or, coarser, by buckets of 2^s cells in x within each row, in
 *    the rows' one scatter (a histogram of rows by buckets, capped at half the layer; Zen
 *    5, 6d450bc, random order, min / median of 4: 1e7 66.7 / 70.0 -> s = 2 69.0 / 70.2,
 *    s = 3 70.9 / 72.9, s = 4 70.7 / 71.1, the same pairs);
 *  - step 1's copy by layer and row (a count of each layer's rows, then each element to its
 *    row's place, so that the layers come in rows and are left as they are): N = 1e7
 *    preparation 8.6 -> 24.3, the search the same (84.9 -> 84.0).
 * An input already in layer order, each layer's rows together and each row in x order (the
 * rows then left as they are), runs N = 1e7 at 74.1-76.4 (min of 6; medians 82.1-82.2),
 * against 83.6 (90.8) with each row's elements in random order: the x order is worth about
 * 8 ns per element there, and a sort that costs less than that is what is missing.
 *
 * Measured on the 2-core AMD EPYC of bench/README.md, N = 1e6, fraction 0.5, random order,
 * one thread, before and after the deviations that are about speed, back to back: 3D 548 ->
 * 297 ns per element for the side-by-side walks and the records (side by side: 548 -> 395,
 * then step 11 side by side 433 -> 326, then the records 382 -> 297), 2D 229 -> 115 ns; then
 * the layer block, against the five rows of steps 6-10 walked side by side with prefetches
 * it replaced: 3D 290 -> 200 ns (interleaved runs, minimum of 6; sorted order 115 -> 108).
 * What did not help, tried and left out: caching each element's cell coordinates next to its
 * links (an array of {Y, X, ix, iy} structs, or one of {Z, Y, X, iy}: 3D 10-30% slower, 2D
 * up to 60% slower; the coordinates must be read for the contact test anyway); walking the
 * next central layer ahead during steps 3-4 to prefetch it (2%, within the noise); and, with
 * the block, walking the z-lists of the next one or three central layers together with this
 * one's into blocks of their own (4 or 8 walks side by side): the walks take less time
 * (84 -> 47 ns per element with 8, one run each), but the blocks then no longer fit the
 * core's cache together and steps 5-10 lose what the walks gained (minimum of 6: 173, 175
 * and 176 ns for 2, 4 and 8 walks).
 * Then, step by step, each against the one before (3D, interleaved, minimum of 4-6; this VM
 * drifts by 10-20% within an hour, so the figures chain loosely): the branch-free pair
 * store 230 -> 206 ns; 32-byte entries 190 -> 174; gathered candidates 190 -> 171; 4 z-lists
 * per layer 193 -> 175; the tests of one element against many in one loop 167 -> 160; chains
 * of layers 157 -> 141; 8 z-lists 139 -> 132; RC and chains of rows the same at 1e6 (129),
 * 183 -> 168 at 1e7; prefetched walks 129 -> 119 (LAMMPS: about 195 on this machine);
 * sorted order 128 -> 84 before the last three. 2D with the same representation: 123 -> 66,
 * and 71 -> 63 with the prefetches. Tried and left out: an AVX-512 test of the gathered candidates
 * (gathers of the coordinates, a compressed store: 201 against 195 for the generic loop;
 * gathers are slow on this core), the x-list index cached in the block (135 against 132),
 * 16 z-lists per layer (within the noise of 8). (The AVX-512 test now in use copies the
 * candidates as they are gathered instead, and reads them in order: see below.)
 * Then the five rows of steps 6-7 side by side instead of one after the other (interleaved,
 * min of 3, ns per element, N = 1e4, 1e6, 1e7): 72.1 -> 68.5, 116.2 -> 104.0, 141.1 ->
 * 123.6; 1e6 sparse, clustered, huge 115.8 -> 106.3, 116.4 -> 107.3, 64.6 -> 54.9. 16 or 32
 * z-lists per layer with it: within the noise of 8 (at 1e7 123.0, 123.6, 124.9).
 * Then the AVX-512 test of the gathered candidates (min of 3): 3D 1e4 68.6 -> 69.2 (65.1-66.1
 * in other runs), 1e6 108.2 -> 102.3, 1e7 139.2 -> 121.2; with radii (the scene `wide`) 3D
 * N = 1e5 209.7 -> 134.3, 2D 1e4 42.8 -> 39.4. In 2D without radii, about four candidates
 * per cell, the copies cost what the vector saves (1e4 29.0 -> 31.4), and it is not used.
 * The AVX2 twin (nbs__nbs_test256, for processors without AVX-512; measured here with
 * NBS_SIMD=avx2 against the plain loop it replaced there, interleaved, min of 3-4): 3D 1e4
 * 69.5 -> 71.4, 1e6 109.3 -> 106.6, 1e7 140.5 -> 131.5; `wide` 3D 1e4 165.9 -> 117.1, 1e5
 * 209.0 -> 144.0; 2D 1e4 42.8 -> 43.7, 1e5 57.6 -> 54.5, 1e6 82.3 -> 79.6. Used where the
 * AVX-512 test is.
 *
 * The work block (ctx->work, work_kind NBS__WORK_NBS) holds, as int32:
 *   [ C: nz+2 ] [ B0: ny+2 ] [ B1: ny+2 ] [ A0: nx+2 ] [ A1: nx+2 ] [ CN: nz+2 ]
 *   [ RC: nz+1 ] [ RB0: ny+1 ] [ RB1: ny+1 ] [ RA0: nx+1 ] [ RA1: nx+1 ] [ Z: N ]
 * in 3D, and in 2D
 *   [ B: ny+2 ] [ A0: nx+2 ] [ A1: nx+2 ] [ CN: ny+2 ] [ RC: ny+1 ] [ RA0: nx+1 ]
 *   [ RA1: nx+1 ] [ Y: N ]
 * that is 4 (N + 3nz + 4ny + 4nx + 17) bytes in 3D and 4 (N + 3ny + 4nx + 11) in 2D: eqs.
 * 3.80 and 3.65
 * without the links the block holds, the records, the counts and the padding (a record has one
 * spare entry, written and not counted by a push that starts no list). nx, ny, nz, N here are the
 * capacities ctx->work_cap[0], [1], [2], [3]: exactly the lists per axis (the grid's cells, or
 * fewer on a folded axis) and N of the first detection, grown later only when a detection needs
 * more (axes then get 1/8 slack, within the cell budget). work_cap[2] is 0 for the 2D layout (a 3D
 * grid always has nz >= 1), which is how the dimension is encoded. The layer block is its own
 * allocation (ctx->nbs_block), of M + 4 sqrt(M) entries and the sentinel the first time and grown
 * with 1/8 slack when a later detection needs more (nbs__nbs_block_cap); with rows together
 * (3D, a block of need over 512 KiB), followed on 8 bytes by the copy of a layer, of the
 * fullest layer's count F and 4 sqrt(F) entries of 32 bytes (and a radius each) the first time,
 * grown the same way; nothing in it outlives a detection but the sentinel, which is written
 * at every detection.
 * The elements in layer order (3D, an input over NBS__NBS_ORDER_MIN) are a third allocation
 * (ctx->nbs_order) of exactly N * 3 doubles (4 with radii), grown only for a larger N.
 * All heads are contiguous at the start, and between detections every head is NBS__EMPTY
 * and every count 0 (the book's step 0, done once when the layout is created); the next
 * arrays, the records and the block need no initialisation because an entry is always
 * written before it is read. A detection that stops early (pair buffer failure, callback
 * stop) leaves heads dirty, so it resets work_kind to NBS__WORK_NONE and the next detection
 * initialises the layout again.
 */
#include "internal.h"

#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

/* ---- the work-block layout ----------------------------------------------------------- */

/* The rows' walks of steps 6-7 look ahead (3D). Their lists link entries of the layer block,
 * which at N = 1e7 (fraction 0.5) is 3.3 MB, in the L3, not the core's L2; a row's entries
 * lie anywhere in it (in the order steps 3-4 met them), so every step of a walk missed L2 on
 * the entry, and the five walks side by side kept only a few of those misses in flight (the
 * walk's links, Y, 4 bytes an entry, stay in L2). Each walk has a second cursor
 * NBS__NBS_AHEAD entries further down its list, which asks for its entry: the walk then
 * finds its entries in L1. Only where the block is larger than NBS__NBS_AHEAD_MIN bytes:
 * below, it sits in L2 and the cursors' instructions only cost (N = 1e4, 3.5% more
 * instructions). Measured on the Zen 4 instance (3D, N = 1e7, random order, one thread,
 * interleaved, ns per element, min / median): 141.6 / 160.4 -> 126.0 / 139.9 in 8 rounds,
 * 127.7 / 148.3 -> 120.2 / 146.5 in 20 (the machine's memory drifting by 20% within a
 * run); perf: the walks' waits on their entries 39% -> 4% of nbs__nbs's samples, the rest
 * of the time now the z-lists' walks of steps 3-4, which wait on memory. N = 1e6 (a block of
 * 720 kB, no look-ahead) the same. The same lists, the same pairs in the same order. */
#define NBS__NBS_AHEAD 8
#define NBS__NBS_AHEAD_MIN ((size_t)1 << 20)

/* An override read from the environment variable `name`: "always" 1, "never" -1, else 0
 * (by size). */
static int8_t nbs__nbs_env_mode(const char *name) {
  const char *e = getenv(name);
  if (e && strcmp(e, "always") == 0) return 1;
  if (e && strcmp(e, "never") == 0) return -1;
  return 0;
}

int8_t nbs__nbs_rows_mode(void) { return nbs__nbs_env_mode("NBS_NBS_ROWS"); }

int8_t nbs__nbs_order_mode(void) { return nbs__nbs_env_mode("NBS_NBS_ORDER"); }

typedef struct nbs__nbs_layout {
  size_t bytes;       /* heads, counts, records and the runs */
  int32_t *C;         /* z-list heads (3D only): where each layer's run starts in Z */
  int32_t *B0;        /* y-list heads; in 2D the only set, where each row's run starts in Y */
  int32_t *B1;        /* y-list heads of the layer below the central one (3D only) */
  int32_t *A0;        /* x-list heads of the central row */
  int32_t *A1;        /* x-list heads of the neighbouring rows */
  int32_t *CN;        /* number of elements of each z-list (2D: y-list; see the block) */
  int32_t *Z, *Y;     /* the runs of the elements' lists (N ints): Z in 3D, Y in 2D */
  double *XS;         /* the elements in layer order (3D, ctx->nbs_order): element Z[p]'s
                       * coordinates at XS[p * S], S = 3 (4 with radii: the radius last);
                       * NULL where the runs' walks read the input */
  /* The heads each set's lists were started at, in the order they were started: at most
   * ny (RB0, RB1; 3D only) and nx (RA0, RA1) entries; RC, the layers (2D: rows) in the
   * order step 1 met their first element, at most nz (ny). */
  int32_t *RC, *RB0, *RB1, *RA0, *RA1;
} nbs__nbs_layout;

/* Number of heads for capacities cap[] = {nx, ny, nz (0 in 2D), N}, padding included. */
static int64_t nbs__nbs_head_count(int dim, const int64_t cap[4]) {
  int64_t h = 2 * (cap[0] + 2); /* A[2][nx] */
  if (dim == 3) h += 2 * (cap[1] + 2); /* B[2][ny] */
  h += cap[dim - 1] + 2; /* C[nz] in 3D, B[ny] in 2D: the lists of the elements */
  return h;
}

/* Number of entries of the started-heads records: 2 (nx + 1) and RC's nz + 1 (3D) or
 * ny + 1 (2D), and in 3D 2 (ny + 1) (each record has room for one entry more than the heads
 * it can name, written and not counted by a push that starts no list). */
static int64_t nbs__nbs_record_count(int dim, const int64_t cap[4]) {
  return 2 * (cap[0] + 1) + cap[dim - 1] + 1 + (dim == 3 ? 2 * (cap[1] + 1) : 0);
}

/* Number of counts CN of the lists of the elements (nz + 2 in 3D, ny + 2 in 2D: padded like
 * their heads). */
static int64_t nbs__nbs_count_count(int dim, const int64_t cap[4]) { return cap[dim - 1] + 2; }

/* Bytes of the arrays that follow the cells per axis, heads, layer counts and records: what
 * the cell budget bounds. */
static uint64_t nbs__nbs_axis_bytes(int dim, const int64_t cap[4]) {
  return (uint64_t)(nbs__nbs_head_count(dim, cap) + nbs__nbs_count_count(dim, cap) +
                    nbs__nbs_record_count(dim, cap)) *
         sizeof(int32_t);
}

/* Bytes of the whole layout: heads, counts, records of started heads and the runs of the
 * lists of the elements, N int32 (Z in 3D, Y in 2D; the other lists' links are in the
 * block). */
static uint64_t nbs__nbs_layout_bytes(int dim, const int64_t cap[4]) {
  uint64_t ints = nbs__nbs_axis_bytes(dim, cap) / sizeof(int32_t) + (uint64_t)cap[3];
  return ints * sizeof(int32_t);
}

/* Points the arrays of *L into `work`, laid out for dimension dim and capacities cap[]. */
static void nbs__nbs_layout_at(nbs__nbs_layout *L, void *work, int dim, const int64_t cap[4]) {
  int32_t *w = work;
  const int64_t nl = cap[dim - 1]; /* the lists of the elements: layers (3D), rows (2D) */
  L->bytes = (size_t)nbs__nbs_layout_bytes(dim, cap);
  if (dim == 3) {
    L->C = w;
    w += nl + 2;
    L->B0 = w;
    w += cap[1] + 2;
    L->B1 = w;
    w += cap[1] + 2;
  } else {
    L->C = NULL;
    L->B0 = w;
    w += nl + 2;
    L->B1 = NULL;
  }
  L->A0 = w;
  w += cap[0] + 2;
  L->A1 = w;
  w += cap[0] + 2;
  L->CN = w;
  w += nl + 2;
  L->RC = w;
  w += nl + 1;
  if (dim == 3) {
    L->RB0 = w;
    w += cap[1] + 1;
    L->RB1 = w;
    w += cap[1] + 1;
  } else {
    L->RB0 = L->RB1 = NULL;
  }
  L->RA0 = w;
  w += cap[0] + 1;
  L->RA1 = w;
  w += cap[0] + 1;
  L->Z = dim == 3 ? w : NULL;
  L->Y = dim == 3 ? NULL : w;
}

/* The dimension of the NBS layout that ctx->work holds (see the file comment). */
static int nbs__nbs_layout_dim(const nbs_context *ctx) { return ctx->work_cap[2] > 0 ? 3 : 2; }

bool nbs__nbs_heads_empty(const nbs_context *ctx) {
  if (ctx->work_kind != NBS__WORK_NBS) return true;
  const int32_t *h = ctx->work;
  const int dim = nbs__nbs_layout_dim(ctx);
  const int64_t count = nbs__nbs_head_count(dim, ctx->work_cap);
  for (int64_t i = 0; i < count; i++) {
    if (h[i] != NBS__EMPTY) return false;
  }
  /* the layer counts follow the heads, and are all 0 between detections */
  const int64_t counts = nbs__nbs_count_count(dim, ctx->work_cap);
  for (int64_t i = count; i < count + counts; i++) {
    if (h[i] != 0) return false;
  }
  return true;
}

/* ---- helpers of the detection -------------------------------------------------------- */

/* The cells the lists are indexed by: the grid's, each axis folded or not (see "Folded
 * axes" in the file comment), and taken in the order the lists nest (see "The order of the
 * axes"): NBS's axis a (0: the x-lists', 1: the y-lists', 2: the z-lists'; in 2D 1 is the
 * rows') is the coordinate at[a], and g is the grid with its axes in NBS's order. The
 * coordinates themselves, in the block too, stay in the caller's order, so that the
 * distance test rounds as direct's does. */
typedef struct nbs__nbs_axes {
  const nbs__grid *g;
  int32_t mask[3]; /* a folded axis of m lists: m - 1 (cell c is on list c mod m); else -1 */
  int32_t at[3];   /* the coordinate of each of NBS's axes */
  bool fold;       /* an axis is folded (a constant in each compiled copy of the steps) */
} nbs__nbs_axes;

/* Padded list index of the point p (dim coordinates, in the caller's order) on NBS's
 * `axis`: 1 + Int((x - xmin) / d) (eq. 3.26, whose book form is 1-based as well), the cell
 * coordinate folded first on a folded axis. */
static inline int32_t nbs__nbs_at(const nbs__nbs_axes *g, const double *p, int axis) {
  const int32_t c = nbs__cell_of(g->g, p[g->at[axis]], axis);
  return 1 + (g->fold ? c & g->mask[axis] : c);
}

/* The same for element k of coordinates x (dim per element). dim is a constant at every
 * call, so this folds away. */
static inline int32_t nbs__nbs_cell(const nbs__nbs_axes *g, const double *x, int dim, int32_t k,
                                    int axis) {
  return nbs__nbs_at(g, x + (size_t)k * (size_t)dim, axis);
}

/* The padded index of the neighbour at offset d (-1 or +1) of the list at index i on `axis`:
 * i + d, which is the padding (an always empty head) beyond either end of an unfolded axis
 * and wraps around a folded one. */
static inline int32_t nbs__nbs_near(const nbs__nbs_axes *g, int32_t i, int32_t d, int axis) {
  return g->fold ? ((i - 1 + d) & g->mask[axis]) + 1 : i + d;
}

/* Heads are dirty when a detection stops in the middle: forget the layout, so that the next
 * detection sets every head to empty again (step 0). */
static nbs_status nbs__nbs_abort(nbs__run *run, nbs_status s) {
  run->ctx->work_kind = NBS__WORK_NONE;
  return s;
}

/* NBS's block (3D: the layer block; 2D: the same for rows). When a layer becomes central,
 * steps 3 and 4 walk its z-list and that of the layer below it; every element they meet is
 * copied, in the order met, into the block: its coordinates (and radius), its number, and
 * room for its x-list link and, in 3D, its y-list link. Steps 5-11 then build and walk the
 * y- and x-lists over block entries instead of element numbers, and the pairs are stored
 * under the elements' numbers (id). Each list receives the same elements as in the book's
 * text: this is representation only.
 *
 * Why: in random element order the elements of a layer are scattered over all N, and steps
 * 5-10 visit each of them many times: five rows put it on x-lists (its own and, as a
 * neighbour, four others), and the cell checks read it for every cell of whose mask its cell
 * is part. Scattered, every visit can miss the cache, on its coordinates and on its links
 * (before the block, a fifth of the time went to walking the five rows ahead with
 * prefetches, only to overlap those misses); copied, the two layers sit in M * 36 bytes
 * (about 720 kB at N = 1e6, fraction 0.5), in the core's own cache. Only steps 3 and 4 still
 * walk scattered elements.
 *
 * Its capacity is the largest number of elements in a layer and the one below it, counted
 * by step 1 (CN[iz], one int per layer) and taken before step 2. */
typedef struct nbs__nbs_entry {
  double x[3]; /* the element's coordinates */
  int32_t X;   /* the entry's link in the x-lists */
  int32_t id;  /* the element's number */
} nbs__nbs_entry;

typedef struct nbs__nbs_block {
  nbs__nbs_entry *e; /* the entries */
  double *r;         /* a radius per entry, or NULL */
  int32_t *Y;        /* the entry's link in the y-lists (3D; NULL in 2D) */
  bool ahead;        /* larger than a core's L2, rows not together: the rows' walks look ahead
                      (nbs__nbs_3d_row) */
  nbs__nbs_entry *se; /* rows together (nbs__nbs_rows; 3D): room for the fullest layer's
                       entries; else NULL */
  double *sr;        /* and their radii, or NULL */
} nbs__nbs_block;

/* Bytes of one entry of the block: the entry, its radius, and in 3D its y-link. */
static size_t nbs__nbs_entry_bytes(int dim, bool radii) {
  return sizeof(nbs__nbs_entry) + (radii ? sizeof(double) : 0) +
         (dim == 3 ? sizeof(int32_t) : 0);
}

/* Checks the central cell, whose x-list (set 0, linked by the entries' X) starts at c,
 * with the contact mask (2D: the mask of section 3.8, cells (ix-1,iy-1) (ix,iy-1)
 * (ix+1,iy-1) (ix-1,iy); 3D: the 13 cells of eq. 3.73):
 *   - the cell itself: every element against those after it in the list (each pair once);
 *   - the cell (ix-1) of the central row, nb[0]: A0[ix-1], unmarked by the caller;
 *   - the cells ix-1, ix, ix+1 of the neighbouring rows, nb[1..3]: A1[ix-1], A1[ix],
 *     A1[ix+1]. In 2D they are row iy-1; in 3D set 1 merges rows (iy-1,iz), (iy-1,iz-1),
 *     (iy,iz-1), (iy+1,iz-1), so these three lists cover the 3 cells of row iy-1 in layer
 *     iz and the 9 cells of layer iz-1.
 * Together 4 (2D) or 13 (3D) neighbour cells: each pair of neighbouring cells is visited
 * from exactly one of the two. The lists link entries of the block K, which holds the
 * coordinates the test reads (dim of them); the pairs are stored under the elements'
 * numbers. nbs__nbs_pair offers one pair, nbs__nbs_pairs one element against many, and
 * nbs__nbs_check_cell the whole mask. */
static inline nbs_status nbs__nbs_pair(nbs__run *run, const nbs__nbs_block *K, int dim,
                                       int32_t a, int32_t b) {
  /* nbs__offer on the block's copies. (One nbs__offer_at taking the points, shared with
   * nbs__offer, made direct 3-17% slower and this 3% slower with GCC 12, depending on how
   * it passed the radii.) */
  run->candidates++;
  const nbs__nbs_entry *ea = &K->e[a], *eb = &K->e[b];
  if (run->mode == NBS_MODE_CONTACTS) {
    const bool r = K->r != NULL;
    const bool t = nbs__touch_at(ea->x, eb->x, dim, r, r ? K->r[a] : 0, r ? K->r[b] : 0, run->d2);
    /* a full buffer is flushed (or found at max_pairs) only for a pair that touches */
    if (run->count == run->cap) return t ? nbs__emit(run, ea->id, eb->id) : NBS_OK;
    run->buf[run->count] = nbs__pair_of(ea->id, eb->id);
    run->count += t;
    run->emitted += t;
    return NBS_OK;
  }
  return nbs__emit(run, ea->id, eb->id);
}

/* Entries gathered from the neighbour lists at a time (nbs__nbs_check_cell). */
#define NBS__NBS_GATHER 64

/* The candidates gathered from the neighbour lists of a central cell (nbs__nbs_check_cell):
 * each one's entry, and its coordinates, radius and number copied next to the others', so
 * that the test of an element against them reads them in order. */
typedef struct nbs__nbs_got {
  int32_t e[NBS__NBS_GATHER];
  int32_t id[NBS__NBS_GATHER];
  double x[NBS__NBS_GATHER], y[NBS__NBS_GATHER], z[NBS__NBS_GATHER], r[NBS__NBS_GATHER];
} nbs__nbs_got;

#if NBS__X86_SIMD
/* The pairs of the element at pa (radius ra, number ia) with the n candidates of G that it
 * touches, into out, in G's order: eight candidates at a time, the operations of
 * nbs__touch_at lane by lane (no contraction: the build has -ffp-contract=off), and the
 * pairs that pass packed by a compress. Writes up to 8 entries past the pairs it returns. */
__attribute__((target("avx512f,avx512vl,popcnt"))) static size_t
nbs__nbs_test512(const double *pa, double ra, double d2, int32_t ia, const nbs__nbs_got *G,
                 int n, int dim, bool radii, nbs_pair *out) {
  const __m512d AX = _mm512_set1_pd(pa[0]), AY = _mm512_set1_pd(pa[1]);
  const __m512d AZ = _mm512_set1_pd(dim == 3 ? pa[2] : 0), RA = _mm512_set1_pd(ra);
  const __m512d LIM = _mm512_set1_pd(d2);
  const __m256i IA = _mm256_set1_epi32(ia);
  size_t kept = 0;
  for (int j = 0; j < n; j += 8) {
    const __mmask8 m = (__mmask8)(n - j >= 8 ? 0xFF : (1u << (n - j)) - 1);
    const __m512d dx = _mm512_sub_pd(AX, _mm512_maskz_loadu_pd(m, G->x + j));
    const __m512d dy = _mm512_sub_pd(AY, _mm512_maskz_loadu_pd(m, G->y + j));
    __m512d d = _mm512_add_pd(_mm512_mul_pd(dx, dx), _mm512_mul_pd(dy, dy));
    if (dim == 3) {
      const __m512d dz = _mm512_sub_pd(AZ, _mm512_maskz_loadu_pd(m, G->z + j));
      d = _mm512_add_pd(d, _mm512_mul_pd(dz, dz));
    }
    __m512d lim = LIM;
    if (radii) {
      const __m512d rr = _mm512_add_pd(RA, _mm512_maskz_loadu_pd(m, G->r + j));
      lim = _mm512_mul_pd(rr, rr);
    }
    const __mmask8 hit = _mm512_mask_cmp_pd_mask(m, d, lim, _CMP_LE_OQ);
    const __m256i id = _mm256_maskz_loadu_epi32(m, G->id + j);
    const __m512i lo = _mm512_cvtepu32_epi64(_mm256_min_epi32(IA, id));
    const __m512i hi = _mm512_cvtepu32_epi64(_mm256_max_epi32(IA, id));
    const __m512i pr = _mm512_or_si512(lo, _mm512_slli_epi64(hi, 32));
    _mm512_storeu_si512((void *)(out + kept), _mm512_maskz_compress_epi64(hit, pr));
    kept += (size_t)__builtin_popcount(hit);
  }
  return kept;
}

/* The same test with AVX2, for processors without AVX-512: four candidates at a time, the
 * pairs that pass packed by a permutation looked up from their 4-bit mask (nbs__pack4).
 * Same pairs in the same order. Writes up to 4 entries past the pairs it returns. */
__attribute__((target("avx2,popcnt"))) static size_t
nbs__nbs_test256(const double *pa, double ra, double d2, int32_t ia, const nbs__nbs_got *G,
                 int n, int dim, bool radii, nbs_pair *out) {
  const __m256d AX = _mm256_set1_pd(pa[0]), AY = _mm256_set1_pd(pa[1]);
  const __m256d AZ = _mm256_set1_pd(dim == 3 ? pa[2] : 0), RA = _mm256_set1_pd(ra);
  const __m256d LIM = _mm256_set1_pd(d2);
  const __m256i IA = _mm256_set1_epi32(ia);
  size_t kept = 0;
  for (int j = 0; j < n; j += 4) {
    /* G's arrays hold NBS__NBS_GATHER (a multiple of 4) entries: the loads stay inside
     * them, and the lanes past n are dropped from the mask */
    const unsigned m = n - j >= 4 ? 0xFu : (1u << (n - j)) - 1;
    const __m256d dx = _mm256_sub_pd(AX, _mm256_loadu_pd(G->x + j));
    const __m256d dy = _mm256_sub_pd(AY, _mm256_loadu_pd(G->y + j));
    __m256d d = _mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy));
    if (dim == 3) {
      const __m256d dz = _mm256_sub_pd(AZ, _mm256_loadu_pd(G->z + j));
      d = _mm256_add_pd(d, _mm256_mul_pd(dz, dz));
    }
    __m256d lim = LIM;
    if (radii) {
      const __m256d rr = _mm256_add_pd(RA, _mm256_loadu_pd(G->r + j));
      lim = _mm256_mul_pd(rr, rr);
    }
    const unsigned hit = (unsigned)_mm256_movemask_pd(_mm256_cmp_pd(d, lim, _CMP_LE_OQ)) & m;
    const __m256i id = nbs__twice4(G->id + j); /* each candidate's number twice */
    const __m256i pr =
        _mm256_blend_epi32(_mm256_min_epi32(IA, id), _mm256_max_epi32(IA, id), 0xAA);
    const __m256i pk = _mm256_loadu_si256((const __m256i *)(const void *)nbs__pack4[hit]);
    _mm256_storeu_si256((__m256i *)(void *)(out + kept), _mm256_permutevar8x32_epi32(pr, pk));
    kept += (size_t)__builtin_popcount(hit);
  }
  return kept;
}
#endif

/* nbs__nbs_pair of entry a with each of the n candidates of G: in contact mode, where the
 * pair buffer has room for them all (and 8 more, for the vector tests' last store), without
 * a branch per pair (each pair is stored, and kept by counting it only when the elements
 * touch). */
static inline __attribute__((always_inline)) nbs_status
nbs__nbs_pairs(nbs__run *run, const nbs__nbs_block *K, int dim, int32_t a, const nbs__nbs_got *G,
               int n, bool soa) {
  if (run->mode != NBS_MODE_CONTACTS || run->cap - run->count < (size_t)n + 8) {
    for (int j = 0; j < n; j++) NBS__TRY(nbs__nbs_pair(run, K, dim, a, G->e[j]));
    return NBS_OK;
  }
  const nbs__nbs_entry *ea = &K->e[a];
  const bool radii = K->r != NULL;
  const double ra = radii ? K->r[a] : 0, d2 = run->d2;
  const int32_t ia = ea->id;
  nbs_pair *out = run->buf + run->count;
  size_t kept = 0;
#if NBS__X86_SIMD
  if (soa && run->ctx->simd == NBS__SIMD_AVX512) {
    kept = nbs__nbs_test512(ea->x, ra, d2, ia, G, n, dim, radii, out);
  } else if (soa) {
    kept = nbs__nbs_test256(ea->x, ra, d2, ia, G, n, dim, radii, out);
  } else
#endif
  {
    (void)soa;
    for (int j = 0; j < n; j++) {
      const nbs__nbs_entry *eb = &K->e[G->e[j]];
      const bool t = nbs__touch_at(ea->x, eb->x, dim, radii, ra, radii ? K->r[G->e[j]] : 0, d2);
      out[kept] = nbs__pair_of(ia, eb->id);
      kept += t;
    }
  }
  run->count += kept;
  run->emitted += kept;
  run->candidates += (uint64_t)n;
  return NBS_OK;
}

/* The four neighbour lists are walked side by side. K->e[-1] is a sentinel whose link is
 * NBS__EMPTY, so that a walk that has ended stays ended without a branch; the entries met
 * are gathered, up to NBS__NBS_GATHER at a time, and every element of the central cell is
 * tested against them. With `soa` (AVX-512 or AVX2, in 3D or with radii) their
 * coordinates, radii and numbers are copied as they are met, for nbs__nbs_test512 or
 * nbs__nbs_test256 (figures in the file comment); without the vector test the copies cost
 * more than they save (3D, N = 1e4: 68.5 -> 75.7 ns per element), so otherwise only the
 * entries are gathered. Same pairs in the same order either way. */
static inline nbs_status nbs__nbs_check_cell(nbs__run *run, const nbs__nbs_block *K, int dim,
                                             int32_t c, const int32_t nb[4]) {
  /* the vector test where the candidates are many: 3D, or radii (whose cells are larger);
   * 2D's cells of equal elements have about four */
  const bool soa = NBS__X86_SIMD && run->ctx->simd != NBS__SIMD_GENERIC &&
                   (dim == 3 || K->r != NULL);
  const nbs__nbs_entry *E = K->e;
  for (int32_t a = c; a != NBS__EMPTY; a = E[a].X) {
    for (int32_t b = E[a].X; b != NBS__EMPTY; b = E[b].X) {
      NBS__TRY(nbs__nbs_pair(run, K, dim, a, b));
    }
  }
  int32_t b0 = nb[0], b1 = nb[1], b2 = nb[2], b3 = nb[3];
  const double *R = K->r;
  nbs__nbs_got G;
  /* the next candidate: entry b (the sentinel's copy is overwritten by the next, or not
   * counted) */
#define NBS__NBS_GOT(b)                                                                       \
  do {                                                                                        \
    G.e[n] = (b);                                                                             \
    if (soa) {                                                                                \
      const nbs__nbs_entry *nbs__q = &E[b];                                                   \
      G.id[n] = nbs__q->id;                                                                   \
      G.x[n] = nbs__q->x[0];                                                                  \
      G.y[n] = nbs__q->x[1];                                                                  \
      if (dim == 3) G.z[n] = nbs__q->x[2];                                                    \
      if (R) G.r[n] = R[(b) < 0 ? 0 : (b)];                                                   \
    }                                                                                         \
    n += (b) != NBS__EMPTY;                                                                   \
  } while (0)
  while ((b0 & b1 & b2 & b3) != NBS__EMPTY) { /* some walk goes on (EMPTY is all ones) */
    int n = 0;
    do {
      NBS__NBS_GOT(b0);
      NBS__NBS_GOT(b1);
      NBS__NBS_GOT(b2);
      NBS__NBS_GOT(b3);
      b0 = E[b0].X;
      b1 = E[b1].X;
      b2 = E[b2].X;
      b3 = E[b3].X;
    } while (n <= NBS__NBS_GATHER - 4 && (b0 & b1 & b2 & b3) != NBS__EMPTY);
    for (int32_t a = c; a != NBS__EMPTY; a = E[a].X) {
      NBS__TRY(nbs__nbs_pairs(run, K, dim, a, &G, n, soa));
    }
  }
#undef NBS__NBS_GOT
  return NBS_OK;
}


/* Marks the central cell of the entry e (set 0, A0), if it is new, and checks it with the
 * contact mask: the loop over a central row of steps 8 (3D) and of section 3.8, for one of
 * its elements. */
static inline nbs_status nbs__nbs_check_at(nbs__run *run, const nbs__nbs_axes *g,
                                           const nbs__nbs_block *K, int dim, int32_t *A0,
                                           const int32_t *A1, int32_t e) {
  const int32_t ix = nbs__nbs_at(g, K->e[e].x, 0);
  if (nbs__is_marked(A0[ix])) return NBS_OK;
  const int32_t c = A0[ix];
  A0[ix] = nbs__mark(c);
  const int32_t il = nbs__nbs_near(g, ix, -1, 0), ir = nbs__nbs_near(g, ix, 1, 0);
  const int32_t nb[4] = {nbs__unmark(A0[il]), A1[il], A1[ix], A1[ir]};
  return nbs__nbs_check_cell(run, K, dim, c, nb);
}

/* Propagates an error of the pair sink, forgetting the (now dirty) layout. */
#define NBS__NBS_TRY(expr)                                                                    \
  do {                                                                                        \
    nbs_status nbs__s = (expr);                                                               \
    if (nbs__s != NBS_OK) return nbs__nbs_abort(run, nbs__s);                                 \
  } while (0)

/* Pushes element e onto the list of head H[i] (its link: next), and records i in R[top++]
 * when the list was empty, i.e. when e starts it. */
#define NBS__NBS_PUSH(e, next, H, i, R, top)                                                  \
  do {                                                                                        \
    const int32_t nbs__h = (H)[i];                                                            \
    (next) = nbs__h;                                                                          \
    (H)[i] = (e);                                                                             \
    (R)[top] = (i);                                                                           \
    (top) += nbs__h == NBS__EMPTY;                                                            \
  } while (0)

/* Pushes entry e of the block K onto the x-list of its cell in the set A (record R, top). */
#define NBS__NBS_PUSH_X(l, A, R, top)                                                         \
  do {                                                                                        \
    const int32_t nbs__ix = nbs__nbs_at(g, K->e[l].x, 0);                                     \
    NBS__NBS_PUSH((l), K->e[l].X, A, nbs__ix, R, top);                                        \
  } while (0)

/* Empties the heads H[R[0..top-1]] that a set's lists were started at. */
static inline void nbs__nbs_clear(int32_t *H, const int32_t *R, int32_t top) {
  for (int32_t i = 0; i < top; i++) H[R[i]] = NBS__EMPTY;
}

/* ---- the detection (3D: section 3.10, steps of the pseudocode on p. 127; 2D: 3.8) ---- */

/* The entries the layer block is allocated with when `need` entries (the two fullest
 * neighbouring layers; 2D rows) are needed of n elements: the first block (grown = false)
 * need and four standard deviations of a count of need, a later growth an eighth more;
 * never more than n. */
static int64_t nbs__nbs_block_cap(int64_t need, int64_t n, bool grown) {
  const int64_t slack = grown ? need / 8 : (int64_t)ceil(4.0 * sqrt((double)need));
  return need + slack < n ? need + slack : n;
}

/* Makes the layer block hold `need` entries (need >= 1), with radii or not, and points *K
 * into it. What it held is not kept: nothing in it is live between layers. The block is
 * allocated with slack (nbs__nbs_block_cap), so that time steps do not allocate:
 *  - the first, four standard deviations of a count of `need` (4 sqrt(need) entries, 2.8% at
 *    N = 1e6 in 3D): the two fullest layers of a scene whose elements move about hold a
 *    few sqrt(need) more or less from step to step. Allocated exactly, the block grew within
 *    the first 40 steps of a random walk (N = 5000 to 1e6, 3D and 2D, steps of 0.02
 *    diameters; at the first or second in 3D), which the header's promise of no allocation
 *    after the first detection does not allow; with the slack, none in 1000 steps
 *    (tests/test_memory.c, nbs_block_steps);
 *  - a later, larger need (the elements crowd into fewer layers), an eighth more, so that a
 *    scene whose layers fill up step after step does not allocate every time. */
/* Bytes of a layer block of `need` entries (`entry` bytes each) and the sentinel, and with
 * `rows` the copy of a layer after it, on 8 bytes (the block's int32 arrays may end on 4), of
 * `layer` entries of `copy` bytes. */
static size_t nbs__nbs_block_bytes(int64_t need, int64_t layer, size_t entry, size_t copy,
                                   bool rows) {
  const size_t block = ((size_t)need + 1) * entry;
  return rows ? ((block + 7) & ~(size_t)7) + (size_t)layer * copy : block;
}

static nbs_status nbs__nbs_block_reserve(nbs__run *run, int32_t need, int32_t layer,
                                         nbs__nbs_block *K) {
  nbs_context *ctx = run->ctx;
  const bool radii = run->r != NULL;
  const size_t entry = nbs__nbs_entry_bytes(run->dim, radii);
  /* the copy of a layer (nbs__nbs_rows): its entries and radii */
  const size_t copy = sizeof(nbs__nbs_entry) + (radii ? sizeof(double) : 0);
  /* need, layer and the capacities grown from them are at most N, and the sentinel is one
   * more */
  if ((uint64_t)run->n + 1 > SIZE_MAX / (entry + copy) - 1) {
    return nbs__fail(ctx, NBS_ERR_NOMEM, -1,
                     "nbs: a layer block of up to %ld entries cannot be addressed", (long)run->n);
  }
  const size_t block = nbs__nbs_block_bytes(need, 0, entry, copy, false);
  /* Rows together (3D): where the block is past NBS__NBS_ROWS_MIN, or as NBS_NBS_ROWS says */
  const bool rows =
      run->dim == 3 && (ctx->nbs_rows > 0 || (ctx->nbs_rows == 0 && block > NBS__NBS_ROWS_MIN));
  const size_t bytes = nbs__nbs_block_bytes(need, layer, entry, copy, rows);
  if (bytes > ctx->nbs_block_size) {
    const bool grown = ctx->nbs_block != NULL;
    const size_t want =
        nbs__nbs_block_bytes(nbs__nbs_block_cap(need, run->n, grown),
                             nbs__nbs_block_cap(layer, run->n, grown), entry, copy, rows);
    if (!nbs__replace(ctx, &ctx->nbs_block, &ctx->nbs_block_size, want)) {
      return nbs__fail(ctx, NBS_ERR_NOMEM, -1,
                       "nbs: cannot allocate %zu bytes for the layer block", want);
    }
  }
  /* doubles first, then the int32 arrays: every array is aligned */
  char *w = ctx->nbs_block;
  K->e = (nbs__nbs_entry *)(void *)w + 1;
  w += ((size_t)need + 1) * sizeof(nbs__nbs_entry);
  K->e[-1] = (nbs__nbs_entry){{0, 0, 0}, NBS__EMPTY, NBS__EMPTY}; /* read, never counted */
  K->r = NULL;
  if (radii) {
    K->r = (double *)(void *)w;
    w += (size_t)need * sizeof(double);
  }
  K->Y = run->dim == 3 ? (int32_t *)(void *)w : NULL;
  K->se = NULL;
  K->sr = NULL;
  if (rows) {
    char *c = (char *)ctx->nbs_block + (bytes - (size_t)layer * copy);
    K->se = (nbs__nbs_entry *)(void *)c;
    if (radii) K->sr = (double *)(void *)(c + (size_t)layer * sizeof(nbs__nbs_entry));
  }
  /* with rows together, the rows' walks go through consecutive entries: no look-ahead */
  K->ahead = !rows && block > NBS__NBS_AHEAD_MIN;
  return NBS_OK;
}

/* Steps 6-10 for the central row iy of the central layer (set 0 of the y-lists, B0), whose
 * neighbouring rows of eq. 3.79 are (iy-1,iz) in B0 and three rows of layer iz-1 in B1.
 * With `ahead` (the block is larger than a core's L2, K->ahead), each walk of steps 6-7 asks
 * for the entry NBS__NBS_AHEAD places further down its list (see NBS__NBS_AHEAD). */
static inline __attribute__((always_inline)) nbs_status
nbs__nbs_3d_row(nbs__run *run, const nbs__nbs_layout *L, const nbs__nbs_axes *g,
                const nbs__nbs_block *K, int32_t iy, bool ahead) {
  int32_t *restrict B0 = L->B0;
  const int32_t *restrict B1 = L->B1;
  int32_t *restrict A0 = L->A0;
  int32_t *restrict A1 = L->A1;
  int32_t *restrict RA0 = L->RA0;
  int32_t *restrict RA1 = L->RA1;
  const int32_t *restrict Y = K->Y;
  const int32_t row = B0[iy];
  B0[iy] = nbs__mark(row); /* mark the row "old" */
  /* (iy-1,iz) may have been central already (read unmarked); rows of layer iz-1 are set 1
   * and never marked. */
  const int32_t yl = nbs__nbs_near(g, iy, -1, 1), yr = nbs__nbs_near(g, iy, 1, 1);
  const int32_t nrow[4] = {nbs__unmark(B0[yl]), B1[yl], B1[iy], B1[yr]};

  /* Step 6: the elements of the central row onto the x-lists of set 0; step 7: the elements
   * of the neighbouring rows onto the x-lists of set 1. The five walks go side by side, so
   * that their misses overlap (the block may be larger than the core's cache); the lists
   * receive the same entries, set 1's in another order. */
  int32_t na0 = 0, na1 = 0;
  int32_t w[5] = {row, nrow[0], nrow[1], nrow[2], nrow[3]};
  /* the look-ahead cursors (NBS__EMPTY without `ahead`) */
  int32_t lead[5] = {NBS__EMPTY, NBS__EMPTY, NBS__EMPTY, NBS__EMPTY, NBS__EMPTY};
  if (ahead) {
    for (int l = 0; l < 5; l++) {
      int32_t f = w[l];
      for (int d = 0; d < NBS__NBS_AHEAD && f != NBS__EMPTY; d++) f = Y[f];
      lead[l] = f;
    }
  }
  while ((w[0] & w[1] & w[2] & w[3] & w[4]) != NBS__EMPTY) { /* EMPTY is all ones */
    for (int l = 0; l < 5; l++) {
      if (w[l] == NBS__EMPTY) continue;
      if (ahead && lead[l] != NBS__EMPTY) {
        __builtin_prefetch(&K->e[lead[l]]);
        lead[l] = Y[lead[l]];
      }
      const int32_t next = Y[w[l]];
      if (l == 0) {
        NBS__NBS_PUSH_X(w[l], A0, RA0, na0);
      } else {
        NBS__NBS_PUSH_X(w[l], A1, RA1, na1);
      }
      w[l] = next;
    }
  }

  /* Step 8: loop over the central row; the first element in a "new" cell (ix,iy,iz) makes
   * it the central cell: mark it and check it with the 13-cell mask (eq. 3.73). */
  for (int32_t e = row; e != NBS__EMPTY; e = Y[e]) {
    NBS__TRY(nbs__nbs_check_at(run, g, K, 3, A0, A1, e));
  }

  /* Steps 9 and 10: remove the x-lists of the central and of the neighbouring rows,
   * resetting the heads they started. */
  nbs__nbs_clear(A0, RA0, na0);
  nbs__nbs_clear(A1, RA1, na1);
  return NBS_OK;
}

/* Steps 5-11 for the central layer, whose elements and those of the layer below it are in
 * the block K, on the y-lists of sets 0 and 1 (started at the heads RB0[0..nb0-1],
 * RB1[0..nb1-1]). */
static inline __attribute__((always_inline)) nbs_status
nbs__nbs_3d_layer(nbs__run *run, const nbs__nbs_layout *L, const nbs__nbs_axes *g,
                  const nbs__nbs_block *K, int32_t nb0, int32_t nb1) {
  int32_t *restrict B0 = L->B0;
  const int32_t *restrict RB0 = L->RB0;

  /* Step 5: loop over the central layer; the first element in a "new" row (iy,iz) makes it
   * the central row. Those first elements, in the order of the layer, are the ones step 3
   * met first in their rows: RB0 lists their rows in that order, so the loop runs over RB0
   * instead of walking the layer a second time. Then the row above, while it is new and not
   * empty (chains of rows), while the rows it shares with this one are in the core's
   * cache. */
  for (int32_t i = 0; i < nb0; i++) {
    int32_t iy = RB0[i];
    if (nbs__is_marked(B0[iy])) continue; /* central already, in a chain of rows */
    do {
      if (K->ahead) {
        NBS__TRY(nbs__nbs_3d_row(run, L, g, K, iy, true));
      } else {
        NBS__TRY(nbs__nbs_3d_row(run, L, g, K, iy, false));
      }
      iy = nbs__nbs_near(g, iy, 1, 1);
    } while (B0[iy] >= 0); /* not empty (EMPTY) nor old (marked) */
  }

  /* Step 11: remove the y-lists of the central layer and of layer iz-1. */
  nbs__nbs_clear(B0, RB0, nb0);
  nbs__nbs_clear(L->B1, L->RB1, nb1);
  return NBS_OK;
}

/* Pushes entry l of the block onto the list of its cell one level down in the set H
 * (record R, top): in 3D the y-lists (linked by K->Y), in 2D the x-lists of section 3.8
 * (linked by the entries' X). dim is a constant at every call. */
static inline __attribute__((always_inline)) void
nbs__nbs_retake(const nbs__nbs_axes *g, const nbs__nbs_block *K, int dim, int32_t l, int32_t *H,
                int32_t *R, int32_t *top) {
  nbs__nbs_entry *q = &K->e[l];
  const int32_t i = nbs__nbs_at(g, q->x, dim == 3 ? 1 : 0);
  NBS__NBS_PUSH(l, *(dim == 3 ? &K->Y[l] : &q->X), H, i, R, *top);
}

/* Copies element k, whose coordinates are p[0..dim) and radius *r (where the input has
 * radii), into entry l of the block and pushes that entry as nbs__nbs_retake does: steps 3
 * and 4 for one element. */
static inline __attribute__((always_inline)) void
nbs__nbs_take(const nbs__run *run, const nbs__nbs_axes *g, const nbs__nbs_block *K, int dim,
              int32_t k, const double *p, const double *r, int32_t l, int32_t *H, int32_t *R,
              int32_t *top) {
  nbs__nbs_entry *q = &K->e[l];
  q->x[0] = p[0];
  q->x[1] = p[1];
  if (dim == 3) q->x[2] = p[2];
  if (run->r) K->r[l] = *r;
  q->id = k;
  nbs__nbs_retake(g, K, dim, l, H, R, top);
}

/* Steps 3-4 for a layer (2D: a row) whose z-list is the run ids[0..len) of Z: each element
 * taken (nbs__nbs_take) into entries l0, l0 + step, ... of the ring of cap entries (step 1,
 * or -1 from the block's end for the layer below). With xs (the elements in layer order, 3D:
 * the run's coordinates, S doubles per element, the radius last where there are radii), the
 * walk reads them in order. Without, it reads them from the input, where the run gives the
 * elements ahead of the walk: each one's coordinates (both ends: in 3D a quarter of them
 * straddle two lines) and radius are asked for NBS__NBS_FAR places ahead into L2 (locality
 * 1: no L1 miss buffer held while memory answers) and NBS__NBS_NEAR ahead into L1, as
 * cellsort's gather does (nbs__cs_prefetch). Distances of 32/8, 128/32 and 256/16 measured
 * the same (3D, N = 1e7, interleaved, min of 3: 113.0, 116.6, 115.5, 107.9 ns per element,
 * noise). */
#define NBS__NBS_FAR 64
#define NBS__NBS_NEAR 16
static inline __attribute__((always_inline)) void
nbs__nbs_run(const nbs__run *run, const nbs__nbs_axes *g, const nbs__nbs_block *K, int dim,
             const int32_t *ids, const double *xs, int32_t len, int32_t l0, int32_t cap,
             int32_t *H, int32_t *R, int32_t *top, int step) {
  const double *x = run->x, *r = run->r;
  int32_t l = l0;
  if (xs) {
    const size_t S = (size_t)dim + (r ? 1 : 0);
    for (int32_t j = 0; j < len; j++) {
      const double *p = xs + (size_t)j * S;
      nbs__nbs_take(run, g, K, dim, ids[j], p, p + dim, l, H, R, top);
      l += step;
      l = l == cap ? 0 : l;
    }
    return;
  }
  for (int32_t j = 0; j < len; j++) {
    if (j + NBS__NBS_FAR < len) {
      const int32_t k = ids[j + NBS__NBS_FAR];
      const double *p = x + (size_t)k * (size_t)dim;
      __builtin_prefetch(p, 0, 1);
      __builtin_prefetch(p + dim - 1, 0, 1);
      if (r) __builtin_prefetch(r + k, 0, 1);
    }
    if (j + NBS__NBS_NEAR < len) {
      const int32_t k = ids[j + NBS__NBS_NEAR];
      const double *p = x + (size_t)k * (size_t)dim;
      __builtin_prefetch(p);
      __builtin_prefetch(p + dim - 1);
      if (r) __builtin_prefetch(r + k);
    }
    const int32_t k = ids[j];
    nbs__nbs_take(run, g, K, dim, k, x + (size_t)k * (size_t)dim, r ? r + k : NULL, l, H, R,
                  top);
    l += step;
    l = l == cap ? 0 : l;
  }
}

/* Rows together (3D, K->se): the layer whose entries are the ring's [s, s + len) (mod cap),
 * on the y-lists H[R[0..nr-1]] (set 0 or 1, R their rows in the order started), laid out
 * again so that each row's entries follow one another, the rows in R's order, and its
 * y-lists rebuilt through them (each row's list in the order of its entries). The lists
 * hold the same entries; only where they sit in the block changes. Steps 3-4 take a layer's
 * elements in the order its z-lists meet them, which in random element order scatters a
 * row's entries over the whole layer: at N = 1e6 (fraction 0.5) a row of 100 entries among
 * the layer's 10,000, 720 kB of block, so that steps 6-7, which walk each row five times (as
 * the central one and as a neighbour of four others), and the cell checks, which read the
 * candidates of 13 cells from five rows, miss L1 at almost every entry. Together, a central
 * row's five rows are about 18 kB of consecutive entries. Three passes over the layer, in
 * order: its rows' counts (into H, which is rebuilt after), each row's first place, then
 * the entries copied to K->se and back to their places. A layer already in rows, or near
 * enough (the elements in cell order: each row's entries come in a few runs from the walks),
 * is left as it is, as a sample of its neighbouring entries says. */
static void nbs__nbs_rows(const nbs__nbs_axes *g, const nbs__nbs_block *K, int32_t *H,
                          const int32_t *R, int32_t nr, int32_t s, int32_t len, int32_t cap) {
  nbs__nbs_entry *restrict E = K->e;
  int32_t *restrict Y = K->Y;
  /* Already in rows, or near enough: of every 16th entry and the one after it, at most one
   * pair in 4 in two rows (in random order nearly all are; in cell order, whose cells need
   * not be NBS's, a row's entries come in a few runs of dozens, and with one in 8 a few of
   * its layers were still laid out again, at a cost) */
  int32_t pairs = 0, apart = 0;
  for (int32_t j = 0; j + 1 < len; j += 16) {
    int32_t l = s + j;
    l = l >= cap ? l - cap : l;
    const int32_t l1 = l + 1 == cap ? 0 : l + 1;
    apart += nbs__nbs_at(g, E[l].x, 1) != nbs__nbs_at(g, E[l1].x, 1);
    pairs++;
  }
  if (4 * apart <= pairs) return;
  /* the rows' counts; the entries copied, in order, each with its row in its x-link (which
   * steps 6-7 write before anything reads it) */
  for (int32_t i = 0; i < nr; i++) H[R[i]] = 0;
  for (int32_t j = 0, l = s; j < len; j++) {
    K->se[j] = E[l];
    if (K->r) K->sr[j] = K->r[l];
    K->se[j].X = nbs__nbs_at(g, E[l].x, 1);
    H[K->se[j].X]++;
    l = l + 1 == cap ? 0 : l + 1;
  }
  /* each row's first place (from s), in R's order */
  for (int32_t i = 0, at = 0; i < nr; i++) {
    const int32_t c = H[R[i]];
    H[R[i]] = at;
    at += c;
  }
  /* the entries to their places: H[iy] ends as the place after row iy's last */
  for (int32_t j = 0; j < len; j++) {
    int32_t l = s + H[K->se[j].X]++;
    l = l >= cap ? l - cap : l;
    E[l] = K->se[j];
    if (K->r) K->r[l] = K->sr[j];
  }
  /* the y-lists through consecutive entries: row R[i] from where row R[i-1] ended */
  for (int32_t i = 0, from = 0; i < nr; i++) {
    const int32_t iy = R[i], to = H[iy];
    int32_t l = s + from;
    l = l >= cap ? l - cap : l;
    H[iy] = l;
    for (int32_t k = from; k < to; k++) {
      const int32_t next = l + 1 == cap ? 0 : l + 1;
      Y[l] = k + 1 < to ? next : NBS__EMPTY;
      l = next;
    }
    from = to;
  }
}

/* The loop over the central row, whose entries are the ring's [s, s + len) (mod cap): the
 * first element in a "new" cell makes it the central cell (nbs__nbs_check_at). */
static inline nbs_status nbs__nbs_2d_row(nbs__run *run, const nbs__nbs_axes *g,
                                         const nbs__nbs_block *K, int32_t *A0, const int32_t *A1,
                                         int32_t s, int32_t len, int32_t cap) {
  for (int32_t j = 0, e = s; j < len; j++) {
    NBS__TRY(nbs__nbs_check_at(run, g, K, 2, A0, A1, e));
    e = e + 1 == cap ? 0 : e + 1;
  }
  return NBS_OK;
}

/* The central layer (3D: steps 5-11, nbs__nbs_3d_layer, which finds its rows through RB0)
 * or row (2D: its entries are the ring's [s, s + len), mod cap; then the removal of the
 * x-lists), with the layer or row below it, on the lists of sets 0 and 1 started at n0 and
 * n1 heads. */
static inline __attribute__((always_inline)) nbs_status
nbs__nbs_central(nbs__run *run, const nbs__nbs_layout *L, const nbs__nbs_axes *g,
                 const nbs__nbs_block *K, int dim, int32_t s, int32_t len, int32_t cap,
                 int32_t n0, int32_t n1) {
  if (dim == 3) return nbs__nbs_3d_layer(run, L, g, K, n0, n1);
  NBS__TRY(nbs__nbs_2d_row(run, g, K, L->A0, L->A1, s, len, cap));
  nbs__nbs_clear(L->A0, L->RA0, n0);
  nbs__nbs_clear(L->A1, L->RA1, n1);
  return NBS_OK;
}

/* Both dimensions (3D: section 3.10, the numbered steps those of the pseudocode on p. 127;
 * 2D: section 3.8 one level shorter). The lists of the elements are the z-lists of the
 * layers in 3D (C, Z) and the y-lists of the rows in 2D (B, Y); the level below them is the
 * y-lists of a layer in 3D (B0, B1, records RB0, RB1) and the x-lists of a row in 2D (A0,
 * A1, records RA0, RA1). Each of the elements' lists is stored as a run of Z, its elements
 * in the order the book's list links them (see the file comment); the central one and the
 * one below it are copied into the block as they are walked, and the central ones chain
 * upwards. dim is a constant in each compiled copy. */
static inline __attribute__((always_inline)) nbs_status
nbs__nbs_body(nbs__run *run, const nbs__nbs_layout *L, nbs__nbs_axes axes, bool fold, int dim) {
  axes.fold = fold;
  const nbs__nbs_axes *g = &axes; /* a copy: the heads' stores cannot alias its masks */
  const int a = dim - 1; /* the axis of the elements' lists */
  const double *x = run->x;
  const int32_t n = run->n;
  int32_t *restrict C = dim == 3 ? L->C : L->B0;
  int32_t *restrict Z = dim == 3 ? L->Z : L->Y;
  int32_t *restrict CN = L->CN;
  int32_t *restrict RC = L->RC;
  int32_t *H0 = dim == 3 ? L->B0 : L->A0, *H1 = dim == 3 ? L->B1 : L->A1;
  int32_t *R0 = dim == 3 ? L->RB0 : L->RA0, *R1 = dim == 3 ? L->RB1 : L->RA1;

  /* Step 1: map every element onto its z-list (layer; in 2D its y-list, row), each list a
   * run of Z (see "runs" in the file comment): a pass counts each layer's elements (CN[iz])
   * and notes each layer in RC at its first element; the runs follow one another in RC's
   * order; a second pass puts each element k, in increasing k, at the end of its layer's
   * run still free (C[iz], which ends as the run's first place), so that a run holds its
   * elements in the order of the book's list (Z[k] = C[iz]; C[iz] = k), the last pushed
   * first. All layers are "new" (CN[iz] >= 0). */
  int32_t nc = 0; /* RC[0..nc-1]: the layers, in the order of their first elements */
  for (int32_t k = 0; k < n; k++) {
    const int32_t iz = nbs__nbs_cell(g, x, dim, k, a);
    RC[nc] = iz;
    nc += CN[iz]++ == 0;
  }
  for (int32_t i = 0, at = 0; i < nc; i++) {
    at += CN[RC[i]];
    C[RC[i]] = at;
  }
  /* (with XS, 3D, each element's coordinates and radius to the same place of XS: see "The
   * elements in layer order" in the file comment) */
  double *restrict XS = L->XS;
  const double *restrict r = run->r;
  const size_t S = (size_t)dim + (r ? 1 : 0);
  for (int32_t k = 0; k < n; k++) {
    const int32_t iz = nbs__nbs_cell(g, x, dim, k, a);
    const int32_t at = --C[iz];
    Z[at] = k;
    if (XS) {
      const double *p = x + (size_t)k * (size_t)dim;
      double *q = XS + (size_t)at * S;
      for (int c = 0; c < dim; c++) q[c] = p[c];
      if (r) q[dim] = r[k];
    }
  }

  /* The block: as many entries as the largest layer and the one below it hold. */
  int32_t need = 1, layer = 1; /* and the fullest layer alone (nbs__nbs_rows' copy) */
  for (int32_t i = 0; i < nc; i++) {
    const int32_t iz = RC[i];
    const int32_t t = CN[iz] + CN[nbs__nbs_near(g, iz, -1, a)];
    need = t > need ? t : need;
    layer = CN[iz] > layer ? CN[iz] : layer;
  }
  nbs__nbs_block K = {0};
  NBS__NBS_TRY(nbs__nbs_block_reserve(run, need, layer, &K));
  nbs__search_begins(run);

  /* Step 2: loop over the elements; the first one in a "new" z-list makes it the central
   * layer. The first elements of the layers, in the order of the elements, are those step 1
   * noted in RC, so the loop runs over RC (as step 5 runs over RB0). Then the layer above
   * it, if it is new and not empty, is the next central layer, and so on up (see "chains of
   * layers" in the file comment): its neighbouring layer is the one just done, already in
   * the block. */
  const int32_t cap = need; /* the block, used as a ring */
  for (int32_t i = 0; i < nc; i++) {
    int32_t iz = RC[i];
    if (CN[iz] < 0) continue;
    const int32_t m = CN[iz];
    CN[iz] = ~m; /* mark the layer "old" (its count kept, complemented) */
    const int32_t iu = nbs__nbs_near(g, iz, -1, a);
    const int32_t mu = CN[iu] >= 0 ? CN[iu] : ~CN[iu]; /* (an empty one: 0) */

    /* Step 3: the elements of the central layer onto the lists of set 0; step 4: the
     * elements of the neighbouring layer iz-1 onto the lists of set 1; each copied into the
     * block on the way, the central layer's from entry 0 up, the other's from the last entry
     * down. R0 records the lists of the central layer in the order in which this walk meets
     * their first element. */
    int32_t n0 = 0, n1 = 0;
    nbs__nbs_run(run, g, &K, dim, Z + C[iz], XS ? XS + (size_t)C[iz] * S : NULL, m, 0, cap, H0,
                 R0, &n0, 1);
    if (mu > 0) {
      nbs__nbs_run(run, g, &K, dim, Z + C[iu], XS ? XS + (size_t)C[iu] * S : NULL, mu, cap - 1,
                   cap, H1, R1, &n1, -1);
    }
    if (dim == 3 && K.se) { /* each layer's rows together (nbs__nbs_rows) */
      nbs__nbs_rows(g, &K, H0, R0, n0, 0, m, cap);
      nbs__nbs_rows(g, &K, H1, R1, n1, cap - mu, mu, cap);
    }
    /* Steps 5-11 over the block. */
    NBS__NBS_TRY(nbs__nbs_central(run, L, g, &K, dim, 0, m, cap, n0, n1));

    /* The central layer's entries are the ring's [s, s + len) (mod cap). */
    int32_t s = 0, len = m;
    for (;;) {
      const int32_t iv = nbs__nbs_near(g, iz, 1, a);
      if (CN[iv] <= 0) break; /* empty or old: the chain ends */
      iz = iv;
      CN[iz] = ~CN[iz]; /* mark the layer "old" */
      n0 = n1 = 0;
      /* Step 4 for the layer just done, now the neighbouring one: its entries onto the
       * lists of set 1, in the order they were taken. */
      for (int32_t j = 0, l = s; j < len; j++) {
        nbs__nbs_retake(g, &K, dim, l, H1, R1, &n1);
        l = l + 1 == cap ? 0 : l + 1;
      }
      /* Step 3: the new central layer's elements into the ring after them. */
      s = s + len;
      s = s >= cap ? s - cap : s;
      len = ~CN[iz];
      nbs__nbs_run(run, g, &K, dim, Z + C[iz], XS ? XS + (size_t)C[iz] * S : NULL, len, s, cap,
                   H0, R0, &n0, 1);
      /* (the layer below, the one just done, is in rows already: retaken in order) */
      if (dim == 3 && K.se) nbs__nbs_rows(g, &K, H0, R0, n0, s, len, cap);
      NBS__NBS_TRY(nbs__nbs_central(run, L, g, &K, dim, s, len, cap, n0, n1));
    }
  }

  /* Finally remove the z-lists (and their counts): reset the heads of the layers step 1
   * noted. */
  for (int32_t i = 0; i < nc; i++) {
    const int32_t iz = RC[i];
    C[iz] = NBS__EMPTY;
    CN[iz] = 0;
  }
  return NBS_OK;
}

/* Each dimension with an axis folded or not: four copies, so that an unfolded grid does its
 * index arithmetic exactly as before folding existed. */
static nbs_status nbs__nbs_3d(nbs__run *run, const nbs__nbs_layout *L, nbs__nbs_axes axes) {
  return axes.fold ? nbs__nbs_body(run, L, axes, true, 3) : nbs__nbs_body(run, L, axes, false, 3);
}

static nbs_status nbs__nbs_2d(nbs__run *run, const nbs__nbs_layout *L, nbs__nbs_axes axes) {
  return axes.fold ? nbs__nbs_body(run, L, axes, true, 2) : nbs__nbs_body(run, L, axes, false, 2);
}

#undef NBS__NBS_PUSH
#undef NBS__NBS_PUSH_X
#undef NBS__NBS_TRY

/* ---- the dispatcher ------------------------------------------------------------------ */

/* An axis capacity grown with 1/8 slack, so that a domain creeping outwards step after
 * step does not re-lay the block every time; never beyond what an axis can need. */
static int64_t nbs__nbs_grow(int64_t need) {
  int64_t c = need + need / 8;
  return c < NBS__AXIS_MAX ? c : NBS__AXIS_MAX;
}

/* The elements the fold is measured on (see nbs__nbs_fold): at most this many, evenly
 * spaced in the input. */
#define NBS__NBS_SAMPLE 1024

/* The k-th smallest of v[0..s-1] (0-based), reordering v: Hoare's selection, O(s). */
static uint32_t nbs__nbs_select(uint32_t *v, int64_t s, int64_t k) {
  int64_t lo = 0, hi = s - 1;
  while (lo < hi) {
    const uint32_t p = v[lo + (hi - lo) / 2];
    int64_t i = lo, j = hi;
    while (i <= j) {
      while (v[i] < p) i++;
      while (v[j] > p) j--;
      if (i <= j) {
        const uint32_t t = v[i];
        v[i++] = v[j];
        v[j--] = t;
      }
    }
    if (k <= j) {
      hi = j;
    } else if (k >= i) {
      lo = i;
    } else {
      break; /* v[j+1..i-1] all equal p */
    }
  }
  return v[k];
}

/* Element i of the fold's sample of s. */
static const double *nbs__nbs_sample(const nbs__run *run, int64_t i, int64_t s) {
  return run->x + (size_t)(i * run->n / s) * (size_t)run->dim;
}

/* Scratch of the fold's measurements (on the stack: 24 kB). */
typedef struct nbs__nbs_probe {
  uint32_t cell[NBS__NBS_SAMPLE];
  uint64_t key[2 * NBS__NBS_SAMPLE]; /* open addressing, at most half full */
  uint16_t count[2 * NBS__NBS_SAMPLE];
} nbs__nbs_probe;

/* The pairs of the sample of s that share a list on every axis, with lists[a] lists on
 * axis a (cell c on list c mod lists[a]), counted in a hash table of the lists met. A
 * list's numbers are mixed into one 64-bit key: two lists taken for one only add a pair to
 * an estimate. */
static int64_t nbs__nbs_shared(const nbs__run *run, int64_t s, const int64_t lists[3],
                               nbs__nbs_probe *P) {
  static const uint64_t mix[3] = {0x9e3779b97f4a7c15u, 0xc2b2ae3d27d4eb4fu, 0x165667b19e3779f9u};
  uint64_t size = 4;
  while (size < 2 * (uint64_t)s) size *= 2;
  memset(P->count, 0, size * sizeof *P->count);
  int64_t pairs = 0;
  for (int64_t i = 0; i < s; i++) {
    const double *p = nbs__nbs_sample(run, i, s);
    uint64_t k = 0;
    for (int a = 0; a < run->dim; a++) {
      k += ((uint32_t)nbs__cell(&run->grid, p, a) % (uint64_t)lists[a] + 1) * mix[a];
    }
    uint64_t h = (k ^ k >> 29) & (size - 1);
    while (P->count[h] && P->key[h] != k) h = (h + 1) & (size - 1);
    pairs += P->count[h]; /* the pairs this element makes with those on its list before it */
    P->key[h] = k;
    P->count[h]++;
  }
  return pairs;
}

/* Two axes a and b scaled by one factor so that they have about `budget` lists together,
 * neither below 3 nor above its own e (nbs__nbs_fold then rounds to a power of two >= 4). */
static void nbs__nbs_scale2(const int64_t e[3], int64_t t[3], int a, int b, double budget) {
  if ((double)e[a] * (double)e[b] <= budget) return;
  const double f = sqrt(budget / ((double)e[a] * (double)e[b]));
  t[a] = (int64_t)ceil((double)e[a] * f);
  t[b] = (int64_t)ceil((double)e[b] * f);
  if (t[a] < 3) {
    t[a] = e[a] < 3 ? e[a] : 3;
    t[b] = (int64_t)ceil(budget / (double)t[a]);
  } else if (t[b] < 3) {
    t[b] = e[b] < 3 ? e[b] : 3;
    t[a] = (int64_t)ceil(budget / (double)t[b]);
  }
  if (t[a] > e[a]) t[a] = e[a];
  if (t[b] > e[b]) t[b] = e[b];
}

bool nbs__nbs_fold(const nbs__run *run, int64_t lists[3]) {
  const nbs__grid *g = &run->grid;
  const int dim = run->dim;
  const int64_t n = run->n;
  for (int a = 0; a < 3; a++) lists[a] = a < dim ? g->n[a] : 1;
  const int64_t cap[4] = {g->n[0], g->n[1], dim == 3 ? g->n[2] : 0, n};
  if (!g->fits || n < 2 || nbs__nbs_axis_bytes(dim, cap) <= (uint64_t)n * sizeof(int32_t) / 2) {
    return false;
  }
  const int64_t s = n < NBS__NBS_SAMPLE ? n : NBS__NBS_SAMPLE;
  nbs__nbs_probe P;

  /* 1. Each axis's extent to cover, e: its core (the cells from the 2% to the 98% point of
   * the sample) with 1/16 and 2 cells more, enough for the whole of a crowded box whose 2%
   * at either end the core leaves out; never more than the axis. */
  int64_t e[3] = {1, 1, 1};
  for (int a = 0; a < dim; a++) {
    for (int64_t i = 0; i < s; i++) {
      P.cell[i] = (uint32_t)nbs__cell(g, nbs__nbs_sample(run, i, s), a);
    }
    const uint32_t low = nbs__nbs_select(P.cell, s, s / 50);
    const int64_t core = (int64_t)nbs__nbs_select(P.cell, s, s - 1 - s / 50) - low + 1;
    e[a] = core + core / 16 + 2;
    if (e[a] > g->n[a]) e[a] = g->n[a];
  }

  /* 2. Where the extents hold more cells than a budget, the domain is sparse (or its
   * elements are spread thin), and the axes are scaled down to about that many cells. In
   * 2D the x-lists' heads and records are what grows with the cells (4 ints per list), so
   * the budget is 1.5 N, about the cells of N elements crowded at fraction 0.5 (1.57 N): a
   * list holds about as many elements as in a crowded grid, and the heads take no more than
   * there. In 3D the links and the layer block outweigh the heads, so the budget is 64 N:
   * the heads stay a few percent of the memory and a list holds 1/64 of an element. The
   * layers are kept, up to N/4 of them (scaling z would fill the layer block). */
  int64_t t[3] = {e[0], e[1], e[2]};
  if (dim == 2) {
    nbs__nbs_scale2(e, t, 0, 1, 1.5 * (double)n);
  } else {
    if (4 * t[2] > n) t[2] = n / 4 > 3 ? n / 4 : 3;
    if (t[2] > e[2]) t[2] = e[2];
    nbs__nbs_scale2(e, t, 0, 1, 64.0 * (double)n / (double)t[2]);
  }

  /* 3. The lists of each axis: a power of two (a list is c AND m - 1) of at least 4 (so
   * that the offsets -1, 0, +1 stay distinct), rounded down from a scaled t (the budget
   * holds; in 2D with both axes scaled, y up and x down by as much more, see the file
   * comment) and up from an extent (its cells never share a list); an axis is folded where
   * that is fewer than its cells.
   * Scaling overlays cells that are far apart, which costs only candidates when the
   * elements are spread, but could pile them up if they are not (a sheet, a lattice whose
   * period the lists repeat). The sample says: the pairs of it that would share a list must
   * not estimate more than twice the grid's own crowding plus 4 more elements per list; else
   * the scaled axes are doubled (up to their e) until they do. */
  const int64_t cells[3] = {g->n[0], g->n[1], dim == 3 ? g->n[2] : 1};
  const int64_t own = nbs__nbs_shared(run, s, cells, &P);
  const double allowed = 2.0 * (double)own + 2.0 * (double)s * (double)(s - 1) / (double)(n - 1);
  bool folded, scaled;
  for (;;) {
    folded = scaled = false;
    /* 2D with both axes scaled: y (the rows, whose two largest neighbours size the block)
     * is rounded up, and x down by as much more as that added */
    const bool both = dim == 2 && t[0] < e[0] && t[1] < e[1];
    double over = 1;
    for (int a = dim - 1; a >= 0; a--) {
      int64_t m = 4;
      while (m < t[a]) m *= 2;
      if (t[a] < e[a]) {
        scaled = true;
        if (both && a == 1) {
          over = (double)m / (double)t[1];
        } else if (dim == 2) {
          while (m > 4 && (double)m * over > (double)t[a]) m /= 2;
        }
      }
      lists[a] = m < g->n[a] ? m : g->n[a];
      folded |= m < g->n[a];
    }
    if (!scaled || nbs__nbs_shared(run, s, lists, &P) <= allowed) break;
    for (int a = 0; a < dim; a++) t[a] = 2 * t[a] < e[a] ? 2 * t[a] : e[a];
  }
  return folded;
}

/* Whether NBS's detection of n elements in dimension dim (with radii or not) puts them in
 * layer order on context ctx: 3D, and an input over NBS__NBS_ORDER_MIN or NBS_NBS_ORDER. */
static bool nbs__nbs_ordered(const nbs_context *ctx, int dim, int64_t n, bool radii) {
  if (dim != 3 || n < 1 || ctx->nbs_order_mode < 0) return false;
  return ctx->nbs_order_mode > 0 ||
         (uint64_t)n * (uint64_t)(dim + (radii ? 1 : 0)) * sizeof(double) > NBS__NBS_ORDER_MIN;
}

/* Makes ctx->nbs_order hold the elements in layer order: n * S doubles (S = 3, 4 with
 * radii), exactly (a time step has the same n; a later, larger n grows it). */
static nbs_status nbs__nbs_order_reserve(nbs__run *run) {
  nbs_context *ctx = run->ctx;
  const uint64_t S = (uint64_t)run->dim + (run->r ? 1 : 0);
  const uint64_t bytes = (uint64_t)run->n * S * sizeof(double);
  if (bytes > SIZE_MAX) {
    return nbs__fail(ctx, NBS_ERR_NOMEM, -1,
                     "nbs: %llu bytes of elements in layer order cannot be addressed",
                     (unsigned long long)bytes);
  }
  if (bytes <= ctx->nbs_order_size) return NBS_OK;
  if (!nbs__replace(ctx, &ctx->nbs_order, &ctx->nbs_order_size, (size_t)bytes)) {
    return nbs__fail(ctx, NBS_ERR_NOMEM, -1,
                     "nbs: cannot allocate %llu bytes for the elements in layer order",
                     (unsigned long long)bytes);
  }
  return NBS_OK;
}

nbs_status nbs__nbs(nbs__run *run) {
  nbs_context *ctx = run->ctx;
  const nbs__grid *g = &run->grid;
  const int dim = run->dim;

  run->ran = NBS_NBS;
  run->compressed = false;
  run->work_bytes = 0;
  run->cells[0] = g->n[0];
  run->cells[1] = g->n[1];
  run->cells[2] = dim == 3 ? g->n[2] : 1;

  if (!g->fits) {
    return nbs__fail(ctx, NBS_ERR_EXTENT, -1,
                     "nbs: the grid needs more than %lld cells on an axis (cells per axis: x "
                     "%lld, y %lld%s%lld; -1 means too many); use 'auto' or 'sorting'",
                     (long long)NBS__AXIS_MAX, (long long)g->n[0], (long long)g->n[1],
                     dim == 3 ? ", z " : "", dim == 3 ? (long long)g->n[2] : 0LL);
  }

  /* The lists per axis (folded or not), and what this detection needs: {nx, ny, nz (0 in
   * 2D), N} lists. */
  int64_t lists[3];
  const bool fold = run->compressed = nbs__nbs_fold(run, lists);
  for (int a = 0; a < dim; a++) run->cells[a] = lists[a];
  /* NBS's axes in their order (the grid's, permuted), and the lists of each */
  int at[3];
  nbs__axis_order(dim, lists, dim - 1, at);
  for (int a = 0; a < 3; a++) ctx->axes[a] = (int8_t)at[a];
  const nbs__grid grid = nbs__grid_reorder(g, at);
  nbs__nbs_axes axes = {&grid, {-1, -1, -1}, {0, 1, 2}, fold};
  int64_t nl[3] = {1, 1, 1};
  for (int a = 0; a < dim; a++) {
    const int c = at[a];
    axes.at[a] = c;
    nl[a] = lists[c];
    if (lists[c] < g->n[c]) axes.mask[a] = (int32_t)(lists[c] - 1);
  }
  const int64_t need[4] = {nl[0], nl[1], dim == 3 ? nl[2] : 0, run->n};
  const uint64_t need_heads = nbs__nbs_axis_bytes(dim, need);
  if (need_heads > ctx->cell_budget) {
    return nbs__fail(ctx, NBS_ERR_BUDGET, -1,
                     "nbs: the head arrays and their records need %llu bytes (%lld x %lld%s%lld "
                     "lists), the cell budget is %zu bytes",
                     (unsigned long long)need_heads, (long long)need[0], (long long)need[1],
                     dim == 3 ? " x " : "", dim == 3 ? (long long)need[2] : 0LL,
                     ctx->cell_budget);
  }

  const bool same = ctx->work_kind == NBS__WORK_NBS && nbs__nbs_layout_dim(ctx) == dim;
  bool fits = same;
  for (int a = 0; a < 4 && fits; a++) fits = need[a] <= ctx->work_cap[a];

  if (!fits) {
    int64_t cap[4];
    if (!same) {
      /* First use (or another layout was in the block): exactly the need. */
      for (int a = 0; a < 4; a++) cap[a] = need[a];
    } else {
      /* Growth: keep what the old layout could hold; axes that grow get 1/8 slack. */
      for (int a = 0; a < 3; a++) {
        cap[a] = need[a] > ctx->work_cap[a] ? nbs__nbs_grow(need[a]) : ctx->work_cap[a];
      }
      cap[3] = need[3] > ctx->work_cap[3] ? need[3] : ctx->work_cap[3];
      /* Heads and records must stay within the budget: drop the slack, then the old capacities. */
      if (nbs__nbs_axis_bytes(dim, cap) > ctx->cell_budget) {
        for (int a = 0; a < 3; a++) {
          cap[a] = need[a] > ctx->work_cap[a] ? need[a] : ctx->work_cap[a];
        }
      }
      if (nbs__nbs_axis_bytes(dim, cap) > ctx->cell_budget) {
        for (int a = 0; a < 3; a++) cap[a] = need[a];
      }
    }
    const uint64_t bytes = nbs__nbs_layout_bytes(dim, cap);
    if (bytes > SIZE_MAX) {
      return nbs__fail(ctx, NBS_ERR_NOMEM, -1, "nbs: %llu bytes of work arrays cannot be addressed",
                       (unsigned long long)bytes);
    }
    NBS__TRY(nbs__work_reserve(ctx, (size_t)bytes));
    /* Step 0 (eqs. 3.32-3.33 for lists): every head empty, once for this layout. */
    int32_t *h = ctx->work;
    const int64_t count = nbs__nbs_head_count(dim, cap);
    for (int64_t i = 0; i < count; i++) h[i] = NBS__EMPTY;
    /* and every layer count 0 (3D; they follow the heads) */
    const int64_t counts = nbs__nbs_count_count(dim, cap);
    for (int64_t i = count; i < count + counts; i++) h[i] = 0;
    ctx->work_kind = NBS__WORK_NBS;
    for (int a = 0; a < 4; a++) ctx->work_cap[a] = cap[a];
  }

  nbs__nbs_layout L;
  nbs__nbs_layout_at(&L, ctx->work, dim, ctx->work_cap);
  L.XS = NULL;
  if (nbs__nbs_ordered(ctx, dim, run->n, run->r != NULL)) {
    NBS__TRY(nbs__nbs_order_reserve(run));
    L.XS = ctx->nbs_order;
  }
  const nbs_status s = dim == 2 ? nbs__nbs_2d(run, &L, axes) : nbs__nbs_3d(run, &L, axes);
  run->work_bytes = L.bytes + ctx->nbs_block_size + ctx->nbs_order_size;
  return s;
}
