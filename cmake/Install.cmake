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

# Shell completion and the man page, made from the built executable's own commands and help, so
# that they never describe a command it does not have.
set(ROBOTPERF_COMPLETIONS ${CMAKE_BINARY_DIR}/completions)
add_custom_command(
  OUTPUT ${ROBOTPERF_COMPLETIONS}/robotperf ${ROBOTPERF_COMPLETIONS}/_robotperf
  COMMAND ${CMAKE_COMMAND} -E make_directory ${ROBOTPERF_COMPLETIONS}
  COMMAND sh -c "\"$1\" completion bash > \"$2/robotperf\" && \"$1\" completion zsh > \"$2/_robotperf\""
          completions $<TARGET_FILE:robotperf> ${ROBOTPERF_COMPLETIONS}
  DEPENDS robotperf
  COMMENT "Writing the bash and zsh completion of robotperf"
  VERBATIM)
add_custom_target(robotperf_completions ALL
  DEPENDS ${ROBOTPERF_COMPLETIONS}/robotperf ${ROBOTPERF_COMPLETIONS}/_robotperf)
install(FILES ${ROBOTPERF_COMPLETIONS}/robotperf
  DESTINATION ${CMAKE_INSTALL_DATADIR}/bash-completion/completions)
install(FILES ${ROBOTPERF_COMPLETIONS}/_robotperf
  DESTINATION ${CMAKE_INSTALL_DATADIR}/zsh/vendor-completions)

find_program(ROBOTPERF_HELP2MAN help2man)
if(ROBOTPERF_HELP2MAN)
  add_custom_command(
    OUTPUT ${CMAKE_BINARY_DIR}/man/robotperf.1
    COMMAND bash ${CMAKE_SOURCE_DIR}/scripts/man-page.sh $<TARGET_FILE:robotperf>
            ${CMAKE_BINARY_DIR}/man/robotperf.1
    DEPENDS robotperf ${CMAKE_SOURCE_DIR}/scripts/man-page.sh
    COMMENT "Writing robotperf's man page"
    VERBATIM)
  add_custom_target(robotperf_man ALL DEPENDS ${CMAKE_BINARY_DIR}/man/robotperf.1)
  install(FILES ${CMAKE_BINARY_DIR}/man/robotperf.1 DESTINATION ${CMAKE_INSTALL_MANDIR}/man1)
else()
  message(STATUS "help2man not found: no man page (scripts/install-deps.sh installs it)")
endif()
