#include <mgn/core/error.hpp>
#include <mgn/geometry/mesh.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <numeric>
#include <unordered_map>

namespace mgn {

namespace {

Vec3d row(const Points3f& v, std::int64_t i) { return v.row(i).transpose().cast<double>(); }

double bbox_diagonal(const Points3f& v) {
  if (v.rows() == 0) return 0.0;
  return (v.colwise().maxCoeff() - v.colwise().minCoeff()).cast<double>().norm();
}

struct PositionKey {
  std::uint32_t bits[3];
  bool operator==(const PositionKey& o) const {
    return bits[0] == o.bits[0] && bits[1] == o.bits[1] && bits[2] == o.bits[2];
  }
};
struct PositionHash {
  std::size_t operator()(const PositionKey& k) const {
    std::uint64_t h = 1469598103934665603ULL;
    for (auto b : k.bits) h = (h ^ b) * 1099511628211ULL;
    return static_cast<std::size_t>(h ^ (h >> 29));
  }
};

std::int32_t find_root(std::vector<std::int32_t>& parent, std::int32_t x) {
  while (parent[x] != x) {
    parent[x] = parent[parent[x]];
    x = parent[x];
  }
  return x;
}

}  // namespace

std::vector<std::int64_t> find_degenerate_faces(const Points3f& vertices, const Faces& faces) {
  const double diag = bbox_diagonal(vertices);
  const double min_double_area = 2.0e-14 * diag * diag;  // 2 * (area threshold)
  const double min_cross2 = min_double_area * min_double_area;
  std::vector<std::int64_t> bad;
  for (std::int64_t f = 0; f < faces.rows(); ++f) {
    const auto a = faces(f, 0), b = faces(f, 1), c = faces(f, 2);
    if (a == b || b == c || a == c) {
      bad.push_back(f);
      continue;
    }
    const Vec3d e1 = row(vertices, b) - row(vertices, a);
    const Vec3d e2 = row(vertices, c) - row(vertices, a);
    const double cross2 = e1.cross(e2).squaredNorm();  // (2*area)^2
    if (!(cross2 > min_cross2)) bad.push_back(f);
  }
  return bad;
}

Mesh::Mesh(Points3f vertices, Faces faces, Points2f uvs, std::vector<Material> materials,
           std::vector<std::int32_t> face_materials, std::string name)
    : vertices_(std::move(vertices)),
      faces_(std::move(faces)),
      uvs_(std::move(uvs)),
      materials_(std::move(materials)),
      face_materials_(std::move(face_materials)),
      name_(std::move(name)) {
  const std::string who = name_.empty() ? std::string("Mesh") : "Mesh '" + name_ + "'";
  const std::int64_t nv = vertices_.rows();
  for (std::int64_t i = 0; i < nv; ++i) {
    if (!vertices_.row(i).allFinite()) {
      throw_error<InvalidArgument>(who, ": vertex ", i, " is not finite (", vertices_(i, 0), ", ",
                                   vertices_(i, 1), ", ", vertices_(i, 2),
                                   "); expected finite coordinates in metres");
    }
  }
  for (std::int64_t f = 0; f < faces_.rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const auto idx = faces_(f, k);
      if (idx < 0 || idx >= nv) {
        throw_error<InvalidArgument>(who, ": face ", f, " references vertex ", idx,
                                     "; expected an index in [0, ", nv, ")");
      }
    }
  }
  const auto degenerate = find_degenerate_faces(vertices_, faces_);
  if (!degenerate.empty()) {
    throw_error<InvalidArgument>(who, ": ", degenerate.size(),
                                 " face(s) have zero area (first: face ", degenerate.front(),
                                 "); expected non-degenerate triangles");
  }
  if (uvs_.rows() != 0 && uvs_.rows() != nv) {
    throw_error<InvalidArgument>(who, ": uvs has ", uvs_.rows(), " rows; expected 0 or ", nv,
                                 " (one per vertex)");
  }
  if (!face_materials_.empty()) {
    if (static_cast<std::int64_t>(face_materials_.size()) != faces_.rows()) {
      throw_error<InvalidArgument>(who, ": face_materials has ", face_materials_.size(),
                                   " entries; expected 0 or ", faces_.rows(), " (one per face)");
    }
    for (auto m : face_materials_) {
      if (m < 0 || m >= static_cast<std::int32_t>(materials_.size())) {
        throw_error<InvalidArgument>(who, ": face material index ", m, "; expected [0, ",
                                     materials_.size(), ")");
      }
    }
  }
}

