# --help for every subcommand (with an example), --version, no command.
cmake_minimum_required(VERSION 3.25)
include(${CMAKE_CURRENT_LIST_DIR}/common.cmake)

expect(NAME version CODE 0 OUT "^nbs [0-9]+\\.[0-9]+\\.[0-9]+ \\(library [0-9]+\\.[0-9]+\\.[0-9]+\\)\n$"
       ARGS --version)
expect(NAME help CODE 0 OUT "Usage: nbs COMMAND.*Example" ARGS --help)
expect(NAME "no command" CODE 2 ERR "Usage: nbs COMMAND" ARGS)
foreach(cmd ${COMMANDS})
  expect(NAME "${cmd} --help" CODE 0 OUT "Usage: nbs ${cmd}.*Examples?:\n.*  nbs ${cmd}" ERR_EMPTY
         ARGS ${cmd} --help)
  expect(NAME "${cmd} -h" CODE 0 OUT "Usage: nbs ${cmd}" ARGS ${cmd} -h)
  expect(NAME "${cmd} bad option" CODE 2 ERR "nbs ${cmd}: unknown option '--no-such-option'\nTry 'nbs ${cmd} --help'.\n"
         ARGS ${cmd} --no-such-option)
endforeach()
done()
