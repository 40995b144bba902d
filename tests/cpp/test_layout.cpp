// Layout labels on hand-built label images with known answers: rectangles at known depths,
// rendered by a z-buffer written here (the nearest rectangle wins each pixel).
#include <gtest/gtest.h>
#include <mgn/core/error.hpp>
#include <mgn/core/rng.hpp>
#include <mgn/scene/layout.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace {

using mgn::compute_layout;
using mgn::Layout;
using mgn::LayoutImages;
using mgn::LayoutOptions;

struct Rect {
  int r0, c0, r1, c1;  // inclusive-exclusive: rows [r0, r1), cols [c0, c1)
  float z;             // depth, m
  int category;
};

/// Label images of axis-aligned rectangles, each at a constant depth.
struct Synthetic {
  int H, W, N;
  std::vector<std::int32_t> visible;
  std::vector<std::uint8_t> amodal;
  std::vector<float> depth;
  std::vector<std::int32_t> categories;
  std::vector<double> occlusion;

  Synthetic(int h, int w, const std::vector<Rect>& rects)
      : H(h), W(w), N(static_cast<int>(rects.size())) {
    visible.assign(static_cast<std::size_t>(H) * W, 0);
    depth.assign(visible.size(), 0.0f);
    amodal.assign(static_cast<std::size_t>(N) * H * W, 0);
    for (int i = 0; i < N; ++i) {
      const Rect& q = rects[i];
      categories.push_back(q.category);
      for (int r = q.r0; r < q.r1; ++r)
        for (int c = q.c0; c < q.c1; ++c) {
          const std::size_t p = static_cast<std::size_t>(r) * W + c;
          amodal[static_cast<std::size_t>(i) * H * W + p] = 1;
          if (visible[p] == 0 || q.z < depth[p]) {
            visible[p] = i + 1;
            depth[p] = q.z;
          }
        }
    }
    recompute_occlusion();
  }

  void recompute_occlusion() {
    occlusion.assign(static_cast<std::size_t>(N), 0.0);
    for (int i = 0; i < N; ++i) {
      double a = 0, v = 0;
      for (std::size_t p = 0; p < visible.size(); ++p) {
        a += amodal[static_cast<std::size_t>(i) * H * W + p];
        v += visible[p] == i + 1;
      }
      occlusion[static_cast<std::size_t>(i)] = a > 0 ? 1.0 - v / a : 1.0;
    }
  }

  LayoutImages images() const {
    LayoutImages im;
    im.height = H;
    im.width = W;
    im.num_objects = N;
    im.visible = visible.data();
    im.amodal = amodal.data();
    im.depth = depth.data();
    im.categories = categories.data();
    im.occlusion = occlusion.data();
    return im;
  }

  int M(const Layout& L, int i, int j) const {
    return L.relation[static_cast<std::size_t>(i) * N + j];
  }
};

const mgn::LayoutRelation* find_relation(const Layout& L, int parent, int child) {
  for (const auto& r : L.relations)
    if (r.parent == parent && r.child == child) return &r;
  return nullptr;
}

TEST(Layout, SideBySideRectanglesHaveNoRelation) {
  const Synthetic s(40, 60, {{5, 5, 25, 25, 0.8f, 1}, {5, 30, 25, 55, 0.8f, 2}});
  const Layout L = compute_layout(s.images());
  EXPECT_TRUE(L.relations.empty());
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) EXPECT_EQ(s.M(L, i, j), 0);
  EXPECT_EQ(L.layer[0], 0);
  EXPECT_EQ(L.layer[1], 0);
  EXPECT_EQ(L.num_layers, 1);
  EXPECT_TRUE(L.classes_unique);
  EXPECT_EQ(L.difficulty, 1);
  EXPECT_EQ(L.order, (std::vector<std::int32_t>{1, 2}));
  EXPECT_EQ(L.visible_px[0], 400);
  EXPECT_EQ(L.total_covered_edge[0], 0);
}

