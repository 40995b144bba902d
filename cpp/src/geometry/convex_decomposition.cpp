#include <mgn/core/error.hpp>
#include <mgn/geometry/convex_decomposition.hpp>

#include <HACD/hacdHACD.h>
#include <LinearMath/btConvexHullComputer.h>

#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <map>
#include <set>
#include <unordered_map>

namespace mgn {

namespace {

void check_finite(const Mesh& mesh, const char* fn) {
  require_non_empty(mesh, fn);
  if (!mesh.vertices().allFinite())
    throw_error<InvalidArgument>(fn, ": mesh '", mesh.name(), "' has non-finite vertices");
}

/// Volume (m^3) of the convex hull of `pts` (x, y, z, x, ...; 0 if they span no volume). With
/// `hull`, that receives the hull's vertices in the same layout.
double hull_volume(const std::vector<double>& pts, std::vector<double>* hull = nullptr) {
  btConvexHullComputer hc;
  hc.compute(pts.data(), static_cast<int>(3 * sizeof(double)), static_cast<int>(pts.size() / 3),
             0.0, 0.0);
  if (hull) {
    hull->clear();
    for (int k = 0; k < hc.vertices.size(); ++k)
      hull->insert(hull->end(), {double(hc.vertices[k].x()), double(hc.vertices[k].y()),
                                 double(hc.vertices[k].z())});
    if (hc.vertices.size() < 4) *hull = pts;
  }
  if (hc.vertices.size() < 4) return 0.0;
  const btVector3 o = hc.vertices[0];
  double six_v = 0.0;
  for (int f = 0; f < hc.faces.size(); ++f) {
    const btConvexHullComputer::Edge* first = &hc.edges[hc.faces[f]];
    const btVector3 a = hc.vertices[first->getSourceVertex()] - o;
    const btConvexHullComputer::Edge* e = first->getNextEdgeOfFace();
    while (e->getTargetVertex() != first->getSourceVertex()) {
      const btVector3 b = hc.vertices[e->getSourceVertex()] - o;
      const btVector3 c = hc.vertices[e->getTargetVertex()] - o;
      six_v += double(a.dot(b.cross(c)));
      e = e->getNextEdgeOfFace();
    }
  }
  return std::abs(six_v) / 6.0;
}

/// Greedy merging of convex point clusters (see ConvexDecompositionOptions::
/// merge_volume_tolerance): returns the merged clusters. `budget` is the volume (m^3) that may be
/// added in total; beyond it, merging goes on only while more than `max_parts` (0: no cap) are
/// left. Deterministic: ties go to the lowest pair of indices.
std::vector<Points3f> merge_clusters(std::vector<Points3f> clusters, double budget, int max_parts) {
  auto coords = [](const Points3f& a) {
    std::vector<double> c(static_cast<std::size_t>(3 * a.rows()));
    for (Eigen::Index i = 0; i < a.rows(); ++i)
      for (int k = 0; k < 3; ++k) c[static_cast<std::size_t>(3 * i + k)] = double(a(i, k));
    return c;
  };
  std::vector<std::vector<double>> pts;
  std::vector<double> vol;
  for (const auto& c : clusters) {  // pts: hull vertices only (the pair hulls are the same)
    std::vector<double> h;
    vol.push_back(hull_volume(coords(c), &h));
    pts.push_back(std::move(h));
  }
  // cost[i][j] (i < j): volume the merged hull adds.
  const std::size_t n = clusters.size();
  std::vector<std::vector<double>> cost(n, std::vector<double>(n, 0.0));
  auto pair_cost = [&](std::size_t i, std::size_t j) {
    std::vector<double> both = pts[i];
    both.insert(both.end(), pts[j].begin(), pts[j].end());
    return std::max(0.0, hull_volume(both) - vol[i] - vol[j]);
  };
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j) cost[i][j] = pair_cost(i, j);
  std::vector<char> alive(n, 1);
  std::size_t left = n;
  double added = 0.0;
  while (left > 1) {
    std::size_t bi = 0, bj = 0;
    double best = 1e300;
    for (std::size_t i = 0; i < n; ++i) {
      if (!alive[i]) continue;
      for (std::size_t j = i + 1; j < n; ++j)
        if (alive[j] && cost[i][j] < best) best = cost[i][j], bi = i, bj = j;
    }
    const bool within = added + best <= budget;
    const bool forced = max_parts > 0 && left > static_cast<std::size_t>(max_parts);
    if (!within && !forced) break;
    added += best;
    Points3f merged(clusters[bi].rows() + clusters[bj].rows(), 3);
    merged << clusters[bi], clusters[bj];
    clusters[bi] = std::move(merged);
    pts[bi].insert(pts[bi].end(), pts[bj].begin(), pts[bj].end());
    std::vector<double> h;
    vol[bi] = hull_volume(pts[bi], &h);
    pts[bi] = std::move(h);
    alive[bj] = 0;
    --left;
    for (std::size_t k = 0; k < n; ++k) {
      if (!alive[k] || k == bi) continue;
      const double c = pair_cost(std::min(k, bi), std::max(k, bi));
      cost[std::min(k, bi)][std::max(k, bi)] = c;
    }
  }
  std::vector<Points3f> out;
  for (std::size_t i = 0; i < n; ++i)
    if (alive[i]) out.push_back(std::move(clusters[i]));
  return out;
}

}  // namespace

