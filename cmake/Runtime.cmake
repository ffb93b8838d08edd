# The runtime libraries: what robotperf and the plug-ins it loads share (msgs, rmw, graph, the
# tracepoint provider and the plug-in API). They are shared libraries so that a process holds one
# copy of each (one registry, one set of type supports, one tracepoint provider), and they are
# installed with their headers for plug-ins to build against (find_package(robotperf)).
include(GNUInstallDirs)

# Installed programs and libraries find the runtime libraries beside them.
set(CMAKE_INSTALL_RPATH "$ORIGIN/../${CMAKE_INSTALL_LIBDIR}")

# robotperf_runtime_library(<target> [HEADERS <include dir>]): a runtime library, its public
# headers (the folder holding robotperf/) installed under include/.
function(robotperf_runtime_library target)
  cmake_parse_arguments(R "" "HEADERS" "" ${ARGN})
  # Imported as robotperf::msgs, robotperf::plugin, ...
  string(REGEX REPLACE "^robotperf_" "" export_name ${target})
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${export_name}
    VERSION ${PROJECT_VERSION} SOVERSION ${PROJECT_VERSION_MAJOR}.${PROJECT_VERSION_MINOR})
  install(TARGETS ${target} EXPORT robotperfTargets
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
    INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
  if(R_HEADERS)
    install(DIRECTORY ${R_HEADERS}/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
  endif()
endfunction()