Points3f Mesh::face_normals() const {
  Points3f n(faces_.rows(), 3);
  for (std::int64_t f = 0; f < faces_.rows(); ++f) {
    const Vec3d a = row(vertices_, faces_(f, 0));
    const Vec3d e1 = row(vertices_, faces_(f, 1)) - a;
    const Vec3d e2 = row(vertices_, faces_(f, 2)) - a;
    Vec3d c = e1.cross(e2);
    const double len = c.norm();
    if (len > 0) c /= len;
    n.row(f) = c.cast<float>().transpose();
  }
  return n;
}

Eigen::VectorXd Mesh::face_areas() const {
  Eigen::VectorXd areas(faces_.rows());
  for (std::int64_t f = 0; f < faces_.rows(); ++f) {
    const Vec3d a = row(vertices_, faces_(f, 0));
    areas[f] =
        0.5 * (row(vertices_, faces_(f, 1)) - a).cross(row(vertices_, faces_(f, 2)) - a).norm();
  }
  return areas;
}

double Mesh::area() const { return face_areas().sum(); }

Eigen::Matrix<double, 2, 3, Eigen::RowMajor> Mesh::bounds() const {
  require_non_empty(*this, "Mesh::bounds");
  Eigen::Matrix<double, 2, 3, Eigen::RowMajor> b;
  b.row(0) = vertices_.colwise().minCoeff().cast<double>();
  b.row(1) = vertices_.colwise().maxCoeff().cast<double>();
  return b;
}

std::vector<std::int32_t> Mesh::weld_map() const {
  std::vector<std::int32_t> weld(static_cast<std::size_t>(vertices_.rows()));
  std::unordered_map<PositionKey, std::int32_t, PositionHash> first;
  first.reserve(weld.size() * 2);
  for (std::int64_t i = 0; i < vertices_.rows(); ++i) {
    PositionKey key;
    for (int k = 0; k < 3; ++k) {
      const float x = vertices_(i, k) + 0.0f;  // -0 and +0 weld together
      std::memcpy(&key.bits[k], &x, sizeof(float));
    }
    auto [it, inserted] = first.emplace(key, static_cast<std::int32_t>(i));
    weld[i] = it->second;
  }
  return weld;
}

namespace {

/// Undirected edges of the faces, over a vertex id per face corner (corner 3f+k is faces(f,k)):
/// one edge per pair of distinct ids, the edge of every corner, and per edge its uses in each
/// direction and its first two faces.
struct EdgeTable {
  std::vector<std::int32_t> corner_edge;   ///< 3F: edge from corner k to corner (k+1)%3, or -1
  std::vector<std::int32_t> forward;       ///< uses from the smaller id to the larger
  std::vector<std::int32_t> backward;      ///< uses from the larger id to the smaller
  std::vector<std::int64_t> face0, face1;  ///< first and second face using the edge (or -1)

