# SPDX-License-Identifier: BSD-3-Clause
# render/shaders/embed_shader.cmake -- writes a GLSL file into a C++ source as a raw string.
# cmake -DINPUT=shader.comp -DOUTPUT=file.cpp -DSYMBOL=kName -P embed_shader.cmake
file(READ "${INPUT}" source)
string(FIND "${source}" ")pnbglsl\"" clash)
if(NOT clash EQUAL -1)
  message(FATAL_ERROR "${INPUT} contains the raw-string delimiter )pnbglsl\"")
endif()
get_filename_component(name "${INPUT}" NAME)
file(WRITE "${OUTPUT}.tmp"
  "// Generated from render/shaders/${name} at build time; edit that file instead.\n"
  "namespace penumbra::render::gpu {\n"
  "extern const char* const ${SYMBOL};\n"
  "const char* const ${SYMBOL} = R\"pnbglsl(${source})pnbglsl\";\n"
  "}  // namespace penumbra::render::gpu\n")
file(RENAME "${OUTPUT}.tmp" "${OUTPUT}")