TEST(Layout, RectangleOnRectangle) {
  // B (index 1) at 0.9 m: rows 10..29, cols 10..49. A (index 0) at 0.8 m: rows 20..39, cols
  // 20..29 -- covers B's rows 20..29 over 10 columns (100 px).
  const Synthetic s(50, 60, {{20, 20, 40, 30, 0.8f, 1}, {10, 10, 30, 50, 0.9f, 2}});
  const Layout L = compute_layout(s.images());
  EXPECT_EQ(s.M(L, 1, 0), -1);  // A lies on B
  EXPECT_EQ(s.M(L, 0, 1), 1);
  EXPECT_EQ(s.M(L, 0, 0), 0);
  EXPECT_EQ(L.layer[0], 0);
  EXPECT_EQ(L.layer[1], 1);
  ASSERT_EQ(L.relations.size(), 1u);
  const auto* r = find_relation(L, 0, 1);
  ASSERT_NE(r, nullptr);
  EXPECT_EQ(r->seen_px, 100);
  EXPECT_NEAR(r->depth_diff, 0.1, 1e-6);
  // B pixels 4-adjacent to A: row 19 over cols 20..29 (10), col 19 and col 30 over rows 20..29
  // (10 each).
  EXPECT_EQ(r->edge_size, 30);
  // MetaGraspNet: the sum of the children's edge sizes (A covers B along 30 px).
  EXPECT_EQ(L.total_covered_edge[0], 30);
  EXPECT_EQ(L.total_covered_edge[1], 0);
  EXPECT_EQ(L.order, (std::vector<std::int32_t>{1, 2}));
  EXPECT_EQ(L.complete[1], 1);  // B is a U shape: one region
  // B is 100/800 = 12.5 % occluded: level 2 (not 1).
  EXPECT_NEAR(L.max_occlusion, 0.125, 1e-12);
  EXPECT_EQ(L.difficulty, 2);
  LayoutOptions o;
  o.max_occlusion_level1 = 0.2;
  EXPECT_EQ(compute_layout(s.images(), o).difficulty, 1);
}

TEST(Layout, PaperExampleGivesLayersZeroOneThree) {
  // A on B on C, and A also directly on C.
  const Synthetic s(80, 80,
                    {{30, 30, 50, 50, 0.7f, 1},    // A
                     {20, 20, 45, 45, 0.8f, 2},    // B
                     {10, 10, 70, 70, 0.9f, 3}});  // C
  const Layout L = compute_layout(s.images());
  EXPECT_EQ(L.layer[0], 0);
  EXPECT_EQ(L.layer[1], 1);
  EXPECT_EQ(L.layer[2], 3);
  EXPECT_EQ(s.M(L, 1, 0), -1);
  EXPECT_EQ(s.M(L, 2, 0), -1);
  EXPECT_EQ(s.M(L, 2, 1), -1);
  EXPECT_EQ(L.order, (std::vector<std::int32_t>{1, 2, 3}));
  EXPECT_EQ(L.num_layers, 3);
  EXPECT_GE(L.difficulty, 2);
  EXPECT_NEAR(find_relation(L, 1, 2)->depth_diff, 0.1, 1e-6);
  EXPECT_NEAR(find_relation(L, 0, 2)->depth_diff, 0.2, 1e-6);
}

TEST(Layout, SplitObjectIsIncomplete) {
  // A vertical bar over a horizontal bar cuts it in two.
  const Synthetic s(40, 60, {{0, 25, 40, 35, 0.7f, 1}, {15, 5, 25, 55, 0.8f, 2}});
  const Layout L = compute_layout(s.images());
  EXPECT_EQ(L.num_regions[1], 2);
  EXPECT_EQ(L.complete[1], 0);
  EXPECT_EQ(L.complete[0], 1);
  EXPECT_EQ(L.difficulty, 3);
  // Both sides of the bar: 2 columns x 10 rows.
  EXPECT_EQ(find_relation(L, 0, 1)->edge_size, 20);
}

TEST(Layout, SpecksAreIgnored) {
  // The bar leaves 2 px of B on its far side: a speck below min_region_px.
  const Synthetic s(40, 60, {{0, 25, 40, 35, 0.7f, 1}, {15, 5, 16, 37, 0.8f, 2}});
  const Layout L = compute_layout(s.images());
  EXPECT_EQ(L.num_regions[1], 1);
  EXPECT_EQ(L.complete[1], 1);
  LayoutOptions o;
  o.min_region_px = 1;
  EXPECT_EQ(compute_layout(s.images(), o).complete[1], 0);
}

TEST(Layout, RepeatedClassesRaiseTheLevel) {
  const Synthetic same(40, 60, {{5, 5, 25, 25, 0.8f, 7}, {5, 30, 25, 55, 0.8f, 7}});
  const Layout L = compute_layout(same.images());
  EXPECT_FALSE(L.classes_unique);
  EXPECT_EQ(L.difficulty, 4);
  const Synthetic split(40, 60, {{0, 25, 40, 35, 0.7f, 4}, {15, 5, 25, 55, 0.8f, 4}});
  EXPECT_EQ(compute_layout(split.images()).difficulty, 5);
}