  std::int32_t uses(std::int32_t e) const { return forward[e] + backward[e]; }
  std::int32_t size() const { return static_cast<std::int32_t>(forward.size()); }
};

EdgeTable edge_table(const std::vector<std::int32_t>& corner_id, std::int64_t nf) {
  EdgeTable t;
  t.corner_edge.assign(static_cast<std::size_t>(nf) * 3, -1);
  std::unordered_map<std::uint64_t, std::int32_t> index;
  index.reserve(static_cast<std::size_t>(nf) * 3);
  for (auto* v : {&t.forward, &t.backward}) v->reserve(static_cast<std::size_t>(nf) * 3 / 2 + 3);
  for (auto* v : {&t.face0, &t.face1}) v->reserve(static_cast<std::size_t>(nf) * 3 / 2 + 3);
  for (std::int64_t f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) {
      const std::int32_t p = corner_id[3 * f + k], q = corner_id[3 * f + (k + 1) % 3];
      if (p == q) continue;
      const std::uint64_t key = (static_cast<std::uint64_t>(std::min(p, q)) << 32) |
                                static_cast<std::uint32_t>(std::max(p, q));
      const auto [it, inserted] = index.emplace(key, t.size());
      const std::int32_t e = it->second;
      if (inserted) {
        t.forward.push_back(0);
        t.backward.push_back(0);
        t.face0.push_back(f);
        t.face1.push_back(-1);
      } else if (t.face1[e] < 0) {
        t.face1[e] = f;
      }
      (p < q ? t.forward[e] : t.backward[e]) += 1;
      t.corner_edge[3 * f + k] = e;
    }
  }
  return t;
}

/// Corner vertex ids after splitting where closed pieces touch (MeshReport::num_split_edges),
/// and the number of welded vertices split. A piece is a set of faces connected through edges of
/// exactly two faces; it is closed when it uses each of its edges exactly twice and has no face
/// (the same three welded vertices) that another piece also has (coincident walls are not a
/// touch). A welded vertex used by two or more pieces, all closed, gets one id per piece.
std::pair<std::vector<std::int32_t>, std::int64_t> split_touching_pieces(
    const std::vector<std::int32_t>& weld_id, std::int64_t nf, std::int32_t num_ids,
    const EdgeTable& t) {
  std::vector<std::int32_t> piece(static_cast<std::size_t>(nf));
  std::iota(piece.begin(), piece.end(), 0);
  for (std::int32_t e = 0; e < t.size(); ++e) {
    if (t.uses(e) != 2) continue;
    const auto a = find_root(piece, static_cast<std::int32_t>(t.face0[e]));
    const auto b = find_root(piece, static_cast<std::int32_t>(t.face1[e]));
    if (a != b) piece[std::max(a, b)] = std::min(a, b);
  }
  for (std::int32_t f = 0; f < nf; ++f) piece[f] = find_root(piece, f);

  std::vector<char> open(static_cast<std::size_t>(nf), 0);    // by piece (its smallest face)
  std::vector<std::pair<std::int32_t, std::int32_t>> shared;  // (over-shared edge, piece)
  std::vector<std::pair<std::array<std::int32_t, 3>, std::int32_t>> walls;  // (face, piece)
  for (std::int64_t f = 0; f < nf; ++f) {
    bool on_shared = false;
    for (int k = 0; k < 3; ++k) {
      const auto e = t.corner_edge[3 * f + k];
      if (e < 0) continue;
      if (t.uses(e) == 1) open[piece[f]] = 1;
      if (t.uses(e) > 2) {
        shared.emplace_back(e, piece[f]);
        on_shared = true;
      }
    }
    if (on_shared) {
      std::array<std::int32_t, 3> v = {weld_id[3 * f], weld_id[3 * f + 1], weld_id[3 * f + 2]};
      std::sort(v.begin(), v.end());
      walls.emplace_back(v, piece[f]);
    }
  }
  std::sort(shared.begin(), shared.end());
  for (std::size_t i = 0; i < shared.size();) {
    std::size_t j = i;
    while (j < shared.size() && shared[j] == shared[i]) ++j;
    if (j - i != 2) open[shared[i].second] = 1;
    i = j;
  }
  std::sort(walls.begin(), walls.end());
  for (std::size_t i = 1; i < walls.size(); ++i) {
    if (walls[i].first == walls[i - 1].first) {
      open[walls[i].second] = 1;
      open[walls[i - 1].second] = 1;
    }
  }

  // A welded vertex of two or more pieces, all closed, is split: the piece that uses it first
  // keeps its id, each other piece gets a new one.
  std::vector<std::int32_t> first(static_cast<std::size_t>(num_ids), -1);
  std::vector<char> several(static_cast<std::size_t>(num_ids), 0);
  std::vector<char> near_open(static_cast<std::size_t>(num_ids), 0);
  for (std::int64_t c = 0; c < 3 * nf; ++c) {
    const auto v = weld_id[c], p = piece[c / 3];
    if (first[v] < 0) first[v] = p;
    if (first[v] != p) several[v] = 1;
    if (open[p]) near_open[v] = 1;
  }
  std::int64_t split = 0;
  for (std::int32_t v = 0; v < num_ids; ++v) split += several[v] && !near_open[v];
  std::vector<std::int32_t> id = weld_id;
  if (split == 0) return {std::move(id), 0};
  std::unordered_map<std::uint64_t, std::int32_t> copy;  // (vertex, piece) -> new id
  std::int32_t next = num_ids;
  for (std::int64_t c = 0; c < 3 * nf; ++c) {
    const auto v = weld_id[c], p = piece[c / 3];
    if (!several[v] || near_open[v] || p == first[v]) continue;
    const auto key = (static_cast<std::uint64_t>(v) << 32) | static_cast<std::uint32_t>(p);
    id[c] = copy.emplace(key, next).first->second;
    if (id[c] == next) ++next;
  }
  return {std::move(id), split};
}

}  // namespace

