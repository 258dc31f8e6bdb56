# SPDX-License-Identifier: BSD-3-Clause
include(CMakePackageConfigHelpers)
set(PNB_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/Penumbra)
install(EXPORT PenumbraTargets NAMESPACE Penumbra:: DESTINATION ${PNB_CMAKE_DIR})
configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/PenumbraConfig.cmake.in
  ${CMAKE_CURRENT_BINARY_DIR}/PenumbraConfig.cmake INSTALL_DESTINATION ${PNB_CMAKE_DIR})
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/PenumbraConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/PenumbraConfig.cmake ${CMAKE_CURRENT_BINARY_DIR}/PenumbraConfigVersion.cmake
  DESTINATION ${PNB_CMAKE_DIR})
configure_file(${CMAKE_CURRENT_LIST_DIR}/penumbra.pc.in ${CMAKE_CURRENT_BINARY_DIR}/penumbra.pc @ONLY)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/penumbra.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
