# Whether to compile mgn's re-implemented parts of Bullet (cpp/src/physics/bullet_ext): they
# mirror Bullet 3.24's internals operation by operation, so they are compiled only against that
# release. Sets MGN_BULLET_EXT_ENABLED (ON/OFF) from the cache option MGN_BULLET_EXTENSIONS:
#   AUTO (default): on with Bullet 3.24, else off (with a message);
#   ON:  on, and configuring fails with another release;
#   OFF: off (Bullet's own solver, narrow phase and hull shapes).
# Bullet's version is BT_BULLET_VERSION of LinearMath/btScalar.h (324 for 3.24), read from the
# include directories of the PkgConfig::BULLET target (cpp/cmake/mgnDependencies.cmake).
include_guard(GLOBAL)

set(MGN_BULLET_EXTENSIONS AUTO CACHE STRING
    "mgn's re-implemented Bullet 3.24 parts: AUTO (on with Bullet 3.24), ON (require 3.24) or OFF")
set_property(CACHE MGN_BULLET_EXTENSIONS PROPERTY STRINGS AUTO ON OFF)
set(MGN_BULLET_EXT_VERSION 324)  # as MGN_BULLET_EXT_VERSION in cpp/src/physics/bullet_ext/version.hpp

set(_mgn_bt_version "")
get_target_property(_mgn_bt_dirs PkgConfig::BULLET INTERFACE_INCLUDE_DIRECTORIES)
foreach(_dir IN LISTS _mgn_bt_dirs)
  if(EXISTS "${_dir}/LinearMath/btScalar.h")
    file(STRINGS "${_dir}/LinearMath/btScalar.h" _mgn_bt_line
         REGEX "^#define[ \t]+BT_BULLET_VERSION[ \t]+[0-9]+")
    if(_mgn_bt_line)
      string(REGEX REPLACE ".*BT_BULLET_VERSION[ \t]+([0-9]+).*" "\\1" _mgn_bt_version
             "${_mgn_bt_line}")
      break()
    endif()
  endif()
endforeach()
if(_mgn_bt_version STREQUAL "")
  set(_mgn_bt_found "an unknown version (no BT_BULLET_VERSION in LinearMath/btScalar.h under ${_mgn_bt_dirs})")
else()
  set(_mgn_bt_found "BT_BULLET_VERSION ${_mgn_bt_version}")
endif()

if(MGN_BULLET_EXTENSIONS STREQUAL "OFF")
  set(MGN_BULLET_EXT_ENABLED OFF)
elseif(_mgn_bt_version STREQUAL "${MGN_BULLET_EXT_VERSION}")
  set(MGN_BULLET_EXT_ENABLED ON)
elseif(MGN_BULLET_EXTENSIONS STREQUAL "ON")
  message(FATAL_ERROR
    "MGN_BULLET_EXTENSIONS=ON needs Bullet 3.24 (BT_BULLET_VERSION ${MGN_BULLET_EXT_VERSION}), "
    "found ${_mgn_bt_found}. Install Bullet 3.24 or configure with -DMGN_BULLET_EXTENSIONS=AUTO "
    "or OFF to build with Bullet's own solver and narrow phase.")
elseif(MGN_BULLET_EXTENSIONS STREQUAL "AUTO")
  set(MGN_BULLET_EXT_ENABLED OFF)
  message(STATUS
    "mgn: Bullet ${_mgn_bt_found} is not 3.24: building with Bullet's own solver, narrow phase "
    "and hull shapes (cpp/src/physics/bullet_ext off: the same models, without mgn's faster "
    "re-implementations; results are that release's)")
else()
  message(FATAL_ERROR
    "MGN_BULLET_EXTENSIONS must be AUTO, ON or OFF, got '${MGN_BULLET_EXTENSIONS}'")
endif()
message(STATUS "mgn: Bullet extensions (cpp/src/physics/bullet_ext): ${MGN_BULLET_EXT_ENABLED} "
               "(Bullet ${_mgn_bt_found}, MGN_BULLET_EXTENSIONS=${MGN_BULLET_EXTENSIONS})")
