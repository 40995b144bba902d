#pragma once
/// @file mesh.hpp  Triangle mesh with materials, and its validation.
///
/// Units: metres. Frame: the object frame O the vertices are given in. Faces are wound
/// counter-clockwise seen from outside (outward normals by the right-hand rule).

#include <mgn/core/types.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace mgn {

/// Surface appearance of (part of) a mesh, as read from the source file.
struct Material {
  std::string name;
  /// Linear RGBA base (diffuse) colour in [0,1]; alpha < 1 means transparent.
  Vec4f base_color = Vec4f(0.7f, 0.7f, 0.7f, 1.0f);
  /// Specular colour in [0,1] and Phong exponent.
  Vec3f specular = Vec3f(0.2f, 0.2f, 0.2f);
  float shininess = 20.0f;
  /// Opacity in [0,1] (1 opaque). Transparent surfaces matter for depth sensors.
  float opacity = 1.0f;
  /// Absolute path of the diffuse texture image, empty if none or embedded.
  std::string texture_path;
  /// Compressed bytes (PNG/JPEG) of an embedded texture (GLB), empty if none.
  std::vector<std::uint8_t> texture_data;

  /// Physically based parameters (glTF 2.0 metallic-roughness with KHR_materials_transmission
  /// and KHR_materials_ior; path_tracer.hpp), used by the path tracer. Meaningful when has_pbr is
  /// true (a glTF/GLB file, a built-in object, a user object with PBR keys); otherwise the path
  /// tracer derives them from the Phong fields above.
  bool has_pbr = false;
  float metallic = 0.0f;      ///< [0,1]
  float roughness = 0.5f;     ///< perceptual roughness in [0,1] (GGX alpha = roughness^2)
  float ior = 1.5f;           ///< index of refraction (>= 1)
  float transmission = 0.0f;  ///< [0,1]; 1 = clear dielectric (glass, clear plastic)
};

/// Result of Mesh::validate(). Topology is computed after welding vertices with identical
/// positions, so texture seams (duplicated vertices) do not break watertightness, and after
/// splitting where closed pieces touch: a piece is a set of faces connected through edges of
/// exactly two faces; a welded vertex used only by closed pieces (each uses every one of its
/// edges exactly twice and shares no whole face with another piece), two or more of them, counts
/// once per piece. So two closed solids that share one edge or one vertex (two cubes along an
/// edge, two tetrahedra at a vertex) are two closed 2-manifolds, and the mesh is watertight with
/// the volume of both. An edge of more than two faces where an open piece (a hole, a stray fin)
/// meets stays non-manifold.
struct MeshReport {
  std::int64_t num_vertices = 0;
  std::int64_t num_faces = 0;
  std::int64_t num_boundary_edges = 0;     ///< edges used by exactly one face
  std::int64_t num_nonmanifold_edges = 0;  ///< edges used by more than two faces (after splits)
  std::int64_t num_misoriented_edges = 0;  ///< interior edges traversed twice the same way
  std::int64_t num_components = 0;         ///< connected components (by vertex, after splits)
  std::int64_t num_split_edges = 0;     ///< welded edges of > 2 faces split between closed pieces
  std::int64_t num_split_vertices = 0;  ///< welded vertices split between closed pieces
  bool is_watertight = false;  ///< closed 2-manifold: every edge shared by exactly two faces
  bool is_winding_consistent = false;  ///< neighbouring faces agree on orientation
  bool is_outward = false;             ///< watertight, consistent and positive signed volume
  double signed_volume = 0.0;          ///< m^3, divergence theorem; meaningful when watertight
  double area = 0.0;                   ///< m^2
};

/// An indexed triangle mesh. Invariants (checked on construction): every vertex is finite, every
/// index is in range, no face has zero area. A default-constructed mesh is empty.
class Mesh {
 public:
  Mesh() = default;
  /// Builds a mesh from arrays. Throws InvalidArgument (naming `name` when given) if a vertex is
  /// not finite, an index is out of range, a face has zero area or repeated vertices, or the sizes
  /// of uvs (V) / face_materials (F) / material indices do not match.
  Mesh(Points3f vertices, Faces faces, Points2f uvs = {}, std::vector<Material> materials = {},
       std::vector<std::int32_t> face_materials = {}, std::string name = {});

  const Points3f& vertices() const { return vertices_; }
  const Faces& faces() const { return faces_; }
  /// Per-vertex texture coordinates (V,2), or empty.
  const Points2f& uvs() const { return uvs_; }
  const std::vector<Material>& materials() const { return materials_; }
  /// Per-face index into materials(), or empty (then every face uses materials()[0] if any).
  const std::vector<std::int32_t>& face_materials() const { return face_materials_; }
  const std::string& name() const { return name_; }
  void set_name(std::string name) { name_ = std::move(name); }

  std::int64_t num_vertices() const { return vertices_.rows(); }
  std::int64_t num_faces() const { return faces_.rows(); }
  bool empty() const { return faces_.rows() == 0; }

  /// Unit outward face normals (F,3) (zero for degenerate faces).
  Points3f face_normals() const;
  /// Face areas in m^2 (F).
  Eigen::VectorXd face_areas() const;
  /// Total surface area in m^2.
  double area() const;
  /// Axis-aligned bounds: row 0 = min, row 1 = max (m). Throws on an empty mesh.
  Eigen::Matrix<double, 2, 3, Eigen::RowMajor> bounds() const;

  /// Topology and sanity checks (see MeshReport).
  MeshReport validate() const;

  /// A copy with every vertex mapped through X (e.g. X_WO: object to world).
  Mesh transformed(const Pose& X) const;
  /// A copy scaled uniformly by `factor` (> 0).
  Mesh scaled(double factor) const;
  /// A copy with the winding of every face reversed.
  Mesh flipped() const;

  /// Vertex map that welds vertices with bit-identical positions: weld[v] = representative.
  std::vector<std::int32_t> weld_map() const;

  /// Concatenates meshes into one (materials appended, face material ids shifted).
  static Mesh merge(const std::vector<Mesh>& meshes, std::string name = {});

 private:
  Points3f vertices_;
  Faces faces_;
  Points2f uvs_;
  std::vector<Material> materials_;
  std::vector<std::int32_t> face_materials_;
  std::string name_;
};

/// Throws InvalidArgument naming `what` (e.g. the caller and the file) if the mesh is empty.
void require_non_empty(const Mesh& mesh, const std::string& what);

/// Indices of faces with (near) zero area: area <= 1e-14 * (bounding-box diagonal)^2, or a
/// repeated vertex index. Used by loaders to clean files before building a Mesh.
std::vector<std::int64_t> find_degenerate_faces(const Points3f& vertices, const Faces& faces);

}  // namespace mgn
