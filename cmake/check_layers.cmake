# Fails when a file includes a header of a subsystem its own subsystem may not depend on, so that
# dependencies keep pointing one way:
#   tools, main -> viewer -> runtime (the core never includes the viewer)
#   tools, main -> runtime -> sessions -> map_files -> mapping -> tracking -> capture -> base
#                  runtime -> sessions -> config -> mapping, slam (every key of a run)
#                  runtime -> drivers -> capture;   slam -> tracking (loop closure; mapping never
#                  sees it);   eval -> sim -> base;   eval -> capture
#   (the run: threads, mode, signals; sessions: what a run leaves to go on from, merging them, a
#   fleet; map_files: map and trajectory file formats; config: the layers' option structs joined)
#   launcher (the `rgbdmap` command: libc only, includes no rgbdmap header)
#   ros (ros/: the ROS adapter) -> runtime and below; nothing includes ros, and no file outside
#   ros/ includes a ROS header (the core builds without ROS)
#   main (src/main.cpp, the rgbdmap-core program) -> what tools may include
#   plugins (plugins/: modules loaded at run time) -> base (the interface they implement)
#   tests, bench -> any layer of the core;   fuzz -> any layer but the viewer and tools
# Headers included by a plain path ("x.hpp", "openni2/x.hpp") are private to their folder: only
# files in it include them (and ros/tests the shared test support of tests/), so that no layer
# reaches into tests/, bench/ or fuzz/ or into another folder's private headers.
# Run as a build step: cmake -DSOURCE_DIR=<root> -P check_layers.cmake
# (tests/layering_check.cmake runs it on small trees with includes against the layering.)
cmake_policy(SET CMP0057 NEW)
set(allowed_base base)
set(allowed_capture base capture)
set(allowed_tracking base capture tracking)
set(allowed_mapping base capture tracking mapping)
set(allowed_slam base capture tracking slam)
set(allowed_sim base sim)
set(allowed_eval base capture sim eval)
set(allowed_drivers base capture drivers)
set(allowed_config base capture tracking mapping slam config)
set(allowed_map_files base capture tracking mapping map_files)
set(allowed_sessions base capture tracking mapping slam config map_files sessions)
set(core base capture tracking mapping slam drivers config map_files sessions runtime)
set(allowed_runtime ${core})
set(allowed_viewer base capture tracking mapping slam config map_files sessions runtime viewer)
set(allowed_tools ${core} sim eval viewer tools)
set(allowed_launcher "")
set(allowed_ros ${core} ros)
set(allowed_main ${allowed_tools})
set(allowed_plugins base)
set(allowed_tests ${core} sim eval viewer tools)
set(allowed_bench ${allowed_tests})
set(allowed_fuzz ${core} sim eval)

set(violations "")
set(layers base capture tracking mapping slam sim eval drivers config map_files sessions runtime
  viewer tools launcher ros main plugins tests bench fuzz)
foreach(layer ${layers})
  file(GLOB_RECURSE files
    ${SOURCE_DIR}/src/${layer}/*.c
    ${SOURCE_DIR}/src/${layer}/*.cpp ${SOURCE_DIR}/src/${layer}/*.hpp
    ${SOURCE_DIR}/include/rgbdmap/${layer}/*.hpp)
  if(layer STREQUAL "drivers")
    file(GLOB_RECURSE more ${SOURCE_DIR}/drivers/*.cpp ${SOURCE_DIR}/drivers/*.hpp)
    list(APPEND files ${more})
  elseif(layer STREQUAL "tools")
    file(GLOB more ${SOURCE_DIR}/tools/*.cpp ${SOURCE_DIR}/tools/*.hpp)
    list(APPEND files ${more})
  elseif(layer STREQUAL "ros")
    file(GLOB_RECURSE files ${SOURCE_DIR}/ros/*.cpp ${SOURCE_DIR}/ros/*.hpp)
  elseif(layer STREQUAL "main")
    file(GLOB files ${SOURCE_DIR}/src/*.cpp)
  elseif(layer MATCHES "^(plugins|tests|bench|fuzz)$")
    file(GLOB_RECURSE files ${SOURCE_DIR}/${layer}/*.cpp ${SOURCE_DIR}/${layer}/*.hpp)
  endif()
  foreach(file ${files})
    file(STRINGS ${file} includes REGEX "^#include \"rgbdmap/[a-z_]+/")
    foreach(line ${includes})
      string(REGEX REPLACE "^#include \"rgbdmap/([a-z_]+)/.*" "\\1" target "${line}")
      if(NOT target IN_LIST allowed_${layer})
        file(RELATIVE_PATH rel ${SOURCE_DIR} ${file})
        string(APPEND violations "  ${rel} (${layer}) includes ${target}: ${line}\n")
      endif()
    endforeach()
    file(STRINGS ${file} private_includes REGEX "^#include \"[^\"]+\"")
    list(FILTER private_includes EXCLUDE REGEX "^#include \"rgbdmap/")
    get_filename_component(folder ${file} DIRECTORY)
    file(RELATIVE_PATH rel_folder ${SOURCE_DIR} ${folder})
    foreach(line ${private_includes})
      string(REGEX REPLACE "^#include \"([^\"]+)\".*" "\\1" header "${line}")
      if(header MATCHES "(^|/)\\.\\.(/|$)" OR NOT EXISTS ${folder}/${header})
        if(NOT (rel_folder STREQUAL "ros/tests" AND header MATCHES "^[^/]+$" AND
                EXISTS ${SOURCE_DIR}/tests/${header}))
          file(RELATIVE_PATH rel ${SOURCE_DIR} ${file})
          string(APPEND violations "  ${rel} includes a header private to another folder: ${line}\n")
        endif()
      endif()
    endforeach()
  endforeach()
endforeach()
# ROS headers only in ros/: the core, its tools and tests build where ROS is not installed.
file(GLOB_RECURSE core_files ${SOURCE_DIR}/src/*.cpp ${SOURCE_DIR}/src/*.hpp ${SOURCE_DIR}/src/*.c
  ${SOURCE_DIR}/include/*.hpp ${SOURCE_DIR}/drivers/*.cpp ${SOURCE_DIR}/drivers/*.hpp
  ${SOURCE_DIR}/tools/*.cpp ${SOURCE_DIR}/tools/*.hpp ${SOURCE_DIR}/tests/*.cpp
  ${SOURCE_DIR}/tests/*.hpp ${SOURCE_DIR}/plugins/*.cpp ${SOURCE_DIR}/fuzz/*.cpp
  ${SOURCE_DIR}/fuzz/*.hpp ${SOURCE_DIR}/bench/*.cpp ${SOURCE_DIR}/bench/*.hpp)
foreach(file ${core_files})
  file(STRINGS ${file} ros_includes REGEX
    "^#include [<\"](ros|rosbag|sensor_msgs|geometry_msgs|std_srvs|std_msgs|tf2|tf2_ros)/")
  foreach(line ${ros_includes})
    file(RELATIVE_PATH rel ${SOURCE_DIR} ${file})
    string(APPEND violations "  ${rel} includes a ROS header outside ros/: ${line}\n")
  endforeach()
endforeach()

if(violations)
  message(FATAL_ERROR "Includes against the layering (see cmake/check_layers.cmake):\n${violations}")
endif()
