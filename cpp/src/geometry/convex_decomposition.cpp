#include <mgn/core/error.hpp>
#include <mgn/geometry/convex_decomposition.hpp>

#include <HACD/hacdHACD.h>
#include <LinearMath/btConvexHullComputer.h>

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <map>
#include <unordered_map>

namespace mgn {

namespace {

void check_finite(const Mesh& mesh, const char* fn) {
  require_non_empty(mesh, fn);
  if (!mesh.vertices().allFinite())
    throw_error<InvalidArgument>(fn, ": mesh '", mesh.name(), "' has non-finite vertices");
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

Mesh convex_hull(const Mesh& mesh) {
  check_finite(mesh, "convex_hull");
  Mesh h = convex_hull_of_points(mesh.vertices());
  h.set_name(mesh.name().empty() ? std::string("hull") : mesh.name() + "_hull");
  return h;
}

std::vector<Mesh> convex_decomposition(const Mesh& mesh, const ConvexDecompositionOptions& o) {
  check_finite(mesh, "convex_decomposition");
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

  Mesh hull = convex_hull(mesh);
  const double hull_volume = closed_mesh_volume(hull);
  const double volume = closed_mesh_volume(mesh);
  const std::string base = mesh.name().empty() ? std::string("part") : mesh.name();
  if (hull_volume <= volume * (1.0 + o.convex_volume_tolerance) || o.max_parts == 1) {
    hull.set_name(base + "_0");
    return {hull};
  }

  // HACD needs a connected vertex graph: weld duplicated (texture seam) vertices first.
  const std::vector<std::int32_t> weld = mesh.weld_map();
  std::unordered_map<std::int32_t, long> compact;
  std::vector<HACD::Vec3<HACD::Real>> points;
  const auto& V = mesh.vertices();
  for (std::size_t v = 0; v < weld.size(); ++v) {
    if (weld[v] != static_cast<std::int32_t>(v)) continue;
    compact.emplace(static_cast<std::int32_t>(v), static_cast<long>(points.size()));
    points.emplace_back(V(v, 0), V(v, 1), V(v, 2));
  }
  std::vector<HACD::Vec3<long>> triangles;
  triangles.reserve(static_cast<std::size_t>(mesh.num_faces()));
  for (Eigen::Index f = 0; f < mesh.num_faces(); ++f) {
    const auto& F = mesh.faces();
    triangles.emplace_back(compact.at(weld[F(f, 0)]), compact.at(weld[F(f, 1)]),
                           compact.at(weld[F(f, 2)]));
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
    hacd.SetAddExtraDistPoints(true);
    hacd.SetAddNeighboursDistPoints(false);
    hacd.SetAddFacesPoints(true);
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

  // Exact hull of each cluster's vertices: every input vertex lies in some part.
  std::map<long, std::vector<std::int32_t>> cluster_vertices;
  const auto& F = mesh.faces();
  for (std::size_t t = 0; t < partition.size(); ++t)
    for (int c = 0; c < 3; ++c)
      cluster_vertices[partition[t]].push_back(F(static_cast<Eigen::Index>(t), c));
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
    const auto sv = svd.singularValues();
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
