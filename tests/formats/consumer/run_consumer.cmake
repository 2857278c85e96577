# ctest -R formats_package_consumer: install the reader component, build a consumer, run it.
cmake_policy(SET CMP0057 NEW)  # if(... IN_LIST ...) in script mode
file(REMOVE_RECURSE ${WORK_DIR})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD_DIR} --component reader
                        --prefix ${WORK_DIR}/prefix
                RESULT_VARIABLE rc OUTPUT_QUIET)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "cmake --install --component reader failed (${rc})")
endif()
if(NOT EXISTS ${WORK_DIR}/prefix/lib/cmake/clothbake/clothbakeConfig.cmake AND
   NOT EXISTS ${WORK_DIR}/prefix/lib64/cmake/clothbake/clothbakeConfig.cmake)
  file(GLOB_RECURSE _configs ${WORK_DIR}/prefix/*Config.cmake)
  if(NOT _configs)
    message(FATAL_ERROR "no clothbakeConfig.cmake installed")
  endif()
endif()
# One translation unit per installed header, each including only that header: every header the
# package ships compiles on its own in a C++17 project outside the tree, so a header that includes
# one the package does not install (model/asg.hpp once) fails here.
file(GLOB_RECURSE _headers RELATIVE ${WORK_DIR}/prefix/include ${WORK_DIR}/prefix/include/*.hpp)
list(LENGTH _headers _count)
if(_count LESS 2 OR NOT "clothbake/model/asg.hpp" IN_LIST _headers OR
   NOT "clothbake/formats/reader/visibility_sections.hpp" IN_LIST _headers)
  message(FATAL_ERROR "the installed headers are incomplete: ${_headers}")
endif()
set(_tus ${WORK_DIR}/header_tus)
file(MAKE_DIRECTORY ${_tus})
foreach(_h ${_headers})
  string(REGEX REPLACE "[/.]" "_" _name "${_h}")
  string(REGEX REPLACE "^clothbake/" "" _include "${_h}")
  file(WRITE ${_tus}/${_name}.cpp "#include <${_include}>\n")
endforeach()
message(STATUS "consumer: compiling ${_count} installed headers one by one")
execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR}/build -G ${GENERATOR}
                        -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=${CXX}
                        -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix -DHEADER_TUS=${_tus}
                RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "configuring the consumer failed (${rc})")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${WORK_DIR}/build RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "building the consumer failed (${rc})")
endif()
execute_process(COMMAND ${WORK_DIR}/build/consumer ${GOLDEN} RESULT_VARIABLE rc
                OUTPUT_VARIABLE out)
if(NOT rc EQUAL 0 OR NOT out MATCHES "resolution 4 yarns 2")
  message(FATAL_ERROR "consumer failed (${rc}): ${out}")
endif()
message(STATUS "consumer: ${out}")
