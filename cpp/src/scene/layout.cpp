#include <mgn/core/error.hpp>
#include <mgn/core/parallel.hpp>
#include <mgn/scene/layout.hpp>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <queue>
#include <set>
#include <utility>

namespace mgn {

namespace {

bool valid_depth(float d) { return std::isfinite(d) && d > 0.0f; }

void check_options(const LayoutOptions& o) {
  if (o.min_overlap_px < 1)
    throw_error<InvalidArgument>("compute_layout: min_overlap_px must be >= 1, got ",
                                 o.min_overlap_px);
  if (!(o.min_overlap_fraction >= 0.0 && o.min_overlap_fraction <= 1.0))
    throw_error<InvalidArgument>("compute_layout: min_overlap_fraction must be in [0, 1], got ",
                                 o.min_overlap_fraction);
  if (o.min_region_px < 1)
    throw_error<InvalidArgument>("compute_layout: min_region_px must be >= 1, got ",
                                 o.min_region_px);
  if (!(o.min_region_fraction >= 0.0 && o.min_region_fraction <= 1.0))
    throw_error<InvalidArgument>("compute_layout: min_region_fraction must be in [0, 1], got ",
                                 o.min_region_fraction);
  if (!(o.max_occlusion_level1 >= 0.0 && o.max_occlusion_level1 <= 1.0))
    throw_error<InvalidArgument>("compute_layout: max_occlusion_level1 must be in [0, 1], got ",
                                 o.max_occlusion_level1);
  resolve_num_threads(o.num_threads);
}

void check_images(const LayoutImages& im) {
  if (im.height < 1 || im.width < 1)
    throw_error<InvalidArgument>("compute_layout: image size must be >= 1 x 1, got ", im.height,
                                 " x ", im.width);
  if (im.num_objects < 0)
    throw_error<InvalidArgument>("compute_layout: num_objects must be >= 0, got ", im.num_objects);
  if (!im.visible || !im.depth)
    throw_error<InvalidArgument>("compute_layout: the visible and depth images must be given");
  if (im.num_objects > 0 && (!im.amodal || !im.categories || !im.occlusion))
    throw_error<InvalidArgument>(
        "compute_layout: amodal masks, categories and "
        "occlusion must be given for ",
        im.num_objects, " objects");
  for (int i = 0; i < im.num_objects; ++i) {
    const double o = im.occlusion[i];
    if (!(o >= 0.0 && o <= 1.0))
      throw_error<InvalidArgument>("compute_layout: occlusion[", i,
                                   "] must be a rate in [0, 1], got ", o);
  }
}

/// Tarjan's strongly connected components of the graph parent -> child over the
/// given nodes. Returns the component index of every node (-1 for nodes not in
/// `nodes`).
std::vector<int> strongly_connected(int n, const std::vector<std::vector<int>>& children,
                                    const std::vector<int>& nodes) {
  std::vector<int> index(n, -1), low(n, 0), comp(n, -1);
  std::vector<std::uint8_t> on_stack(n, 0);
  std::vector<int> stack;
  int next_index = 0, next_comp = 0;
  // Iterative DFS: (node, position in its child list).
  std::vector<std::pair<int, std::size_t>> call;
  for (int root : nodes) {
    if (index[root] >= 0) continue;
    call.emplace_back(root, 0);
    index[root] = low[root] = next_index++;
    stack.push_back(root);
    on_stack[root] = 1;
    while (!call.empty()) {
      auto& [v, pos] = call.back();
      if (pos < children[v].size()) {
        const int w = children[v][pos++];
        if (index[w] < 0) {
          index[w] = low[w] = next_index++;
          stack.push_back(w);
          on_stack[w] = 1;
          call.emplace_back(w, 0);
        } else if (on_stack[w]) {
          low[v] = std::min(low[v], index[w]);
        }
        continue;
      }
      if (low[v] == index[v]) {
        int w;
        do {
          w = stack.back();
          stack.pop_back();
          on_stack[w] = 0;
          comp[w] = next_comp;
        } while (w != v);
        ++next_comp;
      }
      const int done = v;
      call.pop_back();
      if (!call.empty()) {
        const int parent = call.back().first;
        low[parent] = std::min(low[parent], low[done]);
      }
    }
  }
  return comp;
}

double median(std::vector<float>& v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  const std::size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid), v.end());
  const double hi = v[mid];
  if (v.size() % 2 == 1) return hi;
  const double lo = *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid));
  return 0.5 * (lo + hi);
}

