#pragma once
// The one Bullet adapter of mgn (private: Bullet types do not appear in installed headers).
// Used by the drop (scene/drop.cpp) and the shake test (grasp/shake_trial.cpp): unit conversion
// at the Bullet boundary, poses, convex hull shapes of an object's parts (with the hull
// reduction of rigid_object.hpp) and the rigid-body construction info in the principal frame.
#include <mgn/physics/rigid_object.hpp>

#include <LinearMath/btConvexHullComputer.h>
#include <btBulletDynamicsCommon.h>

#include <memory>
#include <vector>

namespace mgn::physics {

/// Bullet's length unit: lengths (and forces, which carry a length) are multiplied by `length`
/// at the Bullet boundary only; time and mass are unchanged, so stiffness (N/m) and damping
/// (N s/m) keep their values, and inertia scales by length^2. Bullet's collision tolerances are
/// absolute (tuned for bodies of 0.1-10 units), which is why the two simulations differ:
///  - the drop runs in metres (kDropUnits): tote-sized piles with polyhedral clipping;
///  - the shake test runs in decimetres (kShakeUnits): at centimetre-sized objects in metres
///    Bullet's GJK misses vertex-face contacts of finely tessellated hulls against the pads.
struct BulletUnits {
  double length = 1.0;  ///< Bullet length units per metre

  btVector3 vector(const Vec3d& v_m) const {
    return btVector3(btScalar(length * v_m.x()), btScalar(length * v_m.y()),
                     btScalar(length * v_m.z()));
  }
  Vec3d vector(const btVector3& v) const { return Vec3d(v.x(), v.y(), v.z()) / length; }
  /// Pose in metres -> Bullet transform (the rotation matrix rounded entry by entry).
  btTransform pose(const Pose& X) const;
  /// Bullet transform -> pose in metres (rotation re-orthonormalised in double precision).
  Pose pose(const btTransform& T) const;
  /// Principal moments (kg m^2) in Bullet units.
  btVector3 inertia(const Vec3d& moments) const {
    const Vec3d I = length * length * moments;
    return btVector3(btScalar(I.x()), btScalar(I.y()), btScalar(I.z()));
  }
  /// Force (N) from an impulse (Bullet units) applied over dt (s).
  double force(double impulse, double dt) const { return impulse / (dt * length); }
};

inline constexpr BulletUnits kDropUnits{1.0};
inline constexpr BulletUnits kShakeUnits{10.0};

/// How a part becomes a Bullet convex hull shape.
struct HullShapeOptions {
  HullReduction reduction = HullReduction::Outer;
  int max_vertices = 0;    ///< 0: keep every hull vertex; else >= 8 (>= 4 for InnerGreedy)
  double tolerance = 0.0;  ///< m, of the reduction (see rigid_object.hpp)
  double margin = 0.0;     ///< Bullet collision margin, m (> 0)
  /// Shrink the hull by the margin before adding it (Bullet adds the margin back, so the
  /// effective surface is the part's, with rounded edges); else the margin lies outside it.
  bool shrink_by_margin = false;
  /// Bullet's polyhedral features (contact clipping of whole faces).
  bool polyhedral = false;
};

/// Hull vertices of one part in the body frame B, Bullet units.
struct HullPoints {
  std::vector<btVector3> points;
  btScalar shrunk = 0;  ///< by how much btConvexHullComputer shrank it (shrink_by_margin)
};

/// The (reduced) convex hull of `part` (object frame O) in the body frame B (X_BO maps O to B).
HullPoints hull_points(const Mesh& part, const Pose& X_BO, const BulletUnits& units,
                       const HullShapeOptions& options);

/// A Bullet convex hull shape of prepared hull points, with the margin and features of `options`.
std::unique_ptr<btConvexHullShape> hull_shape(const HullPoints& hull, const BulletUnits& units,
                                              const HullShapeOptions& options);

/// The hulls of every part of a rigid object in its principal frame B, prepared once.
struct RigidGeometry {
  std::vector<HullPoints> hulls;
  double bounding_radius = 0.0;  ///< largest distance of a hull vertex from the CoM, m
};
RigidGeometry rigid_geometry(const RigidObject& object, const PrincipalFrame& principal,
                             const BulletUnits& units, const HullShapeOptions& options);

/// The collision shape of a rigid object: one hull per part; a compound of them if there are
/// several parts or `always_compound`.
struct RigidShape {
  std::vector<std::unique_ptr<btConvexHullShape>> hulls;
  std::unique_ptr<btCompoundShape> compound;
  btCollisionShape* shape() const {
    return compound ? static_cast<btCollisionShape*>(compound.get()) : hulls.front().get();
  }
};
RigidShape rigid_shape(const RigidGeometry& geometry, const BulletUnits& units,
                       const HullShapeOptions& options, bool always_compound);

/// A compound shape of `hulls` (identity child transforms, Bullet's dynamic AABB tree of the
/// children), as rigid_shape() builds it. The compound only reads its children.
std::unique_ptr<btCompoundShape> compound_of(
    const std::vector<std::unique_ptr<btConvexHullShape>>& hulls);

/// Construction info of the body of a rigid object with principal `moments` (kg m^2, already
/// scaled as wanted), its frame B starting at X_WB (m).
btRigidBody::btRigidBodyConstructionInfo body_info(double mass, const Vec3d& moments,
                                                   btCollisionShape* shape, const Pose& X_WB,
                                                   const BulletUnits& units);

}  // namespace mgn::physics