MeshReport Mesh::validate() const {
  MeshReport r;
  r.num_vertices = vertices_.rows();
  r.num_faces = faces_.rows();
  r.area = area();
  if (faces_.rows() == 0) return r;

  const std::int64_t nf = faces_.rows();
  const auto weld = weld_map();
  std::vector<std::int32_t> weld_id(static_cast<std::size_t>(nf) * 3);
  for (std::int64_t f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) weld_id[3 * f + k] = weld[faces_(f, k)];
  const EdgeTable welded = edge_table(weld_id, nf);
  const auto num_welded_ids = static_cast<std::int32_t>(vertices_.rows());
  const auto [id, split_vertices] = split_touching_pieces(weld_id, nf, num_welded_ids, welded);
  r.num_split_vertices = split_vertices;
  EdgeTable refined;
  if (split_vertices > 0) refined = edge_table(id, nf);
  const EdgeTable& t = split_vertices > 0 ? refined : welded;

  if (split_vertices > 0) {  // welded edges of more than two faces now on separate edges
    std::vector<std::pair<std::int32_t, std::int32_t>> pairs;
    for (std::int64_t c = 0; c < 3 * nf; ++c) {
      const auto e = welded.corner_edge[c];
      if (e >= 0 && welded.uses(e) > 2) pairs.emplace_back(e, t.corner_edge[c]);
    }
    std::sort(pairs.begin(), pairs.end());
    pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
    for (std::size_t i = 0; i < pairs.size();) {
      std::size_t j = i;
      while (j < pairs.size() && pairs[j].first == pairs[i].first) ++j;
      if (j - i >= 2) ++r.num_split_edges;
      i = j;
    }
  }

  for (std::int32_t e = 0; e < t.size(); ++e) {
    const int total = t.uses(e);
    if (total == 1) {
      ++r.num_boundary_edges;
    } else if (total > 2) {
      ++r.num_nonmanifold_edges;
    } else if (t.forward[e] != 1) {
      ++r.num_misoriented_edges;
    }
  }

  // Connected components over the (split) vertex ids.
  const std::int32_t num_ids =
      std::max(num_welded_ids, id.empty() ? 0 : *std::max_element(id.begin(), id.end()) + 1);
  std::vector<std::int32_t> parent(static_cast<std::size_t>(num_ids));
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<char> used(static_cast<std::size_t>(num_ids), 0);
  for (std::int64_t f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) {
      const auto p = id[3 * f + k], q = id[3 * f + (k + 1) % 3];
      used[p] = 1;
      const auto rp = find_root(parent, p), rq = find_root(parent, q);
      if (rp != rq) parent[rp] = rq;
    }
  }
  for (std::int32_t i = 0; i < num_ids; ++i)
    if (used[i] && find_root(parent, i) == i) ++r.num_components;

  double volume6 = 0.0;
  const Vec3d ref = row(vertices_, 0);
  for (std::int64_t f = 0; f < nf; ++f) {
    const Vec3d a = row(vertices_, faces_(f, 0)) - ref;
    const Vec3d b = row(vertices_, faces_(f, 1)) - ref;
    const Vec3d c = row(vertices_, faces_(f, 2)) - ref;
    volume6 += a.dot(b.cross(c));
  }
  r.signed_volume = volume6 / 6.0;
  r.is_watertight = r.num_boundary_edges == 0 && r.num_nonmanifold_edges == 0;
  r.is_winding_consistent = r.num_misoriented_edges == 0 && r.num_nonmanifold_edges == 0;
  r.is_outward = r.is_watertight && r.is_winding_consistent && r.signed_volume > 0.0;
  return r;
}