double closed_mesh_volume(const Mesh& mesh) {
  const auto& V = mesh.vertices();
  const auto& F = mesh.faces();
  double six_v = 0.0;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Vec3d a = V.row(F(f, 0)).cast<double>().transpose();
    const Vec3d b = V.row(F(f, 1)).cast<double>().transpose();
    const Vec3d c = V.row(F(f, 2)).cast<double>().transpose();
    six_v += a.dot(b.cross(c));
  }
  return std::abs(six_v) / 6.0;
}

Mesh convex_hull_of_points(const Points3f& points) {
  if (points.rows() < 4)
    throw_error<InvalidArgument>("convex_hull: expected at least 4 points, got ", points.rows());
  if (!points.allFinite()) throw_error<InvalidArgument>("convex_hull: points must be finite");
  Points3d pd = points.cast<double>();
  btConvexHullComputer hc;
  hc.compute(pd.data(), static_cast<int>(3 * sizeof(double)), static_cast<int>(pd.rows()), 0.0,
             0.0);
  const int nv = hc.vertices.size();
  const int nf = hc.faces.size();
  if (nv < 4 || nf < 4)
    throw_error<InvalidArgument>("convex_hull: the ", points.rows(),
                                 " points span no volume (coplanar or coincident)");
  Points3f verts(nv, 3);
  for (int i = 0; i < nv; ++i) {
    const btVector3& v = hc.vertices[i];
    verts.row(i) << static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z());
  }
  // Each hull face is a planar polygon, counter-clockwise seen from outside: fan-triangulate.
  std::vector<Eigen::Vector3i> tris;
  for (int f = 0; f < nf; ++f) {
    const btConvexHullComputer::Edge* first = &hc.edges[hc.faces[f]];
    const int v0 = first->getSourceVertex();
    const btConvexHullComputer::Edge* e = first->getNextEdgeOfFace();
    while (e->getTargetVertex() != v0) {
      tris.emplace_back(v0, e->getSourceVertex(), e->getTargetVertex());
      e = e->getNextEdgeOfFace();
    }
  }
  // Drop slivers whose float32 area vanishes (a Mesh rejects zero-area faces).
  Faces faces(static_cast<Eigen::Index>(tris.size()), 3);
  Eigen::Index k = 0;
  for (const auto& t : tris) faces.row(k++) = t.transpose();
  const auto bad = find_degenerate_faces(verts, faces);
  if (!bad.empty()) {
    Faces kept(faces.rows() - static_cast<Eigen::Index>(bad.size()), 3);
    Eigen::Index j = 0;
    std::size_t b = 0;
    for (Eigen::Index i = 0; i < faces.rows(); ++i) {
      if (b < bad.size() && bad[b] == i) {
        ++b;
        continue;
      }
      kept.row(j++) = faces.row(i);
    }
    faces = std::move(kept);
  }
  Mesh hull(std::move(verts), std::move(faces));
  if (hull.validate().signed_volume < 0) hull = hull.flipped();
  return hull;
}

