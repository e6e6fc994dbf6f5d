# ctest formats/fuzz_smoke: build the fuzzer with clang if needed, seed a corpus from the shared
# UFF files (small ones; big files slow libFuzzer down) and run it for SECONDS seconds.
if(CLANGXX)  # rebuilt every run so the fuzzer always tests the current sources
  get_filename_component(out_dir "${FUZZ_EXE}" DIRECTORY)
  file(MAKE_DIRECTORY "${out_dir}")
  execute_process(
    COMMAND "${CLANGXX}" -std=c++20 -g -O1 -fsanitize=fuzzer,address,undefined
            -I${SOURCE_DIR}/formats/include -I${SOURCE_DIR}/core/include
            ${SOURCE_DIR}/fuzz/uff_reader_fuzz.cpp
            ${SOURCE_DIR}/formats/src/uff_reader.cpp ${SOURCE_DIR}/formats/src/uff_datasets.cpp
            ${SOURCE_DIR}/formats/src/uff_writer.cpp ${SOURCE_DIR}/formats/src/atomic_file.cpp
            -o "${FUZZ_EXE}"
    RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "building the fuzzer with ${CLANGXX} failed (${rc})")
  endif()
endif()
set(corpus "${WORK_DIR}/corpus")
file(MAKE_DIRECTORY "${corpus}")
file(GLOB_RECURSE seeds "${CORPUS_DIR}/*")
foreach(seed ${seeds})
  file(SIZE "${seed}" size)
  if(size LESS 65536)
    get_filename_component(name "${seed}" NAME)
    string(MAKE_C_IDENTIFIER "${name}" id)
    configure_file("${seed}" "${corpus}/seed_${id}" COPYONLY)
  endif()
endforeach()
execute_process(
  COMMAND "${FUZZ_EXE}" -max_total_time=${SECONDS} -max_len=65536 -timeout=10 -rss_limit_mb=2048
          -print_final_stats=1 "${corpus}"
  WORKING_DIRECTORY "${WORK_DIR}"
  RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the UFF fuzzer found a problem (exit ${rc}); the reproducer crash-* is in ${WORK_DIR}")
endif()