/// Bounding boxes of the visible masks (inclusive; empty when r1 < r0).
struct Boxes {
  std::vector<int> r0, r1, c0, c1;
};

/// Stage 1: visible pixel counts and bounding boxes; checks the id range.
Boxes count_visible(const LayoutImages& im, Layout& L) {
  const int n = im.num_objects;
  const int H = im.height, W = im.width;
  const std::size_t nn = static_cast<std::size_t>(n);
  const std::int32_t* vis = im.visible;
  Boxes bx{std::vector<int>(nn, H), std::vector<int>(nn, -1), std::vector<int>(nn, W),
           std::vector<int>(nn, -1)};
  for (int r = 0; r < H; ++r) {
    const std::int32_t* row = vis + static_cast<std::size_t>(r) * W;
    for (int c = 0; c < W; ++c) {
      const std::int32_t v = row[c];
      if (v == 0) continue;
      if (v < 0 || v > n)
        throw_error<InvalidArgument>("compute_layout: visible id at pixel (row ", r, ", col ", c,
                                     ") must be in [0, ", n, "] (0 = none, else instance id), got ",
                                     v);
      const std::size_t i = static_cast<std::size_t>(v - 1);
      ++L.visible_px[i];
      bx.r0[i] = std::min(bx.r0[i], r);
      bx.r1[i] = std::max(bx.r1[i], r);
      bx.c0[i] = std::min(bx.c0[i], c);
      bx.c1[i] = std::max(bx.c1[i], c);
    }
  }
  for (std::size_t i = 0; i < nn; ++i) L.visible[i] = L.visible_px[i] > 0 ? 1 : 0;
  return bx;
}

/// Stage 2: seen-over counts S[a][b] (row-major a * n + b), one amodal mask
/// (column b) per task.
std::vector<std::int64_t> seen_over_counts(const LayoutImages& im, int num_threads) {
  const std::size_t nn = static_cast<std::size_t>(im.num_objects);
  const std::size_t npx = static_cast<std::size_t>(im.height) * static_cast<std::size_t>(im.width);
  const std::int32_t* vis = im.visible;
  std::vector<std::int64_t> S(nn * nn, 0);
  parallel_for(nn, num_threads, 1, [&](std::size_t begin, std::size_t end) {
    std::vector<std::int64_t> col(nn);
    for (std::size_t b = begin; b < end; ++b) {
      std::fill(col.begin(), col.end(), 0);
      const std::uint8_t* m = im.amodal + b * npx;
      std::size_t p = 0;
      for (; p < npx; ++p) {
        // Skip 8 empty mask bytes at a time.
        if (p % 8 == 0 && p + 8 <= npx) {
          std::uint64_t word;
          std::memcpy(&word, m + p, 8);
          if (word == 0) {
            p += 7;
            continue;
          }
        }
        if (!m[p]) continue;
        const std::int32_t v = vis[p];
        if (v > 0 && static_cast<std::size_t>(v - 1) != b) ++col[static_cast<std::size_t>(v - 1)];
      }
      for (std::size_t a = 0; a < nn; ++a) S[a * nn + b] = col[a];
    }
  });
  return S;
}

/// A candidate relation parent -> child and what its contour measured.
struct Candidate {
  int parent = 0, child = 0;
  std::int64_t seen_px = 0;
  std::int64_t stretch = 0;   // child pixels of the parent's own stretch
  std::int64_t measured = 0;  // child pixels of the contour with valid depths on both sides
  std::vector<float> diffs;   // per stretch pixel: depth(child) - mean depth(parent side)
};

struct Candidates {
  std::vector<Candidate> list;
  std::vector<int> index;                          // [child * n + parent] -> list index, or -1
  std::vector<std::uint8_t> has_candidate_parent;  // [child]
};

