# FindMatio: Debian's libmatio-dev ships a pkg-config file but no CMake package.
# Defines Matio::matio (MATLAB .mat v4/v5/v7.3 files; links HDF5 and zlib as pkg-config says).
find_package(PkgConfig QUIET)
if(PKG_CONFIG_FOUND)
  pkg_check_modules(PC_MATIO QUIET matio)
endif()
find_path(MATIO_INCLUDE_DIR matio.h HINTS ${PC_MATIO_INCLUDE_DIRS})
find_library(MATIO_LIBRARY NAMES matio HINTS ${PC_MATIO_LIBRARY_DIRS})
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(Matio REQUIRED_VARS MATIO_LIBRARY MATIO_INCLUDE_DIR)
if(Matio_FOUND AND NOT TARGET Matio::matio)
  add_library(Matio::matio UNKNOWN IMPORTED)
  set_target_properties(Matio::matio PROPERTIES
    IMPORTED_LOCATION ${MATIO_LIBRARY}
    INTERFACE_INCLUDE_DIRECTORIES "${MATIO_INCLUDE_DIR};${PC_MATIO_INCLUDE_DIRS}")
  # A static libmatio needs HDF5 and zlib at link time; the shared one brings them itself.
  if(PC_MATIO_LIBRARY_DIRS)
    set_property(TARGET Matio::matio PROPERTY INTERFACE_LINK_DIRECTORIES ${PC_MATIO_LIBRARY_DIRS})
  endif()
endif()
mark_as_advanced(MATIO_INCLUDE_DIR MATIO_LIBRARY)
