# `cmake --install build --prefix P`: headers, libraries, the command and a CMake package, so that
# another project's find_package(viewpose) gives viewpose::viewpose and the smaller targets
# (viewpose::core, io, visualize, simulate, eval, sensor). The Python module installs itself
# (python/CMakeLists.txt).
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(VIEWPOSE_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/viewpose)
install(DIRECTORY include/viewpose DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(TARGETS ${VIEWPOSE_INSTALL_TARGETS} EXPORT viewposeTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
if(TARGET viewpose_cli)
  install(TARGETS viewpose_cli RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endif()
install(EXPORT viewposeTargets NAMESPACE viewpose:: DESTINATION ${VIEWPOSE_CMAKE_DIR})

# The package's config finds again what the libraries link (static libraries carry their private
# dependencies to the program that links them; liblzf and the camera drivers by their full paths).
configure_package_config_file(cmake/viewposeConfig.cmake.in ${PROJECT_BINARY_DIR}/viewposeConfig.cmake
                              INSTALL_DESTINATION ${VIEWPOSE_CMAKE_DIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/viewposeConfigVersion.cmake
                                 VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/viewposeConfig.cmake ${PROJECT_BINARY_DIR}/viewposeConfigVersion.cmake
        DESTINATION ${VIEWPOSE_CMAKE_DIR})
