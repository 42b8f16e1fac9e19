# What a pectus-meshlab plugin needs from the MeshLab that Debian ships (2020.09):
#  - headers (src/common + vcglib) from Debian's source package, unpacked by scripts/setup.sh
#    into third_party/meshlab (override with -DMESHLAB_SOURCE_DIR=...)
#  - Debian's libmeshlab-common.so, Qt5 and GLEW (header only)
#  - the ABI: MESHLAB_SCALAR=float, -fPIC, -Wl,--no-undefined
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

if(NOT EXISTS "${MESHLAB_SOURCE_DIR}/src/common/interfaces.h" OR NOT EXISTS "${MESHLAB_SOURCE_DIR}/vcglib/vcg/complex/complex.h")
  message(FATAL_ERROR "MeshLab headers not found in ${MESHLAB_SOURCE_DIR}. Run scripts/setup.sh first.")
endif()

find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(OpenMP REQUIRED COMPONENTS CXX)

add_library(pectus_vcg INTERFACE)
add_library(pectus::vcg ALIAS pectus_vcg)
target_include_directories(pectus_vcg SYSTEM INTERFACE
  "${MESHLAB_SOURCE_DIR}/vcglib" "${MESHLAB_SOURCE_DIR}/src")
# (src/ only for common/ml_mesh_type.h, the header of CMeshO, which needs nothing but vcglib)
target_compile_definitions(pectus_vcg INTERFACE MESHLAB_SCALAR=float)
target_link_libraries(pectus_vcg INTERFACE Eigen3::Eigen OpenMP::OpenMP_CXX)

# vcglib's PLY reader/writer, for host-free tests and tools (the plugins get it from libmeshlab-common)
add_library(pectus_vcg_io STATIC "${MESHLAB_SOURCE_DIR}/vcglib/wrap/ply/plylib.cpp")
set_target_properties(pectus_vcg_io PROPERTIES POSITION_INDEPENDENT_CODE ON)
target_link_libraries(pectus_vcg_io PUBLIC pectus_vcg)
target_compile_options(pectus_vcg_io PRIVATE -w)

if(PECTUS_BUILD_PLUGINS)
  find_package(Qt5 5.15 REQUIRED COMPONENTS Core Gui Widgets OpenGL Xml)
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
