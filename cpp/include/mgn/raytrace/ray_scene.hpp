#pragma once
/// @file ray_scene.hpp  Ray casting against one or many meshes (Embree).
///
/// A RayScene is built once from meshes placed in a world frame W and is then immutable and
/// thread-safe: any number of threads may cast rays at the same time. Batch calls take rays as
/// (N,3) origins and directions in W (directions need not be unit length; distances are in units
/// of the direction's length, i.e. metres for unit directions) and write per-ray results.

#include <mgn/core/parallel.hpp>
#include <mgn/geometry/mesh.hpp>

#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

namespace mgn {

/// One mesh placed in the scene.
struct RayGeometry {
  const Mesh* mesh = nullptr;    ///< copied at build time; need not outlive the scene
  Pose X_WO = Pose::Identity();  ///< pose of the mesh in the world
  std::int32_t instance_id = 0;  ///< reported for hits on this mesh (>= 0)
};

/// Options of a batch cast.
struct CastOptions {
  float tnear = 0.0f;  ///< ignore hits closer than this (in direction units)
  float tfar = std::numeric_limits<float>::infinity();  ///< ignore hits farther than this
  /// Rays are coherent (similar origins and directions, e.g. camera or parallel rays): cast them in
  /// packets of 16 for speed. Results are identical either way.
  bool coherent = false;
  int num_threads = 0;  ///< 0 = all hardware threads
};

/// First hits of a batch. Misses: distance = +inf, instance_id = face_id = -1, point/normal 0.
struct RayHits {
  std::vector<float> distance;             ///< (N)
  Points3f points;                         ///< (N,3) world frame
  Points3f normals;                        ///< (N,3) unit geometric normal, outward for CCW faces
  std::vector<std::int32_t> instance_ids;  ///< (N)
  std::vector<std::int32_t> face_ids;      ///< (N) face index within its mesh
  Points2f barycentric;                    ///< (N,2) (u,v): p = (1-u-v) v0 + u v1 + v v2
};

/// Ids of the first hits of a batch (what RayHits holds in instance_ids and face_ids).
struct RayHitIds {
  std::vector<std::int32_t> instance_ids;  ///< (N) -1 on a miss
  std::vector<std::int32_t> face_ids;      ///< (N) face index within its mesh, -1 on a miss
};

/// All hits along each ray, sorted by distance, in CSR layout: the hits of ray i are the entries
/// offsets[i] .. offsets[i+1]-1. A ray crossing a shared edge or vertex is reported once.
struct RayAllHits {
  std::vector<std::int64_t> offsets;       ///< (N+1)
  std::vector<float> distance;             ///< (H)
  Points3f points;                         ///< (H,3)
  Points3f normals;                        ///< (H,3)
  std::vector<std::int32_t> instance_ids;  ///< (H)
  std::vector<std::int32_t> face_ids;      ///< (H)
  std::vector<std::int32_t> ray_ids;       ///< (H) which ray each hit belongs to
};

/// Immutable Embree scene. Construction copies the geometry into world coordinates.
class RayScene {
 public:
  /// Builds the BVH. Throws InvalidArgument for an empty list, a null or empty mesh, a
  /// non-finite pose or a negative instance id; BackendError if Embree fails. `all_hits`
  /// false builds a scene without intersect_all (it then throws Unsupported), whose other
  /// queries are a few percent faster (no per-query filter check in Embree) and give the
  /// same results.
  explicit RayScene(const std::vector<RayGeometry>& geometries, bool all_hits = true);
  ~RayScene();
  RayScene(const RayScene&) = delete;
  RayScene& operator=(const RayScene&) = delete;
  RayScene(RayScene&&) noexcept;
  RayScene& operator=(RayScene&&) noexcept;

  std::size_t num_geometries() const;
  std::int64_t num_triangles() const;
  /// World-frame bounds of all geometry: row 0 min, row 1 max.
  Eigen::Matrix<double, 2, 3, Eigen::RowMajor> bounds() const;

  /// First hit of every ray. Throws InvalidArgument if the arrays differ in length, contain
  /// non-finite values or a zero direction, or if tnear > tfar.
  RayHits intersect(const Points3f& origins, const Points3f& directions,
                    const CastOptions& options = {}) const;
  /// The instance and face ids of intersect's first hits (identical to its instance_ids and
  /// face_ids), without computing distances, points, normals and barycentrics. Same errors.
  RayHitIds intersect_ids(const Points3f& origins, const Points3f& directions,
                          const CastOptions& options = {}) const;
  /// Whether each ray hits anything in [tnear, tfar] (cheaper than intersect).
  std::vector<std::uint8_t> occluded(const Points3f& origins, const Points3f& directions,
                                     const CastOptions& options = {}) const;
  /// Every hit along each ray in [tnear, tfar], at most `max_hits_per_ray` (> 0) nearest ones.
  RayAllHits intersect_all(const Points3f& origins, const Points3f& directions,
                           int max_hits_per_ray = 64, const CastOptions& options = {}) const;

  /// Internal state (defined in the implementation; used by mgn's private fast paths).
  struct Impl;
  const Impl& impl() const { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

/// Rays of a pinhole camera (OpenCV frame: x right, y down, z forward) through pixel centres,
/// row-major (pixel (u,v) -> ray v*width+u). Origins at the camera centre, unit directions in W.
/// K = [[fx,0,cx],[0,fy,cy],[0,0,1]] in pixels; X_WC = camera pose in the world.
void camera_rays(const Mat3d& K, int width, int height, const Pose& X_WC, Points3f& origins,
                 Points3f& directions);

}  // namespace mgn
