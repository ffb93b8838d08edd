# Checks that the generic parts of robotperf know no category: no source file of FOLDERS includes a
# category's headers (robotperf/<category>/..., robotperf/categories/...) or reaches into
# src/categories, and no CMake file of theirs links a category's library (robotperf_<category>,
# robotperf_categories). The categories are the folders of src/categories, so a new one is
# checked without naming it here.
#
#   cmake -DSOURCE_DIR=<repository> -DFOLDERS=<folder>[:<folder>...] -P category_free_test.cmake
#
# FOLDERS are relative to SOURCE_DIR, ':'-separated (a ';' would not survive add_test). Prints one line per finding and fails when there is any.
if(NOT SOURCE_DIR OR NOT FOLDERS)
  message(FATAL_ERROR "usage: cmake -DSOURCE_DIR=<repository> -DFOLDERS=<folder>[:<folder>...] -P ${CMAKE_CURRENT_LIST_FILE}")
endif()
string(REPLACE ":" ";" FOLDERS "${FOLDERS}")

file(GLOB entries LIST_DIRECTORIES true RELATIVE ${SOURCE_DIR}/src/categories
  ${SOURCE_DIR}/src/categories/*)
set(names categories)
foreach(entry ${entries})
  if(IS_DIRECTORY ${SOURCE_DIR}/src/categories/${entry}
     AND EXISTS ${SOURCE_DIR}/src/categories/${entry}/CMakeLists.txt)
    list(APPEND names ${entry})
  endif()
endforeach()
list(JOIN names "|" alternatives)
set(include_pattern "#[ \t]*include[ \t]*[<\"](robotperf/(${alternatives})/|([./]*/)*categories/)")
set(link_pattern "(robotperf_(${alternatives})([^A-Za-z0-9_]|$)|src/categories)")

set(findings "")
foreach(folder ${FOLDERS})
  if(NOT IS_DIRECTORY ${SOURCE_DIR}/${folder})
    message(FATAL_ERROR "${folder}: no such folder under ${SOURCE_DIR}")
  endif()
  file(GLOB_RECURSE sources ${SOURCE_DIR}/${folder}/*.cpp ${SOURCE_DIR}/${folder}/*.hpp
    ${SOURCE_DIR}/${folder}/*.h ${SOURCE_DIR}/${folder}/*.cu ${SOURCE_DIR}/${folder}/*.in)
  file(GLOB_RECURSE cmake_files ${SOURCE_DIR}/${folder}/CMakeLists.txt
    ${SOURCE_DIR}/${folder}/*.cmake)
  foreach(kind source cmake)
    if(kind STREQUAL "source")
      set(files ${sources})
      set(pattern "${include_pattern}")
      set(what "includes a category's header")
    else()
      set(files ${cmake_files})
      set(pattern "${link_pattern}")
      set(what "names a category's library")
    endif()
    foreach(file ${files})
      file(STRINGS ${file} lines)
      set(number 0)
      foreach(line IN LISTS lines)
        math(EXPR number "${number} + 1")
        # A CMake comment may name a library it does not link.
        if(kind STREQUAL "cmake" AND line MATCHES "^[ \t]*#")
          continue()
        endif()
        if(line MATCHES "${pattern}")
          file(RELATIVE_PATH shown ${SOURCE_DIR} ${file})
          string(STRIP "${line}" text)
          string(APPEND findings "${shown}:${number}: ${what}: ${text}\n")
        endif()
      endforeach()
    endforeach()
  endforeach()
endforeach()

if(findings)
  message("${findings}")
  message(FATAL_ERROR "category knowledge outside src/categories (categories: ${names})")
endif()
message(STATUS "${FOLDERS}: no category header included, no category library linked")
