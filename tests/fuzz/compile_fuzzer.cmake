# Build step of a libFuzzer harness (tests/fuzz/CMakeLists.txt, clothbake_fuzz_harness): compile
# the harness and the sources it covers with clang++ and the fuzzer flags into FUZZER, linking
# LIBS after them. Runs at build time, so that the fuzz tests spend their seconds fuzzing.
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
