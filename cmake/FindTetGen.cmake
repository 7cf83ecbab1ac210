# Finds TetGen 1.5 (Debian: libtet1.5-dev), which ships no CMake config.
# Defines the imported target TetGen::TetGen.
find_path(TetGen_INCLUDE_DIR tetgen.h)
find_library(TetGen_LIBRARY NAMES tet)
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(TetGen DEFAULT_MSG TetGen_LIBRARY TetGen_INCLUDE_DIR)
if(TetGen_FOUND AND NOT TARGET TetGen::TetGen)
  add_library(TetGen::TetGen UNKNOWN IMPORTED)
  set_target_properties(TetGen::TetGen PROPERTIES
    IMPORTED_LOCATION "${TetGen_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${TetGen_INCLUDE_DIR}"
    # tetgen.h must be compiled with TETLIBRARY to expose the library API.
    INTERFACE_COMPILE_DEFINITIONS TETLIBRARY)
endif()
mark_as_advanced(TetGen_INCLUDE_DIR TetGen_LIBRARY)