/// Two objects hiding each other: A over B in rows 0..4, B over A in rows 5..9 of the overlap,
/// where each rises to 0.75 m (both lie at 0.8 m elsewhere).
Synthetic interlocked(const std::vector<Rect>& extra) {
  std::vector<Rect> rects = {{10, 10, 20, 30, 0.8f, 1}, {10, 20, 20, 40, 0.8f, 2}};
  rects.insert(rects.end(), extra.begin(), extra.end());
  Synthetic s(40, 60, rects);
  for (int r = 10; r < 20; ++r)
    for (int c = 20; c < 30; ++c) {
      const std::size_t p = static_cast<std::size_t>(r) * s.W + c;
      if (s.visible[p] == 1 || s.visible[p] == 2) {
        s.visible[p] = r < 15 ? 1 : 2;
        s.depth[p] = 0.75f;
      }
    }
  s.recompute_occlusion();
  return s;
}

TEST(Layout, TwoCycleIsInterlock) {
  const Synthetic s = interlocked({});
  const Layout L = compute_layout(s.images());
  EXPECT_EQ(s.M(L, 0, 1), -1);
  EXPECT_EQ(s.M(L, 1, 0), -1);
  EXPECT_EQ(L.layer[0], 2);
  EXPECT_EQ(L.layer[1], 2);
  // Each on its own stretch: A over B beside A's raised part (B's column 30, rows 10..14), B over
  // A beside B's (A's column 19, rows 15..19); 0.8 - 0.75 m each.
  for (const auto* r : {find_relation(L, 0, 1), find_relation(L, 1, 0)}) {
    ASSERT_NE(r, nullptr);
    EXPECT_EQ(r->edge_size, 5);
    EXPECT_NEAR(r->depth_diff, 0.05, 1e-6);
  }
  // Equal occlusion (25 %): the cycle is broken at the smaller id.
  EXPECT_EQ(L.order, (std::vector<std::int32_t>{1, 2}));
  Synthetic t = s;
  t.occlusion = {0.3, 0.2};
  EXPECT_EQ(compute_layout(t.images()).order, (std::vector<std::int32_t>{2, 1}));

  // One object C on top of both: still interlock; C first.
  const Synthetic c = interlocked({{5, 15, 12, 35, 0.5f, 3}});
  const Layout Lc = compute_layout(c.images());
  EXPECT_EQ(Lc.layer[0], 2);
  EXPECT_EQ(Lc.layer[1], 2);
  EXPECT_EQ(Lc.layer[2], 0);
  EXPECT_EQ(Lc.order.front(), 3);

  // A second outside object D on A: A is covered by two outside objects -> not interlock.
  const Synthetic d = interlocked({{5, 15, 12, 35, 0.5f, 3}, {15, 5, 25, 15, 0.5f, 4}});
  const Layout Ld = compute_layout(d.images());
  EXPECT_EQ(Ld.layer[0], 3);
  EXPECT_EQ(Ld.layer[1], 3);
  EXPECT_EQ(Ld.layer[3], 0);
}

TEST(Layout, HiddenObjectHasNoRelationAndLayerThree) {
  // B lies fully under A.
  const Synthetic s(40, 40, {{5, 5, 30, 30, 0.7f, 1}, {10, 10, 20, 20, 0.8f, 2}});
  const Layout L = compute_layout(s.images());
  EXPECT_EQ(L.visible[1], 0);
  EXPECT_EQ(L.layer[1], 3);
  EXPECT_TRUE(L.relations.empty());
  EXPECT_EQ(L.order, (std::vector<std::int32_t>{1}));
  EXPECT_EQ(L.difficulty, 1);  // only A counts
}

TEST(Layout, SmallOverlapBelowThresholdIsNoRelation) {
  // A covers 3 px of B only.
  const Synthetic s(40, 60, {{5, 5, 25, 26, 0.7f, 1}, {5, 23, 8, 50, 0.8f, 2}});
  EXPECT_TRUE(compute_layout(s.images()).relations.empty());
  LayoutOptions o;
  o.min_overlap_px = 3;
  EXPECT_EQ(compute_layout(s.images(), o).relations.size(), 1u);
}

