# Fails when a compile command defines a macro whose value holds a path of this checkout or
# build tree, except tests/support/test_data.cpp's (the one file meant to carry them), or when
# a unity batch includes a source by its absolute path.
#
#   cmake -DSOURCE_DIR=. -DBUILD_DIR=build -P tests/clone_paths_check.cmake
#
# ccache (scripts/build-env.sh: CCACHE_BASEDIR) rewrites the checkout's paths in -I flags and
# in the source file's name to relative ones, but not a path inside a -D value: a file compiled
# with one gets a new cache key in every clone, and CI builds a fresh clone each time (tests
# name the programs they run by their path inside the build tree instead: tests/CMakeLists.txt,
# findmug_test_program_paths).
foreach(var SOURCE_DIR BUILD_DIR)
  if(NOT ${var})
    message(FATAL_ERROR "usage: cmake -DSOURCE_DIR=<checkout> -DBUILD_DIR=<build tree> -P clone_paths_check.cmake")
  endif()
  get_filename_component(${var} "${${var}}" REALPATH)
endforeach()
set(commands_file ${BUILD_DIR}/compile_commands.json)
if(NOT EXISTS ${commands_file})
  message(FATAL_ERROR "${commands_file} is missing (CMAKE_EXPORT_COMPILE_COMMANDS)")
endif()

# A path as it appears in a -D value of compile_commands.json (-DNAME=\"PATH...\"), as a regex.
function(define_with_path_regex path out)
  string(REGEX REPLACE "([][+.*?()^$|\\\\])" "\\\\\\1" escaped "${path}")
  set(${out} "-D[A-Za-z_0-9]+=[^ ]*${escaped}" PARENT_SCOPE)
endfunction()
define_with_path_regex("${SOURCE_DIR}" source_regex)
define_with_path_regex("${BUILD_DIR}" build_regex)

# Each entry lists "directory", "command", "file" and "output", in that order.
file(STRINGS ${commands_file} lines REGEX "^ *\"(command|file)\": ")
set(command "")
set(checked 0)
set(carrier_seen FALSE)
set(bad "")
set(batch_files "")
foreach(line IN LISTS lines)
  if(line MATCHES "^ *\"command\": ")
    set(command "${line}")
    continue()
  endif()
  string(REGEX REPLACE "^ *\"file\": \"(.*)\",?$" "\\1" file "${line}")
  math(EXPR checked "${checked} + 1")
  set(has_path FALSE)
  if(command MATCHES "${source_regex}" OR command MATCHES "${build_regex}")
    set(has_path TRUE)
  endif()
  if(file MATCHES "/[Uu]nity/[^/]+\\.(cpp|cxx)$")
    list(APPEND batch_files "${file}")
  endif()
  if(file MATCHES "tests/support/test_data\\.cpp$")
    set(carrier_seen ${has_path})
  elseif(has_path)
    list(APPEND bad "${file}")
  endif()
endforeach()

if(checked LESS 100)
  message(FATAL_ERROR "only ${checked} compile commands read from ${commands_file}")
endif()
# The check must see the paths where they are meant to be, or its pattern finds nothing.
if(NOT carrier_seen)
  message(FATAL_ERROR "tests/support/test_data.cpp's command shows no path of ${SOURCE_DIR} or "
                      "${BUILD_DIR}: the pattern of this check no longer matches the paths")
endif()
if(bad)
  list(JOIN bad "\n  " bad_text)
  message(FATAL_ERROR "a path of this checkout or build tree in a -D value (a new ccache key in "
                      "every clone; name it at run time, as tests/support/test_data.hpp does):\n  ${bad_text}")
endif()

# The unity batches (CMakeLists.txt, findmug_unity_batches) name their sources by their path
# inside the checkout; CMake's own UNITY_BUILD would write absolute ones.
file(STRINGS ${BUILD_DIR}/CMakeCache.txt unity_setting REGEX "^FINDMUG_UNITY:BOOL=")
if(unity_setting MATCHES "=ON$" AND NOT batch_files)
  message(FATAL_ERROR "FINDMUG_UNITY is ON but ${BUILD_DIR} holds no unity batch file")
endif()
foreach(batch IN LISTS batch_files)
  file(READ ${batch} text)
  string(FIND "${text}" "${SOURCE_DIR}/" at)
  if(NOT at EQUAL -1 OR text MATCHES "#include \"/")
    list(APPEND bad_batches ${batch})
  endif()
endforeach()
if(bad_batches)
  list(JOIN bad_batches "\n  " bad_text)
  message(FATAL_ERROR "unity batches that include a source by its absolute path (a new ccache "
                      "key in every clone):\n  ${bad_text}")
endif()
list(LENGTH batch_files batch_count)
message(STATUS "${checked} compile commands: no path of the checkout or build tree in a define "
               "but test_data.cpp's; ${batch_count} unity batches name their sources inside the checkout")
