# ctest -R fuzz_reader_20s: run the fuzzer FUZZER (built by compile_fuzzer.cmake at build time, or a
# CMake target) for SECONDS on a scratch copy of the seed corpus. A crash fails the test and leaves
# the reproducer (crash-*) in WORK_DIR.
file(REMOVE_RECURSE ${WORK_DIR}/corpus)
file(MAKE_DIRECTORY ${WORK_DIR}/corpus)
file(GLOB _seeds ${SEED_CORPUS}/*)
file(COPY ${_seeds} DESTINATION ${WORK_DIR}/corpus)
execute_process(COMMAND ${FUZZER} -max_total_time=${SECONDS} -print_final_stats=1
                        -artifact_prefix=${WORK_DIR}/ ${WORK_DIR}/corpus
                WORKING_DIRECTORY ${WORK_DIR}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
string(REGEX MATCH "stat::number_of_executed_units: *[0-9]+" _runs "${err}")
message(STATUS "${FUZZER}: ${_runs}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${FUZZER} found a crash (exit ${rc}):\n${err}")
endif()
