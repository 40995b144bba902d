// Tests of the private one-sided contact solver (cpp/src/physics/bullet_ext/one_sided_solver.hpp):
// a world stepped with it must be the world stepped with Bullet's own sequential-impulse solver,
// bit for bit, step by step; rows of kinematic and static bodies must be solved one-sided (else the
// test would prove nothing about them), and worlds outside its fast path must go to Bullet's loop.
// Its row setup (convertContacts) must give Bullet's rows, field by field, after every setup, and
// manifolds outside its fast path must go to Bullet's convertContact.
#include <gtest/gtest.h>

#include "physics/bullet_ext/one_sided_solver.hpp"

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

bool same_bits(btScalar a, btScalar b) { return std::memcmp(&a, &b, sizeof(btScalar)) == 0; }

/// What a solver's row setup produced in one solve: the rows, the solver bodies' velocity changes
/// (the warm start) and the manifold points' friction directions and flags.
struct SetupRecord {
  struct Point {
    btVector3 direction1, direction2;
    int flags;
  };
  std::vector<btSolverConstraint> contacts, frictions;
  std::vector<btVector3> body_changes;  // linear, angular, per solver body
  std::vector<Point> points;
};

/// A solver that records its row setups (each solveGroup of a step appends one).
template <class Solver>
struct Recording : Solver {
  std::vector<SetupRecord>* records = nullptr;

  void convertContacts(btPersistentManifold** manifolds, int numManifolds,
                       const btContactSolverInfo& info) override {
    Solver::convertContacts(manifolds, numManifolds, info);
    SetupRecord r;
    for (int i = 0; i < this->m_tmpSolverContactConstraintPool.size(); ++i) {
      r.contacts.push_back(this->m_tmpSolverContactConstraintPool[i]);
    }
    for (int i = 0; i < this->m_tmpSolverContactFrictionConstraintPool.size(); ++i) {
      r.frictions.push_back(this->m_tmpSolverContactFrictionConstraintPool[i]);
    }
    for (int i = 0; i < this->m_tmpSolverBodyPool.size(); ++i) {
      r.body_changes.push_back(this->m_tmpSolverBodyPool[i].m_deltaLinearVelocity);
      r.body_changes.push_back(this->m_tmpSolverBodyPool[i].m_deltaAngularVelocity);
    }
    for (int i = 0; i < numManifolds; ++i) {
      for (int j = 0; j < manifolds[i]->getNumContacts(); ++j) {
        const btManifoldPoint& cp = manifolds[i]->getContactPoint(j);
        r.points.push_back(
            {cp.m_lateralFrictionDir1, cp.m_lateralFrictionDir2, cp.m_contactPointFlags});
      }
    }
    records->push_back(std::move(r));
  }
};

/// Rows equal field by field (every field Bullet's setup writes). The angular components may
/// differ in the sign of a zero only (a still body's, which Bullet computes as zero inertia
/// times a lever arm); every other float has the same bits.
::testing::AssertionResult same_rows(const btSolverConstraint& a, const btSolverConstraint& b) {
  auto fail = [](const char* field) { return ::testing::AssertionFailure() << field; };
  if (!same_bits(a.m_relpos1CrossNormal, b.m_relpos1CrossNormal)) return fail("relpos1");
  if (!same_bits(a.m_contactNormal1, b.m_contactNormal1)) return fail("normal1");
  if (!same_bits(a.m_relpos2CrossNormal, b.m_relpos2CrossNormal)) return fail("relpos2");
  if (!same_bits(a.m_contactNormal2, b.m_contactNormal2)) return fail("normal2");
  auto same_or_zeros = [](const btVector3& u, const btVector3& v) {
    return same_bits(u, v) || (u == btVector3(0, 0, 0) && v == btVector3(0, 0, 0));
  };
  if (!same_or_zeros(a.m_angularComponentA, b.m_angularComponentA)) return fail("angularA");
  if (!same_or_zeros(a.m_angularComponentB, b.m_angularComponentB)) return fail("angularB");
  if (!same_bits(a.m_appliedPushImpulse, b.m_appliedPushImpulse)) return fail("push impulse");
  if (!same_bits(a.m_appliedImpulse, b.m_appliedImpulse)) return fail("impulse");
  if (!same_bits(a.m_friction, b.m_friction)) return fail("friction");
  if (!same_bits(a.m_jacDiagABInv, b.m_jacDiagABInv)) return fail("jacDiagABInv");
  if (!same_bits(a.m_rhs, b.m_rhs)) return fail("rhs");
  if (!same_bits(a.m_cfm, b.m_cfm)) return fail("cfm");
  if (!same_bits(a.m_lowerLimit, b.m_lowerLimit)) return fail("lower limit");
  if (!same_bits(a.m_upperLimit, b.m_upperLimit)) return fail("upper limit");
  if (!same_bits(a.m_rhsPenetration, b.m_rhsPenetration)) return fail("rhsPenetration");
  // Each world's rows point to its own manifold points: same kind of row.
  if ((a.m_originalContactPoint == nullptr) != (b.m_originalContactPoint == nullptr)) {
    return fail("contact point");
  }
  if (a.m_frictionIndex != b.m_frictionIndex) return fail("friction index");
  if (a.m_solverBodyIdA != b.m_solverBodyIdA || a.m_solverBodyIdB != b.m_solverBodyIdB) {
    return fail("bodies");
  }
  return ::testing::AssertionSuccess();
}

