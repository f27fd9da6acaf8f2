# Golden files: tiny scenes whose contacts were derived by hand (see data/README.md), read
# in every input variant, detected by every algorithm, written with --output.
cmake_minimum_required(VERSION 3.25)
include(${CMAKE_CURRENT_LIST_DIR}/common.cmake)
set(G ${DATA}/golden)
nbs_algorithms(ALGORITHMS)

# golden(name expected args...): every algorithm writes exactly the expected file, and
# without --output prints 'pairs: N' with N its line count.
function(golden name expected)
  count_lines(want ${expected})
  foreach(a ${ALGORITHMS})
    set(out ${WORK}/${name}.${a}.csv)
    expect(NAME "${name} ${a}" CODE 0 ERR_EMPTY ARGS detect ${ARGN} --algorithm ${a} --output ${out})
    expect_same_file("${name} ${a}" ${out} ${expected})
    expect(NAME "${name} ${a} count" CODE 0 OUT "^pairs: ${want}\n$" ERR_EMPTY
           ARGS detect ${ARGN} --algorithm ${a})
  endforeach()
  set(NBS_CHECKS ${NBS_CHECKS} PARENT_SCOPE)
endfunction()

# 2D, header line, radii in the last column. Touching exactly (distance 1 = 0.5 + 0.5)
# counts.
golden(circles2d ${G}/circles2d.pairs.csv --input ${G}/circles2d.csv --dim 2)
# 3D, no header, one diameter for all.
golden(spheres3d ${G}/spheres3d.pairs.csv --input ${G}/spheres3d.csv --dim 3 --diameter 2)
golden(spheres3d_f64 ${G}/spheres3d.pairs.csv --input ${G}/spheres3d.f64 --dim 3 --diameter 2)
# 3D with radii of different sizes: CSV, the same numbers as raw f64, and a header that
# names the columns in another order (plus an id column).
golden(radii3d ${G}/radii3d.pairs.csv --input ${G}/radii3d.csv --dim 3)
golden(radii3d_f64 ${G}/radii3d.pairs.csv --input ${G}/radii3d.f64 --dim 3)
golden(named3d ${G}/radii3d.pairs.csv --input ${G}/named3d.csv)
golden(named3d_columns ${G}/radii3d.pairs.csv --input ${G}/named3d.csv --dim 3 --columns x,y,z,radius)
golden(named3d_index ${G}/radii3d.pairs.csv --input ${G}/named3d.csv --dim 3 --columns 5,4,3,2)
# Blank-separated values, comments and a blank line; lattice of spacing exactly 1.
golden(lattice2d ${G}/lattice2d.pairs.csv --input ${G}/lattice2d.txt --dim 2 --diameter 1)
# Standard input, recognised from its content (CSV) or told (f64).
set(NBS_STDIN ${G}/radii3d.f64)
golden(stdin_f64 ${G}/radii3d.pairs.csv --input - --format f64 --dim 3)
set(NBS_STDIN ${G}/circles2d.csv)
golden(stdin_csv ${G}/circles2d.pairs.csv --input - --dim 2)
unset(NBS_STDIN)

# --diameter overrides the radius column: with diameter 2.6 in radii3d, pairs are those at
# distance <= 2.6: (0,2)? no, 5; (2,4) 0.9 yes; (0,1) 3 no; (1,3) 4 no; (2,3) sqrt(10) no.
file(WRITE ${WORK}/override.expected "2,4\n")
golden(override ${WORK}/override.expected --input ${G}/radii3d.csv --dim 3 --diameter 2.6)

# Candidates: direct yields every pair (n(n-1)/2); every algorithm's candidates include the
# contacts.
expect(NAME "direct candidates" CODE 0 OUT "^pairs: 10\n$"
       ARGS detect --input ${G}/spheres3d.csv --dim 3 --diameter 2 --algorithm direct --candidates)
foreach(a ${ALGORITHMS})
  expect(NAME "candidates ${a}" CODE 0
         ARGS detect --input ${G}/spheres3d.csv --dim 3 --diameter 2 --algorithm ${a} --candidates
              --output ${WORK}/cand.${a}.csv)
  file(STRINGS ${WORK}/cand.${a}.csv cand)
  file(STRINGS ${G}/spheres3d.pairs.csv contacts)
  foreach(p ${contacts})
    list(FIND cand ${p} found)
    if(found LESS 0)
      fail("candidates ${a}: contact ${p} is not a candidate")
    endif()
  endforeach()
endforeach()

# generate: a lattice is known exactly (spacing = diameter, row-major, radius column), in
# CSV and in f64 (the same numbers as little-endian doubles).
expect(NAME "generate lattice" CODE 0 OUT "^x,y,radius\n0,0,0\\.5\n1,0,0\\.5\n0,1,0\\.5\n1,1,0\\.5\n$"
       ARGS generate lattice --dim 2 --n 4)
expect(NAME "generate lattice 3D" CODE 0
       OUT "^x,y,z,radius\n0\\.5,0\\.5,0\\.5,1\n2\\.5,0\\.5,0\\.5,1\n0\\.5,2\\.5,0\\.5,1\n2\\.5,2\\.5,0\\.5,1\n0\\.5,0\\.5,2\\.5,1\n"
       ARGS generate lattice --dim 3 --n 8 --diameter 2 --offset 0.5)
expect(NAME "generate lattice f64" CODE 0 ARGS generate lattice --dim 2 --n 2 --output ${WORK}/l.f64)
file(READ ${WORK}/l.f64 hex HEX)
# (0, 0, 0.5) (1, 0, 0.5): 0.5 = 0x3fe0000000000000, 1 = 0x3ff0000000000000.
expect_equal("lattice f64 bytes" "${hex}"
  "00000000000000000000000000000000000000000000e03f000000000000f03f0000000000000000000000000000e03f")
# The lattice's own contacts: every horizontal and vertical neighbour, as in lattice2d.txt.
expect(NAME "generate lattice 9" CODE 0 ARGS generate lattice --dim 2 --n 9 --output ${WORK}/l9.csv)
golden(lattice_generated ${G}/lattice2d.pairs.csv --input ${WORK}/l9.csv)

# The 0-based indices, i < j, sorted: check the order in a larger file.
expect(NAME "generate" CODE 0 ARGS generate uniform --dim 2 --n 3000 --output ${WORK}/u2.csv)
expect(NAME "sorted output" CODE 0 ARGS detect --input ${WORK}/u2.csv --output ${WORK}/u2.pairs.csv)
file(STRINGS ${WORK}/u2.pairs.csv lines)
set(prev_i -1)
set(prev_j -1)
set(bad "")
foreach(l ${lines})
  string(REGEX MATCH "^([0-9]+),([0-9]+)$" m "${l}")
  if(NOT m)
    set(bad "line '${l}' is not i,j")
    break()
  endif()
  set(i ${CMAKE_MATCH_1})
  set(j ${CMAKE_MATCH_2})
  if(NOT i LESS j OR i LESS prev_i OR (i EQUAL prev_i AND NOT j GREATER prev_j))
    set(bad "line '${l}' after ${prev_i},${prev_j}")
    break()
  endif()
  set(prev_i ${i})
  set(prev_j ${j})
endforeach()
expect_equal("pairs sorted with i < j" "${bad}" "")
list(LENGTH lines npairs)
if(npairs LESS 100)
  fail("sorted output: only ${npairs} pairs in a 2D scene at fraction 0.5")
endif()

done()