namespace {

// The outward unit normals and offsets (n . x = offset, m) of the faces of the convex hull of
// the chosen rows of points, by Bullet's btConvexHullComputer; faces of zero area are left out.
// coords: scratch space.
void hull_face_planes(const Points3d& points, const std::vector<Eigen::Index>& chosen,
                      std::vector<double>& coords, std::vector<Vec3d>& normals,
                      std::vector<double>& offsets) {
  coords.clear();
  for (Eigen::Index i : chosen)
    coords.insert(coords.end(), {points(i, 0), points(i, 1), points(i, 2)});
  btConvexHullComputer hc;
  hc.compute(coords.data(), static_cast<int>(3 * sizeof(double)), static_cast<int>(chosen.size()),
             0.0, 0.0);
  normals.clear();
  offsets.clear();
  for (int f = 0; f < hc.faces.size(); ++f) {
    // Newell normal of the face polygon (outward: counter-clockwise seen from outside).
    const btConvexHullComputer::Edge* first = &hc.edges[hc.faces[f]];
    const btConvexHullComputer::Edge* e = first;
    Vec3d nn = Vec3d::Zero(), centre = Vec3d::Zero();
    int count = 0;
    do {
      const btVector3& u = hc.vertices[e->getSourceVertex()];
      const btVector3& v = hc.vertices[e->getTargetVertex()];
      nn.x() += (double(u.y()) - double(v.y())) * (double(u.z()) + double(v.z()));
      nn.y() += (double(u.z()) - double(v.z())) * (double(u.x()) + double(v.x()));
      nn.z() += (double(u.x()) - double(v.x())) * (double(u.y()) + double(v.y()));
      centre += Vec3d(double(u.x()), double(u.y()), double(u.z()));
      ++count;
      e = e->getNextEdgeOfFace();
    } while (e != first && count < 100000);
    const double len = nn.norm();
    if (!(len > 0)) continue;
    nn /= len;
    normals.push_back(nn);
    offsets.push_back(nn.dot(centre / count));
  }
}

}  // namespace

