#pragma once
// The Bullet dynamics world of mgn's simulations (private: Bullet types do not appear in
// installed headers). The one place that assembles Bullet's world — collision configuration,
// dispatcher, broadphase, constraint solver — and that plugs in the re-implemented parts of
// cpp/src/physics/bullet_ext; the drop (scene/drop.cpp) and the shake trial
// (grasp/shake_trial.cpp) build their worlds here.
//
// With the Bullet extensions compiled in (CMake option MGN_BULLET_EXTENSIONS, on with Bullet
// 3.24; see bullet_extensions()):
//  - the solver is OneSidedContactSolver (bullet_ext/one_sided_solver.hpp), Bullet's
//    sequential-impulse solver without the still body's half of each contact row;
//  - with WorldOptions::skip_separated_pairs, the narrow phase of pairs of boxes and hulls is
//    skipped while a pair is provably apart (bullet_ext/separated_pair_skip.hpp);
//  - hull shapes are FastHullShapes (bullet_ext/hull_support.hpp, made in physics/bullet.cpp).
// Each gives Bullet's own simulation bit for bit, only faster. Without them (another Bullet
// release), the world runs Bullet's btSequentialImpulseConstraintSolver and narrow phase.
#include <memory>

// Bullet's classes (btBulletDynamicsCommon.h), declared only: users of the switches below need no
// Bullet headers.
class btCollisionDispatcher;
class btDiscreteDynamicsWorld;

namespace mgn::physics {

/// How a world is assembled.
struct WorldOptions {
  /// Blocks of the dispatcher's pools of contact manifolds and of collision algorithms, each,
  /// allocated up front (more are allocated on demand when a pool is full); 0: Bullet's default
  /// (btDefaultCollisionConstructionInfo, 4096). A small world saves the allocation.
  int pool_size = 0;
  /// Skip Bullet's narrow phase for pairs of boxes and hulls while a pair is provably apart (no
  /// effect without the Bullet extensions).
  bool skip_separated_pairs = false;
};

/// Whether this build has the Bullet extensions (cpp/src/physics/bullet_ext) compiled in.
bool bullet_extensions();

/// Tests and benchmarks only: which Bullet extensions worlds built from now on use (process-wide;
/// both on by default). Off, a world runs Bullet's own code for that part; every simulation is
/// the same bit for bit either way (tests/cpp/test_shake.cpp, test_one_sided_solver.cpp).
struct ExtensionSwitches {
  bool one_sided_rows = true;        ///< OneSidedContactSolver's own rows and iterations
  bool skip_separated_pairs = true;  ///< the separated-pair skip where WorldOptions asks for it
};
void set_extension_switches(const ExtensionSwitches& switches);
ExtensionSwitches extension_switches();

/// One Bullet dynamics world and the objects it runs on. Bodies and shapes stay the caller's.
class World {
 public:
  explicit World(const WorldOptions& options = {});
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  btDiscreteDynamicsWorld& dynamics() { return *dynamics_; }
  btCollisionDispatcher& dispatcher() { return *dispatcher_; }

 private:
  struct Parts;  // configuration, skip, broadphase, solver (their types depend on the build)
  std::unique_ptr<Parts> parts_;
  btCollisionDispatcher* dispatcher_ = nullptr;
  btDiscreteDynamicsWorld* dynamics_ = nullptr;
};

}  // namespace mgn::physics
