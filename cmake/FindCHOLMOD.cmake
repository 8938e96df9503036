# FindCHOLMOD: SuiteSparse's CHOLMOD and UMFPACK, which ship no CMake config on Debian 12.
# Defines the imported target CHOLMOD::CHOLMOD (headers in include/suitesparse).
find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse)
find_library(CHOLMOD_LIBRARY cholmod)
find_library(SUITESPARSE_CONFIG_LIBRARY suitesparseconfig)
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(CHOLMOD REQUIRED_VARS CHOLMOD_LIBRARY SUITESPARSE_CONFIG_LIBRARY CHOLMOD_INCLUDE_DIR)
if(CHOLMOD_FOUND AND NOT TARGET CHOLMOD::CHOLMOD)
  add_library(CHOLMOD::CHOLMOD UNKNOWN IMPORTED)
  set_target_properties(CHOLMOD::CHOLMOD PROPERTIES
    IMPORTED_LOCATION "${CHOLMOD_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${CHOLMOD_INCLUDE_DIR}"
    INTERFACE_LINK_LIBRARIES "${SUITESPARSE_CONFIG_LIBRARY}")
endif()
mark_as_advanced(CHOLMOD_INCLUDE_DIR CHOLMOD_LIBRARY SUITESPARSE_CONFIG_LIBRARY)

# UMFPACK, SuiteSparse's multifrontal sparse LU (the implicit methods' Newton matrix on a sparse Jacobian), from the
# same package: the imported target UMFPACK::UMFPACK
find_library(UMFPACK_LIBRARY umfpack)
if(UMFPACK_LIBRARY AND NOT TARGET UMFPACK::UMFPACK)
  add_library(UMFPACK::UMFPACK UNKNOWN IMPORTED)
  set_target_properties(UMFPACK::UMFPACK PROPERTIES
    IMPORTED_LOCATION "${UMFPACK_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${CHOLMOD_INCLUDE_DIR}"
    INTERFACE_LINK_LIBRARIES "${SUITESPARSE_CONFIG_LIBRARY}")
endif()
if(NOT UMFPACK_LIBRARY)
  set(CHOLMOD_FOUND FALSE)
  message(FATAL_ERROR "UMFPACK (libsuitesparse-dev) not found")
endif()
mark_as_advanced(UMFPACK_LIBRARY)
