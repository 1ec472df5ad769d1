# Every dependency comes from Debian's archive (see scripts/bootstrap.sh for the packages).
list(APPEND CMAKE_MODULE_PATH /usr/lib/x86_64-linux-gnu/cmake/OpenVDB)
find_package(OpenVDB REQUIRED COMPONENTS openvdb)
find_package(TBB REQUIRED)
find_package(nlohmann_json 3 REQUIRED)
find_package(CLI11 REQUIRED)
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(ZLIB REQUIRED)
find_package(SQLite3 REQUIRED)
find_package(assimp 5 REQUIRED)
# Blosc (OpenVDB's compressor) directly: density bricks, and checking the blocks of untrusted files.
find_library(BLOSC_LIBRARY NAMES blosc REQUIRED)
find_path(BLOSC_INCLUDE_DIR NAMES blosc.h REQUIRED)
if(NOT TARGET Blosc::blosc)
  add_library(Blosc::blosc UNKNOWN IMPORTED)
  set_target_properties(Blosc::blosc PROPERTIES IMPORTED_LOCATION "${BLOSC_LIBRARY}" INTERFACE_INCLUDE_DIRECTORIES "${BLOSC_INCLUDE_DIR}")
endif()
find_package(PkgConfig REQUIRED)
pkg_check_modules(PLplot REQUIRED IMPORTED_TARGET plplot)
# The editor tells whether a .vdb changed under its working store by a hash of its content (XXH3).
pkg_check_modules(XXHASH REQUIRED IMPORTED_TARGET libxxhash)
# The renderer: Vulkan (glslc compiles the shaders at build time), GLM, stb for pictures.
find_package(Vulkan REQUIRED COMPONENTS glslc)
find_package(glm REQUIRED)
pkg_check_modules(STB REQUIRED IMPORTED_TARGET stb)
# The desktop editor: a GLFW window, Dear ImGui menus (static libimgui.a with its GLFW and Vulkan backends).
find_package(glfw3 3.3 REQUIRED)
pkg_check_modules(IMGUI REQUIRED IMPORTED_TARGET imgui)
# The desktop tests press mouse buttons as the X server delivers them (XTEST, which Xvfb has).
pkg_check_modules(XTST REQUIRED IMPORTED_TARGET xtst x11)
# The VR front end: the OpenXR loader (libopenxr-dev); the tests also run Khronos' sample (hello_xr,
# libopenxr-utils) and the core validation layer (openxr-layer-corevalidation).
find_package(OpenXR REQUIRED)
# Retrieval: FLANN's nearest-neighbour indexes (libflann-dev; its save and load use LZ4).
find_package(flann CONFIG REQUIRED)
