# Precompiled headers. Nearly every file includes Eigen's dense and sparse cores, fmt and the standard library's
# containers (through solvers/ode_system.hpp and the headers over it): about 3.5 s of parsing a file, paid by some
# 180 files of a fresh build. They are parsed once for each kind of target whose flags they must share:
# the libraries (position-independent code), the programs (position-independent executables) and the tests
# (GoogleTest's header too); each target reuses its kind's. The solvers, built with OpenMP (whose _OPENMP Eigen's
# headers read), precompile their own. scripts/build-times lists a build's compiler time and its slowest files.
# GCC only (the release and debug presets): clang, the fuzz preset's, refuses a header precompiled under other
# options with an error where GCC warns and reads the headers instead, and the fuzz build is two programs.
if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
  function(stepwise_reuse_pch kind)
  endfunction()
  function(stepwise_own_pch target)
  endfunction()
  return()
endif()

set(stepwise_pch_headers <Eigen/Dense> <Eigen/SparseCore> <fmt/format.h> <algorithm> <array> <cmath> <functional> <map> <memory> <optional>
    <span> <string> <string_view> <vector>)

# the kinds' providers: a file with nothing of its own, compiled with the kind's flags and no macro of its own (one
# defined there and not where the headers are read makes GCC refuse them)
add_library(stepwise_pch_library OBJECT ${CMAKE_CURRENT_LIST_DIR}/pch_provider.cpp)
target_link_libraries(stepwise_pch_library PRIVATE stepwise_flags Eigen3::Eigen fmt::fmt)
target_precompile_headers(stepwise_pch_library PRIVATE ${stepwise_pch_headers})
add_executable(stepwise_pch_program ${CMAKE_CURRENT_LIST_DIR}/pch_main.cpp)
target_link_libraries(stepwise_pch_program PRIVATE stepwise_flags Eigen3::Eigen fmt::fmt)
target_precompile_headers(stepwise_pch_program PRIVATE ${stepwise_pch_headers})
add_executable(stepwise_pch_test ${CMAKE_CURRENT_LIST_DIR}/pch_provider.cpp)
target_link_libraries(stepwise_pch_test PRIVATE stepwise_flags Eigen3::Eigen fmt::fmt GTest::gtest_main)
target_precompile_headers(stepwise_pch_test PRIVATE ${stepwise_pch_headers} <gtest/gtest.h>)


# stepwise_reuse_pch(KIND target...): each target's files read KIND's precompiled headers (library, program or test)
function(stepwise_reuse_pch kind)
  foreach(target ${ARGN})
    target_precompile_headers(${target} REUSE_FROM stepwise_pch_${kind})
  endforeach()
endfunction()

# stepwise_own_pch(target): the target precompiles the headers itself (its flags are its own: the solvers' OpenMP)
function(stepwise_own_pch target)
  target_precompile_headers(${target} PRIVATE ${stepwise_pch_headers})
endfunction()
