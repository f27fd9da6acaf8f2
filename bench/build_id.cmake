# Writes OUT: the commit the benchmark drivers were just linked from, with '+' when src/ or
# include/ had changes then; "unknown" outside a git checkout. Run after every link of
# nbs_bench (bench/CMakeLists.txt), however the build was started, so that results.csv's
# nbs_build column and machine.txt name the library actually measured.
execute_process(COMMAND git -C "${ROOT}" rev-parse --short HEAD
                OUTPUT_VARIABLE id OUTPUT_STRIP_TRAILING_WHITESPACE RESULT_VARIABLE failed
                ERROR_QUIET)
if(failed OR id STREQUAL "")
  set(id "unknown")
else()
  execute_process(COMMAND git -C "${ROOT}" status --porcelain -- src include
                  OUTPUT_VARIABLE dirty OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
  if(NOT dirty STREQUAL "")
    string(APPEND id "+")
  endif()
endif()
file(WRITE "${OUT}" "${id}\n")
