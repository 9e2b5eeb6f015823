# Install rules. Headers, the static library and the CMake package go to the "indoorloc_dev"
# component, which the wheel does not install (pyproject.toml installs only "python"):
#   cmake --install <build> --component indoorloc_dev --prefix <prefix>
# An outside app then does find_package(indoorloc) and links indoorloc::indoorloc.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(INDOORLOC_INSTALL_CMAKEDIR "${CMAKE_INSTALL_LIBDIR}/cmake/indoorloc")

install(TARGETS indoorloc EXPORT indoorlocTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT indoorloc_dev
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT indoorloc_dev
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/cpp/include/indoorloc
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} COMPONENT indoorloc_dev
        PATTERN "*.in" EXCLUDE)
install(EXPORT indoorlocTargets NAMESPACE indoorloc:: DESTINATION ${INDOORLOC_INSTALL_CMAKEDIR}
        COMPONENT indoorloc_dev)

configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/indoorlocConfig.cmake.in
  ${PROJECT_BINARY_DIR}/indoorlocConfig.cmake INSTALL_DESTINATION ${INDOORLOC_INSTALL_CMAKEDIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/indoorlocConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/indoorlocConfig.cmake
              ${PROJECT_BINARY_DIR}/indoorlocConfigVersion.cmake
        DESTINATION ${INDOORLOC_INSTALL_CMAKEDIR} COMPONENT indoorloc_dev)
