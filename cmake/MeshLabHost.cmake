# What a pectus-meshlab plugin needs from the MeshLab that Debian ships (bookworm's 2020.09, or
# 2021.05 and later: trixie's 2022.02, forky's 2025.07):
#  - headers (src/common + vcglib) from the MeshLab source of the same version, unpacked by
#    scripts/setup.sh into third_party/meshlab (2020.09) or by scripts/host.sh
#    (override with -DMESHLAB_SOURCE_DIR=...)
#  - that MeshLab's libmeshlab-common.so, Qt5 and GLEW (header only)
#  - the ABI: MESHLAB_SCALAR as MeshLab was built (Debian: float; pymeshlab: double), -fPIC,
#    -Wl,--no-undefined; from 2021.05 on also MESHLAB_VERSION, which the plugin loader compares
# The API generation (PECTUS_MESHLAB_API 2020 or 2021) follows from the headers; common/meshlab/ml_compat.h
# maps the differences.
#
# Targets defined here:
#   pectus::vcg      host-free: vcglib + Eigen + MESHLAB_SCALAR (what the algorithm cores use)
#   pectus::meshlab  the MeshLab plugin API (Qt, libmeshlab-common)
# Function:
#   pectus_add_plugin(<name> SOURCES ... LIBS ...)

set(MESHLAB_SOURCE_DIR "${CMAKE_SOURCE_DIR}/third_party/meshlab" CACHE PATH
    "Unpacked MeshLab source package (needs src/common and vcglib)")
set(MESHLAB_LIB_DIR "/usr/lib/x86_64-linux-gnu/meshlab" CACHE PATH
    "Folder of Debian's libmeshlab-common.so")
set(MESHLAB_PLUGIN_INSTALL_DIR "lib/x86_64-linux-gnu/meshlab/plugins" CACHE STRING
    "Plugin folder relative to the install prefix (Debian's MeshLab only loads from here)")

set(MESHLAB_SCALAR "float" CACHE STRING "MeshLab's scalar type (float: Debian's MeshLab; double: pymeshlab)")
set_property(CACHE MESHLAB_SCALAR PROPERTY STRINGS float double)

if(NOT EXISTS "${MESHLAB_SOURCE_DIR}/vcglib/vcg/complex/complex.h")
  message(FATAL_ERROR "MeshLab headers not found in ${MESHLAB_SOURCE_DIR}. Run scripts/setup.sh first "
                      "(scripts/host.sh for MeshLab 2022.02 and 2025.07).")
endif()
if(EXISTS "${MESHLAB_SOURCE_DIR}/src/common/interfaces.h")
  set(PECTUS_MESHLAB_API 2020)
elseif(EXISTS "${MESHLAB_SOURCE_DIR}/src/common/plugins/interfaces/filter_plugin.h")
  set(PECTUS_MESHLAB_API 2021)
else()
  message(FATAL_ERROR "${MESHLAB_SOURCE_DIR}/src/common holds neither MeshLab 2020.09's nor 2021.05+'s plugin API")
endif()
# The release the plugins load into: the installed meshlab package's version (the loader of 2021.05+
# refuses a plugin whose MESHLAB_VERSION differs in its first 6 characters)
execute_process(COMMAND dpkg-query -W -f=\${Version} meshlab OUTPUT_VARIABLE _mlpkg ERROR_QUIET)
string(REGEX MATCH "^[0-9]+\\.[0-9]+" _mlpkgver "${_mlpkg}")
if(NOT _mlpkgver)
  string(REGEX MATCH "[0-9][0-9][0-9][0-9]\\.[0-9][0-9]" _mlpkgver "${MESHLAB_SOURCE_DIR}")
endif()
set(MESHLAB_VERSION "" CACHE STRING "MeshLab release the plugins are built for (e.g. 2020.09, 2025.07; empty: detect)")
if(NOT MESHLAB_VERSION)
  set(MESHLAB_VERSION "${_mlpkgver}" CACHE STRING "MeshLab release the plugins are built for (e.g. 2020.09, 2025.07; empty: detect)" FORCE)
endif()
if(PECTUS_MESHLAB_API EQUAL 2021 AND NOT MESHLAB_VERSION)
  message(FATAL_ERROR "MESHLAB_VERSION unknown: pass -DMESHLAB_VERSION=2025.07 (the MeshLab the plugins load into)")
endif()
message(STATUS "MeshLab ${MESHLAB_VERSION} (plugin API ${PECTUS_MESHLAB_API}), MESHLAB_SCALAR=${MESHLAB_SCALAR}")

# Eigen 3.4 (bookworm, trixie) and 5.0 (forky) both serve. Each one's version file accepts only its own
# major version (3.4 refuses a range reaching past 4, 5.0 refuses a plain 3.3), so ask for none and check.
find_package(Eigen3 REQUIRED NO_MODULE)
if(Eigen3_VERSION VERSION_LESS 3.3)
  message(FATAL_ERROR "Eigen ${Eigen3_VERSION} found; 3.3 or later (3.4, 5.0) is needed")
endif()
find_package(OpenMP REQUIRED COMPONENTS CXX)

add_library(pectus_vcg INTERFACE)
add_library(pectus::vcg ALIAS pectus_vcg)
target_include_directories(pectus_vcg SYSTEM INTERFACE
  "${MESHLAB_SOURCE_DIR}/vcglib" "${MESHLAB_SOURCE_DIR}/src")
