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
