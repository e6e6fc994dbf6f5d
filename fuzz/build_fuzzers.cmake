# ctest fuzz/build (GCC builds): configure and build the libFuzzer targets in a clang tree of
# their own. Rebuilt every run (incrementally) so the fuzzers always test the current sources.
set(launcher "")
if(LAUNCHER)
  set(launcher -DCMAKE_CXX_COMPILER_LAUNCHER=${LAUNCHER})
endif()
execute_process(
  COMMAND ${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${BUILD_DIR} -DCMAKE_BUILD_TYPE=Release
          -DCMAKE_CXX_COMPILER=${CLANGXX} ${launcher}
          -DEMA_BUILD_FUZZ=ON -DEMA_BUILD_TESTS=OFF -DEMA_BUILD_BENCH=OFF
  RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "configuring the clang fuzz tree failed (${rc})")
endif()
cmake_host_system_information(RESULT cores QUERY NUMBER_OF_PHYSICAL_CORES)
if(cores LESS 1)
  set(cores 2)
endif()
set(targets "")
foreach(t ${TARGETS})
  list(APPEND targets --target fuzz_${t})
endforeach()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${BUILD_DIR} -j${cores} ${targets} RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "building the fuzzers with ${CLANGXX} failed (${rc})")
endif()
