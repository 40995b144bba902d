#pragma once
// A convex–convex narrow phase that skips pairs which are provably apart (private: Bullet types
// do not appear in installed headers).
//
// Mirrors Bullet 3.24: wraps btConvexConvexAlgorithm::processCollision (the algorithm of
// btDefaultCollisionConfiguration for convex pairs) and skips a call only where that function
// would add no contact point (its distance threshold: both margins plus
// btPersistentManifold::getContactBreakingThreshold); allocates as
// btCollisionDispatcher::freeCollisionAlgorithm frees.
//
// Bullet runs its full convex–convex narrow phase (an intersection GJK, a distance GJK and, if
// the cores overlap, EPA and polyhedral clipping) on every pair whose bounding boxes overlap. In
// the shake test most such pairs are apart: a compound object's hulls near, but not touching, a
// finger pad, and the palm above the object; for a 27-part mug they cost about half of a trial.
// SkipSeparatedConvexAlgorithm wraps Bullet's algorithm and, for a pair whose contact manifold
// exists and is empty, first looks for a separating axis (the axis that separated the pair at
// the last step, the direction between the shapes' bounding-box centres, and a box's face
// normal closest to it): if the shapes' cores, projected on it, are further apart than the
// distance at which Bullet's algorithm adds a contact point (both margins + the manifold's
// contact breaking threshold, plus a safety gap), Bullet's algorithm would add no contact point
// and refresh an empty manifold, so the call is skipped. Otherwise (or while the manifold holds
// points, or before it exists) Bullet's algorithm runs as usual. The simulation is unchanged,
// bit for bit: manifolds are created and released at the same steps, and the skipped calls
// would have changed nothing.
#include "physics/bullet_ext/version.hpp"

#include <btBulletCollisionCommon.h>

namespace mgn::physics {

/// Creates SkipSeparatedConvexAlgorithm around the algorithm of `inner` (Bullet's convex–convex
/// create function of the collision configuration, which must outlive this). Register it with
/// btCollisionDispatcher::registerCollisionCreateFunc for the convex shape type pairs to cull.
class SkipSeparatedConvexCreateFunc : public btCollisionAlgorithmCreateFunc {
 public:
  explicit SkipSeparatedConvexCreateFunc(btCollisionAlgorithmCreateFunc* inner) : inner_(inner) {}
  btCollisionAlgorithm* CreateCollisionAlgorithm(btCollisionAlgorithmConstructionInfo& ci,
                                                 const btCollisionObjectWrapper* body0,
                                                 const btCollisionObjectWrapper* body1) override;

  /// Calls skipped / run by the algorithms of this function (for tests and benchmarks).
  long skipped = 0;
  long run = 0;

 private:
  btCollisionAlgorithmCreateFunc* inner_;
};

}  // namespace mgn::physics
