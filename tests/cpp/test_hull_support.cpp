// Tests of the private vectorised hull support search
// (cpp/src/physics/bullet_ext/hull_support.hpp): it must give exactly Bullet's answers
// (btVector3::maxDot, btConvexHullShape, GJK), ties included, so that the drop and the shake test
// are unchanged bit for bit.
#include <gtest/gtest.h>

#include "physics/bullet_ext/hull_support.hpp"
#include "physics/bullet_ext/separated_pair_skip.hpp"

#include <BulletCollision/NarrowPhaseCollision/btGjkEpaPenetrationDepthSolver.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkPairDetector.h>
#include <BulletCollision/NarrowPhaseCollision/btPointCollector.h>
#include <BulletCollision/NarrowPhaseCollision/btVoronoiSimplexSolver.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

namespace {

using mgn::physics::FastHullShape;
using mgn::physics::HullSupport;

std::vector<btVector3> random_points(std::mt19937& rng, int n) {
  std::normal_distribution<float> g(0.0f, 0.05f);
  std::vector<btVector3> p;
  for (int i = 0; i < n; ++i) p.emplace_back(g(rng), g(rng), g(rng));
  return p;
}

btVector3 random_direction(std::mt19937& rng) {
  std::normal_distribution<float> g(0.0f, 1.0f);
  return btVector3(g(rng), g(rng), g(rng));
}

bool same_bits(const btVector3& a, const btVector3& b) {
  return std::memcmp(&a.x(), &b.x(), 3 * sizeof(btScalar)) == 0;
}

/// Bullet's own scan (the truth): index and dot product of btVector3::maxDot.
long bullet_argmax(const std::vector<btVector3>& p, const btVector3& d, btScalar& dot) {
  return d.maxDot(p.data(), static_cast<long>(p.size()), dot);
}

/// Runs `body` with every scan width the processor has (8, 4, 1), then restores the widest.
template <class F>
void for_each_width(F body) {
  for (int w : {8, 4, 1}) {
    if (HullSupport::set_width(w) != w) continue;
    SCOPED_TRACE(testing::Message() << "width " << w);
    body();
  }
  HullSupport::set_width(0);
}

TEST(HullSupport, SameVertexAndDotAsBulletsScanForRandomHulls) {
  for_each_width([] {
    std::mt19937 rng(7);
    for (int n : {1, 3, 4, 7, 8, 9, 15, 16, 17, 31, 64, 96, 97, 300}) {
      const std::vector<btVector3> p = random_points(rng, n);
      const HullSupport s(p.data(), n);
      for (int k = 0; k < 500; ++k) {
        const btVector3 d = random_direction(rng);
        btScalar want_dot, got_dot;
        const long want = bullet_argmax(p, d, want_dot);
        const long got = s.argmax(d, got_dot);
        ASSERT_EQ(got, want) << "n " << n << " direction " << k;
        ASSERT_EQ(got_dot, want_dot);
      }
    }
  });
}

TEST(HullSupport, TiesGoToTheFirstVertexAsInBulletsScan) {
  for_each_width([] {
    // A cube's corners (repeated, so that equal maxima fall in different SIMD lanes) queried
    // along the axes and face diagonals: whole faces and edges tie.
    std::vector<btVector3> p;
    for (int rep = 0; rep < 3; ++rep)
      for (int i = 0; i < 8; ++i)
        p.emplace_back(i & 1 ? 0.1f : -0.1f, i & 2 ? 0.1f : -0.1f, i & 4 ? 0.1f : -0.1f);
    std::swap(p[3], p[17]);  // not in lane order
    const HullSupport s(p.data(), static_cast<int>(p.size()));
    int ties = 0;
    for (int x = -1; x <= 1; ++x)
      for (int y = -1; y <= 1; ++y)
        for (int z = -1; z <= 1; ++z) {
          const btVector3 d{btScalar(x), btScalar(y), btScalar(z)};
          btScalar want_dot, got_dot;
          const long want = bullet_argmax(p, d, want_dot);
          EXPECT_EQ(s.argmax(d, got_dot), want) << x << " " << y << " " << z;
          EXPECT_EQ(got_dot, want_dot);
          int equal = 0;
          for (const btVector3& v : p) equal += v.dot(d) == want_dot;
          ties += equal > 1;
        }
    EXPECT_EQ(ties, 27);  // every direction ties: 3 copies of each corner
  });
}

TEST(HullSupport, HugeAndNanDirectionsAsBullet) {
  for_each_width([] {
    const std::vector<btVector3> p = {btVector3(1, 0, 0), btVector3(2, 0, 0), btVector3(-3, 0, 0)};
    const HullSupport s(p.data(), 3);
    for (const btVector3& d :
         {btVector3(-1e30f, 0, 0), btVector3(1e38f, 0, 0), btVector3(std::nanf(""), 0, 0)}) {
      btScalar want_dot, got_dot;
      EXPECT_EQ(s.argmax(d, got_dot), bullet_argmax(p, d, want_dot));
      EXPECT_EQ(got_dot, want_dot);
    }
    btScalar dot;
    EXPECT_EQ(HullSupport().argmax(btVector3(1, 0, 0), dot), -1);
  });
}

std::unique_ptr<btConvexHullShape> bullet_hull(const std::vector<btVector3>& p, float margin) {
  auto h = std::make_unique<btConvexHullShape>();
  for (const btVector3& v : p) h->addPoint(v, false);
  h->recalcLocalAabb();
  h->setMargin(margin);
  h->initializePolyhedralFeatures();
  return h;
}

std::unique_ptr<FastHullShape> fast_hull(const std::vector<btVector3>& p, float margin) {
  auto h = std::make_unique<FastHullShape>(p);
  h->recalcLocalAabb();
  h->setMargin(margin);
  h->initializePolyhedralFeatures();
  return h;
}

TEST(FastHullShape, SupportAabbAndMarginAsBulletsConvexHullShape) {
  std::mt19937 rng(11);
  const std::vector<btVector3> p = random_points(rng, 90);
  const auto a = bullet_hull(p, 0.001f);
  const auto b = fast_hull(p, 0.001f);
  EXPECT_NE(b->getShapeType(), CONVEX_HULL_SHAPE_PROXYTYPE);  // Bullet calls its virtuals
  EXPECT_TRUE(b->isPolyhedral());
  EXPECT_TRUE(b->isConvex());
  EXPECT_EQ(a->getMarginNonVirtual(), b->getMarginNonVirtual());
  btTransform X(btQuaternion(btVector3(1, 2, 3).normalized(), 0.7f), btVector3(0.1f, -0.2f, 0.3f));
  btVector3 a_lo, a_hi, b_lo, b_hi;
  a->getAabbNonVirtual(X, a_lo, a_hi);
  b->getAabbNonVirtual(X, b_lo, b_hi);
  EXPECT_TRUE(same_bits(a_lo, b_lo) && same_bits(a_hi, b_hi));
  std::vector<btVector3> dirs;
  for (int k = 0; k < 200; ++k) dirs.push_back(random_direction(rng));
  for (const btVector3& d : dirs) {
    ASSERT_TRUE(same_bits(a->localGetSupportVertexWithoutMarginNonVirtual(d),
                          b->localGetSupportVertexWithoutMarginNonVirtual(d)));
    ASSERT_TRUE(
        same_bits(a->localGetSupportVertexNonVirtual(d), b->localGetSupportVertexNonVirtual(d)));
    ASSERT_TRUE(same_bits(a->localGetSupportingVertex(d), b->localGetSupportingVertex(d)));
  }
  std::vector<btVector3> unit(dirs.size()), out_a(dirs.size()), out_b(dirs.size());
  for (std::size_t k = 0; k < dirs.size(); ++k) unit[k] = dirs[k].normalized();
  a->batchedUnitVectorGetSupportingVertexWithoutMargin(unit.data(), out_a.data(), int(unit.size()));
  b->batchedUnitVectorGetSupportingVertexWithoutMargin(unit.data(), out_b.data(), int(unit.size()));
  for (std::size_t k = 0; k < dirs.size(); ++k)
    ASSERT_EQ(std::memcmp(&out_a[k], &out_b[k], sizeof(btVector3)), 0) << k;
}

TEST(FastHullShape, GjkAndEpaGiveBulletsClosestPointsBitForBit) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  int penetrating = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const std::vector<btVector3> p = random_points(rng, 40 + trial % 60);
    const std::vector<btVector3> q = random_points(rng, 8 + trial % 90);
    const auto a0 = bullet_hull(p, 0.001f), b0 = bullet_hull(q, 0.001f);
    const auto a1 = fast_hull(p, 0.001f), b1 = fast_hull(q, 0.001f);
    btGjkPairDetector::ClosestPointInput in;
    in.m_transformA = btTransform(btQuaternion(random_direction(rng).normalized(), u(rng) * 3),
                                  btVector3(0, 0, 0));
    in.m_transformB = btTransform(btQuaternion(random_direction(rng).normalized(), u(rng) * 3),
                                  0.15f * btVector3(u(rng), u(rng), u(rng)));
    btPointCollector c0, c1;
    btVoronoiSimplexSolver s0, s1;
    btGjkEpaPenetrationDepthSolver e0, e1;
    btGjkPairDetector(a0.get(), b0.get(), &s0, &e0).getClosestPoints(in, c0, nullptr);
    btGjkPairDetector(a1.get(), b1.get(), &s1, &e1).getClosestPoints(in, c1, nullptr);
    ASSERT_EQ(c0.m_hasResult, c1.m_hasResult) << trial;
    if (!c0.m_hasResult) continue;
    ASSERT_EQ(c0.m_distance, c1.m_distance) << trial;
    ASSERT_TRUE(same_bits(c0.m_pointInWorld, c1.m_pointInWorld)) << trial;
    ASSERT_TRUE(same_bits(c0.m_normalOnBInWorld, c1.m_normalOnBInWorld)) << trial;
    penetrating += c0.m_distance < 0;
  }
  EXPECT_GT(penetrating, 20);  // both GJK and the penetration-depth (EPA) path were exercised
}

}  // namespace

