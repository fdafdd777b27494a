# Finds Debian's libosmesa6-dev and defines the imported target OSMesa::OSMesa.
find_package(PkgConfig QUIET)
if(PkgConfig_FOUND)
  pkg_check_modules(PC_OSMESA QUIET osmesa)
endif()
find_path(OSMesa_INCLUDE_DIR GL/osmesa.h HINTS ${PC_OSMESA_INCLUDE_DIRS})
find_library(OSMesa_LIBRARY NAMES OSMesa HINTS ${PC_OSMESA_LIBRARY_DIRS})
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(OSMesa REQUIRED_VARS OSMesa_LIBRARY OSMesa_INCLUDE_DIR)
if(OSMesa_FOUND AND NOT TARGET OSMesa::OSMesa)
  add_library(OSMesa::OSMesa UNKNOWN IMPORTED)
  set_target_properties(OSMesa::OSMesa PROPERTIES
    IMPORTED_LOCATION "${OSMesa_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${OSMesa_INCLUDE_DIR}")
endif()
mark_as_advanced(OSMesa_INCLUDE_DIR OSMesa_LIBRARY)
