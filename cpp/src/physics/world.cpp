#include "physics/world.hpp"

#include <btBulletDynamicsCommon.h>

#ifndef MGN_BULLET_EXT
#error "MGN_BULLET_EXT (0 or 1) is set by cpp/CMakeLists.txt"
#endif

#if MGN_BULLET_EXT
#include "physics/bullet_ext/one_sided_solver.hpp"
#include "physics/bullet_ext/separated_pair_skip.hpp"
#endif

#include <atomic>

namespace mgn::physics {

namespace {

std::atomic<bool> g_one_sided_rows{true};
std::atomic<bool> g_skip_separated_pairs{true};

btDefaultCollisionConstructionInfo construction_info(const WorldOptions& o) {
  btDefaultCollisionConstructionInfo info;
  if (o.pool_size > 0) {
    info.m_defaultMaxPersistentManifoldPoolSize = o.pool_size;
    info.m_defaultMaxCollisionAlgorithmPoolSize = o.pool_size;
  }
  return info;
}

}  // namespace

bool bullet_extensions() { return MGN_BULLET_EXT != 0; }

void set_extension_switches(const ExtensionSwitches& s) {
  g_one_sided_rows.store(s.one_sided_rows);
  g_skip_separated_pairs.store(s.skip_separated_pairs);
}

ExtensionSwitches extension_switches() {
  return {g_one_sided_rows.load(), g_skip_separated_pairs.load()};
}

#if MGN_BULLET_EXT
using Solver = OneSidedContactSolver;  // Bullet's, the still body's half of its rows left out
#else
using Solver = btSequentialImpulseConstraintSolver;
#endif

struct World::Parts {
  explicit Parts(const WorldOptions& o)
      : config(construction_info(o)),
#if MGN_BULLET_EXT
        skip_separated(config.getCollisionAlgorithmCreateFunc(BOX_SHAPE_PROXYTYPE,
                                                              CUSTOM_POLYHEDRAL_SHAPE_TYPE)),
#endif
        dispatcher(&config),
        world(&dispatcher, &broadphase, &solver, &config) {
  }

  btDefaultCollisionConfiguration config;
#if MGN_BULLET_EXT
  SkipSeparatedConvexCreateFunc skip_separated;  // outlives the world's algorithms
#endif
  btCollisionDispatcher dispatcher;
  btDbvtBroadphase broadphase;
  Solver solver;
  btDiscreteDynamicsWorld world;
};

World::World(const WorldOptions& o) : parts_(std::make_unique<Parts>(o)) {
  dispatcher_ = &parts_->dispatcher;
  dynamics_ = &parts_->world;
#if MGN_BULLET_EXT
  const ExtensionSwitches use = extension_switches();
  if (o.skip_separated_pairs && use.skip_separated_pairs) {
    // Pairs of boxes and hulls (FastHullShape): Bullet's narrow phase, skipped while a pair is
    // provably apart (same simulation, see bullet_ext/separated_pair_skip.hpp).
    for (const int t0 : {BOX_SHAPE_PROXYTYPE, CUSTOM_POLYHEDRAL_SHAPE_TYPE})
      for (const int t1 : {BOX_SHAPE_PROXYTYPE, CUSTOM_POLYHEDRAL_SHAPE_TYPE})
        parts_->dispatcher.registerCollisionCreateFunc(t0, t1, &parts_->skip_separated);
  }
  parts_->solver.enabled = use.one_sided_rows;
#endif
}

World::~World() = default;

}  // namespace mgn::physics