TEST(Layout, InvalidDepthIsLeftOutOfTheMedian) {
  // Without any valid depth the masks alone decide: the relation stands, unmeasured.
  Synthetic s(50, 60, {{20, 20, 40, 30, 0.8f, 1}, {10, 10, 30, 50, 0.9f, 2}});
  for (auto& d : s.depth) d = std::numeric_limits<float>::quiet_NaN();
  const Layout L = compute_layout(s.images());
  ASSERT_EQ(L.relations.size(), 1u);
  EXPECT_TRUE(std::isnan(L.relations.at(0).depth_diff));
  EXPECT_EQ(L.relations.at(0).edge_size, 0);
  // Valid depth only across A's top edge (rows 19 and 20, cols 20..29): the stretch is B's 10
  // pixels of row 19; the 20 pixels beside A's sides have no valid depth.
  Synthetic t(50, 60, {{20, 20, 40, 30, 0.8f, 1}, {10, 10, 30, 50, 0.9f, 2}});
  for (int r = 0; r < t.H; ++r)
    for (int c = 0; c < t.W; ++c)
      if (!((r == 19 || r == 20) && c >= 20 && c < 30))
        t.depth[static_cast<std::size_t>(r) * t.W + c] = std::nanf("");
  const Layout Lt = compute_layout(t.images());
  EXPECT_EQ(Lt.relations.at(0).edge_size, 10);
  EXPECT_NEAR(Lt.relations.at(0).depth_diff, 0.1, 1e-6);
}

/// B (index 1) a bowl: rows 10..29 x cols 10..39, its floor at 0.8 m and its front rim (rows
/// 25..29) at `rim` m; A (index 0) inside it at 0.75 m, rows 15..24 x cols 15..34 seen, its
/// amodal mask reaching row 29 behind the rim.
Synthetic nested(float rim) {
  Synthetic s(40, 50, {{15, 15, 30, 35, 0.75f, 1}, {10, 10, 30, 40, 0.8f, 2}});
  for (int r = 10; r < 30; ++r)
    for (int c = 10; c < 40; ++c) {
      const std::size_t p = static_cast<std::size_t>(r) * s.W + c;
      const bool a = r >= 15 && r < 25 && c >= 15 && c < 35;
      s.visible[p] = a ? 1 : 2;
      s.depth[p] = a ? 0.75f : (r >= 25 ? rim : 0.8f);
    }
  s.recompute_occlusion();
  return s;
}

TEST(Layout, NestedObjectsEachCoverTheOtherOnTheirOwnStretch) {
  // A hides B's floor, B's rim hides A's lower part. The whole boundary counted for B over A
  // would give A's top and sides (40 px at -5 cm) and the rim (20 px at +7 cm): a median of
  // -5 cm, B behind its child. On its own stretch each is in front: A over B beside A's top
  // and sides (40 px, +5 cm), B over A along the rim (20 px, +7 cm).
  const Synthetic s = nested(0.68f);
  const Layout L = compute_layout(s.images());
  EXPECT_EQ(s.M(L, 0, 1), -1);
  EXPECT_EQ(s.M(L, 1, 0), -1);
  const auto* ab = find_relation(L, 0, 1);
  const auto* ba = find_relation(L, 1, 0);
  ASSERT_NE(ab, nullptr);
  ASSERT_NE(ba, nullptr);
  EXPECT_EQ(ab->edge_size, 40);
  EXPECT_NEAR(ab->depth_diff, 0.05, 1e-6);
  EXPECT_EQ(ba->edge_size, 20);
  EXPECT_NEAR(ba->depth_diff, 0.07, 1e-6);
  EXPECT_EQ(L.total_covered_edge[0], 40);
  EXPECT_EQ(L.total_covered_edge[1], 20);
  EXPECT_EQ(L.layer[0], 2);
  EXPECT_EQ(L.layer[1], 2);
}

TEST(Layout, ParentBehindItsChildIsNoParent) {
  // The rim at the floor's depth: B's mask still covers A's lower part (100 px), but wherever
  // they meet A is in front. B is no parent of A; A lies on B (60 px: top, sides and bottom).
  const Synthetic s = nested(0.8f);
  const Layout L = compute_layout(s.images());
  ASSERT_EQ(L.relations.size(), 1u);
  EXPECT_EQ(L.relations[0].parent, 0);
  EXPECT_EQ(L.relations[0].child, 1);
  EXPECT_EQ(L.relations[0].edge_size, 60);
  EXPECT_EQ(s.M(L, 0, 1), 1);
  EXPECT_EQ(s.M(L, 1, 0), -1);
  EXPECT_EQ(L.layer[0], 0);
  EXPECT_EQ(L.layer[1], 1);
  for (const auto& r : L.relations) EXPECT_GT(r.depth_diff, 0.0);
}

