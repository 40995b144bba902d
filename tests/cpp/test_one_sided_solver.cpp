// Tests of the private one-sided contact solver (cpp/src/physics/one_sided_solver.hpp): a world
// stepped with it must be the world stepped with Bullet's own sequential-impulse solver, bit for
// bit, step by step; rows of kinematic and static bodies must be solved one-sided (else the test
// would prove nothing about them), and worlds outside its fast path must go to Bullet's loop.
#include <gtest/gtest.h>

#include "physics/one_sided_solver.hpp"

#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <random>
#include <vector>

namespace {

using mgn::physics::OneSidedContactSolver;

bool same_bits(const btVector3& a, const btVector3& b) {
  return std::memcmp(&a.x(), &b.x(), 3 * sizeof(btScalar)) == 0;
}

/// A tray (static), a kinematic pusher squeezing and shaking, and a pile of dynamic boxes and
/// hulls: contacts of every kind (dynamic-static, dynamic-kinematic, dynamic-dynamic).
struct PileWorld {
  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  std::unique_ptr<btSequentialImpulseConstraintSolver> solver;
  std::unique_ptr<btDiscreteDynamicsWorld> world;
  btBoxShape floor_shape{btVector3(1.0f, 1.0f, 0.05f)};
  btBoxShape pusher_shape{btVector3(0.05f, 0.3f, 0.2f)};
  btBoxShape box_shape{btVector3(0.08f, 0.06f, 0.05f)};
  btConvexHullShape hull_shape;
  std::vector<std::unique_ptr<btRigidBody>> bodies;
  btRigidBody* pusher = nullptr;
  std::unique_ptr<btTypedConstraint> joint;

