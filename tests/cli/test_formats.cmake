# Formats: the fixtures of data/formats (written by VTK itself, and LAMMPS-style dumps) give
# the pairs computed by brute force when they were made; round trips through every format
# the tool writes give the same pairs as the CSV; pairs in binary; recognition by content.
cmake_minimum_required(VERSION 3.25)
include(${CMAKE_CURRENT_LIST_DIR}/common.cmake)
set(F ${DATA}/formats)

# fixture(file expected args...): auto and every other algorithm that can take 60 elements.
function(fixture file expected)
  foreach(a auto nbs sorting direct)
    set(out ${WORK}/${file}.${a}.pairs)
    expect(NAME "${file} ${a}" CODE 0 ERR_EMPTY ARGS detect --input ${F}/${file} --algorithm ${a}
           --output ${out} ${ARGN})
    expect_same_file("${file} ${a}" ${out} ${F}/${expected})
  endforeach()
  set(NBS_CHECKS ${NBS_CHECKS} PARENT_SCOPE)
endfunction()

# VTK XML as VTK writes it: appended (base64 and raw), inline base64, ascii; zlib or not;
# UInt32 and UInt64 headers; big-endian; Float32; several pieces; UnstructuredGrid.
foreach(f vtk_default.vtp paraview_raw_zlib_u64.vtp appended_raw_none.vtp
          appended_base64_none_u64.vtp binary_zlib.vtp binary_none.vtp ascii.vtp
          bigendian_raw_zlib.vtp bigendian_binary_none_u64.vtp grid.vtu)
  fixture(${f} scene.pairs.csv)
endforeach()
fixture(float32.vtp scene32.pairs.csv)
fixture(diameter.vtp scene.pairs.csv)
fixture(pieces3_raw_zlib.vtp pieces3.pairs.csv)
# Legacy VTK 5.1 (FIELD arrays, OFFSETS/CONNECTIVITY, METADATA) and 4.2 (SCALARS), ASCII and
# BINARY, PolyData and UnstructuredGrid.
foreach(f legacy_ascii.vtk legacy_binary.vtk legacy42_ascii_scalars.vtk
          legacy42_binary_scalars.vtk legacy_diameter.vtk legacy_grid_binary.vtk)
  fixture(${f} scene.pairs.csv)
endforeach()
# Dumps: columns in any order, diameter instead of radius, scaled coordinates, snapshots.
fixture(liggghts.dump scene.pairs.csv)
fixture(diameter.dump scene.pairs.csv)
fixture(scaled.dump scaled.pairs.csv)
fixture(snapshots.dump spread3.pairs.csv)
fixture(snapshots.dump scene.pairs.csv --snapshot 1)
fixture(snapshots.dump scene.pairs.csv --timestep 1000)
fixture(snapshots.dump spread3.pairs.csv --snapshot last)
fixture(last.dump scene.pairs.csv --snapshot last)
# 2D: --dim 2 drops z.
fixture(paraview_raw_zlib_u64.vtp scene2d.pairs.csv --dim 2)
fixture(legacy_binary.vtk scene2d.pairs.csv --dim 2)
fixture(liggghts.dump scene2d.pairs.csv --dim 2)
# --radius names the array; --diameter ignores the file's radii.
fixture(vtk_default.vtp scene.pairs.csv --radius radius)
expect(NAME "--radius missing" CODE 3 ERR "no point array 'velocity_magnitude'"
       ARGS detect --input ${F}/vtk_default.vtp --radius velocity_magnitude)
expect(NAME "--radius of a vector" CODE 3 ERR "the radius array has 3 components"
       ARGS detect --input ${F}/vtk_default.vtp --radius velocity)
expect(NAME "diameter overrides" CODE 0 OUT "^pairs: [0-9]+\n$"
       ARGS detect --input ${F}/legacy_binary.vtk --diameter 0.001)
nbs_run(r detect --input ${F}/legacy_binary.vtk --diameter 1e-9)
expect_equal("tiny diameter: no pairs" "${r_out}" "pairs: 0\n")

# Recognition by content whatever the name, and --format.
foreach(pair "paraview_raw_zlib_u64.vtp;scene.xml" "legacy_binary.vtk;scene.dat"
             "liggghts.dump;scene.txt")
  list(GET pair 0 src)
  list(GET pair 1 dst)
  file(COPY_FILE ${F}/${src} ${WORK}/${dst})
  expect(NAME "sniff ${dst}" CODE 0 ARGS detect --input ${WORK}/${dst} --output ${WORK}/${dst}.pairs --stats)
  expect_same_file("sniff ${dst}" ${WORK}/${dst}.pairs ${F}/scene.pairs.csv)
endforeach()
nbs_run(r detect --input ${WORK}/scene.dat --stats)
string(JSON fmt GET "${r_err}" format)
expect_equal("recognised as vtk" "${fmt}" "vtk")
set(NBS_STDIN ${F}/binary_zlib.vtp)
expect(NAME "vtp on stdin" CODE 0 ARGS detect --input - --output ${WORK}/stdin.pairs)
unset(NBS_STDIN)
expect_same_file("vtp on stdin" ${WORK}/stdin.pairs ${F}/scene.pairs.csv)

