# FindCHOLMOD: SuiteSparse's CHOLMOD and UMFPACK, which ship no CMake config on Debian 12.
# Defines the imported targets CHOLMOD::CHOLMOD and UMFPACK::UMFPACK (the implicit methods' sparse LU), headers in
# include/suitesparse.
find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse)
find_library(CHOLMOD_LIBRARY cholmod)
find_library(UMFPACK_LIBRARY umfpack)
find_library(SUITESPARSE_CONFIG_LIBRARY suitesparseconfig)
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(CHOLMOD REQUIRED_VARS CHOLMOD_LIBRARY UMFPACK_LIBRARY SUITESPARSE_CONFIG_LIBRARY CHOLMOD_INCLUDE_DIR)

# an imported target NAME for LIBRARY, with SuiteSparse's headers and config library
function(suitesparse_target name library)
  if(NOT TARGET ${name})
    add_library(${name} UNKNOWN IMPORTED)
    set_target_properties(${name} PROPERTIES
      IMPORTED_LOCATION "${library}"
      INTERFACE_INCLUDE_DIRECTORIES "${CHOLMOD_INCLUDE_DIR}"
      INTERFACE_LINK_LIBRARIES "${SUITESPARSE_CONFIG_LIBRARY}")
  endif()
endfunction()
if(CHOLMOD_FOUND)
  suitesparse_target(CHOLMOD::CHOLMOD "${CHOLMOD_LIBRARY}")
  suitesparse_target(UMFPACK::UMFPACK "${UMFPACK_LIBRARY}")
endif()
mark_as_advanced(CHOLMOD_INCLUDE_DIR CHOLMOD_LIBRARY UMFPACK_LIBRARY SUITESPARSE_CONFIG_LIBRARY)
