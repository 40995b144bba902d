// Tests of the private hull cache of the drop (cpp/src/physics/hull_cache.hpp): an entry holds
// exactly what a fresh preparation builds (rigid_geometry + rigid_shape, compared array by
// array, bit for bit), any changed input of the preparation is a new entry, the capacity bounds
// the memory (least recently used evicted), and concurrent use gives the serial results.
#include <gtest/gtest.h>
#include <mgn/geometry/convex_decomposition.hpp>
#include <mgn/geometry/mass_properties.hpp>
#include <mgn/geometry/primitives.hpp>

#include "physics/bullet.hpp"
#include "physics/hull_cache.hpp"

#include <BulletCollision/CollisionShapes/btConvexPolyhedron.h>

#include <cmath>
#include <cstring>
#include <thread>
#include <vector>

namespace {

using mgn::physics::HullShapeOptions;
using mgn::physics::kDropUnits;
using mgn::physics::prepared_hulls;

mgn::RigidObject object_of(const mgn::Mesh& mesh) {
  const auto mp = mgn::compute_mass_properties(mesh, {700.0});
  mgn::RigidObject o;
  o.convex_parts = mgn::convex_decomposition(mesh);
  o.mass = mp.mass;
  o.com = mp.center_of_mass;
  o.inertia = mp.inertia;
  o.name = "o";
  return o;
}

/// An L-shaped bracket (two boxes: a decomposition of several parts).
mgn::Mesh bracket() {
  mgn::Mesh a = mgn::make_box({0.08, 0.02, 0.01});
  mgn::Mesh b = mgn::make_box({0.02, 0.06, 0.01});
  mgn::Pose X = mgn::Pose::Identity();
  X.translation() = mgn::Vec3d(-0.03, 0.04, 0.0);
  return mgn::Mesh::merge({a, b.transformed(X)});
}

HullShapeOptions drop_options() {  // the drop's defaults (DropOptions -> hull_options)
  HullShapeOptions h;
  h.reduction = mgn::HullReduction::Outer;
  h.max_vertices = 48;
  h.tolerance = 0.0002;
  h.margin = 0.001;
  h.polyhedral = true;
  return h;
}

bool same_bytes(const void* a, const void* b, std::size_t n) { return std::memcmp(a, b, n) == 0; }

/// Every array a simulation reads from a hull shape, compared bit for bit.
void expect_same_shape(const btConvexHullShape& a, const btConvexHullShape& b) {
  ASSERT_EQ(a.getNumPoints(), b.getNumPoints());
  for (int k = 0; k < a.getNumPoints(); ++k)
    EXPECT_TRUE(same_bytes(&a.getUnscaledPoints()[k], &b.getUnscaledPoints()[k], 12)) << k;
  EXPECT_EQ(a.getMargin(), b.getMargin());
  EXPECT_EQ(a.getShapeType(), b.getShapeType());
  btVector3 alo, ahi, blo, bhi;
  a.getAabb(btTransform::getIdentity(), alo, ahi);
  b.getAabb(btTransform::getIdentity(), blo, bhi);
  EXPECT_TRUE(same_bytes(&alo, &blo, 12) && same_bytes(&ahi, &bhi, 12));
  const btConvexPolyhedron* p = a.getConvexPolyhedron();
  const btConvexPolyhedron* q = b.getConvexPolyhedron();
  ASSERT_EQ(p == nullptr, q == nullptr);
  if (p == nullptr) return;
  ASSERT_EQ(p->m_vertices.size(), q->m_vertices.size());
  for (int k = 0; k < p->m_vertices.size(); ++k)
    EXPECT_TRUE(same_bytes(&p->m_vertices[k], &q->m_vertices[k], 12)) << k;
  ASSERT_EQ(p->m_faces.size(), q->m_faces.size());
  for (int f = 0; f < p->m_faces.size(); ++f) {
    ASSERT_EQ(p->m_faces[f].m_indices.size(), q->m_faces[f].m_indices.size());
    for (int k = 0; k < p->m_faces[f].m_indices.size(); ++k)
      EXPECT_EQ(p->m_faces[f].m_indices[k], q->m_faces[f].m_indices[k]);
    EXPECT_TRUE(same_bytes(p->m_faces[f].m_plane, q->m_faces[f].m_plane, 4 * sizeof(btScalar)));
  }
  ASSERT_EQ(p->m_uniqueEdges.size(), q->m_uniqueEdges.size());
  for (int k = 0; k < p->m_uniqueEdges.size(); ++k)
    EXPECT_TRUE(same_bytes(&p->m_uniqueEdges[k], &q->m_uniqueEdges[k], 12)) << k;
  EXPECT_TRUE(same_bytes(&p->m_localCenter, &q->m_localCenter, 12));
  EXPECT_TRUE(same_bytes(&p->m_extents, &q->m_extents, 12));
  EXPECT_EQ(p->m_radius, q->m_radius);
  // Support queries along many directions: the same vertex.
  for (int k = 0; k < 200; ++k) {
    const btVector3 d(btScalar(std::cos(0.37 * k)), btScalar(std::sin(0.21 * k)),
                      btScalar(std::cos(0.11 * k + 1.0)));
    const btVector3 u = a.localGetSupportingVertex(d), v = b.localGetSupportingVertex(d);
    EXPECT_TRUE(same_bytes(&u, &v, 12)) << k;
  }
}

/// A fresh preparation, as the drop made it before the cache: rigid_geometry + rigid_shape.
mgn::physics::RigidShape fresh(const mgn::RigidObject& o, const HullShapeOptions& h) {
  const auto pr = mgn::principal_frame(o, "test");
  return mgn::physics::rigid_shape(mgn::physics::rigid_geometry(o, pr, kDropUnits, h), kDropUnits,
                                   h, true);
}

class HullCache : public ::testing::Test {
 protected:
  void SetUp() override {
    mgn::physics::set_hull_cache_capacity(mgn::physics::kDefaultHullCacheCapacity);
    mgn::physics::clear_hull_cache();
  }
  void TearDown() override { SetUp(); }
};

}  // namespace