/// Stage 3: candidate relations between visible objects: the seen-over counts
/// decide them.
Candidates candidate_relations(const std::vector<std::int64_t>& S,
                               const std::vector<std::uint8_t>& visible, const LayoutOptions& opt) {
  const std::size_t nn = visible.size();
  Candidates cs;
  cs.index.assign(nn * nn, -1);
  cs.has_candidate_parent.assign(nn, 0);
  for (std::size_t b = 0; b < nn; ++b) {
    if (!visible[b]) continue;
    for (std::size_t a = 0; a < nn; ++a) {
      if (a == b || !visible[a]) continue;
      const std::int64_t ab = S[a * nn + b], ba = S[b * nn + a];
      if (ab >= opt.min_overlap_px &&
          static_cast<double>(ab) >= opt.min_overlap_fraction * static_cast<double>(ab + ba)) {
        cs.index[b * nn + a] = static_cast<int>(cs.list.size());
        cs.has_candidate_parent[b] = 1;
        Candidate c;
        c.parent = static_cast<int>(a);
        c.child = static_cast<int>(b);
        c.seen_px = ab;
        cs.list.push_back(std::move(c));
      }
    }
  }
  return cs;
}

/// The contour neighbours of one child pixel: candidate index and depth of each
/// 4-neighbour that shows a candidate parent inside the child's amodal mask.
struct ContourNeighbours {
  int cand[4] = {};
  float depth[4] = {};
  int count = 0;
};

ContourNeighbours contour_neighbours(const LayoutImages& im, const Candidates& cs, int r, int c) {
  const int H = im.height, W = im.width;
  const std::size_t nn = static_cast<std::size_t>(im.num_objects);
  const std::size_t npx = static_cast<std::size_t>(H) * static_cast<std::size_t>(W);
  const std::size_t p = static_cast<std::size_t>(r) * W + c;
  const std::int32_t v = im.visible[p];
  const std::size_t b = static_cast<std::size_t>(v - 1);
  const std::uint8_t* child_amodal = im.amodal + b * npx;
  ContourNeighbours nb;
  auto look = [&](std::size_t q) {
    const std::int32_t u = im.visible[q];
    if (u == 0 || u == v || !child_amodal[q]) return;
    const int ci = cs.index[b * nn + static_cast<std::size_t>(u - 1)];
    if (ci < 0) return;
    nb.cand[nb.count] = ci;
    nb.depth[nb.count] = im.depth[q];
    ++nb.count;
  };
  if (r > 0) look(p - W);
  if (r + 1 < H) look(p + W);
  if (c > 0) look(p - 1);
  if (c + 1 < W) look(p + 1);
  return nb;
}

/// Adds child pixel p (depth dp, valid) to the contour of every candidate among
/// its neighbours: once per candidate, on its stretch when at least one of its
/// neighbours lies in front.
void measure_contour_pixel(ContourNeighbours& nb, float dp, Candidates& cs) {
  for (int i = 0; i < nb.count; ++i) {
    if (nb.cand[i] < 0) continue;  // already counted for this pixel
    const int ci = nb.cand[i];
    double front_sum = 0.0;
    int front = 0;
    bool measured = false;
    for (int j = i; j < nb.count; ++j) {
      if (nb.cand[j] != ci) continue;
      if (valid_depth(nb.depth[j])) {
        measured = true;
        if (dp > nb.depth[j]) {
          front_sum += nb.depth[j];
          ++front;
        }
      }
      if (j > i) nb.cand[j] = -1;
    }
    Candidate& cd = cs.list[static_cast<std::size_t>(ci)];
    if (measured) ++cd.measured;
    if (front > 0) {
      ++cd.stretch;
      cd.diffs.push_back(static_cast<float>(static_cast<double>(dp) - front_sum / front));
    }
  }
}

/// Stage 4: the parent's own stretch of boundary: child pixels p with a
/// 4-neighbour q that shows the parent inside the child's amodal mask (the
/// parent covers the child at q) and lies in front of p (depth(q) < depth(p)).
/// A contour pixel pair is on the stretch of the one object that is in front
/// there, so no boundary counts for both directions of a mutual pair.
void measure_stretches(const LayoutImages& im, Candidates& cs) {
  if (cs.list.empty()) return;
  for (int r = 0; r < im.height; ++r) {
    for (int c = 0; c < im.width; ++c) {
      const std::size_t p = static_cast<std::size_t>(r) * im.width + c;
      const std::int32_t v = im.visible[p];
      if (v == 0) continue;
      if (!cs.has_candidate_parent[static_cast<std::size_t>(v - 1)]) continue;
      ContourNeighbours nb = contour_neighbours(im, cs, r, c);
      if (nb.count == 0) continue;
      const float dp = im.depth[p];
      if (!valid_depth(dp)) continue;
      measure_contour_pixel(nb, dp, cs);
    }
  }
}