std::vector<Eigen::Index> reduce_convex_points(const Points3d& points, int max_vertices,
                                               double tolerance, double* max_deviation) {
  constexpr const char* fn = "reduce_convex_points";
  if (max_vertices < 4)
    throw_error<InvalidArgument>(fn, ": max_vertices must be >= 4, got ", max_vertices);
  if (!(std::isfinite(tolerance) && tolerance >= 0))
    throw_error<InvalidArgument>(fn, ": tolerance must be finite and >= 0 m, got ", tolerance);
  if (!points.allFinite()) throw_error<InvalidArgument>(fn, ": points must be finite");
  const Eigen::Index n = points.rows();
  std::vector<Eigen::Index> all(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) all[static_cast<std::size_t>(i)] = i;
  if (max_deviation) *max_deviation = 0.0;
  if (n <= max_vertices) return all;
  auto p = [&](Eigen::Index i) -> Vec3d { return points.row(i).transpose(); };
  // Initial tetrahedron of extreme points.
  Eigen::Index a = 0;
  for (Eigen::Index i = 1; i < n; ++i)
    if (points(i, 0) < points(a, 0)) a = i;
  auto farthest = [&](auto&& dist) {
    Eigen::Index best = 0;
    double d_best = -1.0;
    for (Eigen::Index i = 0; i < n; ++i) {
      const double d = dist(p(i));
      if (d > d_best) d_best = d, best = i;
    }
    return std::make_pair(best, d_best);
  };
  const auto [b, d_ab] = farthest([&](const Vec3d& q) { return (q - p(a)).squaredNorm(); });
  const Vec3d ab = (p(b) - p(a)).normalized();
  const auto [c, d_line] = farthest([&](const Vec3d& q) {
    const Vec3d r = q - p(a);
    return (r - r.dot(ab) * ab).squaredNorm();
  });
  const Vec3d nrm = (p(b) - p(a)).cross(p(c) - p(a)).normalized();
  const auto [d, d_plane] = farthest([&](const Vec3d& q) { return std::abs((q - p(a)).dot(nrm)); });
  const double scale = std::sqrt(d_ab);
  if (!(scale > 0) || !(std::sqrt(d_line) > 1e-9 * scale) || !(d_plane > 1e-9 * scale))
    return all;  // no volume: nothing sensible to reduce
  std::vector<Eigen::Index> chosen = {a, b, c, d};
  std::vector<char> in(static_cast<std::size_t>(n), 0);
  for (Eigen::Index i : chosen) in[static_cast<std::size_t>(i)] = 1;
  std::vector<double> coords;
  std::vector<Vec3d> normals;
  std::vector<double> offsets;
  double deviation = 0.0;
  while (true) {
    hull_face_planes(points, chosen, coords, normals, offsets);
    // Each point's distance outside the hull; per face, its farthest point beyond tolerance.
    std::vector<std::pair<double, Eigen::Index>> per_face(normals.size(), {0.0, -1});
    deviation = 0.0;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (in[static_cast<std::size_t>(i)]) continue;
      const Vec3d q = p(i);
      double out = -1e300;
      std::size_t face = 0;
      for (std::size_t f = 0; f < normals.size(); ++f) {
        const double d = normals[f].dot(q) - offsets[f];
        if (d > out) out = d, face = f;
      }
      deviation = std::max(deviation, out);
      if (out > tolerance && out > per_face[face].first) per_face[face] = {out, i};
    }
    const auto budget = static_cast<std::size_t>(max_vertices) - chosen.size();
    if (budget == 0) break;
    // Add the farthest point of every face that has one (quickhull-like rounds keep the work
    // logarithmic in the number of points added), farthest first while the budget lasts.
    std::vector<std::pair<double, Eigen::Index>> add;
    for (const auto& c : per_face)
      if (c.second >= 0) add.push_back(c);
    if (add.empty()) break;
    std::sort(add.begin(), add.end(), [](const auto& x, const auto& y) {
      return x.first != y.first ? x.first > y.first : x.second < y.second;
    });
    // At most half as many as chosen so far per round: later rounds see the refined hull.
    const std::size_t round = std::min(budget, std::max<std::size_t>(1, chosen.size() / 2));
    for (std::size_t k = 0; k < add.size() && k < round; ++k) {
      if (in[static_cast<std::size_t>(add[k].second)]) continue;  // farthest for two faces
      chosen.push_back(add[k].second);
      in[static_cast<std::size_t>(add[k].second)] = 1;
    }
  }
  if (max_deviation) *max_deviation = deviation;
  return chosen;
}

Mesh convex_hull(const Mesh& mesh) {
  check_finite(mesh, "convex_hull");
  Mesh h = convex_hull_of_points(mesh.vertices());
  h.set_name(mesh.name().empty() ? std::string("hull") : mesh.name() + "_hull");
  return h;
}

namespace {

// Fails with InvalidArgument naming the first option of o out of its range.
void check_options(const ConvexDecompositionOptions& o) {
  auto bad_option = [](const char* name, double v, const char* expected) {
    throw_error<InvalidArgument>("convex_decomposition: options.", name, " must be ", expected,
                                 ", got ", v);
  };
  if (!(std::isfinite(o.convex_volume_tolerance) && o.convex_volume_tolerance >= 0))
    bad_option("convex_volume_tolerance", o.convex_volume_tolerance, "finite and >= 0");
  if (!(std::isfinite(o.max_concavity) && o.max_concavity > 0))
    bad_option("max_concavity", o.max_concavity, "finite and > 0");
  if (o.min_parts < 1) bad_option("min_parts", o.min_parts, ">= 1");
  if (o.max_parts < o.min_parts) bad_option("max_parts", o.max_parts, ">= min_parts");
  if (!(std::isfinite(o.compactness_weight) && o.compactness_weight >= 0))
    bad_option("compactness_weight", o.compactness_weight, "finite and >= 0");
  if (!(std::isfinite(o.volume_weight) && o.volume_weight >= 0))
    bad_option("volume_weight", o.volume_weight, "finite and >= 0");
  if (o.max_hacd_faces < 4) bad_option("max_hacd_faces", o.max_hacd_faces, ">= 4");
  if (o.grid_resolution < 4) bad_option("grid_resolution", o.grid_resolution, ">= 4");
  if (!(std::isfinite(o.merge_volume_tolerance) && o.merge_volume_tolerance >= 0))
    bad_option("merge_volume_tolerance", o.merge_volume_tolerance, "finite and >= 0");
  if (o.merge_max_parts < 0) bad_option("merge_max_parts", o.merge_max_parts, "0 (no cap) or >= 1");
}

}  // namespace

