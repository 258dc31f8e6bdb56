# SPDX-License-Identifier: BSD-3-Clause
# pnb_add_module(NAME DIR SOURCES...): a library target penumbra_NAME with aliases Penumbra::NAME
# and penumbra::NAME, public headers in DIR/include, exported as NAME. It is built with hidden
# visibility: it exports what its public headers declare (penumbra/core/export.h) and nothing
# else. penumbra_NAME_internal is the same objects as a static library with the src/ headers too,
# for the tests and benchmarks that check a module's internals; an executable links either the
# libraries or the internal variants, never both. Compile settings go on penumbra_NAME_objects;
# dependencies through pnb_module_link.
function(pnb_add_module name dir)
  add_library(penumbra_${name}_objects OBJECT ${ARGN})
  set_target_properties(penumbra_${name}_objects PROPERTIES POSITION_INDEPENDENT_CODE ON
    CXX_VISIBILITY_PRESET hidden C_VISIBILITY_PRESET hidden VISIBILITY_INLINES_HIDDEN ON)
  target_include_directories(penumbra_${name}_objects PUBLIC $<BUILD_INTERFACE:${dir}/include> PRIVATE ${dir}/src)
  target_compile_options(penumbra_${name}_objects PRIVATE -Wall -Wextra)
  # No fused multiply-add contraction, so that a module computes the same bits on every
  # architecture: GCC contracts a * b + c wherever the baseline has FMA (aarch64, not x86-64; on
  # aarch64 it fused products in mesh validation's orientation tests and in the cameras' set-up).
  # Render and compression need it for reasons of their own too (their CMakeLists.txt).
  target_compile_options(penumbra_${name}_objects PRIVATE $<$<CXX_COMPILER_ID:GNU,Clang,AppleClang,IntelLLVM>:-ffp-contract=off>)

  add_library(penumbra_${name} $<TARGET_OBJECTS:penumbra_${name}_objects>)
  add_library(Penumbra::${name} ALIAS penumbra_${name})
  add_library(penumbra::${name} ALIAS penumbra_${name})
  set_target_properties(penumbra_${name} PROPERTIES EXPORT_NAME ${name} OUTPUT_NAME penumbra_${name})
  target_include_directories(penumbra_${name} PUBLIC
    $<BUILD_INTERFACE:${dir}/include>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  install(TARGETS penumbra_${name} EXPORT PenumbraTargets
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
    RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
    INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
  install(DIRECTORY ${dir}/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})

  add_library(penumbra_${name}_internal STATIC $<TARGET_OBJECTS:penumbra_${name}_objects>)
  target_include_directories(penumbra_${name}_internal PUBLIC ${dir}/include ${dir}/src)
endfunction()

# The internal variant of each of `deps` that has one, into `out`.
function(pnb_internal_variants out)
  set(result)
  foreach(dep ${ARGN})
    if(TARGET ${dep}_internal)
      list(APPEND result ${dep}_internal)
    else()
      list(APPEND result ${dep})
    endif()
  endforeach()
  set(${out} ${result} PARENT_SCOPE)
endfunction()

# pnb_module_link(NAME [PUBLIC deps...] [PRIVATE deps...]): a module's dependencies, for its
# objects (their headers and definitions), its library, and its internal variant (which links the
# other modules' internal variants).
function(pnb_module_link name)
  cmake_parse_arguments(ARG "" "" "PUBLIC;PRIVATE" ${ARGN})
  target_link_libraries(penumbra_${name}_objects PUBLIC ${ARG_PUBLIC} PRIVATE ${ARG_PRIVATE})
  target_link_libraries(penumbra_${name} PUBLIC ${ARG_PUBLIC} PRIVATE ${ARG_PRIVATE})
  pnb_internal_variants(public ${ARG_PUBLIC})
  pnb_internal_variants(private ${ARG_PRIVATE})
  target_link_libraries(penumbra_${name}_internal PUBLIC ${public} PRIVATE ${private})
endfunction()