// A box (a finger pad) and a hull moving around it in Bullet collision worlds with and without
// SkipSeparatedConvexCreateFunc on their pair: the skipped calls must change nothing, so every
// manifold point must be the same bit for bit at every step.
struct PairWorld {
  btDefaultCollisionConfiguration config;
  mgn::physics::SkipSeparatedConvexCreateFunc skip;
  btCollisionDispatcher dispatcher;
  btDbvtBroadphase broadphase;
  btCollisionWorld world;
  btCollisionObject box, hull;

  PairWorld(bool skipping, btCollisionShape* box_shape, btCollisionShape* hull_shape)
      : skip(config.getCollisionAlgorithmCreateFunc(BOX_SHAPE_PROXYTYPE,
                                                    CUSTOM_POLYHEDRAL_SHAPE_TYPE)),
        dispatcher(&config),
        world(&dispatcher, &broadphase, &config) {
    if (skipping) {
      for (const int t0 : {BOX_SHAPE_PROXYTYPE, CUSTOM_POLYHEDRAL_SHAPE_TYPE})
        for (const int t1 : {BOX_SHAPE_PROXYTYPE, CUSTOM_POLYHEDRAL_SHAPE_TYPE})
          dispatcher.registerCollisionCreateFunc(t0, t1, &skip);
    }
    box.setCollisionShape(box_shape);
    hull.setCollisionShape(hull_shape);
    hull.setCollisionFlags(0);  // moving: collides with the (static) box
    world.addCollisionObject(&box);
    world.addCollisionObject(&hull);
  }
  ~PairWorld() {
    world.removeCollisionObject(&hull);
    world.removeCollisionObject(&box);
  }
};