TEST_F(HullCache, AnEntryIsWhatAFreshPreparationBuilds) {
  for (const mgn::Mesh& mesh : {mgn::make_box({0.1, 0.06, 0.04}), mgn::make_sphere(0.03, 48, 24),
                                bracket(), mgn::make_cylinder(0.03, 0.1, 96)}) {
    const mgn::RigidObject o = object_of(mesh);
    for (bool polyhedral : {true, false}) {
      HullShapeOptions h = drop_options();
      h.polyhedral = polyhedral;
      h.shrink_by_margin = !polyhedral;
      const auto pr = mgn::principal_frame(o, "test");
      const auto first = prepared_hulls(o, pr, kDropUnits, h);   // prepared now
      const auto second = prepared_hulls(o, pr, kDropUnits, h);  // from the cache
      EXPECT_EQ(first.get(), second.get());
      const mgn::physics::RigidShape reference = fresh(o, h);
      ASSERT_EQ(first->hulls.size(), reference.hulls.size());
      ASSERT_EQ(first->hulls.size(), o.convex_parts.size());
      for (std::size_t k = 0; k < reference.hulls.size(); ++k)
        expect_same_shape(*first->hulls[k], *reference.hulls[k]);
      EXPECT_GT(first->bytes, 0u);
    }
  }
  const auto info = mgn::physics::hull_cache_info();
  EXPECT_EQ(info.misses, 8);
  EXPECT_EQ(info.hits, 8);
  EXPECT_EQ(info.entries, 8u);
}

TEST_F(HullCache, EveryChangedInputIsANewEntry) {
  const mgn::RigidObject o = object_of(bracket());
  const HullShapeOptions h = drop_options();
  const auto pr = mgn::principal_frame(o, "test");
  const auto base = prepared_hulls(o, pr, kDropUnits, h);

  std::vector<std::pair<const char*, std::shared_ptr<const mgn::physics::PreparedHulls>>> changed;
  mgn::RigidObject one_ulp = o;  // one vertex coordinate moved by one float ulp
  {
    mgn::Points3f V = one_ulp.convex_parts[0].vertices();
    V(0, 0) = std::nextafter(V(0, 0), 1.0f);
    one_ulp.convex_parts[0] = mgn::Mesh(V, one_ulp.convex_parts[0].faces());
    changed.emplace_back(
        "vertex", prepared_hulls(one_ulp, mgn::principal_frame(one_ulp, "t"), kDropUnits, h));
  }
  mgn::RigidObject scaled = object_of(bracket().scaled(1.25));
  changed.emplace_back("scale",
                       prepared_hulls(scaled, mgn::principal_frame(scaled, "t"), kDropUnits, h));
  mgn::RigidObject com = o;
  com.com.x() += 1e-4;
  changed.emplace_back("com", prepared_hulls(com, mgn::principal_frame(com, "t"), kDropUnits, h));
  mgn::RigidObject inertia = o;  // other principal moments and axes
  inertia.inertia(0, 1) = inertia.inertia(1, 0) = 0.1 * inertia.inertia(0, 0);
  changed.emplace_back("inertia",
                       prepared_hulls(inertia, mgn::principal_frame(inertia, "t"), kDropUnits, h));
  mgn::RigidObject fewer = o;  // a part less
  fewer.convex_parts.pop_back();
  changed.emplace_back("parts",
                       prepared_hulls(fewer, mgn::principal_frame(fewer, "t"), kDropUnits, h));
  auto with = [&](const char* what, HullShapeOptions x) {
    changed.emplace_back(what, prepared_hulls(o, pr, kDropUnits, x));
  };
  HullShapeOptions x = h;
  x.max_vertices = 16;
  with("max_vertices", x);
  x = h;
  x.tolerance = 0.0003;
  with("tolerance", x);
  x = h;
  x.margin = 0.002;
  with("margin", x);
  x = h;
  x.polyhedral = false;
  with("polyhedral", x);
  x = h;
  x.shrink_by_margin = true;
  with("shrink_by_margin", x);
  x = h;
  x.reduction = mgn::HullReduction::InnerGreedy;
  with("reduction", x);
  changed.emplace_back("units", prepared_hulls(o, pr, mgn::physics::kShakeUnits, h));

  for (const auto& [what, entry] : changed) EXPECT_NE(entry.get(), base.get()) << what;
  auto info = mgn::physics::hull_cache_info();
  EXPECT_EQ(info.misses, 1 + static_cast<std::int64_t>(changed.size()));
  EXPECT_EQ(info.hits, 0);
  // The original inputs still find the original entry; each changed one equals its fresh build.
  EXPECT_EQ(prepared_hulls(o, pr, kDropUnits, h).get(), base.get());
  const mgn::physics::RigidShape ref = fresh(scaled, h);
  const auto again = prepared_hulls(scaled, mgn::principal_frame(scaled, "t"), kDropUnits, h);
  ASSERT_EQ(again->hulls.size(), ref.hulls.size());
  for (std::size_t k = 0; k < ref.hulls.size(); ++k)
    expect_same_shape(*again->hulls[k], *ref.hulls[k]);
}

