# Records the git revision and build settings in generated headers so that
# every result can state exactly which robotperf produced it. The revision is read at every build
# (robotperf/git_revision.hpp, target robotperf_git_revision; those that include it depend on
# it), the settings at configure time (robotperf/build_info.hpp).
set(_robotperf_git_revision_command
    ${CMAKE_COMMAND} -DSOURCE_DIR=${CMAKE_SOURCE_DIR}
    -DOUTPUT=${CMAKE_BINARY_DIR}/generated/robotperf/git_revision.hpp
    -P ${CMAKE_CURRENT_LIST_DIR}/GitRevision.cmake)
execute_process(COMMAND ${_robotperf_git_revision_command})
add_custom_target(robotperf_git_revision
  COMMAND ${_robotperf_git_revision_command}
  BYPRODUCTS ${CMAKE_BINARY_DIR}/generated/robotperf/git_revision.hpp
  VERBATIM)
set(ROBOTPERF_COMPILER "${CMAKE_CXX_COMPILER_ID} ${CMAKE_CXX_COMPILER_VERSION}")
string(TOUPPER "${CMAKE_BUILD_TYPE}" _bt)
set(ROBOTPERF_CXX_FLAGS "${CMAKE_CXX_FLAGS} ${CMAKE_CXX_FLAGS_${_bt}}")
# Options added with add_compile_options() (warnings, sanitizers) are part of the flags too. They
# are generator expressions, unexpanded here: $<$<COMPILE_LANGUAGE:...>:FLAGS> is recorded as
# FLAGS where the languages include CXX and left out otherwise; any other kind stops the
# configuration rather than being recorded as written.
get_directory_property(_robotperf_compile_options COMPILE_OPTIONS)
list(JOIN _robotperf_compile_options " " _robotperf_compile_options)
set(_robotperf_language_genex "\\$<\\$<COMPILE_LANGUAGE:([^>]*)>:([^>]*)>")
string(REGEX MATCHALL "${_robotperf_language_genex}" _robotperf_genexes
       "${_robotperf_compile_options}")
foreach(_genex IN LISTS _robotperf_genexes)
  string(REGEX REPLACE "^${_robotperf_language_genex}$" "\\1" _languages "${_genex}")
  string(REPLACE "," ";" _languages "${_languages}")
  set(_flags "")
  if("CXX" IN_LIST _languages)
    string(REGEX REPLACE "^${_robotperf_language_genex}$" "\\2" _flags "${_genex}")
  endif()
  string(REPLACE "${_genex}" "${_flags}" _robotperf_compile_options "${_robotperf_compile_options}")
endforeach()
string(REGEX REPLACE "  +" " " _robotperf_compile_options "${_robotperf_compile_options}")
if(_robotperf_compile_options MATCHES "\\$<")
  message(FATAL_ERROR "cmake/Version.cmake cannot record the compile options "
                      "'${_robotperf_compile_options}': expand their generator expressions there")
endif()
set(ROBOTPERF_CXX_FLAGS "${ROBOTPERF_CXX_FLAGS} ${_robotperf_compile_options}")
string(STRIP "${ROBOTPERF_CXX_FLAGS}" ROBOTPERF_CXX_FLAGS)
if(ROBOTPERF_SANITIZE)
  set(ROBOTPERF_SANITIZE_BOOL true)
else()
  set(ROBOTPERF_SANITIZE_BOOL false)
endif()
configure_file(${CMAKE_CURRENT_LIST_DIR}/build_info.hpp.in
               ${CMAKE_BINARY_DIR}/generated/robotperf/build_info.hpp @ONLY)
