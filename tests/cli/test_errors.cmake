# Bad input: each file of data/bad gives its FILE:LINE:COLUMN: message and exit code 3;
# bad command lines give exit code 2; no output file is left behind.
cmake_minimum_required(VERSION 3.25)
include(${CMAKE_CURRENT_LIST_DIR}/common.cmake)
set(B ${DATA}/bad)
set(OUT ${WORK}/pairs.csv)

function(bad name code err)
  expect(NAME "${name}" CODE ${code} ERR "${err}" ARGS ${ARGN})
  expect_no_file("${name}: no output" ${OUT})
  set(NBS_CHECKS ${NBS_CHECKS} PARENT_SCOPE)
endfunction()

# Malformed CSV.
bad(nonnumber 3 "nonnumber.csv:2:3: 'x1' is not a number\n"
    detect --input ${B}/nonnumber.csv --dim 2 --output ${OUT})
bad(columns 3 "columns.csv:2:4: 2 values, expected 3 as on line 1\n"
    detect --input ${B}/columns.csv --dim 2 --output ${OUT})
bad(fivecols 3 "fivecols.csv:1:1: 5 values: expected 2 \\(x,y\\) with --diameter, or 3 \\(x,y,radius\\)\n"
    detect --input ${B}/fivecols.csv --dim 2 --output ${OUT})
bad(twocols_3d 3 "twocols.csv:1:1: 2 values: expected 3 \\(x,y,z\\) with --diameter, or 4 \\(x,y,z,radius\\)\n"
    detect --input ${B}/twocols.csv --dim 3 --output ${OUT})
bad(no_radius 3 "twocols.csv:1:1: 2 values: no radius column .* and no --diameter\n"
    detect --input ${B}/twocols.csv --dim 2 --output ${OUT})
bad(headercount 3 "headercount.csv:2:1: 3 values, but the header on line 1 names 4 columns\n"
    detect --input ${B}/headercount.csv --dim 3 --output ${OUT})
bad(header_no_z 3 "circles2d.csv:1:1: the header names x and y but no z column"
    detect --input ${DATA}/golden/circles2d.csv --dim 3 --output ${OUT})
bad(nan 3 "nan.csv:2:3: y is NaN\n" detect --input ${B}/nan.csv --dim 2 --output ${OUT})
bad(inf 3 "inf.csv:1:1: x is infinite\n" detect --input ${B}/inf.csv --dim 2 --output ${OUT})
bad(negradius 3 "negradius.csv:2:5: radius -0.5 is negative\n"
    detect --input ${B}/negradius.csv --dim 2 --output ${OUT})
bad(zeroradius 3 "zeroradius.csv:1:5: radius is 0: it must be > 0\n"
    detect --input ${B}/zeroradius.csv --dim 2 --output ${OUT})
bad(empty 3 "empty.csv:1:1: empty file: no elements\n"
    detect --input ${B}/empty.csv --dim 2 --output ${OUT})
bad(headeronly 3 "headeronly.csv:1:1: no elements \\(no data lines\\)\n"
    detect --input ${B}/headeronly.csv --dim 2 --output ${OUT})
bad(nul 3 "nul.csv:2:2: a NUL byte: this is not a text file"
    detect --input ${B}/nul.csv --format csv --dim 2 --output ${OUT})

# Malformed raw f64.
bad(truncated_f64 3 "truncated.f64:5:4: truncated: 156 bytes are not a whole number of elements of 4 doubles \\(32 bytes\\); element 5, at byte 128, has only 28 bytes\n"
    detect --input ${B}/truncated.f64 --dim 3 --output ${OUT})
bad(nan_f64 3 "nan.f64:2:2: y is NaN \\(element 2, byte 40\\)\n"
    detect --input ${B}/nan.f64 --dim 3 --output ${OUT})
bad(negradius_f64 3 "negradius.f64:2:4: radius -2 is negative \\(element 2, byte 56\\)\n"
    detect --input ${B}/negradius.f64 --dim 3 --output ${OUT})
bad(empty_f64 3 "empty.f64:1:1: empty file: no elements\n"
    detect --input ${B}/empty.f64 --dim 3 --output ${OUT})