# Round trips: a scene written in every format and encoding reads back to the same pairs
# as its CSV (the values are written so that they read back exactly).
foreach(dim 2 3)
  expect(NAME "rt generate ${dim}" CODE 0 ARGS generate wide --dim ${dim} --n 2500 --size-ratio 5
         --output ${WORK}/rt${dim}.csv)
  expect(NAME "rt csv ${dim}" CODE 0 ARGS detect --input ${WORK}/rt${dim}.csv --output ${WORK}/rt${dim}.ref)
  count_lines(nref ${WORK}/rt${dim}.ref)
  if(nref LESS 100)
    fail("round trip ${dim}D: only ${nref} pairs")
  endif()
  foreach(variant "f64" "dump" "vtk" "vtp;--vtp-encoding;appended" "vtp;--vtp-encoding;base64"
                  "vtp;--vtp-encoding;ascii" "vtp;--vtp-encoding;appended;--no-compress"
                  "vtp;--vtp-encoding;base64;--no-compress")
    list(POP_FRONT variant ext)
    string(REPLACE ";" "" tag "${variant}")
    set(file ${WORK}/rt${dim}${tag}.${ext})
    expect(NAME "rt ${dim} write ${ext} ${variant}" CODE 0
           ARGS generate wide --dim ${dim} --n 2500 --size-ratio 5 --output ${file} ${variant})
    expect(NAME "rt ${dim} read ${ext} ${variant}" CODE 0
           ARGS detect --input ${file} --dim ${dim} --output ${file}.pairs)
    expect_same_file("round trip ${dim}D ${ext} ${variant}" ${file}.pairs ${WORK}/rt${dim}.ref)
  endforeach()
  # The .vtp that detect writes (scene and contacts) reads back to the same pairs.
  foreach(enc appended base64 ascii)
    expect(NAME "detect --vtp ${dim} ${enc}" CODE 0
           ARGS detect --input ${WORK}/rt${dim}.csv --vtp ${WORK}/net${dim}${enc}.vtp --vtp-encoding ${enc})
    expect(NAME "read --vtp ${dim} ${enc}" CODE 0
           ARGS detect --input ${WORK}/net${dim}${enc}.vtp --dim ${dim} --output ${WORK}/net${dim}${enc}.pairs)
    expect_same_file("detect --vtp ${dim}D ${enc}" ${WORK}/net${dim}${enc}.pairs ${WORK}/rt${dim}.ref)
  endforeach()
endforeach()
# The ascii .vtp: as many connectivity pairs in Lines as contacts, and as many points.
file(READ ${WORK}/net3ascii.vtp vtp)
string(REGEX MATCH "NumberOfPoints=\"([0-9]+)\"" m "${vtp}")
expect_equal("vtp NumberOfPoints" "${CMAKE_MATCH_1}" "2500")
string(REGEX MATCH "NumberOfLines=\"([0-9]+)\"" m "${vtp}")
count_lines(nref ${WORK}/rt3.ref)
expect_equal("vtp NumberOfLines" "${CMAKE_MATCH_1}" "${nref}")

# Pairs as raw binary: the golden circles2d pairs (0,1) (0,3), little-endian.
set(G ${DATA}/golden)
expect(NAME "u32" CODE 0 ARGS detect --input ${G}/circles2d.csv --dim 2 --output ${WORK}/p.u32 --pairs-format u32)
file(READ ${WORK}/p.u32 hex HEX)
expect_equal("u32 pairs" "${hex}" "00000000010000000000000003000000")
expect(NAME "u64" CODE 0 ARGS detect --input ${G}/circles2d.csv --dim 2 --output ${WORK}/p.u64 --pairs-format u64)
file(READ ${WORK}/p.u64 hex HEX)
expect_equal("u64 pairs" "${hex}" "0000000000000000010000000000000000000000000000000300000000000000")
# and on a generated scene, the binary pairs are the CSV pairs.
expect(NAME "u32 big" CODE 0 ARGS detect --input ${WORK}/rt3.csv --output ${WORK}/rt3.u32 --pairs-format u32)
file(SIZE ${WORK}/rt3.u32 size)
math(EXPR want "${nref} * 8")
expect_equal("u32 size" "${size}" "${want}")
file(READ ${WORK}/rt3.u32 hex HEX LIMIT 16)
file(STRINGS ${WORK}/rt3.ref first LIMIT_COUNT 2)
set(want "")
foreach(p ${first})
  string(REPLACE "," ";" ij "${p}")
  foreach(v ${ij})
    math(EXPR b0 "${v} & 255" OUTPUT_FORMAT HEXADECIMAL)
    math(EXPR b1 "(${v} >> 8) & 255" OUTPUT_FORMAT HEXADECIMAL)
    foreach(b b0 b1)
      string(SUBSTRING "${${b}}" 2 -1 h)
      string(LENGTH "${h}" l)
      if(l EQUAL 1)
        set(h "0${h}")
      endif()
      string(APPEND want "${h}")
    endforeach()
    string(APPEND want "0000")
  endforeach()
endforeach()
string(TOLOWER "${want}" want)
expect_equal("u32 first pairs = csv" "${hex}" "${want}")

done()
