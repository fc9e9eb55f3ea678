# The layering check (cmake/check_layers.cmake) on small trees: one whose includes follow the
# layers passes, and each include against them fails the check with a message naming the file.
# Registered as a CTest test in tests/CMakeLists.txt:
#   cmake -DSOURCE_DIR=<repository> -DWORK_DIR=<scratch folder> -P layering_check.cmake
cmake_minimum_required(VERSION 3.18)

# Writes a tree under `root`: each pair in ARGN is a file (relative) and the header it includes.
function(write_tree root)
  file(REMOVE_RECURSE ${root})
  set(pairs ${ARGN})
  list(LENGTH pairs count)
  math(EXPR last "${count} - 1")
  foreach(i RANGE 0 ${last} 2)
    math(EXPR j "${i} + 1")
    list(GET pairs ${i} path)
    list(GET pairs ${j} header)
    file(WRITE ${root}/${path} "#include \"${header}\"\n")
  endforeach()
endfunction()

function(run_check root result output)
  execute_process(COMMAND ${CMAKE_COMMAND} -DSOURCE_DIR=${root}
                          -P ${SOURCE_DIR}/cmake/check_layers.cmake
                  RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
  set(${result} ${code} PARENT_SCOPE)
  set(${output} "${out}${err}" PARENT_SCOPE)
endfunction()

# Includes that point the way the layers do: down from the run to sessions, map files and the
# configuration, and from each of them to the layers below.
set(follows
  src/runtime/pipeline.cpp rgbdmap/sessions/session_file.hpp
  src/runtime/checkpoint_writer.cpp rgbdmap/map_files/pcd_file.hpp
  src/runtime/source_factory.cpp rgbdmap/config/config.hpp
  src/sessions/session_file.cpp rgbdmap/map_files/atomic_write.hpp
  src/sessions/session_merge.cpp rgbdmap/config/config.hpp
  src/sessions/session_stream.cpp rgbdmap/slam/loop_closer.hpp
  src/map_files/ply_file.cpp rgbdmap/mapping/triangle_mesh.hpp
  src/config/config.cpp rgbdmap/slam/loop_options.hpp
  tools/merge.cpp rgbdmap/sessions/session_merge.hpp
  ros/merger/main.cpp rgbdmap/sessions/fleet_merger.hpp
  tests/test_session_file.cpp rgbdmap/sessions/session_file.hpp)
write_tree(${WORK_DIR}/follows ${follows})
run_check(${WORK_DIR}/follows code output)
if(NOT code EQUAL 0)
  message(FATAL_ERROR "a tree that follows the layers failed the check:\n${output}")
endif()

# Each: a file, the header it must not include, and the layer named in the message.
set(against
  "src/map_files/grid_file.cpp|rgbdmap/sessions/session_file.hpp|map_files) includes sessions"
  "src/map_files/octomap_file.cpp|rgbdmap/config/config.hpp|map_files) includes config"
  "src/map_files/trajectory_stream.cpp|rgbdmap/runtime/output_files.hpp|map_files) includes runtime"
  "src/sessions/session_file.cpp|rgbdmap/runtime/output_files.hpp|sessions) includes runtime"
  "include/rgbdmap/sessions/fleet_merger.hpp|rgbdmap/viewer/viewer.hpp|sessions) includes viewer"
  "include/rgbdmap/config/config.hpp|rgbdmap/sessions/session_file.hpp|config) includes sessions"
  "src/config/run_options.cpp|rgbdmap/map_files/atomic_write.hpp|config) includes map_files"
  "src/mapping/mapper.cpp|rgbdmap/map_files/ply_file.hpp|mapping) includes map_files"
  "src/slam/loop_closer.cpp|rgbdmap/sessions/session_file.hpp|slam) includes sessions"
  "src/base/file_io.cpp|rgbdmap/config/config.hpp|base) includes config")
foreach(case ${against})
  string(REPLACE "|" ";" fields "${case}")
  list(GET fields 0 path)
  list(GET fields 1 header)
  list(GET fields 2 says)
  write_tree(${WORK_DIR}/against ${follows} ${path} ${header})
  run_check(${WORK_DIR}/against code output)
  if(code EQUAL 0)
    message(FATAL_ERROR "${path} including ${header} passed the layering check")
  endif()
  string(FIND "${output}" "${path} (${says}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "the check failed for ${path} including ${header}, but its message does "
                        "not say '${path} (${says}':\n${output}")
  endif()
  message(STATUS "refused, as it must be: ${path} includes ${header}")
endforeach()