/// The parent -> child graph of the relations.
struct Graph {
  std::vector<std::vector<int>> parents, children;
};

/// Stage 4b: relations. A candidate whose parent meets its child on a measured
/// contour but is in front nowhere on it lies behind the child (a sign error,
/// or the child's boundary counted for the parent): dropped. Without a measured
/// contour the masks alone decide.
Graph keep_relations(Candidates& cs, Layout& L) {
  const std::size_t nn = static_cast<std::size_t>(L.num_objects);
  std::vector<std::uint8_t> is_parent(nn * nn, 0);  // [child * n + parent]
  Graph g{std::vector<std::vector<int>>(nn), std::vector<std::vector<int>>(nn)};
  for (Candidate& cd : cs.list) {
    if (cd.measured > 0 && cd.stretch == 0) continue;
    const auto a = static_cast<std::size_t>(cd.parent), b = static_cast<std::size_t>(cd.child);
    is_parent[b * nn + a] = 1;
    g.parents[b].push_back(cd.parent);
    g.children[a].push_back(cd.child);
    LayoutRelation rel;
    rel.parent = cd.parent;
    rel.child = cd.child;
    rel.seen_px = cd.seen_px;
    rel.edge_size = static_cast<int>(cd.stretch);
    rel.depth_diff = median(cd.diffs);
    L.total_covered_edge[a] += cd.stretch;
    L.relations.push_back(rel);
  }
  for (std::size_t i = 0; i < nn; ++i)
    for (std::size_t j = 0; j < nn; ++j) {
      if (is_parent[i * nn + j])
        L.relation[i * nn + j] = -1;
      else if (is_parent[j * nn + i])
        L.relation[i * nn + j] = 1;
    }
  return g;
}

/// Stage 5: connected regions of each visible mask (8-connectivity, OpenCV),
/// inside its box.
void count_regions(const LayoutImages& im, const Boxes& bx, const LayoutOptions& opt, Layout& L) {
  const int H = im.height, W = im.width;
  parallel_for(L.visible.size(), opt.num_threads, 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      if (!L.visible[i]) continue;
      const cv::Mat ids(H, W, CV_32S, const_cast<std::int32_t*>(im.visible),
                        static_cast<std::size_t>(W) * sizeof(std::int32_t));
      const cv::Rect box(bx.c0[i], bx.r0[i], bx.c1[i] - bx.c0[i] + 1, bx.r1[i] - bx.r0[i] + 1);
      cv::Mat mask;
      cv::compare(ids(box), cv::Scalar(static_cast<double>(i + 1)), mask, cv::CMP_EQ);
      cv::Mat labels, stats, centroids;
      const int count = cv::connectedComponentsWithStats(mask, labels, stats, centroids, 8, CV_32S);
      const double min_area =
          std::max(static_cast<double>(opt.min_region_px),
                   opt.min_region_fraction * static_cast<double>(L.visible_px[i]));
      int regions = 0;
      for (int k = 1; k < count; ++k)  // label 0 is the background
        if (stats.at<int>(k, cv::CC_STAT_AREA) >= min_area) ++regions;
      L.num_regions[i] = regions;
      L.complete[i] = regions <= 1 ? 1 : 0;
    }
  });
}

/// Stage 6: layers of the visible objects (comp: their strongly connected
/// components).
void assign_layers(const Graph& g, const std::vector<int>& visible_nodes,
                   const std::vector<int>& comp, Layout& L) {
  const std::size_t nn = static_cast<std::size_t>(L.num_objects);
  std::vector<int> comp_size(nn, 0);
  for (int v : visible_nodes) ++comp_size[static_cast<std::size_t>(comp[v])];
  std::vector<std::uint8_t> comp_interlock(nn, 1);
  for (int v : visible_nodes) {
    int outside = 0;
    for (int a : g.parents[v])
      if (comp[a] != comp[v]) ++outside;
    if (outside > 1) comp_interlock[static_cast<std::size_t>(comp[v])] = 0;
  }
  for (int v : visible_nodes)
    if (g.parents[v].empty()) L.layer[v] = 0;
  for (int v : visible_nodes) {
    const auto cv_ = static_cast<std::size_t>(comp[v]);
    if (g.parents[v].size() == 1 && L.layer[g.parents[v][0]] == 0 && comp_size[cv_] == 1)
      L.layer[v] = 1;
    else if (comp_size[cv_] >= 2 && comp_interlock[cv_])
      L.layer[v] = 2;
  }
}

