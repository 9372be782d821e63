# candi_library(<folder> [DEPS ...]): the library candi_<folder> from <folder>/*.cc (tests
# excluded), includes rooted at the repository, warnings on.
function(candi_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wno-unused-parameter)
  if(CANDI_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()

# candi_precompile(<target> [OWN]): a precompiled header of the standard and Eigen headers most of
# candi's sources include (Eigen/Core and Eigen/Geometry alone cost ~2.5 s of parsing per
# translation unit). It is built once, by candi_lib_pch (CMakeLists.txt), and shared by every
# library whose flags match it; a target whose own flags reach those headers or GCC's check of a
# header (-fPIC, -frounding-math from CGAL, render's -fno-math-errno) says OWN and builds its own
# (~6 s), with its own flags, when it has five or more sources. Measured 2026-11-27 on the 2-core
# VM, the library targets from scratch at -j2: 1,150 s of CPU without any, 934 s with one each
# (588 s and 479 s wall); sharing one saves another ~6 s a target and gives it to the small ones.
set(CANDI_LIB_PCH_HEADERS <Eigen/Core> <Eigen/Geometry> <algorithm> <cmath> <cstdint> <filesystem>
    <functional> <memory> <string> <vector>)
function(candi_precompile target)
  cmake_parse_arguments(ARG "OWN" "" "" ${ARGN})
  if(NOT ARG_OWN)
    target_precompile_headers(${target} REUSE_FROM candi_lib_pch)
    return()
  endif()
  get_target_property(sources ${target} SOURCES)
  list(LENGTH sources count)
  if(count GREATER_EQUAL 5)
    target_precompile_headers(${target} PRIVATE ${CANDI_LIB_PCH_HEADERS})
  endif()
endfunction()

function(candi_library folder)
  cmake_parse_arguments(ARG "OWN_PCH" "" "PUBLIC_DEPS;PRIVATE_DEPS;EXCLUDE" ${ARGN})
  file(GLOB_RECURSE sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/*.cc)
  list(FILTER sources EXCLUDE REGEX "_test\\.cc$")
  foreach(pattern ${ARG_EXCLUDE})
    list(FILTER sources EXCLUDE REGEX "${pattern}")
  endforeach()
  set(target candi_${folder})
  if(sources)
    add_library(${target} STATIC ${sources})
    target_include_directories(${target} PUBLIC ${PROJECT_SOURCE_DIR})
    target_link_libraries(${target} PUBLIC ${ARG_PUBLIC_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
    candi_warnings(${target})
    if(ARG_OWN_PCH)
      candi_precompile(${target} OWN)
    else()
      candi_precompile(${target})
    endif()
  else()
    add_library(${target} INTERFACE)
    target_include_directories(${target} INTERFACE ${PROJECT_SOURCE_DIR})
    target_link_libraries(${target} INTERFACE ${ARG_PUBLIC_DEPS})
  endif()
endfunction()

# Test code is compiled for build speed: -O1 (the code under test is in the -O3 libraries), in
# unity batches of eight files (CMake's UNITY_BUILD: the headers and templates a target's tests share
# are compiled once a batch, not once a file), and with a precompiled header of what every test
# includes (GoogleTest and Eigen cost ~8 s of parsing per translation unit on the 2-core machines
# this is built on). A batch is one translation unit, so the helpers in a test file's anonymous
# namespace share it with seven other files': give a helper a name no other test of the target
# gives a different meaning (the compiler names a clash; a helper that hides a library function of
# the same name is the case it cannot always catch). The header is built once, by
# candi_test_pch (CMakeLists.txt), and shared by every test target whose flags match it; a target
# whose dependencies add definitions that reach those headers (libtorch's -D_GLIBCXX_USE_CXX11_ABI)
# says OWN_PCH and builds its own when it has three or more sources.
set(CANDI_TEST_PCH_HEADERS <gtest/gtest.h> <Eigen/Core> <algorithm> <cmath> <cstdint> <filesystem>
    <functional> <memory> <string> <vector>)
function(candi_test_compile_options target)
  cmake_parse_arguments(ARG "OWN_PCH" "" "" ${ARGN})
  target_compile_options(${target} PRIVATE -O1)
  set_target_properties(${target} PROPERTIES UNITY_BUILD ON UNITY_BUILD_BATCH_SIZE 8)
  if(NOT ARG_OWN_PCH)
    target_precompile_headers(${target} REUSE_FROM candi_test_pch)
    return()
  endif()
  get_target_property(sources ${target} SOURCES)
  list(LENGTH sources count)
  if(count GREATER_EQUAL 3)
    target_precompile_headers(${target} PRIVATE ${CANDI_TEST_PCH_HEADERS})
  endif()
endfunction()

# candi_tests(<folder> [DEPS ...] [EXCLUDE regex...]): one test executable candi_<folder>_test from the unit tests
# beside the sources (<folder>/**/*_test.cc), registered with ctest at test time.
function(candi_tests folder)
  cmake_parse_arguments(ARG "OWN_PCH" "" "DEPS;EXCLUDE" ${ARGN})
  if(NOT CANDI_BUILD_TESTS)
    return()
  endif()
  file(GLOB_RECURSE tests CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/*_test.cc)
  foreach(pattern ${ARG_EXCLUDE})
    list(FILTER tests EXCLUDE REGEX "${pattern}")
  endforeach()
  if(NOT tests)
    return()
  endif()
  set(target candi_${folder}_test)
  add_executable(${target} ${tests})
  target_link_libraries(${target} PRIVATE candi_${folder} candi_test_util ${ARG_DEPS} GTest::gtest_main)
  candi_warnings(${target})
  if(ARG_OWN_PCH)
    candi_test_compile_options(${target} OWN_PCH)
  else()
    candi_test_compile_options(${target})
  endif()
  include(GoogleTest)
  # Discovery runs the executable at test time; 600 s, not 60, so that a loaded machine (libtorch
  # alone takes seconds to load) cannot fail a run by timing (`make test-stress`).
  gtest_discover_tests(${target} DISCOVERY_MODE PRE_TEST WORKING_DIRECTORY ${PROJECT_SOURCE_DIR}
                       PROPERTIES LABELS ${folder} DISCOVERY_TIMEOUT 600)
endfunction()
