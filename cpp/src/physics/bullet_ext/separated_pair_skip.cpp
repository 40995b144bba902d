#include "physics/bullet_ext/separated_pair_skip.hpp"

#include <BulletCollision/CollisionDispatch/btCollisionObjectWrapper.h>

#include <BulletCollision/NarrowPhaseCollision/btGjkPairDetector.h>
#include <BulletCollision/NarrowPhaseCollision/btVoronoiSimplexSolver.h>
#include <new>

namespace mgn::physics {

namespace {

/// Gap between the cores (the shapes without their margins) of a and b along the unit world
/// axis n pointing from a towards b: min over b of n·x − max over a of n·x. A lower bound of
/// the distance between the cores (negative if they overlap along n).
btScalar core_gap(const btConvexShape& a, const btTransform& Ta, const btConvexShape& b,
                  const btTransform& Tb, const btVector3& n) {
  const btVector3 pa = Ta(a.localGetSupportVertexWithoutMarginNonVirtual(n * Ta.getBasis()));
  const btVector3 pb = Tb(b.localGetSupportVertexWithoutMarginNonVirtual(-n * Tb.getBasis()));
  return n.dot(pb - pa);
}

class SkipSeparatedConvexAlgorithm : public btCollisionAlgorithm {
 public:
  SkipSeparatedConvexAlgorithm(const btCollisionAlgorithmConstructionInfo& ci,
                               btCollisionAlgorithm* inner, SkipSeparatedConvexCreateFunc* owner)
      : btCollisionAlgorithm(ci), inner_(inner), owner_(owner) {}

  ~SkipSeparatedConvexAlgorithm() override {
    inner_->~btCollisionAlgorithm();
    m_dispatcher->freeCollisionAlgorithm(inner_);
  }

  SkipSeparatedConvexAlgorithm(const SkipSeparatedConvexAlgorithm&) = delete;
  SkipSeparatedConvexAlgorithm& operator=(const SkipSeparatedConvexAlgorithm&) = delete;

  void processCollision(const btCollisionObjectWrapper* body0,
                        const btCollisionObjectWrapper* body1, const btDispatcherInfo& info,
                        btManifoldResult* result) override {
    if (apart(*body0, *body1, *result)) {
      ++owner_->skipped;
      return;
    }
    ++owner_->run;
    inner_->processCollision(body0, body1, info, result);
  }

  btScalar calculateTimeOfImpact(btCollisionObject* body0, btCollisionObject* body1,
                                 const btDispatcherInfo& info, btManifoldResult* result) override {
    return inner_->calculateTimeOfImpact(body0, body1, info, result);
  }

  void getAllContactManifolds(btManifoldArray& manifolds) override {
    inner_->getAllContactManifolds(manifolds);
  }