TEST(SkipSeparatedPairs, ManifoldsAreBulletsBitForBitWhileSkippingApartSteps) {
  btBoxShape pad(btVector3(0.05f, 0.1f, 0.2f));  // the shake test's pad size in decimetres
  pad.setMargin(0.005f);
  pad.initializePolyhedralFeatures();
  std::mt19937 rng(7);
  std::vector<btVector3> points;
  std::normal_distribution<float> g(0.0f, 1.0f);
  for (int i = 0; i < 40; ++i) {
    const btVector3 d = btVector3(g(rng), g(rng), g(rng)).normalized();
    points.push_back(d * btVector3(0.15f, 0.1f, 0.12f));
  }
  FastHullShape hull(points);
  hull.setMargin(0.005f);
  hull.initializePolyhedralFeatures();

  for (const bool polyhedral_features : {true, false}) {
    // Without polyhedral features Bullet takes its GJK-point path (the same skip applies).
    btBoxShape plain_pad(btVector3(0.05f, 0.1f, 0.2f));
    plain_pad.setMargin(0.005f);
    FastHullShape plain_hull(points);
    plain_hull.setMargin(0.005f);
    btCollisionShape* a = polyhedral_features ? static_cast<btCollisionShape*>(&pad) : &plain_pad;
    btCollisionShape* b = polyhedral_features ? static_cast<btCollisionShape*>(&hull) : &plain_hull;
    PairWorld with(true, a, b), without(false, a, b);
    // The hull wanders around the pad: into it, along it, beside it and away, turning.
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    btVector3 x(0.3f, 0.0f, 0.0f), v(0, 0, 0);
    btQuaternion q = btQuaternion::getIdentity();
    int with_points = 0, without_points = 0;
    for (int step = 0; step < 3000; ++step) {
      v = 0.9f * v + 0.004f * btVector3(u(rng), u(rng), u(rng)) - 0.002f * x;
      x += v;
      q = (q * btQuaternion(btVector3(u(rng), u(rng), u(rng)).normalized(), 0.02f)).normalized();
      const btTransform T(q, x);
      with.hull.setWorldTransform(T);
      without.hull.setWorldTransform(T);
      with.world.performDiscreteCollisionDetection();
      without.world.performDiscreteCollisionDetection();
      const int n = without.dispatcher.getNumManifolds();
      ASSERT_EQ(with.dispatcher.getNumManifolds(), n) << "step " << step;
      for (int i = 0; i < n; ++i) {
        const btPersistentManifold* m0 = without.dispatcher.getManifoldByIndexInternal(i);
        const btPersistentManifold* m1 = with.dispatcher.getManifoldByIndexInternal(i);
        ASSERT_EQ(m1->getNumContacts(), m0->getNumContacts()) << "step " << step;
        for (int c = 0; c < m0->getNumContacts(); ++c) {
          const btManifoldPoint& p0 = m0->getContactPoint(c);
          const btManifoldPoint& p1 = m1->getContactPoint(c);
          for (int k = 0; k < 3; ++k) {
            ASSERT_EQ(p1.m_positionWorldOnB[k], p0.m_positionWorldOnB[k]) << "step " << step;
            ASSERT_EQ(p1.m_positionWorldOnA[k], p0.m_positionWorldOnA[k]) << "step " << step;
            ASSERT_EQ(p1.m_normalWorldOnB[k], p0.m_normalWorldOnB[k]) << "step " << step;
          }
          ASSERT_EQ(p1.m_distance1, p0.m_distance1) << "step " << step;
          ASSERT_EQ(p1.m_lifeTime, p0.m_lifeTime) << "step " << step;
        }
        with_points += m1->getNumContacts() > 0;
        without_points += m0->getNumContacts() > 0;
      }
    }
    // The walk covered both cases, and the skip happened (else the test would prove nothing).
    EXPECT_GT(without_points, 100) << polyhedral_features;
    EXPECT_GT(with.skip.skipped, 100) << polyhedral_features;
    EXPECT_GT(with.skip.run, 100) << polyhedral_features;
    EXPECT_EQ(without.skip.skipped + without.skip.run, 0);
  }
}
