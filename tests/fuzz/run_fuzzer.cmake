# ctest -R fuzz_reader_20s: (compile the harness with clang++ if CLANGXX is set, then) run the
# fuzzer for SECONDS on a scratch copy of the seed corpus. A crash fails the test and leaves the
# reproducer (crash-*) in WORK_DIR.
file(REMOVE_RECURSE ${WORK_DIR}/corpus)
file(MAKE_DIRECTORY ${WORK_DIR}/corpus)
file(GLOB _seeds ${SEED_CORPUS}/*)
file(COPY ${_seeds} DESTINATION ${WORK_DIR}/corpus)
if(CLANGXX)
  string(REPLACE "|" ";" _sources "${SOURCES}")
  string(REPLACE "|" ";" _flags "${FLAGS}")
  if(NOT STD)
    set(STD c++17)
  endif()
  # Optional: a second include directory (generated headers) and libraries linked after the
  # instrumented sources ("|"-separated: the project's static libraries, then -l system ones).
  set(_extra "")
  if(EXTRA_INCLUDE_DIR)
    list(APPEND _extra -I${EXTRA_INCLUDE_DIR})
  endif()
  set(_libs "")
  if(LIBS)
    string(REPLACE "|" ";" _libs "${LIBS}")
    set(_libs -Wl,--start-group ${_libs} -Wl,--end-group)
  endif()
  execute_process(COMMAND ${CLANGXX} -std=${STD} ${_flags} -I${INCLUDE_DIR} ${_extra} ${_sources}
                          ${_libs} -o ${FUZZER}
                  RESULT_VARIABLE rc ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "compiling the fuzzer with ${CLANGXX} failed:\n${err}")
  endif()
endif()
execute_process(COMMAND ${FUZZER} -max_total_time=${SECONDS} -print_final_stats=1
                        -artifact_prefix=${WORK_DIR}/ ${WORK_DIR}/corpus
                WORKING_DIRECTORY ${WORK_DIR}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
string(REGEX MATCH "stat::number_of_executed_units: *[0-9]+" _runs "${err}")
message(STATUS "${FUZZER}: ${_runs}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${FUZZER} found a crash (exit ${rc}):\n${err}")
endif()
