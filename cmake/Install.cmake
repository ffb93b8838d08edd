# `cmake --install build --prefix P`: the robotperf executable, the runtime libraries with their
# headers (cmake/Runtime.cmake), the built-in benchmark packages, and a CMake package config, so
# that a plug-in outside this tree builds with
#   find_package(robotperf REQUIRED)
#   target_link_libraries(my_plugin PRIVATE robotperf::plugin)
include(CMakePackageConfigHelpers)

install(TARGETS robotperf RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(DIRECTORY ${CMAKE_SOURCE_DIR}/benchmarks/ DESTINATION ${ROBOTPERF_INSTALLED_BENCHMARKS_DIR})

set(ROBOTPERF_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/robotperf)
install(EXPORT robotperfTargets NAMESPACE robotperf:: DESTINATION ${ROBOTPERF_CMAKE_DIR})
configure_package_config_file(${CMAKE_SOURCE_DIR}/cmake/robotperfConfig.cmake.in
  ${CMAKE_BINARY_DIR}/robotperfConfig.cmake INSTALL_DESTINATION ${ROBOTPERF_CMAKE_DIR}
  PATH_VARS CMAKE_INSTALL_BINDIR)
# 0.x: a new minor version may change the plug-in API (its version is checked at load time too).
write_basic_package_version_file(${CMAKE_BINARY_DIR}/robotperfConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_BINARY_DIR}/robotperfConfig.cmake
  ${CMAKE_BINARY_DIR}/robotperfConfigVersion.cmake DESTINATION ${ROBOTPERF_CMAKE_DIR})
