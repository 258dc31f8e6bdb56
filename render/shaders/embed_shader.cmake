# SPDX-License-Identifier: BSD-3-Clause
# render/shaders/embed_shader.cmake -- writes a GLSL file into a C++ source as a raw string, with
# the constants of render/src/shader_constants.h (its PNB_SHARED lines) after its #version line.
# cmake -DINPUT=shader.comp -DOUTPUT=file.cpp -DSYMBOL=kName -DCONSTANTS=shader_constants.h -P embed_shader.cmake
file(READ "${INPUT}" source)
string(FIND "${source}" ")pnbglsl\"" clash)
if(NOT clash EQUAL -1)
  message(FATAL_ERROR "${INPUT} contains the raw-string delimiter )pnbglsl\"")
endif()

# PNB_SHARED(type, name, value) -> const <glsl type> name = value;
file(STRINGS "${CONSTANTS}" lines REGEX "^PNB_SHARED\\(")
set(glsl "// Shared with C++ (render/src/shader_constants.h), written at build time:\n")
foreach(line ${lines})
  if(NOT line MATCHES "^PNB_SHARED\\(([a-z]+), *(k[A-Za-z0-9]+), *([^)]+)\\)")
    message(FATAL_ERROR "${CONSTANTS}: cannot read '${line}'")
  endif()
  set(type "${CMAKE_MATCH_1}")
  set(name "${CMAKE_MATCH_2}")
  set(value "${CMAKE_MATCH_3}")
  if(type STREQUAL "double")
    set(type float)
  elseif(type STREQUAL "unsigned")
    set(type uint)
    string(APPEND value "u")
  elseif(NOT type STREQUAL "int")
    message(FATAL_ERROR "${CONSTANTS}: no GLSL type for '${type}' (${name})")
  endif()
  string(FIND "${source}" "const ${type} ${name} " defined)
  if(NOT defined EQUAL -1)
    message(FATAL_ERROR "${INPUT} defines ${name} itself; it comes from ${CONSTANTS}")
  endif()
  string(APPEND glsl "const ${type} ${name} = ${value};\n")
endforeach()
string(REGEX MATCH "^[^\n]*#version[^\n]*\n|\n#version[^\n]*\n" version_line "${source}")
if(version_line STREQUAL "")
  message(FATAL_ERROR "${INPUT} has no #version line")
endif()
string(FIND "${source}" "${version_line}" at)
string(LENGTH "${version_line}" length)
math(EXPR after "${at} + ${length}")
string(SUBSTRING "${source}" 0 ${after} head)
string(SUBSTRING "${source}" ${after} -1 tail)
set(source "${head}${glsl}${tail}")

get_filename_component(name "${INPUT}" NAME)
file(WRITE "${OUTPUT}.tmp"
  "// Generated from render/shaders/${name} at build time; edit that file instead.\n"
  "namespace penumbra::render::gpu {\n"
  "extern const char* const ${SYMBOL};\n"
  "const char* const ${SYMBOL} = R\"pnbglsl(${source})pnbglsl\";\n"
  "}  // namespace penumbra::render::gpu\n")
file(RENAME "${OUTPUT}.tmp" "${OUTPUT}")