 private:
  /// True if Bullet's algorithm would add no contact point and its manifold is empty.
  bool apart(const btCollisionObjectWrapper& w0, const btCollisionObjectWrapper& w1,
             const btManifoldResult& result) {
    manifolds_.resize(0);
    inner_->getAllContactManifolds(manifolds_);
    // Before the first call the manifold does not exist yet (Bullet creates it then); a
    // manifold with points is refreshed by every call.
    if (manifolds_.size() != 1 || manifolds_[0]->getNumContacts() != 0) return false;
    const auto& a = *static_cast<const btConvexShape*>(w0.getCollisionShape());
    const auto& b = *static_cast<const btConvexShape*>(w1.getCollisionShape());
    const btTransform& Ta = w0.getWorldTransform();
    const btTransform& Tb = w1.getWorldTransform();
    // Bullet's GJK reports a point only if its distance between the cores, less both margins,
    // is below reach = both margins + the contact breaking threshold (btConvexConvexAlgorithm's
    // maximum distance); without it there is no clipping either. That GJK distance is at least
    // the core gap along any axis, so a core gap above reach + both margins means no point. The
    // safety gap (1 % + 1e-4 units: 10 µm in the shake test's decimetres; single-precision
    // coordinates of a few units round at ~1e-6) covers GJK's rounding.
    const btScalar margins = a.getMargin() + b.getMargin();
    const btScalar reach = margins + manifolds_[0]->getContactBreakingThreshold() +
                           result.m_closestPointDistanceThreshold;
    const btScalar need = reach * btScalar(1.01) + btScalar(1e-4) + margins;
    if (has_axis_ && core_gap(a, Ta, b, Tb, axis_) > need) return true;
    btVector3 amin, amax, bmin, bmax;
    a.getAabb(Ta, amin, amax);
    b.getAabb(Tb, bmin, bmax);
    btVector3 d = (bmin + bmax) - (amin + amax);
    if (!(d.length2() > SIMD_EPSILON)) return false;
    d.normalize();
    if (try_axis(a, Ta, b, Tb, d, need)) return true;
    // A box's face normal closest to the centre direction (a finger pad facing a hull).
    for (int k = 0; k < 2; ++k) {
      const btCollisionShape& s = k == 0 ? static_cast<const btCollisionShape&>(a) : b;
      if (s.getShapeType() != BOX_SHAPE_PROXYTYPE) continue;
      const btMatrix3x3& R = (k == 0 ? Ta : Tb).getBasis();
      int best = 0;
      btScalar best_dot = 0;
      for (int i = 0; i < 3; ++i) {
        const btScalar c = R.getColumn(i).dot(d);
        if (btFabs(c) > btFabs(best_dot)) {
          best = i;
          best_dot = c;
        }
      }
      const btVector3 n = best_dot < 0 ? -R.getColumn(best) : R.getColumn(best);
      if (try_axis(a, Ta, b, Tb, n, need)) return true;
    }
    // Bullet's GJK (distance only) for the axis of the closest points; the core gap along
    // it (a lower bound again) is then about the distance. A pair found too close waits a few
    // calls before the next try (it is usually still close).
    if (wait_ > 0) {
      --wait_;
      return false;
    }
    btVoronoiSimplexSolver simplex;
    btGjkPairDetector gjk(&a, &b, &simplex, nullptr);
    btGjkPairDetector::ClosestPointInput input;
    input.m_transformA = Ta;
    input.m_transformB = Tb;
    NormalResult closest;
    gjk.getClosestPoints(input, closest, nullptr);
    if (closest.found && try_axis(a, Ta, b, Tb, -closest.normal_on_b, need)) return true;
    wait_ = kWait;
    return false;
  }

  bool try_axis(const btConvexShape& a, const btTransform& Ta, const btConvexShape& b,
                const btTransform& Tb, const btVector3& n, btScalar need) {
    if (!(core_gap(a, Ta, b, Tb, n) > need)) return false;
    axis_ = n;
    has_axis_ = true;
    return true;
  }

  /// The normal of the closest points that Bullet's GJK reports (from b towards a).
  struct NormalResult : btDiscreteCollisionDetectorInterface::Result {
    btVector3 normal_on_b{0, 0, 0};
    bool found = false;
    void setShapeIdentifiersA(int, int) override {}
    void setShapeIdentifiersB(int, int) override {}
    void addContactPoint(const btVector3& normal, const btVector3&, btScalar) override {
      normal_on_b = normal;
      found = true;
    }
  };
  static constexpr int kWait = 8;

  btCollisionAlgorithm* inner_;
  SkipSeparatedConvexCreateFunc* owner_;
  int wait_ = 0;  // calls before the next GJK try
  btManifoldArray manifolds_;
  btVector3 axis_{0, 0, 1};  // world axis that separated the pair last (from body 0 to body 1)
  bool has_axis_ = false;
};

}  // namespace

btCollisionAlgorithm* SkipSeparatedConvexCreateFunc::CreateCollisionAlgorithm(
    btCollisionAlgorithmConstructionInfo& ci, const btCollisionObjectWrapper* body0,
    const btCollisionObjectWrapper* body1) {
  btCollisionAlgorithm* inner = inner_->CreateCollisionAlgorithm(ci, body0, body1);
  // Not from the dispatcher's pool (its blocks are sized for Bullet's algorithms):
  // btCollisionDispatcher::freeCollisionAlgorithm frees a block outside the pool with
  // btAlignedFree.
  void* mem = btAlignedAlloc(sizeof(SkipSeparatedConvexAlgorithm), 16);
  return new (mem) SkipSeparatedConvexAlgorithm(ci, inner, this);
}

}  // namespace mgn::physics
