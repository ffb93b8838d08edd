# Records the git revision and build settings in a generated header so that
# every result can state exactly which robotperf produced it.
execute_process(
  COMMAND git -C "${CMAKE_SOURCE_DIR}" describe --always --dirty --abbrev=12
  OUTPUT_VARIABLE ROBOTPERF_GIT_REVISION
  OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
if(NOT ROBOTPERF_GIT_REVISION)
  set(ROBOTPERF_GIT_REVISION "unknown")
endif()
set(ROBOTPERF_COMPILER "${CMAKE_CXX_COMPILER_ID} ${CMAKE_CXX_COMPILER_VERSION}")
string(TOUPPER "${CMAKE_BUILD_TYPE}" _bt)
set(ROBOTPERF_CXX_FLAGS "${CMAKE_CXX_FLAGS} ${CMAKE_CXX_FLAGS_${_bt}}")
# Options added with add_compile_options() (warnings, sanitizers) are part of the flags too.
get_directory_property(_robotperf_compile_options COMPILE_OPTIONS)
list(JOIN _robotperf_compile_options " " _robotperf_compile_options)
set(ROBOTPERF_CXX_FLAGS "${ROBOTPERF_CXX_FLAGS} ${_robotperf_compile_options}")
string(STRIP "${ROBOTPERF_CXX_FLAGS}" ROBOTPERF_CXX_FLAGS)
if(ROBOTPERF_SANITIZE)
  set(ROBOTPERF_SANITIZE_BOOL true)
else()
  set(ROBOTPERF_SANITIZE_BOOL false)
endif()
configure_file(${CMAKE_CURRENT_LIST_DIR}/build_info.hpp.in
               ${CMAKE_BINARY_DIR}/generated/robotperf/build_info.hpp @ONLY)
