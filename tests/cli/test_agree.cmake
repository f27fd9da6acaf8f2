# Every algorithm writes identical --output files on generated scenes (the library's
# contract: sorted pair lists are identical), and the count is the same without --output.
cmake_minimum_required(VERSION 3.25)
include(${CMAKE_CURRENT_LIST_DIR}/common.cmake)
nbs_algorithms(ALGORITHMS)

# agree(name generate-args...): generates the scene as CSV and f64, detects with every
# algorithm from both, and compares every output with the direct one. Algorithms in SKIP
# must refuse the scene with a resource error (4) instead.
function(agree name)
  expect(NAME "${name} generate" CODE 0 ARGS generate ${ARGN} --output ${WORK}/${name}.csv)
  expect(NAME "${name} generate f64" CODE 0 ARGS generate ${ARGN} --output ${WORK}/${name}.f64)
  if(ARGN MATCHES "--dim;2")
    set(dim 2)
  else()
    set(dim 3)
  endif()
  set(ref ${WORK}/${name}.direct.pairs)
  expect(NAME "${name} reference" CODE 0 ARGS detect --input ${WORK}/${name}.csv --dim ${dim}
         --algorithm direct --output ${ref})
  foreach(a ${ALGORITHMS})
    foreach(fmt csv f64)
      set(out ${WORK}/${name}.${fmt}.${a}.pairs)
      if(a IN_LIST SKIP)
        expect(NAME "${name} ${fmt} ${a} refuses" CODE 4 ERR "\\((budget|extent)\\)\n$"
               ARGS detect --input ${WORK}/${name}.${fmt} --dim ${dim} --algorithm ${a} --output ${out})
        expect_no_file("${name} ${fmt} ${a} writes nothing" ${out})
        continue()
      endif()
      expect(NAME "${name} ${fmt} ${a}" CODE 0 ARGS detect --input ${WORK}/${name}.${fmt}
             --dim ${dim} --algorithm ${a} --output ${out})
      expect_same_file("${name} ${fmt} ${a} = direct" ${out} ${ref})
    endforeach()
  endforeach()
  count_lines(npairs ${ref})
  if(npairs EQUAL 0)
    fail("${name}: no contacts at all, the comparison proves little")
  endif()
  set(NBS_CHECKS ${NBS_CHECKS} PARENT_SCOPE)
endfunction()

agree(uniform3d uniform --dim 3 --n 3000 --seed 7)
agree(uniform2d uniform --dim 2 --n 3000 --seed 8 --fraction 0.6)
agree(lattice3d lattice --dim 3 --n 1000)
agree(lattice2d lattice --dim 2 --n 900)
agree(wide3d wide --dim 3 --n 2000 --size-ratio 8)
agree(wide2d wide --dim 2 --n 2000 --size-ratio 30)
# Clustered: 1% of the elements spread over a box 1000 times as wide; screening's cell array
# would take 11 GB.
set(SKIP screening)
agree(clustered2d clustered --dim 2 --n 2000)
unset(SKIP)
agree(faces3d faces --dim 3 --n 1000)
agree(offset3d uniform --dim 3 --n 2000 --offset 1e9)

# A sparse scene with outliers 1e6 diameters away: screening's cell array (about 1e18
# cells) exceeds its budget, a resource error (4) with the library's message; the others
# agree.
expect(NAME "sparse generate" CODE 0 ARGS generate sparse --dim 3 --n 2000 --output ${WORK}/sparse.csv)
expect(NAME "sparse screening" CODE 4 ERR "sparse.csv: screening needs .*budget.*\\(budget\\)"
       ARGS detect --input ${WORK}/sparse.csv --algorithm screening)
set(others ${ALGORITHMS})
list(REMOVE_ITEM others screening direct)
expect(NAME "sparse direct" CODE 0
       ARGS detect --input ${WORK}/sparse.csv --algorithm direct --output ${WORK}/sparse.direct.pairs)
foreach(a ${others})
  expect(NAME "sparse ${a}" CODE 0
         ARGS detect --input ${WORK}/sparse.csv --algorithm ${a} --output ${WORK}/sparse.${a}.pairs)
  expect_same_file("sparse ${a} = direct" ${WORK}/sparse.${a}.pairs ${WORK}/sparse.direct.pairs)
endforeach()

done()
