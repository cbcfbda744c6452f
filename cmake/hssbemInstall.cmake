# Install rules and the CMake package of hssbem, so other projects can write
#   find_package(hssbem REQUIRED)
#   target_link_libraries(app PRIVATE hssbem::hssbem)
# Included by the top-level CMakeLists.txt after add_subdirectory(src) when HSSBEM_INSTALL is ON.
# The rules live here rather than in src/CMakeLists.txt (CMake >= 3.13 installs targets of any
# directory), so the packaging stays in one file.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(HSSBEM_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/hssbem)

install(TARGETS hssbem EXPORT hssbemTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(TARGETS hssbem_app RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
# The whole public header tree; the library's INSTALL_INTERFACE include directory is "include".
install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/hssbem DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
  FILES_MATCHING PATTERN "*.h" PATTERN "*.hpp" PATTERN "*.def")
install(EXPORT hssbemTargets NAMESPACE hssbem:: DESTINATION ${HSSBEM_INSTALL_CMAKEDIR})

# The pkg-config directories of the PETSc and HDF5 found above. hssbemConfig.cmake searches them
# first, so a consumer links the builds the library was compiled against even when its own
# PKG_CONFIG_PATH points elsewhere or is unset (PETSC_DIR/PETSC_ARCH installs).
set(HSSBEM_PKG_CONFIG_DIRS "")
foreach(_hssbem_module IN ITEMS ${PETSC_MODULE_NAME} ${HDF5_MODULE_NAME})
  pkg_get_variable(_hssbem_pcfiledir ${_hssbem_module} pcfiledir)
  if(_hssbem_pcfiledir)
    list(APPEND HSSBEM_PKG_CONFIG_DIRS ${_hssbem_pcfiledir})
  endif()
endforeach()
list(REMOVE_DUPLICATES HSSBEM_PKG_CONFIG_DIRS)

configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/hssbemConfig.cmake.in
  ${PROJECT_BINARY_DIR}/hssbemConfig.cmake
  INSTALL_DESTINATION ${HSSBEM_INSTALL_CMAKEDIR})
# 0.y releases: only the same minor version is compatible.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/hssbemConfigVersion.cmake
  VERSION ${PROJECT_VERSION}
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/hssbemConfig.cmake ${PROJECT_BINARY_DIR}/hssbemConfigVersion.cmake
  DESTINATION ${HSSBEM_INSTALL_CMAKEDIR})