/// Variants of the pile world's materials and solver options.
struct Variant {
  bool soft_pad = true;        // the pusher's contacts soft (stiffness and damping)
  bool two_directions = true;  // SOLVER_USE_2_FRICTION_DIRECTIONS
  float restitution = 0;       // every body's (the contacts' is the product of two)
  bool friction_anchor = false;
  float rolling_friction = 0;         // on dynamic body 3 (its manifolds go to Bullet's setup)
  bool anisotropic_friction = false;  // on dynamic body 4 (likewise)
  bool warm_start = true;             // SOLVER_USE_WARMSTARTING (Bullet's default: on)
  bool split_impulse = true;          // m_splitImpulse (Bullet's default: on)
  // The dynamic bodies enter the world before the floor and the pusher: a manifold's first body
  // is the one added first, so the still body is then B in every contact row (else A).
  bool dynamic_first = false;
};

/// A tray (static), a kinematic pusher squeezing and shaking, and a pile of dynamic boxes and
/// hulls: contacts of every kind (dynamic-static, dynamic-kinematic, dynamic-dynamic).
struct PileWorld {
  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  std::unique_ptr<btSequentialImpulseConstraintSolver> solver;
  std::vector<SetupRecord> setups;  // the row setups of the last step
  std::unique_ptr<btDiscreteDynamicsWorld> world;
  btBoxShape floor_shape{btVector3(1.0f, 1.0f, 0.05f)};
  btBoxShape pusher_shape{btVector3(0.05f, 0.3f, 0.2f)};
  btBoxShape box_shape{btVector3(0.08f, 0.06f, 0.05f)};
  btConvexHullShape hull_shape;
  std::vector<std::unique_ptr<btRigidBody>> bodies;
  btRigidBody* pusher = nullptr;
  std::unique_ptr<btTypedConstraint> joint;

  PileWorld(bool one_sided, int solver_mode_flags, bool with_joint, int num_dynamic = 8,
            const Variant& variant = {}) {
    if (one_sided) {
      auto s = std::make_unique<Recording<OneSidedContactSolver>>();
      s->records = &setups;
      solver = std::move(s);
    } else {
      auto s = std::make_unique<Recording<btSequentialImpulseConstraintSolver>>();
      s->records = &setups;
      solver = std::move(s);
    }
    world =
        std::make_unique<btDiscreteDynamicsWorld>(&dispatcher, &broadphase, solver.get(), &config);
    world->setGravity(btVector3(0, 0, -9.81f));
    world->getSolverInfo().m_solverMode |= solver_mode_flags;
    if (variant.two_directions) {
      world->getSolverInfo().m_solverMode |= SOLVER_USE_2_FRICTION_DIRECTIONS;
    }
    if (!variant.warm_start) world->getSolverInfo().m_solverMode &= ~SOLVER_USE_WARMSTARTING;
    world->getSolverInfo().m_splitImpulse = variant.split_impulse;
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
    if (variant.soft_pad) {
      pusher->setContactStiffnessAndDamping(3e4f, 200.0f);  // a soft pad, as the shake test's
    }
    std::uniform_real_distribution<float> u(-0.15f, 0.15f);
    for (int i = 0; i < num_dynamic; ++i) {
      btCollisionShape* s = i % 2 ? static_cast<btCollisionShape*>(&hull_shape) : &box_shape;
      btRigidBody* b = add(s, 0.2f + 0.1f * i, btVector3(u(rng), u(rng), 0.1f + 0.15f * i));
      b->setWorldTransform(
          btTransform(btQuaternion(u(rng), u(rng), u(rng)), b->getWorldTransform().getOrigin()));
    }
    for (auto& b : bodies) {
      b->setRestitution(variant.restitution);
      if (variant.friction_anchor) {
        b->setCollisionFlags(b->getCollisionFlags() | btCollisionObject::CF_HAS_FRICTION_ANCHOR);
      }
    }
    if (variant.rolling_friction > 0) bodies[3]->setRollingFriction(variant.rolling_friction);
    if (variant.anisotropic_friction) {
      bodies[4]->setAnisotropicFriction(btVector3(1.0f, 0.3f, 1.0f));
    }
    // Into the world in the variant's order (the body list keeps floor, pusher, dynamic ones).
    if (variant.dynamic_first) std::rotate(bodies.begin(), bodies.begin() + 2, bodies.end());
    for (auto& b : bodies) world->addRigidBody(b.get());
    if (variant.dynamic_first) std::rotate(bodies.begin(), bodies.end() - 2, bodies.end());
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
    return bodies.back().get();
  }

