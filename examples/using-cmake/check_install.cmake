# SPDX-License-Identifier: BSD-3-Clause
# Installs the build tree into a scratch prefix, then configures, builds and runs
# examples/using-cmake against it. Run with: cmake -DBUILD_DIR=... -DSOURCE_DIR=... -DWORK_DIR=... -DLIBDIR=lib -P check_install.cmake
foreach(v BUILD_DIR SOURCE_DIR WORK_DIR LIBDIR)
  if(NOT DEFINED ${v})
    message(FATAL_ERROR "check_install.cmake: ${v} is not set")
  endif()
endforeach()
file(REMOVE_RECURSE ${WORK_DIR})
set(prefix ${WORK_DIR}/prefix)
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}\n${out}")
  endif()
  message(STATUS "${out}")
endfunction()
run(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})
run(${CMAKE_COMMAND} -S ${SOURCE_DIR}/examples/using-cmake -B ${WORK_DIR}/build -DCMAKE_PREFIX_PATH=${prefix}
    -DCMAKE_BUILD_TYPE=Release)
run(${CMAKE_COMMAND} --build ${WORK_DIR}/build)
# No LD_LIBRARY_PATH: the installed libraries find each other through their $ORIGIN run path.
run(${WORK_DIR}/build/penumbra-using-cmake)
# The pkg-config file is relocatable: compile and run the same program through it.
find_program(PKG_CONFIG pkg-config REQUIRED)
execute_process(COMMAND ${CMAKE_COMMAND} -E env PKG_CONFIG_PATH=${prefix}/${LIBDIR}/pkgconfig ${PKG_CONFIG} --cflags --libs penumbra
  OUTPUT_VARIABLE pc_flags OUTPUT_STRIP_TRAILING_WHITESPACE RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "pkg-config cannot find penumbra in ${prefix}")
endif()
separate_arguments(pc_flags UNIX_COMMAND "${pc_flags}")
run(cc ${SOURCE_DIR}/examples/using-cmake/main.c ${pc_flags} -o ${WORK_DIR}/penumbra-using-pkg-config)
run(${WORK_DIR}/penumbra-using-pkg-config)
file(REMOVE_RECURSE ${WORK_DIR})
