# tests/layering/layers.cmake — the layering rule of the source tree, checked.
#
#   core    src/ROOM/, include/findmug/ROOM/ (findmug_core)       may use: nothing of ours
#   offline src/offline/, include/findmug/offline/ (findmug_offline: training, metrics,
#           the .mat reader)                                        may use: core
#   synth   src/synth/, include/findmug/synth/ (findmug_synth)     may use: core
#   lcm     lcmtypes/ (generated findmug_lcm:: headers)            may use: nothing of ours
#   io      io/ (findmug_io)                                       may use: core, lcm
#   cli     cli/ (findmug_cli)                                     may use: core
#   daemon  daemon/ (findmug_daemon, findmugd)                     may use: core, lcm, io, cli
#   clients clients/                                               may use: core, lcm, io, cli
#   tools   tools/                                                 may use: core, offline, synth, lcm,
#                                                                           io, cli, daemon
#   tests   tests/                                                 may use anything
# (tools may use the daemon's pipeline library: findmug-sequential runs it on one thread.)
#
# Three checks, each fails with a message naming the file or target and the rule:
#   * includes: every #include "..." / <...> of a layer's sources is matched against the
#     header prefixes of the layers it may not use (and the core may not include LCM);
#   * the core's rooms: inside the core, a room's files include only rooms below it
#     (findmug_core_rooms, the order DEVELOPERS.md documents);
#   * links (configure time only, needs the targets): LINK_LIBRARIES and
#     INTERFACE_LINK_LIBRARIES of every target defined in a layer's folder name only
#     targets of layers it may use.
# Included from the top-level CMakeLists.txt after all targets are defined (both
# checks; a violation stops the configure), and run by ctest `layering` in script
# mode (cmake -DFINDMUG_SOURCE_DIR=... -P layers.cmake: the include check).

# A path belongs to the last layer whose folder holds it (src/offline is offline, not core).
set(findmug_layers core offline synth lcm io cli daemon clients tools)
set(findmug_layer_dirs_core src include)
set(findmug_layer_dirs_offline src/offline include/findmug/offline)
set(findmug_layer_dirs_synth src/synth include/findmug/synth)
set(findmug_layer_dirs_lcm lcmtypes)
set(findmug_layer_dirs_io io)
set(findmug_layer_dirs_cli cli)
set(findmug_layer_dirs_daemon daemon)
set(findmug_layer_dirs_clients clients)
set(findmug_layer_dirs_tools tools)

set(findmug_layer_uses_core "")
set(findmug_layer_uses_offline core)
set(findmug_layer_uses_synth core)
set(findmug_layer_uses_lcm "")
set(findmug_layer_uses_io core lcm)
set(findmug_layer_uses_cli core)
set(findmug_layer_uses_daemon core lcm io cli)
set(findmug_layer_uses_clients core lcm io cli)
set(findmug_layer_uses_tools core offline synth lcm io cli daemon)

# What an #include of each layer looks like (regular expressions on the included name).
# The core's rooms (scripts/dev/rooms.py).
set(findmug_layer_headers_core
    "^findmug/(common|frame|cloud|ground|oversegmentation|features|learner|mrf|labels|segmenter|tables|objects|map|settings)/"
    "^findmug/version\\.hpp$")
set(findmug_layer_headers_offline "^findmug/offline/")
set(findmug_layer_headers_synth "^findmug/synth/")
set(findmug_layer_headers_lcm "^findmug_lcm/" "^lcm/")
set(findmug_layer_headers_io "^findmug/io/")
set(findmug_layer_headers_cli "^findmug_cli\\.hpp$" "^findmug_signals\\.hpp$" "^findmug_json\\.hpp$"
    "^program_settings\\.hpp$" "^CLI/")
set(findmug_layer_headers_daemon "^findmug/daemon/")
set(findmug_layer_headers_clients "^client_common\\.hpp$" "^picture\\.hpp$")
set(findmug_layer_headers_tools "^tool_common\\.hpp$" "^eval_report\\.hpp$" "^replay_check\\.hpp$"
    "^oni_writer\\.hpp$" "^search_sim\\.hpp$" "^findmug_tables\\.hpp$" "^strategies\\.hpp$"
    "^report\\.hpp$")

# Layer of a source-tree path relative to the top ("" if none, e.g. tests/).
function(findmug_layer_of relative out)
  set(result "")
  foreach(layer IN LISTS findmug_layers)
    foreach(dir IN LISTS findmug_layer_dirs_${layer})
      if(relative STREQUAL dir OR relative MATCHES "^${dir}/")
        set(result ${layer})
      endif()
    endforeach()
  endforeach()
  set(${out} "${result}" PARENT_SCOPE)