  /// The pusher closes in and shakes (kinematic: pose set, velocity from the move).
  void step(int k) {
    const float t = k / 240.0f;
    btTransform T = pusher->getWorldTransform();
    T.setOrigin(btVector3(-0.35f + 0.3f * std::min(t, 1.0f), 0.05f * std::sin(9.0f * t),
                          0.2f + 0.03f * std::sin(13.0f * t)));
    pusher->setWorldTransform(T);
    setups.clear();
    world->stepSimulation(1.0f / 240.0f, 0, 1.0f / 240.0f);
  }

  ~PileWorld() {
    if (joint) world->removeConstraint(joint.get());
    for (auto& b : bodies) world->removeRigidBody(b.get());
  }
};

/// Compares the row setups of one step.
void expect_same_setups(const PileWorld& bullet, const PileWorld& ours, int k) {
  ASSERT_EQ(bullet.setups.size(), ours.setups.size()) << "step " << k;
  for (std::size_t s = 0; s < bullet.setups.size(); ++s) {
    const SetupRecord& a = bullet.setups[s];
    const SetupRecord& b = ours.setups[s];
    ASSERT_EQ(a.contacts.size(), b.contacts.size()) << "step " << k;
    ASSERT_EQ(a.frictions.size(), b.frictions.size()) << "step " << k;
    for (std::size_t i = 0; i < a.contacts.size(); ++i) {
      ASSERT_TRUE(same_rows(a.contacts[i], b.contacts[i])) << "contact row " << i << " step " << k;
    }
    for (std::size_t i = 0; i < a.frictions.size(); ++i) {
      ASSERT_TRUE(same_rows(a.frictions[i], b.frictions[i]))
          << "friction row " << i << " step " << k;
    }
    ASSERT_EQ(a.body_changes.size(), b.body_changes.size()) << "step " << k;
    for (std::size_t i = 0; i < a.body_changes.size(); ++i) {
      ASSERT_TRUE(same_bits(a.body_changes[i], b.body_changes[i]))
          << "solver body " << i / 2 << " step " << k;
    }
    ASSERT_EQ(a.points.size(), b.points.size()) << "step " << k;
    for (std::size_t i = 0; i < a.points.size(); ++i) {
      ASSERT_TRUE(same_bits(a.points[i].direction1, b.points[i].direction1))
          << "point " << i << " step " << k;
      ASSERT_TRUE(same_bits(a.points[i].direction2, b.points[i].direction2))
          << "point " << i << " step " << k;
      ASSERT_EQ(a.points[i].flags, b.points[i].flags) << "point " << i << " step " << k;
    }
  }
}

