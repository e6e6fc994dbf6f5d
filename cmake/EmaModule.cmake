# ema_add_module(NAME [PUBLIC_DEPS ...] [PRIVATE_DEPS ...])
# One static library per module folder: sources are <module>/src/*.cpp, public headers live under
# <module>/include/ema/<module>/. Sources are globbed (CONFIGURE_DEPENDS) so that adding a file
# needs no edit of a shared CMake list.
set(EMA_WARNINGS -Wall -Wextra -Wpedantic)

function(ema_add_module name)
  cmake_parse_arguments(ARG "" "" "PUBLIC_DEPS;PRIVATE_DEPS" ${ARGN})
  file(GLOB_RECURSE sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/src/*.cpp)
  add_library(ema_${name} STATIC ${sources})
  add_library(ema::${name} ALIAS ema_${name})
  set_target_properties(ema_${name} PROPERTIES EXPORT_NAME ${name} OUTPUT_NAME ema_${name})
  target_include_directories(ema_${name} PUBLIC
    $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  target_link_libraries(ema_${name} PUBLIC ${ARG_PUBLIC_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  target_compile_options(ema_${name} PRIVATE ${EMA_WARNINGS} ${EMA_LIBRARY_OPTIMISATION})
  if(name STREQUAL "formats")
    target_compile_options(ema_${name} PRIVATE ${EMA_FUZZ_COVERAGE})  # the parsers (fuzz/)
  endif()
  install(TARGETS ema_${name} EXPORT emaTargets ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
  install(DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
endfunction()

# CHOLMOD (SuiteSparse; Debian's libsuitesparse-dev), PRIVATE to `target` with EMA_HAVE_CHOLMOD
# defined: the supernodal sparse Cholesky of model/ (shift-invert solves, reduced models, and
# CheckPositiveDefinite, which `ema fe-import` checks each part with). Debian 12's SuiteSparse 5 ships no
# CMake package, so its header and library are found directly; without them Eigen's SimplicialLDLT
# factorises (the same results, slower on large 3-D meshes).
function(ema_link_cholmod target)
  find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse)
  find_library(CHOLMOD_LIBRARY cholmod)
  if(CHOLMOD_INCLUDE_DIR AND CHOLMOD_LIBRARY)
    target_include_directories(${target} PRIVATE ${CHOLMOD_INCLUDE_DIR})
    target_link_libraries(${target} PRIVATE ${CHOLMOD_LIBRARY})
    target_compile_definitions(${target} PRIVATE EMA_HAVE_CHOLMOD)
    message(STATUS "CHOLMOD for ${target}: ${CHOLMOD_LIBRARY} (supernodal sparse Cholesky)")
  else()
    message(STATUS "CHOLMOD not found: ${target}'s sparse factorisations use Eigen's SimplicialLDLT (apt-get install libsuitesparse-dev)")
  endif()
endfunction()
