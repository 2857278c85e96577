# Every child folder of the current one that has a CMakeLists.txt, in sorted order.
macro(clothbake_add_all_subdirs)
  file(GLOB _children LIST_DIRECTORIES true RELATIVE ${CMAKE_CURRENT_SOURCE_DIR} ${CMAKE_CURRENT_SOURCE_DIR}/*)
  list(SORT _children)
  foreach(_child ${_children})
    if(IS_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}/${_child} AND EXISTS ${CMAKE_CURRENT_SOURCE_DIR}/${_child}/CMakeLists.txt)
      add_subdirectory(${_child})
    endif()
  endforeach()
endmacro()

# clothbake_add_gtest(NAME SOURCES... LIBS ... [LABELS ...] [SHARDS N]): one gtest executable, run
# as one ctest entry, or as N entries NAME_1_of_N .. NAME_N_of_N that each run every N-th test case
# (gtest's own sharding, GTEST_TOTAL_SHARDS / GTEST_SHARD_INDEX) so that ctest runs them side by
# side and none runs for minutes.
function(clothbake_add_gtest name)
  cmake_parse_arguments(ARG "" "SHARDS" "SOURCES;LIBS;LABELS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS} GTest::gtest GTest::gtest_main GTest::gmock)
  target_compile_definitions(${name} PRIVATE
    CLOTHBAKE_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    CLOTHBAKE_BINARY_DIR="${PROJECT_BINARY_DIR}")
  # One ctest entry per binary (or per shard), not per test case: every test process pays the
  # dynamic loading of OpenImageIO's ~260 shared libraries (about a second on a loaded machine),
  # which dominated the suite's time when each of hundreds of cases ran in its own process. gtest
  # prints the failing cases with --output-on-failure.
  if(NOT ARG_SHARDS OR ARG_SHARDS LESS 2)
    add_test(NAME ${name} COMMAND ${name} --gtest_color=no)
    set_tests_properties(${name} PROPERTIES LABELS "${ARG_LABELS}" TIMEOUT 1200)
    return()
  endif()
  math(EXPR _last "${ARG_SHARDS} - 1")
  foreach(_shard RANGE ${_last})
    math(EXPR _number "${_shard} + 1")
    set(_test ${name}_${_number}_of_${ARG_SHARDS})
    add_test(NAME ${_test} COMMAND ${name} --gtest_color=no)
    set_tests_properties(${_test} PROPERTIES LABELS "${ARG_LABELS}" TIMEOUT 1200
      ENVIRONMENT "GTEST_TOTAL_SHARDS=${ARG_SHARDS};GTEST_SHARD_INDEX=${_shard}")
  endforeach()
endfunction()