TEST(Layout, ZeroAndOneObject) {
  std::vector<std::int32_t> vis(12, 0);
  std::vector<float> depth(12, 0.0f);
  LayoutImages im;
  im.height = 3;
  im.width = 4;
  im.visible = vis.data();
  im.depth = depth.data();
  const Layout L0 = compute_layout(im);
  EXPECT_EQ(L0.num_objects, 0);
  EXPECT_TRUE(L0.order.empty());
  EXPECT_EQ(L0.difficulty, 1);

  const Synthetic one(10, 10, {{2, 2, 8, 8, 0.8f, 1}});
  const Layout L1 = compute_layout(one.images());
  EXPECT_EQ(L1.layer[0], 0);
  EXPECT_EQ(L1.order, (std::vector<std::int32_t>{1}));
  EXPECT_EQ(L1.difficulty, 1);
}

TEST(Layout, BadInputThrowsInvalidArgument) {
  Synthetic s(10, 10, {{2, 2, 8, 8, 0.8f, 1}});
  s.visible[5] = 2;  // only one object
  EXPECT_THROW(compute_layout(s.images()), mgn::InvalidArgument);
  s.visible[5] = -1;
  EXPECT_THROW(compute_layout(s.images()), mgn::InvalidArgument);
  s.visible[5] = 0;
  s.occlusion[0] = std::nan("");
  EXPECT_THROW(compute_layout(s.images()), mgn::InvalidArgument);
  s.occlusion[0] = 0.0;
  LayoutImages im = s.images();
  im.amodal = nullptr;
  EXPECT_THROW(compute_layout(im), mgn::InvalidArgument);
  im = s.images();
  im.height = 0;
  EXPECT_THROW(compute_layout(im), mgn::InvalidArgument);
  LayoutOptions o;
  o.min_overlap_fraction = 1.5;
  EXPECT_THROW(compute_layout(s.images(), o), mgn::InvalidArgument);
  o = {};
  o.num_threads = -1;
  EXPECT_THROW(compute_layout(s.images(), o), mgn::InvalidArgument);
}

TEST(Layout, RandomStacksOrderAndThreadIndependence) {
  for (std::uint64_t trial = 0; trial < 20; ++trial) {
    mgn::Rng rng(42, trial);
    std::vector<Rect> rects;
    const int n = 2 + static_cast<int>(rng.uniform(0.0, 8.0));
    for (int i = 0; i < n; ++i) {
      const int r0 = static_cast<int>(rng.uniform(0.0, 50.0));
      const int c0 = static_cast<int>(rng.uniform(0.0, 50.0));
      rects.push_back({r0, c0, r0 + 10 + static_cast<int>(rng.uniform(0.0, 30.0)),
                       c0 + 10 + static_cast<int>(rng.uniform(0.0, 30.0)),
                       static_cast<float>(rng.uniform(0.5, 1.0)), i});
    }
    const Synthetic s(90, 90, rects);
    LayoutOptions o1, o2;
    o1.num_threads = 1;
    o2.num_threads = 3;
    const Layout a = compute_layout(s.images(), o1);
    const Layout b = compute_layout(s.images(), o2);
    EXPECT_EQ(a.relation, b.relation);
    EXPECT_EQ(a.order, b.order);
    EXPECT_EQ(a.layer, b.layer);
    EXPECT_EQ(a.total_covered_edge, b.total_covered_edge);
    // Every parent comes before its child; the parent is always the nearer rectangle.
    std::vector<int> pos(static_cast<std::size_t>(n), -1);
    for (std::size_t k = 0; k < a.order.size(); ++k) pos[a.order[k] - 1] = static_cast<int>(k);
    for (const auto& r : a.relations) {
      EXPECT_LT(pos[r.parent], pos[r.child]);
      EXPECT_LT(rects[r.parent].z, rects[r.child].z);
      if (!std::isnan(r.depth_diff)) {
        EXPECT_NEAR(r.depth_diff, rects[r.child].z - rects[r.parent].z, 1e-6);
      }
    }
  }
}

}  // namespace