  PileWorld(bool one_sided, int solver_mode_flags, bool with_joint, int num_dynamic = 8) {
    if (one_sided) {
      solver = std::make_unique<OneSidedContactSolver>();
    } else {
      solver = std::make_unique<btSequentialImpulseConstraintSolver>();
    }
    world =
        std::make_unique<btDiscreteDynamicsWorld>(&dispatcher, &broadphase, solver.get(), &config);
    world->setGravity(btVector3(0, 0, -9.81f));
    world->getSolverInfo().m_solverMode |= SOLVER_USE_2_FRICTION_DIRECTIONS | solver_mode_flags;
    std::mt19937 rng(3);
    std::normal_distribution<float> g(0.0f, 1.0f);
    for (int i = 0; i < 24; ++i) {
      hull_shape.addPoint(btVector3(g(rng), g(rng), g(rng)).normalized() * 0.07f, false);
    }
    hull_shape.recalcLocalAabb();
    for (btPolyhedralConvexShape* s : {static_cast<btPolyhedralConvexShape*>(&box_shape),
                                       static_cast<btPolyhedralConvexShape*>(&hull_shape),
                                       static_cast<btPolyhedralConvexShape*>(&pusher_shape)}) {
      s->setMargin(0.004f);
      s->initializePolyhedralFeatures();
    }
    add(&floor_shape, 0.0f, btVector3(0, 0, -0.05f));
    pusher = add(&pusher_shape, 0.0f, btVector3(-0.35f, 0, 0.2f));
    pusher->setCollisionFlags(pusher->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
    pusher->setContactStiffnessAndDamping(3e4f, 200.0f);  // a soft pad, as the shake test's
    std::uniform_real_distribution<float> u(-0.15f, 0.15f);
    for (int i = 0; i < num_dynamic; ++i) {
      btCollisionShape* s = i % 2 ? static_cast<btCollisionShape*>(&hull_shape) : &box_shape;
      btRigidBody* b = add(s, 0.2f + 0.1f * i, btVector3(u(rng), u(rng), 0.1f + 0.15f * i));
      b->setWorldTransform(
          btTransform(btQuaternion(u(rng), u(rng), u(rng)), b->getWorldTransform().getOrigin()));
    }
    if (with_joint) {
      joint = std::make_unique<btPoint2PointConstraint>(
          *bodies[2], *bodies[3], btVector3(0, 0, 0.1f), btVector3(0, 0, -0.1f));
      world->addConstraint(joint.get());
    }
  }

  btRigidBody* add(btCollisionShape* shape, float mass, const btVector3& at) {
    btVector3 inertia(0, 0, 0);
    if (mass > 0) shape->calculateLocalInertia(mass, inertia);
    btRigidBody::btRigidBodyConstructionInfo ci(mass, nullptr, shape, inertia);
    ci.m_startWorldTransform.setIdentity();
    ci.m_startWorldTransform.setOrigin(at);
    ci.m_friction = 0.6f;
    bodies.push_back(std::make_unique<btRigidBody>(ci));
    bodies.back()->setActivationState(DISABLE_DEACTIVATION);
    world->addRigidBody(bodies.back().get());
    return bodies.back().get();
  }

  /// The pusher closes in and shakes (kinematic: pose set, velocity from the move).
  void step(int k) {
    const float t = k / 240.0f;
    btTransform T = pusher->getWorldTransform();
    T.setOrigin(btVector3(-0.35f + 0.3f * std::min(t, 1.0f), 0.05f * std::sin(9.0f * t),
                          0.2f + 0.03f * std::sin(13.0f * t)));
    pusher->setWorldTransform(T);
    world->stepSimulation(1.0f / 240.0f, 0, 1.0f / 240.0f);
  }

  ~PileWorld() {
    if (joint) world->removeConstraint(joint.get());
    for (auto& b : bodies) world->removeRigidBody(b.get());
  }
};

/// Steps both worlds and compares every body after every step.
void expect_same_worlds(PileWorld& bullet, PileWorld& ours, int steps) {
  for (int k = 0; k < steps; ++k) {
    bullet.step(k);
    ours.step(k);
    for (std::size_t i = 0; i < bullet.bodies.size(); ++i) {
      const btRigidBody& a = *bullet.bodies[i];
      const btRigidBody& b = *ours.bodies[i];
      ASSERT_TRUE(same_bits(a.getWorldTransform().getOrigin(), b.getWorldTransform().getOrigin()))
          << "body " << i << " step " << k;
      for (int r = 0; r < 3; ++r) {
        ASSERT_TRUE(
            same_bits(a.getWorldTransform().getBasis()[r], b.getWorldTransform().getBasis()[r]))
            << "body " << i << " step " << k;
      }
      ASSERT_TRUE(same_bits(a.getLinearVelocity(), b.getLinearVelocity()))
          << "body " << i << " step " << k;
      ASSERT_TRUE(same_bits(a.getAngularVelocity(), b.getAngularVelocity()))
          << "body " << i << " step " << k;
    }
  }
}

TEST(OneSidedSolver, StepsAPileAsBulletsSolverBitForBit) {
  PileWorld bullet(false, 0, false), ours(true, 0, false);
  expect_same_worlds(bullet, ours, 600);
  const auto& solver = static_cast<const OneSidedContactSolver&>(*ours.solver);
  EXPECT_GT(solver.own_iterations, 1000);
  EXPECT_EQ(solver.bullet_iterations, 0);
  // Rows against the floor and the pusher were solved one-sided, rows between two dynamic
  // bodies two-sided: the pile covers both.
  EXPECT_GT(solver.one_sided_rows, 1000);
  EXPECT_GT(solver.two_sided_rows, 100);
  // The pile moved (else equal poses would be trivial).
  EXPECT_GT(ours.bodies.back()->getWorldTransform().getOrigin().distance(btVector3(0, 0, 1.3f)),
            0.2f);
}

TEST(OneSidedSolver, StepsOneBodyAsBulletsSolverBitForBit) {
  // One dynamic hull on the floor, pushed, squeezed and dragged by the soft kinematic pusher
  // (the shake test's case): every row moves the same body, so the rows are packed.
  // With and without linear / angular factors (a body held on some axes).
  for (const int n : {1, 2, -1}) {
    const bool factors = n < 0;
    PileWorld bullet(false, 0, false, std::abs(n)), ours(true, 0, false, std::abs(n));
    if (factors) {
      for (PileWorld* w : {&bullet, &ours}) {
        w->bodies[2]->setLinearFactor(btVector3(1.0f, 0.5f, 1.0f));
        w->bodies[2]->setAngularFactor(btVector3(0.25f, 1.0f, 0.5f));
      }
    }
    expect_same_worlds(bullet, ours, 900);
    const auto& solver = static_cast<const OneSidedContactSolver&>(*ours.solver);
    EXPECT_EQ(solver.bullet_iterations, 0) << n;
    if (n != 2) EXPECT_GT(solver.packed_iterations, 5000);
    if (n == 2) EXPECT_LT(solver.packed_iterations, solver.own_iterations / 2);
    // The body was pushed along (else equal poses would be trivial).
    EXPECT_GT(
        ours.bodies[2]->getLinearVelocity().length() +
            (ours.bodies[2]->getWorldTransform().getOrigin() - btVector3(0, 0, 0.1f)).length(),
        0.05f)
        << n;
  }
}

TEST(OneSidedSolver, DisabledItIsBulletsLoop) {
  PileWorld bullet(false, 0, false), ours(true, 0, false);
  auto& solver = static_cast<OneSidedContactSolver&>(*ours.solver);
  solver.enabled = false;
  expect_same_worlds(bullet, ours, 100);
  EXPECT_EQ(solver.own_iterations, 0);
  EXPECT_GT(solver.bullet_iterations, 0);
}

TEST(OneSidedSolver, HandsWorldsOutsideItsFastPathToBullet) {
  // Randomised row order, interleaved rows and joints: Bullet's own loop runs (and the worlds
  // stay equal: the random order comes from the solver's seed, the same in both).
  for (const int mode :
       {int(SOLVER_RANDMIZE_ORDER), int(SOLVER_INTERLEAVE_CONTACT_AND_FRICTION_CONSTRAINTS)}) {
    PileWorld bullet(false, mode, false), ours(true, mode, false);
    expect_same_worlds(bullet, ours, 200);
    const auto& solver = static_cast<const OneSidedContactSolver&>(*ours.solver);
    EXPECT_EQ(solver.own_iterations, 0) << mode;
    EXPECT_GT(solver.bullet_iterations, 0) << mode;
  }
  PileWorld bullet(false, 0, true), ours(true, 0, true);
  expect_same_worlds(bullet, ours, 200);
  const auto& solver = static_cast<const OneSidedContactSolver&>(*ours.solver);
  EXPECT_EQ(solver.own_iterations, 0);
  EXPECT_GT(solver.bullet_iterations, 0);
}

}  // namespace