std::vector<Mesh> convex_decomposition(const Mesh& mesh, const ConvexDecompositionOptions& o) {
  check_finite(mesh, "convex_decomposition");
  check_options(o);

  Mesh hull = convex_hull(mesh);
  const double hull_volume = closed_mesh_volume(hull);
  const double volume = closed_mesh_volume(mesh);
  const std::string base = mesh.name().empty() ? std::string("part") : mesh.name();
  if (hull_volume <= volume * (1.0 + o.convex_volume_tolerance) || o.max_parts == 1) {
    hull.set_name(base + "_0");
    return {hull};
  }

  // HACD input: vertices welded by position (texture seams would disconnect the graph) and,
  // for large meshes, clustered on a grid (HACD's cost grows quickly with the face count).
  // `members[k]` lists the input vertices behind HACD vertex k, so that part hulls are built from
  // the input vertices and contain them all.
  const auto& V = mesh.vertices();
  const auto bounds = mesh.bounds();
  const Vec3d lo = bounds.row(0).transpose();
  const double diag = (bounds.row(1) - bounds.row(0)).norm();
  double cell = 0.0;  // 0: exact welding
  if (mesh.num_faces() > o.max_hacd_faces) cell = diag / o.grid_resolution;
  std::vector<HACD::Vec3<HACD::Real>> points;
  std::vector<std::vector<std::int32_t>> members;
  std::vector<long> vertex_to_point(static_cast<std::size_t>(V.rows()));
  {
    std::map<std::array<std::int64_t, 3>, long> by_key;
    std::vector<Vec3d> sums;
    for (Eigen::Index v = 0; v < V.rows(); ++v) {
      const Vec3d p = V.row(v).cast<double>().transpose();
      std::array<std::int64_t, 3> key;
      for (int c = 0; c < 3; ++c) {
        if (cell > 0) {
          key[c] = static_cast<std::int64_t>(std::floor((p[c] - lo[c]) / cell));
        } else {
          float f = V(v, c);
          std::int32_t bits;
          std::memcpy(&bits, &f, sizeof bits);
          key[c] = bits;
        }
      }
      auto [it, fresh] = by_key.emplace(key, static_cast<long>(sums.size()));
      if (fresh) {
        sums.push_back(Vec3d::Zero());
        members.emplace_back();
      }
      sums[it->second] += p;
      members[it->second].push_back(static_cast<std::int32_t>(v));
      vertex_to_point[v] = it->second;
    }
    for (std::size_t k = 0; k < sums.size(); ++k) {
      const Vec3d c = sums[k] / double(members[k].size());
      points.emplace_back(c.x(), c.y(), c.z());
    }
  }
  std::vector<HACD::Vec3<long>> triangles;
  {
    std::set<std::array<long, 3>> seen;
    const auto& F = mesh.faces();
    for (Eigen::Index f = 0; f < F.rows(); ++f) {
      const long a = vertex_to_point[F(f, 0)], b = vertex_to_point[F(f, 1)],
                 c = vertex_to_point[F(f, 2)];
      if (a == b || b == c || a == c) continue;  // collapsed by the grid
      std::array<long, 3> k{a, b, c};
      std::sort(k.begin(), k.end());
      if (!seen.insert(k).second) continue;
      triangles.emplace_back(a, b, c);
    }
  }
  if (triangles.size() < 4) {
    hull.set_name(base + "_0");
    return {hull};
  }

  double concavity = o.max_concavity;
  std::vector<long> partition;
  std::size_t num_clusters = 0;
  for (int attempt = 0; attempt < 16; ++attempt) {
    HACD::HACD hacd;
    hacd.SetPoints(points.data());
    hacd.SetNPoints(points.size());
    hacd.SetTriangles(triangles.data());
    hacd.SetNTriangles(triangles.size());
    hacd.SetCompacityWeight(o.compactness_weight);
    hacd.SetVolumeWeight(o.volume_weight);
    hacd.SetNClusters(static_cast<std::size_t>(o.min_parts));
    hacd.SetNVerticesPerCH(1000);
    // HACD normalises the mesh so that its bounding-box diagonal is 2 * scale; its concavity is
    // measured in those units.
    hacd.SetScaleFactor(1000.0);
    hacd.SetConcavity(concavity * 2000.0);
    hacd.SetAddExtraDistPoints(o.extra_concavity_points);
    hacd.SetAddNeighboursDistPoints(false);
    hacd.SetAddFacesPoints(o.extra_concavity_points);
    hacd.SetConnectDist(30.0);
    if (!hacd.Compute(false, false))
      throw_error<BackendError>("convex_decomposition: HACD failed on mesh '", mesh.name(), "'");
    num_clusters = hacd.GetNClusters();
    const long* part = hacd.GetPartition();
    if (part == nullptr)
      throw_error<BackendError>("convex_decomposition: HACD returned no partition");
    partition.assign(part, part + triangles.size());
    if (num_clusters <= static_cast<std::size_t>(o.max_parts)) break;
    concavity *= 2.0;
  }

  // Hull of each cluster's input vertices: every input vertex lies in some part.
  std::map<long, std::vector<std::int32_t>> cluster_vertices;
  for (std::size_t t = 0; t < partition.size(); ++t) {
    auto& ids = cluster_vertices[partition[t]];
    for (long k : {triangles[t].X(), triangles[t].Y(), triangles[t].Z()})
      ids.insert(ids.end(), members[k].begin(), members[k].end());
  }
  std::vector<Points3f> clusters;
  for (auto& [cluster, ids] : cluster_vertices) {
    std::sort(ids.begin(), ids.end());
    ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
    Points3f pts(static_cast<Eigen::Index>(ids.size()), 3);
    for (std::size_t i = 0; i < ids.size(); ++i)
      pts.row(static_cast<Eigen::Index>(i)) = V.row(ids[i]);
    clusters.push_back(std::move(pts));
  }
  // A flat cluster (a planar patch) spans no volume: its points join the cluster with the
  // nearest centroid, so that every input vertex still lies in some part.
  auto is_flat = [](const Points3f& pts) {
    if (pts.rows() < 4) return true;
    const Eigen::RowVector3d c = pts.cast<double>().colwise().mean();
    const Eigen::MatrixXd centred = pts.cast<double>().rowwise() - c;
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(centred);
    const auto& sv = svd.singularValues();
    return sv(2) <= 1e-6 * sv(0);
  };
  std::vector<bool> flat(clusters.size());
  for (std::size_t c = 0; c < clusters.size(); ++c) flat[c] = is_flat(clusters[c]);
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    if (!flat[c]) continue;
    const Eigen::RowVector3f mc = clusters[c].colwise().mean();
    long best = -1;
    double best_d = 1e300;
    for (std::size_t k = 0; k < clusters.size(); ++k) {
      if (flat[k]) continue;
      const double dist = (clusters[k].colwise().mean() - mc).norm();
      if (dist < best_d) best_d = dist, best = static_cast<long>(k);
    }
    if (best < 0) continue;
    Points3f merged(clusters[best].rows() + clusters[c].rows(), 3);
    merged << clusters[best], clusters[c];
    clusters[best] = std::move(merged);
  }
  {
    std::vector<Points3f> solid;
    for (std::size_t c = 0; c < clusters.size(); ++c)
      if (!flat[c]) solid.push_back(std::move(clusters[c]));
    if (o.merge_volume_tolerance > 0 || o.merge_max_parts > 0)
      solid = merge_clusters(std::move(solid), o.merge_volume_tolerance * hull_volume,
                             o.merge_max_parts);
    clusters = std::move(solid);
    flat.assign(clusters.size(), false);
  }
  std::vector<Mesh> parts;
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    if (flat[c]) continue;
    Mesh part = convex_hull_of_points(clusters[c]);
    part.set_name(base + "_" + std::to_string(parts.size()));
    parts.push_back(std::move(part));
  }
  if (parts.empty()) {
    hull.set_name(base + "_0");
    return {hull};
  }
  return parts;
}

}  // namespace mgn