# (src/ only for common/ml_mesh_type.h, the header of CMeshO, which needs nothing but vcglib)
target_compile_definitions(pectus_vcg INTERFACE MESHLAB_SCALAR=${MESHLAB_SCALAR} PECTUS_MESHLAB_API=${PECTUS_MESHLAB_API})
if(PECTUS_MESHLAB_API EQUAL 2021)
  target_compile_definitions(pectus_vcg INTERFACE MESHLAB_VERSION=${MESHLAB_VERSION})
endif()
target_link_libraries(pectus_vcg INTERFACE Eigen3::Eigen OpenMP::OpenMP_CXX)
if(PECTUS_MESHLAB_API EQUAL 2021)
  # CMeshO's constructors and destructor live in cmesh.cpp (libmeshlab-common in MeshLab's build). A float
  # build of the cores links the installed libmeshlab-common; any other scalar compiles cmesh.cpp itself
  # (it needs only vcglib), so the cores and their tests never depend on a MeshLab of that scalar.
  if(MESHLAB_SCALAR STREQUAL "float" AND EXISTS "${MESHLAB_LIB_DIR}/libmeshlab-common.so")
    target_link_libraries(pectus_vcg INTERFACE "${MESHLAB_LIB_DIR}/libmeshlab-common.so")
  else()
    add_library(pectus_cmesh STATIC "${MESHLAB_SOURCE_DIR}/src/common/ml_document/cmesh.cpp")
    set_target_properties(pectus_cmesh PROPERTIES POSITION_INDEPENDENT_CODE ON)
    target_include_directories(pectus_cmesh SYSTEM PRIVATE "${MESHLAB_SOURCE_DIR}/vcglib" "${MESHLAB_SOURCE_DIR}/src")
    target_compile_definitions(pectus_cmesh PRIVATE MESHLAB_SCALAR=${MESHLAB_SCALAR})
    target_link_libraries(pectus_cmesh PRIVATE Eigen3::Eigen)
    target_compile_options(pectus_cmesh PRIVATE -w)
    target_link_libraries(pectus_vcg INTERFACE pectus_cmesh)
  endif()
endif()

# vcglib's PLY reader/writer, for host-free tests and tools (the plugins get it from libmeshlab-common)
add_library(pectus_vcg_io STATIC "${MESHLAB_SOURCE_DIR}/vcglib/wrap/ply/plylib.cpp")
set_target_properties(pectus_vcg_io PROPERTIES POSITION_INDEPENDENT_CODE ON)
target_link_libraries(pectus_vcg_io PUBLIC pectus_vcg)
target_compile_options(pectus_vcg_io PRIVATE -w)

if(PECTUS_BUILD_PLUGINS)
  find_package(Qt5 5.15 REQUIRED COMPONENTS Core Gui Widgets OpenGL Xml)
  if(NOT MESHLAB_SCALAR STREQUAL "float" AND NOT MESHLAB_COMMON_LIB)
    message(WARNING "MESHLAB_SCALAR=${MESHLAB_SCALAR}: the plugins must link the libmeshlab-common.so of a MeshLab "
                    "built with that scalar (pymeshlab's); pass -DMESHLAB_COMMON_LIB=/path/to/it")
  endif()
  find_path(GLEW_INCLUDE_DIR GL/glew.h REQUIRED)
  find_library(MESHLAB_COMMON_LIB meshlab-common PATHS "${MESHLAB_LIB_DIR}" NO_DEFAULT_PATH REQUIRED)

  add_library(pectus_meshlab_api INTERFACE)
  add_library(pectus::meshlab ALIAS pectus_meshlab_api)
  target_include_directories(pectus_meshlab_api SYSTEM INTERFACE "${MESHLAB_SOURCE_DIR}/src" "${GLEW_INCLUDE_DIR}")
  target_link_libraries(pectus_meshlab_api INTERFACE pectus_vcg "${MESHLAB_COMMON_LIB}"
    Qt5::Core Qt5::Gui Qt5::Widgets Qt5::OpenGL Qt5::Xml)

  set(PECTUS_PLUGIN_OUTPUT_DIR "${CMAKE_BINARY_DIR}/plugins")
endif()

function(pectus_add_plugin name)
  if(NOT PECTUS_BUILD_PLUGINS)  # cores-only build (sanitizer/fuzz presets): no Qt, no MeshLab
    return()
  endif()
  cmake_parse_arguments(P "" "" "SOURCES;LIBS" ${ARGN})
  add_library(${name} MODULE ${P_SOURCES})
  set_target_properties(${name} PROPERTIES
    AUTOMOC ON
    PREFIX "lib"
    LIBRARY_OUTPUT_DIRECTORY "${PECTUS_PLUGIN_OUTPUT_DIR}"
    POSITION_INDEPENDENT_CODE ON)
  target_link_libraries(${name} PRIVATE pectus_meshlab_adapter ${P_LIBS})
  target_link_options(${name} PRIVATE "-Wl,--no-undefined")
  install(TARGETS ${name} LIBRARY DESTINATION "${MESHLAB_PLUGIN_INSTALL_DIR}" COMPONENT plugins)
  set_property(GLOBAL APPEND PROPERTY PECTUS_PLUGINS ${name})
endfunction()