bad(f64_needs_dim 2 "a raw f64 file needs --dim 2 or 3"
    detect --input ${B}/nan.f64 --output ${OUT})

# Malformed dumps (LAMMPS / LIGGGHTS), legacy VTK and VTK XML: data/bad/make_bad.py made them
# from the good fixtures. Hostile counts are refused by comparing them with the file's size.
set(dumps
  "hostile_count.dump|hostile_count.dump:4:1: NUMBER OF ATOMS is 999999999999, more than the rest of the file \\(4650 bytes\\) can hold"
  "truncated.dump|truncated.dump:40:1: truncated: NUMBER OF ATOMS is 60, the file ends after 30 atom lines"
  "extra.dump|extra.dump:69:1: NUMBER OF ATOMS is 59, but the snapshot has more atom lines"
  "columns.dump|columns.dump:12:61: 5 values, expected 6 as named by ITEM: ATOMS"
  "number.dump|number.dump:12:24: '0.5x' is not a number"
  "nan.dump|nan.dump:13:43: z is NaN"
  "negradius.dump|negradius.dump:14:61: radius -0.25 is negative"
  "noz.dump|noz.dump:9:1: ITEM: ATOMS has no z column \\(z, zu, zs or zsu\\). use --dim 2 for a 2D dump"
  "noradius.dump|noradius.dump:9:1: ITEM: ATOMS has no radius or diameter column. give --diameter"
  "notimestep.dump|notimestep.dump:1:1: expected 'ITEM: TIMESTEP', found 'ITEM: TIMESTOP'"
  "hostile_points.vtk|hostile_points.vtk:5:8: POINTS declares 2000000000 points, more than the 4877 bytes left can hold"
  "truncated_binary.vtk|truncated_binary.vtk:5:8: POINTS declares 60 points, more than the 700 bytes left can hold"
  "badkeyword.vtk|badkeyword.vtk:62:1: unknown keyword 'POINT_DATTA'"
  "nan.vtk|nan.vtk:6:52: coordinate is NaN"
  "negradius_binary.vtk|negradius_binary.vtk:52:1: radius -1 is negative \\(value 1 of radius, byte 4829\\)"
  "notvtk.vtk|notvtk.vtk:1:1: not a legacy VTK file"
  "noradius.vtk|noradius.vtk: no point array 'radius' or 'diameter'. give --diameter or --radius NAME"
  "hostile_points.vtp|hostile_points.vtp:3:5: NumberOfPoints 900000000: more than the file's data can hold"
  "hostile_blocks.vtp|hostile_blocks.vtp:25:9: Points: the header claims 1099511627776 blocks, more than the file holds"
  "corrupt_zlib.vtp|corrupt_zlib.vtp:25:9: Points: block 0 is not valid zlib data of 1440 bytes"
  "truncated_appended.vtp|truncated_appended.vtp:3:5: NumberOfPoints 60: more than the file's data can hold"
  "badbase64.vtp|badbase64.vtp:20:9: radius: truncated: a character that is not base64"
  "lz4.vtp|lz4.vtp:1:1: compressor 'vtkLZ4DataCompressor' is not supported"
  "nan.vtp|nan.vtp:87:11: coordinate is NaN"
  "negradius.vtp|negradius.vtp:59:11: radius -0.5 is negative"
  "nopoints.vtp|nopoints.vtp:4:5: a Piece of 60 points without a Points array"
  "unterminated.vtp|unterminated.vtp:6:1: truncated: the file ends before </PointData>"
  "wrongcount.vtp|wrongcount.vtp:86:9: Points: 180 values, 183 expected")
foreach(entry ${dumps})
  string(REPLACE "|" ";" entry "${entry}")
  list(GET entry 0 file)
  list(GET entry 1 message)
  bad(${file} 3 "${message}" detect --input ${B}/${file} --output ${OUT})
endforeach()
bad(no_snapshot 3 "snapshots.dump: no snapshot 5: the file has 3 \\(0 to 2\\)"
    detect --input ${DATA}/formats/snapshots.dump --snapshot 5 --output ${OUT})
bad(no_timestep 3 "snapshots.dump: no snapshot of timestep 7 \\(the file has 3\\)"
    detect --input ${DATA}/formats/snapshots.dump --timestep 7 --output ${OUT})