Mesh Mesh::transformed(const Pose& X) const {
  if (!X.matrix().allFinite()) {
    throw_error<InvalidArgument>(
        "Mesh::transformed: the pose has non-finite entries; expected a "
        "finite 4x4 rigid transform");
  }
  Points3f v(vertices_.rows(), 3);
  for (std::int64_t i = 0; i < vertices_.rows(); ++i) {
    v.row(i) = (X * row(vertices_, i)).cast<float>().transpose();
  }
  return Mesh(std::move(v), faces_, uvs_, materials_, face_materials_, name_);
}

Mesh Mesh::scaled(double factor) const {
  if (!(factor > 0.0) || !std::isfinite(factor)) {
    throw_error<InvalidArgument>("Mesh::scaled: factor must be finite and > 0, got ", factor);
  }
  Points3f v = (vertices_.cast<double>() * factor).cast<float>();
  return Mesh(std::move(v), faces_, uvs_, materials_, face_materials_, name_);
}

Mesh Mesh::flipped() const {
  Faces f = faces_;
  f.col(1).swap(f.col(2));
  return Mesh(vertices_, std::move(f), uvs_, materials_, face_materials_, name_);
}

Mesh Mesh::merge(const std::vector<Mesh>& meshes, std::string name) {
  std::int64_t nv = 0, nf = 0;
  bool any_uv = false;
  for (const auto& m : meshes) {
    nv += m.num_vertices();
    nf += m.num_faces();
    any_uv = any_uv || m.uvs().rows() > 0;
  }
  Points3f v(nv, 3);
  Faces f(nf, 3);
  Points2f uv = any_uv ? Points2f::Zero(nv, 2) : Points2f();
  std::vector<Material> materials;
  std::vector<std::int32_t> face_mat;
  face_mat.reserve(static_cast<std::size_t>(nf));
  std::int64_t vo = 0, fo = 0;
  for (const auto& m : meshes) {
    v.middleRows(vo, m.num_vertices()) = m.vertices();
    f.middleRows(fo, m.num_faces()) = (m.faces().array() + static_cast<std::int32_t>(vo)).matrix();
    if (m.uvs().rows() > 0) uv.middleRows(vo, m.num_vertices()) = m.uvs();
    const auto mat_offset = static_cast<std::int32_t>(materials.size());
    if (m.materials().empty()) {
      materials.push_back(Material{});
    } else {
      materials.insert(materials.end(), m.materials().begin(), m.materials().end());
    }
    for (std::int64_t i = 0; i < m.num_faces(); ++i) {
      face_mat.push_back(mat_offset + (m.face_materials().empty() ? 0 : m.face_materials()[i]));
    }
    vo += m.num_vertices();
    fo += m.num_faces();
  }
  return Mesh(std::move(v), std::move(f), std::move(uv), std::move(materials), std::move(face_mat),
              std::move(name));
}

void require_non_empty(const Mesh& mesh, const std::string& what) {
  if (mesh.empty()) {
    throw_error<InvalidArgument>(what, ": the mesh",
                                 mesh.name().empty() ? std::string() : " '" + mesh.name() + "'",
                                 " has no faces; expected at least one triangle");
  }
}

}  // namespace mgn