/// Steps both worlds and compares the row setups and every body after every step.
void expect_same_worlds(PileWorld& bullet, PileWorld& ours, int steps) {
  for (int k = 0; k < steps; ++k) {
    bullet.step(k);
    ours.step(k);
    expect_same_setups(bullet, ours, k);
    if (::testing::Test::HasFatalFailure()) return;
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
  // Every manifold's rows were set up by the solver's own setup.
  EXPECT_GT(solver.own_manifolds, 2000);
  EXPECT_EQ(solver.bullet_manifolds, 0);
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
    if (n != 2) {
      EXPECT_GT(solver.packed_iterations, 5000);
    }
    if (n == 2) {
      EXPECT_LT(solver.packed_iterations, solver.own_iterations / 2);
    }
    EXPECT_GT(solver.own_manifolds, 900) << n;
    EXPECT_EQ(solver.bullet_manifolds, 0) << n;
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
  EXPECT_EQ(solver.own_manifolds, 0);
  EXPECT_GT(solver.bullet_manifolds, 0);
}

TEST(OneSidedSolver, SetsUpRowsAsBulletForEveryCoveredOption) {
  // The pile (contacts with the static floor, the kinematic pusher and between dynamic bodies)
  // and the one-body world (the shake test's case), with the options the setup covers: plain or
  // soft pusher contacts, one or two friction directions, restitution, friction anchors, cached
  // friction directions, warm starting and split impulse off, the still body first or second
  // in the manifolds. expect_same_worlds compares every
  // row setup field by field and the bodies after every step.
  struct Case {
    const char* name;
    int num_dynamic;
    int solver_mode;
    Variant variant;
  };
  Variant plain;
  plain.soft_pad = false;
  Variant one_direction;
  one_direction.two_directions = false;
  Variant plain_one_direction = plain;
  plain_one_direction.two_directions = false;
  Variant bouncy;
  bouncy.restitution = 0.6f;
  Variant anchored;
  anchored.friction_anchor = true;
  Variant cold;
  cold.warm_start = false;
  cold.split_impulse = false;
  Variant dynamic_first;
  dynamic_first.dynamic_first = true;
  Variant dynamic_first_plain = plain;
  dynamic_first_plain.dynamic_first = true;
  const int cached = SOLVER_ENABLE_FRICTION_DIRECTION_CACHING |
                     SOLVER_DISABLE_VELOCITY_DEPENDENT_FRICTION_DIRECTION;
  const Case cases[] = {
      {"pile, plain pad", 8, 0, plain},
      {"pile, one friction direction", 8, 0, one_direction},
      {"pile, restitution", 8, 0, bouncy},
      {"pile, friction anchors", 8, 0, anchored},
      {"pile, no warm start, no split impulse", 8, 0, cold},
      {"pile, cached friction directions", 8, cached, {}},
      {"pile, fixed friction directions, one", 8,
       SOLVER_DISABLE_VELOCITY_DEPENDENT_FRICTION_DIRECTION, one_direction},
      {"pile, still bodies second", 8, 0, dynamic_first},
      {"one body, still bodies second", 1, 0, dynamic_first},
      {"one body, still bodies second, plain pad", 1, 0, dynamic_first_plain},
      {"one body, plain pad, one friction direction", 1, 0, plain_one_direction},
      {"one body, restitution", 1, 0, bouncy},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    PileWorld bullet(false, c.solver_mode, false, c.num_dynamic, c.variant);
    PileWorld ours(true, c.solver_mode, false, c.num_dynamic, c.variant);
    expect_same_worlds(bullet, ours, 400);
    const auto& solver = static_cast<const OneSidedContactSolver&>(*ours.solver);
    EXPECT_GT(solver.own_manifolds, c.num_dynamic > 1 ? 1000 : 300);
    EXPECT_EQ(solver.bullet_manifolds, 0);
    EXPECT_GT(ours.bodies.back()->getLinearVelocity().length() +
                  ours.bodies.back()->getWorldTransform().getOrigin().distance(
                      btVector3(0, 0, 0.1f + 0.15f * (c.num_dynamic - 1))),
              0.05f);
  }
}

TEST(OneSidedSolver, HandsManifoldsOutsideItsSetupToBullet) {
  // Rolling friction (torsional rows) and anisotropic friction on one body each: their
  // manifolds are set up by Bullet's convertContact, the others by the solver's, in one pool.
  Variant v;
  v.rolling_friction = 0.05f;
  v.anisotropic_friction = true;
  PileWorld bullet(false, 0, false, 8, v), ours(true, 0, false, 8, v);
  expect_same_worlds(bullet, ours, 400);
  const auto& solver = static_cast<const OneSidedContactSolver&>(*ours.solver);
  EXPECT_GT(solver.own_manifolds, 500);
  EXPECT_GT(solver.bullet_manifolds, 100);
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
