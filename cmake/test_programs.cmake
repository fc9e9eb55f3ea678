# How a test program is built and how its tests reach CTest (tests/ and ros/tests/).
include(GoogleTest)

# What each sanitizer run of scripts/test.sh builds: the programs whose tests it runs, and what
# those run. ThreadSanitizer takes the threaded programs (label threads, threads-openni2),
# AddressSanitizer + UBSan the rest but those at scale and the ROS programs that start a master
# (and the OpenNI2 ones, threaded but run there too: their drivers parse what devices send).
add_custom_target(threaded_tests)
add_custom_target(asan_tests)

# A test program or library: the project's warnings, the shared precompiled headers, and -O1
# for its own code in optimised builds. What a test exercises runs in the layers, compiled as the
# build says (-O3 in release); a test file's own code compiles in half the time at -O1 (14 s ->
# 7 s for test_png_decoder.cpp), and the test programs were 40% of a release build.
# NO_PRECOMPILED_HEADERS: for programs whose include paths differ from the layers' (ROS).
function(rgbdmap_test_target name)
  cmake_parse_arguments(arg "NO_PRECOMPILED_HEADERS" "" "" ${ARGN})
  rgbdmap_target_defaults(${name})
  if(NOT arg_NO_PRECOMPILED_HEADERS)
    rgbdmap_precompiled_headers(${name})
  endif()
  target_compile_options(${name} PRIVATE $<$<CONFIG:Release,RelWithDebInfo,MinSizeRel>:-O1>)
endfunction()

# rgbdmap_add_tests(<program> SOURCE <file> LABEL <label> TIMEOUT <s>
#                   [PROPERTIES <ctest properties>...])
# Each TEST of the program's source file becomes a CTest test labelled <label>, or <label>-long
# when tests/long_tests.cmake names it. One label a test: ctest -L and -LE take regular expressions,
# so "threads-long" is selected by -L threads and left out by -LE long. RGBDMAP_LONG_TESTS is set
# by the calling folder (tests/long_tests.cmake). The tests are read from
# the source at configure time (gtest_add_tests) rather than listed by running each program after
# it is built: that cost 1-3 s a program and build, and a test needs its own label before then.
function(rgbdmap_add_tests name)
  cmake_parse_arguments(arg "" "SOURCE;LABEL;TIMEOUT" "PROPERTIES" ${ARGN})
  gtest_add_tests(TARGET ${name} SOURCES ${arg_SOURCE} TEST_LIST tests)
  if(arg_LABEL MATCHES "^threads")
    add_dependencies(threaded_tests ${name})
  endif()
  if(NOT arg_LABEL MATCHES "^threads$|^scale$|master")
    add_dependencies(asan_tests ${name})
  endif()
  set_tests_properties(${tests} PROPERTIES LABELS ${arg_LABEL} TIMEOUT ${arg_TIMEOUT}
    SKIP_REGULAR_EXPRESSION "\\[  SKIPPED \\]" ${arg_PROPERTIES})
  # ctest -j starts the tests of highest COST first. A clean build has no timings of its own yet
  # (Testing/Temporary/CTestCostData.txt) and would start them in the order they are declared: the
  # programs at scale come last, and their laps (40-260 s each in a clean run at ctest -j 3,
  # rendering their sequences) ran at the end.
  if(arg_LABEL MATCHES "^scale$|master")
    set_tests_properties(${tests} PROPERTIES COST 60)
  endif()
  foreach(test ${tests})
    if(test IN_LIST RGBDMAP_LONG_TESTS)
      set_tests_properties(${test} PROPERTIES LABELS ${arg_LABEL}-long COST 20)
      set_property(GLOBAL APPEND PROPERTY RGBDMAP_LONG_TESTS_FOUND ${test})
    endif()
  endforeach()
endfunction()

# Fails the configuration when the folder's RGBDMAP_LONG_TESTS names a test that does not exist.
function(rgbdmap_check_long_tests)
  get_property(found GLOBAL PROPERTY RGBDMAP_LONG_TESTS_FOUND)
  foreach(test ${RGBDMAP_LONG_TESTS})
    if(NOT test IN_LIST found)
      message(FATAL_ERROR "tests/long_tests.cmake: ${test} is no test of this build")
    endif()
  endforeach()
endfunction()
