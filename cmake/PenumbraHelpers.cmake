# SPDX-License-Identifier: BSD-3-Clause
# pnb_add_module(NAME SOURCES...): a library target penumbra_NAME with aliases Penumbra::NAME and
# penumbra::NAME, public headers in NAME/include, exported as NAME.
function(pnb_add_module name dir)
  add_library(penumbra_${name} ${ARGN})
  add_library(Penumbra::${name} ALIAS penumbra_${name})
  add_library(penumbra::${name} ALIAS penumbra_${name})
  set_target_properties(penumbra_${name} PROPERTIES EXPORT_NAME ${name} OUTPUT_NAME penumbra_${name})
  target_include_directories(penumbra_${name} PUBLIC
    $<BUILD_INTERFACE:${dir}/include>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  target_compile_options(penumbra_${name} PRIVATE -Wall -Wextra)
  # No fused multiply-add contraction, so that a module computes the same bits on every
  # architecture: GCC contracts a * b + c wherever the baseline has FMA (aarch64, not x86-64; on
  # aarch64 it fused products in mesh validation's orientation tests and in the cameras' set-up).
  # Render and compression need it for reasons of their own too (their CMakeLists.txt).
  target_compile_options(penumbra_${name} PRIVATE $<$<CXX_COMPILER_ID:GNU,Clang,AppleClang,IntelLLVM>:-ffp-contract=off>)
  install(TARGETS penumbra_${name} EXPORT PenumbraTargets
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
    RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
    INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
  install(DIRECTORY ${dir}/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
  # Tests and benchmarks that check a module's internals (its src/ headers) link this target
  # instead of reaching into src/ by include path; it is never installed.
  add_library(penumbra_${name}_internal INTERFACE)
  target_link_libraries(penumbra_${name}_internal INTERFACE penumbra_${name})
  target_include_directories(penumbra_${name}_internal INTERFACE ${dir}/src)
endfunction()