/// Stage 7: picking order (Kahn, smallest id first; cycles broken by the
/// smallest occlusion).
void picking_order(const Graph& g, const std::vector<int>& visible_nodes,
                   const std::vector<int>& comp, const double* occlusion, Layout& L) {
  const std::size_t nn = static_cast<std::size_t>(L.num_objects);
  std::vector<int> remaining_parents(nn, 0);
  std::vector<std::uint8_t> taken(nn, 0);
  std::priority_queue<int, std::vector<int>, std::greater<int>> ready;
  for (int v : visible_nodes) {
    remaining_parents[v] = static_cast<int>(g.parents[v].size());
    if (remaining_parents[v] == 0) ready.push(v);
  }
  auto take = [&](int v) {
    taken[v] = 1;
    L.order.push_back(v + 1);
    for (int w : g.children[v])
      if (!taken[w] && --remaining_parents[w] == 0) ready.push(w);
  };
  while (L.order.size() < visible_nodes.size()) {
    if (!ready.empty()) {
      const int v = ready.top();
      ready.pop();
      if (!taken[v]) take(v);
      continue;
    }
    // Only cycles remain: candidates are objects whose remaining parents share
    // their SCC.
    int best = -1;
    for (int v : visible_nodes) {
      if (taken[v]) continue;
      bool source = true;
      for (int a : g.parents[v])
        if (!taken[a] && comp[a] != comp[v]) source = false;
      if (!source) continue;
      if (best < 0 || occlusion[v] < occlusion[best]) best = v;
    }
    take(best);  // non-empty: the condensation of the remaining graph has a
                 // source
  }
}

/// Stage 8: difficulty level of the view.
void assign_difficulty(const LayoutImages& im, const std::vector<int>& visible_nodes,
                       const LayoutOptions& opt, Layout& L) {
  std::set<int> layers_present;
  std::set<std::int32_t> categories;
  bool all_complete = true;
  for (int v : visible_nodes) {
    layers_present.insert(L.layer[v]);
    L.max_occlusion = std::max(L.max_occlusion, im.occlusion[v]);
    if (!L.complete[v]) all_complete = false;
    if (!categories.insert(im.categories[v]).second) L.classes_unique = false;
  }
  L.num_layers = static_cast<int>(layers_present.size());
  if (L.classes_unique) {
    if (!all_complete)
      L.difficulty = 3;
    else if (L.num_layers <= 2 && L.max_occlusion <= opt.max_occlusion_level1)
      L.difficulty = 1;
    else
      L.difficulty = 2;
  } else {
    L.difficulty = all_complete ? 4 : 5;
  }
}

}  // namespace

Layout compute_layout(const LayoutImages& im, const LayoutOptions& opt) {
  check_options(opt);
  check_images(im);
  const int n = im.num_objects;
  const std::size_t nn = static_cast<std::size_t>(n);

  Layout L;
  L.num_objects = n;
  L.relation.assign(nn * nn, 0);
  L.visible_px.assign(nn, 0);
  L.visible.assign(nn, 0);
  L.layer.assign(nn, 3);
  L.num_regions.assign(nn, 0);
  L.complete.assign(nn, 0);
  L.total_covered_edge.assign(nn, 0);

  const Boxes boxes = count_visible(im, L);                                   // 1
  const std::vector<std::int64_t> S = seen_over_counts(im, opt.num_threads);  // 2
  Candidates cand = candidate_relations(S, L.visible, opt);                   // 3
  measure_stretches(im, cand);                                                // 4
  const Graph graph = keep_relations(cand, L);                                // 4b
  count_regions(im, boxes, opt, L);                                           // 5
  std::vector<int> visible_nodes;
  for (std::size_t i = 0; i < nn; ++i)
    if (L.visible[i]) visible_nodes.push_back(static_cast<int>(i));
  const std::vector<int> comp = strongly_connected(n, graph.children, visible_nodes);
  assign_layers(graph, visible_nodes, comp, L);                // 6
  picking_order(graph, visible_nodes, comp, im.occlusion, L);  // 7
  assign_difficulty(im, visible_nodes, opt, L);                // 8
  return L;
}

}  // namespace mgn
