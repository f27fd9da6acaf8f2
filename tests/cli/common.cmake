# Helpers for the nbs tool's tests, included by each test script (cmake -P).
#   NBS   the tool          DATA  tests/cli/data          WORK  a scratch directory
# A failed check prints what was expected and what came, and makes the script fail at the
# end (SEND_ERROR), so that one run reports every failed check.

if(NOT NBS OR NOT DATA OR NOT WORK)
  message(FATAL_ERROR "run with -DNBS=<tool> -DDATA=<tests/cli/data> -DWORK=<scratch dir>")
endif()
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})
set(NBS_CHECKS 0)

function(fail what)
  message(SEND_ERROR "FAILED: ${what}")
endfunction()

# nbs_run(<var> ARGS...): runs the tool; sets <var>_rc, <var>_out, <var>_err.
# With NBS_STDIN set, that file is the standard input.
function(nbs_run var)
  if(NBS_STDIN)
    set(in INPUT_FILE ${NBS_STDIN})
  else()
    set(in "")
  endif()
  execute_process(COMMAND ${NBS} ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out
                  ERROR_VARIABLE err WORKING_DIRECTORY ${WORK} ${in})
  set(${var}_rc "${rc}" PARENT_SCOPE)
  set(${var}_out "${out}" PARENT_SCOPE)
  set(${var}_err "${err}" PARENT_SCOPE)
endfunction()

# expect(NAME n CODE c [OUT regex] [ERR regex] [ERR_EMPTY] ARGS ...): runs and checks the exit
# code and the outputs (regexes match anywhere; use ^...$ to anchor).
function(expect)
  cmake_parse_arguments(E "ERR_EMPTY" "NAME;CODE;OUT;ERR" "ARGS" ${ARGN})
  nbs_run(r ${E_ARGS})
  math(EXPR n "${NBS_CHECKS} + 1")
  set(NBS_CHECKS ${n} PARENT_SCOPE)
  if(NOT "${r_rc}" STREQUAL "${E_CODE}")
    fail("${E_NAME}: exit code ${r_rc}, expected ${E_CODE}\n  nbs ${E_ARGS}\n  stdout: ${r_out}\n  stderr: ${r_err}")
    return()
  endif()
  if(DEFINED E_OUT AND NOT r_out MATCHES "${E_OUT}")
    fail("${E_NAME}: stdout does not match '${E_OUT}'\n  nbs ${E_ARGS}\n  stdout: ${r_out}")
  endif()
  if(DEFINED E_ERR AND NOT r_err MATCHES "${E_ERR}")
    fail("${E_NAME}: stderr does not match '${E_ERR}'\n  nbs ${E_ARGS}\n  stderr: ${r_err}")
  endif()
  if(E_ERR_EMPTY AND NOT r_err STREQUAL "")
    fail("${E_NAME}: stderr is not empty\n  nbs ${E_ARGS}\n  stderr: ${r_err}")
  endif()
endfunction()

# expect_same_file(name a b): the two files have the same bytes.
function(expect_same_file name a b)
  math(EXPR n "${NBS_CHECKS} + 1")
  set(NBS_CHECKS ${n} PARENT_SCOPE)
  if(NOT EXISTS ${a})
    fail("${name}: ${a} was not written")
    return()
  endif()
  if(NOT EXISTS ${b})
    fail("${name}: ${b} was not written")
    return()
  endif()
  file(SHA256 ${a} ha)
  file(SHA256 ${b} hb)
  if(NOT ha STREQUAL hb)
    file(READ ${a} ca LIMIT 2000)
    file(READ ${b} cb LIMIT 2000)
    fail("${name}: ${a} and ${b} differ\n--- ${a}\n${ca}\n--- ${b}\n${cb}")
  endif()
endfunction()

# count_lines(var file): the number of lines of a text file.
function(count_lines var file)
  file(STRINGS ${file} lines)
  list(LENGTH lines n)
  set(${var} ${n} PARENT_SCOPE)
endfunction()

# expect_no_file(name path): nothing (not even a partial file) is at path.
function(expect_no_file name path)
  math(EXPR n "${NBS_CHECKS} + 1")
  set(NBS_CHECKS ${n} PARENT_SCOPE)
  if(EXISTS ${path})
    fail("${name}: ${path} exists")
  endif()
endfunction()

# expect_equal(name got want)
function(expect_equal name got want)
  math(EXPR n "${NBS_CHECKS} + 1")
  set(NBS_CHECKS ${n} PARENT_SCOPE)
  if(NOT "${got}" STREQUAL "${want}")
    fail("${name}: got '${got}', expected '${want}'")
  endif()
endfunction()

# nbs_algorithms(var): the library's algorithms as `nbs info --algorithms` lists them (auto
# included); fails unless the book's four and auto are there.
function(nbs_algorithms var)
  nbs_run(r info --algorithms)
  string(REGEX REPLACE "\n$" "" list "${r_out}")
  string(REPLACE "\n" ";" list "${list}")
  foreach(a auto direct screening sorting nbs)
    if(NOT a IN_LIST list)
      fail("info --algorithms does not list ${a}: ${r_out}")
    endif()
  endforeach()
  set(${var} ${list} PARENT_SCOPE)
endfunction()

# done(): the closing line; the script fails if a check did.
macro(done)
  message(STATUS "${NBS_CHECKS} checks run")
endmacro()
