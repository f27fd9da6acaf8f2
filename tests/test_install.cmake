# Installs nbs into a scratch prefix and builds examples/step.c against it twice: through
# find_package(nbs) (shared and static targets) and through pkg-config. Each program must run
# and find the lattice's 2700 contacts.
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})
set(prefix ${WORK}/prefix)

function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}\n${out}\n${err}")
  endif()
  set(out "${out}" PARENT_SCOPE)
endfunction()

run(${CMAKE_COMMAND} -S ${SRC} -B ${WORK}/build -G ${GENERATOR} -DCMAKE_BUILD_TYPE=Release
    -DNBS_BUILD_TESTS=OFF -DNBS_BUILD_APPS=OFF -DCMAKE_INSTALL_PREFIX=${prefix})
run(${CMAKE_COMMAND} --build ${WORK}/build -j2)
run(${CMAKE_COMMAND} --install ${WORK}/build)

run(${CMAKE_COMMAND} -S ${SRC}/examples -B ${WORK}/consumer -G ${GENERATOR}
    -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_RPATH=${prefix}/lib)
run(${CMAKE_COMMAND} --build ${WORK}/consumer)
foreach(exe step step_static)
  run(${WORK}/consumer/${exe})
  if(NOT out MATCHES "step 0: 2700 contacts")
    message(FATAL_ERROR "${exe} printed:\n${out}")
  endif()
endforeach()

find_program(PKG_CONFIG pkg-config)
find_program(CC NAMES cc gcc clang)
if(PKG_CONFIG AND CC)
  file(GLOB pcdirs ${prefix}/lib*/pkgconfig ${prefix}/lib/*/pkgconfig)
  set(ENV{PKG_CONFIG_PATH} "${pcdirs}")
  run(${PKG_CONFIG} --cflags --libs nbs)
  string(STRIP "${out}" flags)
  separate_arguments(flags UNIX_COMMAND "${flags}")
  get_filename_component(libdir ${pcdirs} DIRECTORY)
  run(${CC} -std=c17 ${SRC}/examples/step.c ${flags} -Wl,-rpath,${libdir} -o ${WORK}/step_pc)
  run(${WORK}/step_pc)
  if(NOT out MATCHES "step 0: 2700 contacts")
    message(FATAL_ERROR "step_pc printed:\n${out}")
  endif()
else()
  message(FATAL_ERROR "pkg-config or a C compiler is missing: the setup script installs them")
endif()
message(STATUS "installed package works through CMake and pkg-config")
