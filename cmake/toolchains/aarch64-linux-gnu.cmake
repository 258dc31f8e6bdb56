# SPDX-License-Identifier: BSD-3-Clause
# Cross build for 64-bit Arm Linux on a Debian x86-64 host, with Debian's cross compiler and arm64
# multiarch libraries (scripts/setup_aarch64.sh installs them; scripts/cross_aarch64.sh uses this):
#
#   cmake -S . -B build-aarch64 -G Ninja --toolchain cmake/toolchains/aarch64-linux-gnu.cmake \
#         -DPNB_ENABLE_VTK=OFF -DPNB_ENABLE_EGL=OFF -DPNB_ENABLE_FORTRAN=OFF
#
# VTK, EGL and gfortran have no arm64 packages that install beside the host's (VTK's arm64 -dev
# packages conflict with the amd64 ones), hence the three options.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)

# Debian multiarch: the target's libraries sit in /usr/lib/aarch64-linux-gnu beside the host's,
# its headers in /usr/include/aarch64-linux-gnu and the shared /usr/include, the cross C library
# in /usr/aarch64-linux-gnu. The library architecture points find_library and find_package at
# lib/aarch64-linux-gnu; the host's library folders are ignored so that nothing links an x86-64
# library by mistake. Programs (the host's tools) are never looked for in the target's folders.
set(CMAKE_LIBRARY_ARCHITECTURE aarch64-linux-gnu)
set(CMAKE_FIND_ROOT_PATH /usr/aarch64-linux-gnu /)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
set(CMAKE_IGNORE_PATH /usr/lib/x86_64-linux-gnu /lib/x86_64-linux-gnu /usr/lib/x86_64-linux-gnu/cmake
    /usr/include/x86_64-linux-gnu)

# libopenmesh-dev:arm64 conflicts with the host's VTK development packages, so unless it is there,
# OpenMesh comes from the target's runtime library and the host's (architecture-free) headers.
if(NOT EXISTS /usr/lib/aarch64-linux-gnu/cmake/OpenMesh/OpenMeshConfig.cmake)
  set(OpenMesh_DIR "${CMAKE_CURRENT_LIST_DIR}/openmesh" CACHE PATH "OpenMesh for the cross build")
endif()

# Test programs run under qemu-user: gtest_discover_tests lists each suite's tests through it, and
# ctest starts every test program through it. The programs load the multiarch C library
# (libc6:arm64, /lib/aarch64-linux-gnu, which the arm64 libraries above depend on) with its own
# loader, /lib/ld-linux-aarch64.so.1: hence -L / (no prefix). With -L /usr/aarch64-linux-gnu the
# loader of the cross package (glibc 2.36-8 on Debian 12) was paired with the multiarch libc.so.6
# (2.36-9+deb12u14), a mismatch under which every thread start hung.
find_program(PNB_QEMU_AARCH64 qemu-aarch64 NO_CMAKE_FIND_ROOT_PATH)
if(PNB_QEMU_AARCH64)
  set(CMAKE_CROSSCOMPILING_EMULATOR "${PNB_QEMU_AARCH64};-L;/")
endif()