# Files that cannot be read.
bad(missing 3 "no-such-file.csv: cannot open: No such file or directory\n"
    detect --input ${WORK}/no-such-file.csv --dim 2 --output ${OUT})
bad(directory 3 ": is a directory\n" detect --input ${B} --dim 2 --output ${OUT})

# Bad command lines: exit 2 and a hint.
bad(dim4 2 "nbs detect: --dim 4: the dimension must be 2 or 3\nTry 'nbs detect --help'.\n"
    detect --input ${B}/nan.csv --dim 4 --output ${OUT})
bad(dim_missing 2 "--dim : the dimension must be 2 or 3" detect --input ${B}/nan.csv --dim)
bad(algorithm 2 "nbs detect: unknown algorithm 'fastest': use direct, screening, sorting, nbs or auto\n"
    detect --input ${B}/nan.csv --dim 2 --algorithm fastest --output ${OUT})
bad(no_input 2 "nbs detect: no input: give --input FILE\n" detect --dim 2 --output ${OUT})
bad(repeat0 2 "--repeat 0: give a count from 1 to 1000000" detect --input ${B}/nan.csv --dim 2 --repeat 0)
bad(diameter 2 "--diameter -1: it must be a finite number > 0" detect --input ${B}/nan.csv --dim 2 --diameter -1)
bad(unknown_option 2 "nbs detect: unknown option '--fast'" detect --input ${B}/nan.csv --fast)
bad(unknown_command 2 "nbs: unknown command 'detcet'" detcet --input ${B}/nan.csv)
bad(csv_needs_dim 2 "give --dim 2 or 3 \\(the file has no header naming x, y, z\\)"
    detect --input ${B}/columns.csv)

# A write that fails leaves nothing behind, and says why (exit 4).
bad(unwritable 4 "no-such-dir/pairs.csv: cannot create: No such file or directory"
    detect --input ${DATA}/golden/circles2d.csv --dim 2 --output ${WORK}/no-such-dir/pairs.csv)

# More pairs than --max-pairs: stopped cleanly (the default limit protects against files
# whose radii make everything touch).
bad(max_pairs 4 "lattice2d.txt: more pairs than the limit of --max-pairs \\(pairs\\)"
    detect --input ${DATA}/golden/lattice2d.txt --dim 2 --diameter 1 --max-pairs 11 --output ${OUT})
expect(NAME "max_pairs exact" CODE 0 OUT "^pairs: 12\n$"
       ARGS detect --input ${DATA}/golden/lattice2d.txt --dim 2 --diameter 1 --max-pairs 12)

# A result that cannot be printed is an error (exit 4), not a silent success.
if(EXISTS /dev/full)
  execute_process(COMMAND ${NBS} detect --input ${DATA}/golden/circles2d.csv --dim 2
                  OUTPUT_FILE /dev/full ERROR_VARIABLE err RESULT_VARIABLE rc)
  expect_equal("stdout full: exit" "${rc}" "4")
  expect_equal("stdout full: message" "${err}" "nbs: standard output: write error\n")
endif()

# The target is a directory: the rename fails, the temporary file is removed.
file(MAKE_DIRECTORY ${WORK}/adir)
expect(NAME "output is a directory" CODE 4 ERR "adir: cannot write: Is a directory"
       ARGS detect --input ${DATA}/golden/circles2d.csv --dim 2 --output ${WORK}/adir)
file(GLOB left ${WORK}/.adir*)
expect_equal("no temporary file next to adir" "${left}" "")
file(REMOVE_RECURSE ${WORK}/adir)

# A library error: screening over its cell budget (exit 4, the library's message).
bad(budget 4 "screening needs [0-9]+ bytes of cell heads .*over the budget of 1000 bytes \\(budget\\)"
    detect --input ${DATA}/golden/spheres3d.csv --dim 3 --diameter 2 --algorithm screening
    --cell-budget 1000 --output ${OUT})

# Nothing else was written to the scratch directory (no temporary files left).
file(GLOB left ${WORK}/* ${WORK}/.*)
expect_equal("no files left in the scratch directory" "${left}" "")

done()