endfunction()

# --- includes -----------------------------------------------------------------------------
function(findmug_check_includes source_dir)
  set(problems "")
  foreach(layer IN LISTS findmug_layers)
    set(globs "")
    foreach(dir IN LISTS findmug_layer_dirs_${layer})
      list(APPEND globs ${source_dir}/${dir}/*.cpp ${source_dir}/${dir}/*.hpp ${source_dir}/${dir}/*.h
           ${source_dir}/${dir}/*.hpp.in)
    endforeach()
    file(GLOB_RECURSE files ${globs})
    set(forbidden "")
    foreach(other IN LISTS findmug_layers)
      if(other STREQUAL layer)
        continue()
      endif()
      list(FIND findmug_layer_uses_${layer} ${other} allowed)
      if(allowed EQUAL -1)
        list(APPEND forbidden ${other})
      endif()
    endforeach()
    foreach(file IN LISTS files)
      file(RELATIVE_PATH rel ${source_dir} ${file})
      findmug_layer_of("${rel}" file_layer)
      if(NOT file_layer STREQUAL layer)
        continue()  # in a sub-folder that is a layer of its own (src/offline in src)
      endif()
      file(STRINGS ${file} lines REGEX "^[ \t]*#[ \t]*include[ \t]*[<\"]")
      foreach(line IN LISTS lines)
        string(REGEX REPLACE "^[ \t]*#[ \t]*include[ \t]*[<\"]([^>\"]+)[>\"].*" "\\1" name "${line}")
        foreach(other IN LISTS forbidden)
          foreach(pattern IN LISTS findmug_layer_headers_${other})
            if(name MATCHES "${pattern}")
              file(RELATIVE_PATH rel ${source_dir} ${file})
              list(APPEND problems "${rel} (${layer}) includes <${name}> of layer ${other}")
            endif()
          endforeach()
        endforeach()
      endforeach()
    endforeach()
  endforeach()
  if(problems)
    list(JOIN problems "\n  " text)
    message(FATAL_ERROR "layering: a lower layer includes a higher one (rule in "
                        "tests/layering/layers.cmake, map in DEVELOPERS.md):\n  ${text}")
  endif()
endfunction()

# --- the core's rooms ---------------------------------------------------------------------
# Inside the core, a room may include only its own files and the rooms below it, lowest
# first (DEVELOPERS.md, "Layout"): the mechanism every room states its settings with sits at
# the bottom, the aggregate of all settings and the Segmenter that runs every step at the top.
set(findmug_core_rooms
    common settings.mechanism labels.ids frame cloud ground oversegmentation labels features mrf
    learner tables objects map settings segmenter)
# Files that are not of their folder's room ("FOLDER/NAME" without the extension = ROOM):
# the settings mechanism (settings/ is otherwise the aggregate) and the label ids and names,
# which frames carry (labels/ is otherwise the label image and its hole filling).
set(findmug_core_room_files
    "settings/settings=settings.mechanism"
    "labels/labels=labels.ids")

# The room of a core path relative to src/ or include/findmug/ ("" when it is no room's).
function(findmug_core_room relative out)
  string(REGEX REPLACE "\\.[a-z]+(\\.in)?$" "" stem "${relative}")
  set(room "")
  foreach(entry IN LISTS findmug_core_room_files)
    string(REPLACE "=" ";" pair "${entry}")
    list(GET pair 0 file_stem)
    list(GET pair 1 file_room)
    if(stem STREQUAL file_stem)
      set(room ${file_room})
    endif()
  endforeach()
  if(NOT room AND relative MATCHES "^([a-z_]+)/")
    list(FIND findmug_core_rooms ${CMAKE_MATCH_1} index)
    if(NOT index EQUAL -1)
      set(room ${CMAKE_MATCH_1})
    endif()
  endif()
  set(${out} "${room}" PARENT_SCOPE)
endfunction()

function(findmug_check_room_order source_dir)
  set(problems "")
  file(GLOB_RECURSE files ${source_dir}/src/*.cpp ${source_dir}/src/*.hpp
       ${source_dir}/include/findmug/*.hpp)
  foreach(file IN LISTS files)
    file(RELATIVE_PATH rel ${source_dir} ${file})
    string(REGEX REPLACE "^(src|include/findmug)/" "" in_core "${rel}")
    findmug_core_room("${in_core}" room)
    if(NOT room)
      continue()  # src/offline, src/synth: layers of their own
    endif()
    list(FIND findmug_core_rooms ${room} level)
    file(STRINGS ${file} lines REGEX "^[ \t]*#[ \t]*include[ \t]*[<\"]")
    foreach(line IN LISTS lines)
      string(REGEX REPLACE "^[ \t]*#[ \t]*include[ \t]*[<\"]([^>\"]+)[>\"].*" "\\1" name "${line}")
      string(REGEX REPLACE "^findmug/" "" included "${name}")
      if(NOT included MATCHES "/")
        continue()  # <map>, "version.hpp": no room's
      endif()
      findmug_core_room("${included}" included_room)
      if(NOT included_room)
        continue()
      endif()
      list(FIND findmug_core_rooms ${included_room} included_level)
      if(included_level GREATER level)
        list(APPEND problems "${rel} (room ${room}) includes <${name}> of room ${included_room}")
      endif()
    endforeach()
  endforeach()
  if(problems)
    list(JOIN findmug_core_rooms " < " order)
    list(JOIN problems "\n  " text)
    message(FATAL_ERROR "layering: a core room includes a room above it (order ${order}; rule in "
                        "tests/layering/layers.cmake, rooms in DEVELOPERS.md):\n  ${text}")
  endif()
endfunction()

# --- links (configure time) ---------------------------------------------------------------
function(findmug_collect_targets dir out)
  get_property(targets DIRECTORY ${dir} PROPERTY BUILDSYSTEM_TARGETS)
  get_property(subdirs DIRECTORY ${dir} PROPERTY SUBDIRECTORIES)
  foreach(sub IN LISTS subdirs)
    findmug_collect_targets(${sub} sub_targets)
    list(APPEND targets ${sub_targets})
  endforeach()
  set(${out} ${targets} PARENT_SCOPE)
endfunction()

function(findmug_target_layer target out)
  get_target_property(aliased ${target} ALIASED_TARGET)
  if(aliased)
    set(target ${aliased})
  endif()
  get_target_property(imported ${target} IMPORTED)
  set(layer "")
  if(NOT imported)
    get_target_property(dir ${target} SOURCE_DIR)
    file(RELATIVE_PATH rel ${PROJECT_SOURCE_DIR} ${dir})
    findmug_layer_of("${rel}" layer)
  endif()
  set(${out} "${layer}" PARENT_SCOPE)
endfunction()

function(findmug_check_links)
  findmug_collect_targets(${PROJECT_SOURCE_DIR} targets)
  set(problems "")
  foreach(target IN LISTS targets)
    findmug_target_layer(${target} layer)
    if(NOT layer)
      continue()
    endif()
    set(deps "")
    foreach(property LINK_LIBRARIES INTERFACE_LINK_LIBRARIES)
      get_target_property(value ${target} ${property})
      if(value)
        list(APPEND deps ${value})
      endif()
    endforeach()
    foreach(dep IN LISTS deps)
      # $<BUILD_INTERFACE:x>, $<LINK_ONLY:x> and the like: the target named inside.
      string(REGEX REPLACE "^\\$<[A-Z_]+:(.*)>$" "\\1" dep "${dep}")
      if(NOT TARGET "${dep}")
        continue()
      endif()
      findmug_target_layer(${dep} dep_layer)
      if(NOT dep_layer OR dep_layer STREQUAL layer)
        continue()
      endif()
      list(FIND findmug_layer_uses_${layer} ${dep_layer} allowed)
      if(allowed EQUAL -1)
        list(APPEND problems "${target} (${layer}) links ${dep} (${dep_layer})")
      endif()
    endforeach()
  endforeach()
  if(problems)
    list(JOIN problems "\n  " text)
    message(FATAL_ERROR "layering: a lower layer links a higher one (rule in "
                        "tests/layering/layers.cmake, map in DEVELOPERS.md):\n  ${text}")
  endif()
endfunction()

if(CMAKE_SCRIPT_MODE_FILE)
  if(NOT FINDMUG_SOURCE_DIR)
    message(FATAL_ERROR "usage: cmake -DFINDMUG_SOURCE_DIR=<source tree> -P layers.cmake")
  endif()
  findmug_check_includes(${FINDMUG_SOURCE_DIR})
  findmug_check_room_order(${FINDMUG_SOURCE_DIR})
  message(STATUS "layering: includes follow the layers and the core's room order")
else()
  findmug_check_includes(${PROJECT_SOURCE_DIR})
  findmug_check_room_order(${PROJECT_SOURCE_DIR})
  findmug_check_links()
endif()
