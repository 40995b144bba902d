# Finds every third-party library mgn builds against and exposes each as an imported target.
# This file is installed next to mgnConfig.cmake so that find_package(mgn) re-creates the same
# targets for consumers of the static library. Why each library is used: third_party_notes/<lib>.md.
include_guard(GLOBAL)
include(CMakeFindDependencyMacro)
find_package(PkgConfig REQUIRED)

find_package(Eigen3 3.3 CONFIG REQUIRED)
find_package(embree 3 CONFIG REQUIRED)
find_package(fcl 0.7 CONFIG REQUIRED)
find_package(assimp 5 CONFIG REQUIRED)

# A plain find_package(NLopt) picks the C library; the C++ one lives in its own config dir.
find_package(NLopt 2.7 CONFIG REQUIRED
  HINTS /usr/lib/${CMAKE_LIBRARY_ARCHITECTURE}/cmake/nlopt_cxx NO_DEFAULT_PATH)

# Debian's BulletConfig.cmake has broken relative paths: use pkg-config.
if(NOT TARGET PkgConfig::BULLET)
  pkg_check_modules(BULLET REQUIRED IMPORTED_TARGET GLOBAL bullet)
endif()
if(NOT TARGET PkgConfig::OSMESA)
  pkg_check_modules(OSMESA REQUIRED IMPORTED_TARGET GLOBAL osmesa)
endif()

# OpenCV without libopencv-dev has no CMake config: find the three modules by hand.
if(NOT TARGET mgn_deps::opencv)
  find_path(MGN_OPENCV_INCLUDE_DIR opencv2/core.hpp PATH_SUFFIXES opencv4 REQUIRED)
  add_library(mgn_deps::opencv INTERFACE IMPORTED GLOBAL)
  foreach(_mod core imgproc imgcodecs)
    find_library(MGN_OPENCV_${_mod}_LIBRARY NAMES opencv_${_mod} REQUIRED)
    if(NOT TARGET mgn_deps::opencv_${_mod})
      add_library(mgn_deps::opencv_${_mod} UNKNOWN IMPORTED GLOBAL)
      set_target_properties(mgn_deps::opencv_${_mod} PROPERTIES
        IMPORTED_LOCATION "${MGN_OPENCV_${_mod}_LIBRARY}"
        INTERFACE_INCLUDE_DIRECTORIES "${MGN_OPENCV_INCLUDE_DIR}")
    endif()
    target_link_libraries(mgn_deps::opencv INTERFACE mgn_deps::opencv_${_mod})
  endforeach()
endif()

# HACD (approximate convex decomposition) ships in libbullet-extras-dev without a .pc file or
# CMake config: find the library by hand. Its headers live under Bullet's include directory.
if(NOT TARGET mgn_deps::hacd)
  find_path(MGN_HACD_INCLUDE_DIR HACD/hacdHACD.h PATH_SUFFIXES bullet REQUIRED)
  find_library(MGN_HACD_LIBRARY NAMES HACD REQUIRED)
  add_library(mgn_deps::hacd UNKNOWN IMPORTED GLOBAL)
  set_target_properties(mgn_deps::hacd PROPERTIES
    IMPORTED_LOCATION "${MGN_HACD_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${MGN_HACD_INCLUDE_DIR}")
endif()

find_package(Threads REQUIRED)