TEST_F(HullCache, TheCapacityBoundsTheMemoryLeastRecentlyUsedFirst) {
  const mgn::RigidObject a = object_of(mgn::make_box({0.1, 0.06, 0.04}));
  const mgn::RigidObject b = object_of(mgn::make_box({0.05, 0.05, 0.05}));
  const mgn::RigidObject c = object_of(mgn::make_box({0.08, 0.03, 0.02}));
  const HullShapeOptions h = drop_options();
  auto get = [&](const mgn::RigidObject& o) {
    return prepared_hulls(o, mgn::principal_frame(o, "t"), kDropUnits, h);
  };
  const std::size_t one = get(a)->bytes;
  mgn::physics::clear_hull_cache();
  // Room for two boxes (all three have one 8-vertex hull: about the same size).
  mgn::physics::set_hull_cache_capacity(2 * one + one / 2);
  const auto pa = get(a);
  const auto pb = get(b);
  EXPECT_EQ(get(a).get(), pa.get());  // a is now the most recently used
  get(c);                             // evicts b, the least recently used
  auto info = mgn::physics::hull_cache_info();
  EXPECT_EQ(info.entries, 2u);
  EXPECT_LE(info.bytes, info.capacity);
  EXPECT_EQ(info.evictions, 1);
  EXPECT_EQ(get(a).get(), pa.get());
  EXPECT_NE(get(b).get(), pb.get());  // prepared again
  EXPECT_EQ(pb->hulls.size(), 1u);    // the evicted entry lives on while it is held
  // A capacity below one entry caches nothing; 0 turns the cache off.
  mgn::physics::set_hull_cache_capacity(one / 2);
  info = mgn::physics::hull_cache_info();
  EXPECT_EQ(info.entries, 0u);
  EXPECT_EQ(info.bytes, 0u);
  EXPECT_NE(get(a).get(), get(a).get());
  mgn::physics::set_hull_cache_capacity(0);
  EXPECT_NE(get(a).get(), get(a).get());
  EXPECT_EQ(mgn::physics::hull_cache_info().entries, 0u);
}

TEST_F(HullCache, TwoThreadsGetTheSameEntriesAsOne) {
  std::vector<mgn::RigidObject> objects;
  for (double s : {1.0, 1.1, 1.2, 1.3}) objects.push_back(object_of(bracket().scaled(s)));
  const HullShapeOptions h = drop_options();
  std::vector<const mgn::physics::PreparedHulls*> seen[2];
  std::vector<std::shared_ptr<const mgn::physics::PreparedHulls>> keep[2];
  auto work = [&](int t) {
    for (int round = 0; round < 20; ++round)
      for (std::size_t i = 0; i < objects.size(); ++i) {
        const std::size_t k = (i + static_cast<std::size_t>(t)) % objects.size();
        keep[t].push_back(
            prepared_hulls(objects[k], mgn::principal_frame(objects[k], "t"), kDropUnits, h));
        if (round == 19) seen[t].push_back(keep[t].back().get());
      }
  };
  std::thread other(work, 1);
  work(0);
  other.join();
  // After both threads are done every object has one entry, the one both threads got last.
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const auto entry =
        prepared_hulls(objects[i], mgn::principal_frame(objects[i], "t"), kDropUnits, h);
    EXPECT_EQ(seen[0][i], entry.get()) << i;
    EXPECT_EQ(seen[1][(i + objects.size() - 1) % objects.size()], entry.get()) << i;
    const mgn::physics::RigidShape ref = fresh(objects[i], h);
    for (std::size_t k = 0; k < ref.hulls.size(); ++k)
      expect_same_shape(*entry->hulls[k], *ref.hulls[k]);
  }
  EXPECT_EQ(mgn::physics::hull_cache_info().entries, objects.size());
}
