# SPDX-License-Identifier: BSD-3-Clause
# OpenMesh for a Debian multiarch cross build (cmake/toolchains/aarch64-linux-gnu.cmake): the
# target's runtime library from libopenmesh1:<arch>, which has neither the libOpenMeshCore.so link
# nor CMake files, with the headers of the host's libopenmesh-dev, which are the same on every
# architecture. Defines the imported target OpenMeshCore, as OpenMesh's own config does.
find_library(OpenMesh_CORE_LIBRARY NAMES OpenMeshCore libOpenMeshCore.so.9.0)
find_path(OpenMesh_INCLUDE_DIR OpenMesh/Core/Mesh/PolyMeshT.hh)
if(NOT OpenMesh_CORE_LIBRARY OR NOT OpenMesh_INCLUDE_DIR)
  set(OpenMesh_FOUND FALSE)
  set(OpenMesh_NOT_FOUND_MESSAGE
      "needs libopenmesh1:<target arch> and the headers of libopenmesh-dev (scripts/setup_aarch64.sh)")
  return()
endif()
if(NOT TARGET OpenMeshCore)
  add_library(OpenMeshCore SHARED IMPORTED)
  set_target_properties(OpenMeshCore PROPERTIES
    IMPORTED_LOCATION "${OpenMesh_CORE_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${OpenMesh_INCLUDE_DIR}")
endif()
set(OpenMesh_FOUND TRUE)
