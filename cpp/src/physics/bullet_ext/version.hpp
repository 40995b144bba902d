#pragma once
// The Bullet release whose internals the files of this folder mirror (private).
//
// Each file of cpp/src/physics/bullet_ext re-implements, or wraps, named functions of Bullet 3.24
// with the same floating-point operations in the same order, so that a simulation gives the same
// bits as with Bullet's own code. Those functions are Bullet's internals, not its API: another
// release may change them without notice. CMake compiles this folder only when Bullet's
// BT_BULLET_VERSION is 324 (option MGN_BULLET_EXTENSIONS, cpp/cmake/mgnDependencies.cmake); this
// header checks it again where the files are compiled.
#include <LinearMath/btScalar.h>

/// BT_BULLET_VERSION of the release mirrored here (3.24).
#define MGN_BULLET_EXT_VERSION 324

#if BT_BULLET_VERSION != MGN_BULLET_EXT_VERSION
#error \
    "cpp/src/physics/bullet_ext mirrors Bullet 3.24 (BT_BULLET_VERSION 324); configure with -DMGN_BULLET_EXTENSIONS=OFF to build with Bullet's own code"
#endif
