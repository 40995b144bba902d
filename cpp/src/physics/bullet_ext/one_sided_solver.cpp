#include "physics/bullet_ext/one_sided_solver.hpp"

#include <LinearMath/btMinMax.h>

namespace mgn::physics {
namespace {

constexpr std::uint8_t kSideA = 1;
constexpr std::uint8_t kSideB = 2;

bool is_zero(const btVector3& v) { return v.x() == 0 && v.y() == 0 && v.z() == 0; }

/// One body's share of a row's impulse, as btSolverBody::internalApplyImpulse adds it.
inline void apply_impulse(btSolverBody& body, const btVector3& linear, const btVector3& angular,
                          btScalar impulse) {
  if (body.m_originalBody == nullptr) return;
  body.m_deltaLinearVelocity += linear * impulse * body.m_linearFactor;
  body.m_deltaAngularVelocity += angular * (impulse * body.m_angularFactor);
}

/// The accumulated impulse of a row after a change `delta`, kept in [lower, upper] (lower only
/// for a contact row, kUpper false): updates `applied` and returns the change actually made.
template <bool kUpper>
inline btScalar clamp_impulse(btScalar delta, btScalar& applied, btScalar lower, btScalar upper) {
  const btScalar sum = applied + delta;
  if (sum < lower) {
    delta = lower - applied;
    applied = lower;
  } else if (kUpper && sum > upper) {
    delta = upper - applied;
    applied = upper;
  } else {
    applied = sum;
  }
  return delta;
}

/// One Projected Gauss-Seidel step on row c: the impulse change that drives the row's relative
/// velocity change to c.m_rhs (softened by c.m_cfm), clamped so that the accumulated impulse stays
/// in [lower, upper] (upper only for friction rows), applied to the bodies that take part
/// (kA, kB); returns the impulse change scaled by the row's effective mass, Bullet's residual.
/// The operations and their order are those of Bullet's scalar row solvers, so a row gives the
/// same bits; a side left out would only add x·0 terms (see the header).
template <bool kA, bool kB, bool kUpper>
inline btScalar solve_row(btSolverBody& a, btSolverBody& b, const btSolverConstraint& c) {
  btScalar delta = c.m_rhs - btScalar(c.m_appliedImpulse) * c.m_cfm;
  btScalar va = 0, vb = 0;
  if (kA) {
    va = c.m_contactNormal1.dot(a.m_deltaLinearVelocity) +
         c.m_relpos1CrossNormal.dot(a.m_deltaAngularVelocity);
  }
  if (kB) {
    vb = c.m_contactNormal2.dot(b.m_deltaLinearVelocity) +
         c.m_relpos2CrossNormal.dot(b.m_deltaAngularVelocity);
  }
  if (kA) delta -= va * c.m_jacDiagABInv;
  if (kB) delta -= vb * c.m_jacDiagABInv;
  delta = clamp_impulse<kUpper>(delta, c.m_appliedImpulse, c.m_lowerLimit, c.m_upperLimit);
  if (kA) apply_impulse(a, c.m_contactNormal1 * a.m_invMass, c.m_angularComponentA, delta);
  if (kB) apply_impulse(b, c.m_contactNormal2 * b.m_invMass, c.m_angularComponentB, delta);
  return btScalar(delta * (1. / c.m_jacDiagABInv));
}

template <bool kUpper>
inline btScalar solve_row(std::uint8_t sides, btSolverBody& a, btSolverBody& b,
                          const btSolverConstraint& c) {
  switch (sides) {
    case kSideA:
      return solve_row<true, false, kUpper>(a, b, c);
    case kSideB:
      return solve_row<false, true, kUpper>(a, b, c);
    case kSideA | kSideB:
      return solve_row<true, true, kUpper>(a, b, c);
    default:
      return solve_row<false, false, kUpper>(a, b, c);
  }
}

// ---- Row setup (convertContacts) ----

/// How a body takes part in the setup of a contact's rows.
enum class Side {
  kFixed,   // Bullet's fixed solver body (no original body): its half of every row is zeros
  kStill,   // a kinematic body (no inverse mass or inertia): its velocity counts, no impulse
  kMoving,  // a body with inverse mass: its half is computed in full
  kOther,   // anything else (e.g. inverse inertia without inverse mass): Bullet's setup
};

Side side_of(const btSolverBody& body) {
  const btRigidBody* rb = body.m_originalBody;
  if (rb == nullptr) return Side::kFixed;
  if (rb->getInvMass() > 0) return Side::kMoving;
  const btMatrix3x3& inv_inertia = rb->getInvInertiaTensorWorld();
  if (rb->getInvMass() == 0 && is_zero(inv_inertia[0]) && is_zero(inv_inertia[1]) &&
      is_zero(inv_inertia[2])) {
    return Side::kStill;
  }
  return Side::kOther;
}

/// What the rows of one manifold are set up from: its two solver bodies (A is the manifold's
/// body 0, B its body 1, as in Bullet's rows) and the pools they go to.
struct ManifoldRows {
  btConstraintArray& contacts;
  btConstraintArray& frictions;
  btSolverBody& a;
  btSolverBody& b;
  int id_a;
  int id_b;
  const btContactSolverInfo& info;
  btScalar relaxation;  // Bullet's successive over-relaxation factor, info.m_sor
  btScalar inv_dt;      // 1 / time step
};

// Below, a still or fixed body's share of a sum is the literal 0 where Bullet adds its computed
// terms: those are ±0 (a zero inverse mass and inertia times finite lever arms, or Bullet's own
// zeros for the fixed body), and x + (±0) = x for every x != 0. The sums that can be zero are
// kept as Bullet forms them (0 + x, not x), so that even a zero's sign matches where it can.

/// One friction row along `axis` (a unit vector in the contact plane) of contact `contact_index`:
/// the impulse along axis on A and against it on B drives their relative velocity along it to
/// `target` (Bullet's desired velocity), softened by `cfm`, within ±friction × normal impulse
/// (the bound is set per iteration). Same fields and operations as Bullet's friction rows.
template <Side kA, Side kB>
void add_friction_row(const ManifoldRows& m, const btVector3& axis, int contact_index,
                      const btManifoldPoint& cp, const btVector3& arm_a, const btVector3& arm_b,
                      btScalar target, btScalar cfm) {
  btSolverConstraint& row = m.frictions.expandNonInitializing();
  row.m_frictionIndex = contact_index;
  row.m_solverBodyIdA = m.id_a;
  row.m_solverBodyIdB = m.id_b;
  row.m_friction = cp.m_combinedFriction;
  row.m_originalContactPoint = nullptr;
  row.m_appliedImpulse = 0;
  row.m_appliedPushImpulse = 0;

  btScalar mass_a = 0, mass_b = 0;    // each body's share of the row's inverse effective mass
  btScalar speed_a = 0, speed_b = 0;  // each body's velocity along its side of the row
  if constexpr (kA == Side::kFixed) {
    row.m_contactNormal1.setZero();
    row.m_relpos1CrossNormal.setZero();
    row.m_angularComponentA.setZero();
  } else {
    const btRigidBody& rb = *m.a.m_originalBody;
    row.m_contactNormal1 = axis;
    row.m_relpos1CrossNormal = arm_a.cross(row.m_contactNormal1);
    if constexpr (kA == Side::kMoving) {
      row.m_angularComponentA =
          rb.getInvInertiaTensorWorld() * row.m_relpos1CrossNormal * rb.getAngularFactor();
      mass_a = rb.getInvMass() + axis.dot(row.m_angularComponentA.cross(arm_a));
    } else {
      row.m_angularComponentA.setZero();
    }
    speed_a = row.m_contactNormal1.dot(m.a.m_linearVelocity + m.a.m_externalForceImpulse) +
              row.m_relpos1CrossNormal.dot(m.a.m_angularVelocity);
  }
  if constexpr (kB == Side::kFixed) {
    row.m_contactNormal2.setZero();
    row.m_relpos2CrossNormal.setZero();
    row.m_angularComponentB.setZero();
  } else {
    const btRigidBody& rb = *m.b.m_originalBody;
    row.m_contactNormal2 = -axis;
    row.m_relpos2CrossNormal = arm_b.cross(row.m_contactNormal2);
    if constexpr (kB == Side::kMoving) {
      row.m_angularComponentB =
          rb.getInvInertiaTensorWorld() * row.m_relpos2CrossNormal * rb.getAngularFactor();
      mass_b = rb.getInvMass() + axis.dot((-row.m_angularComponentB).cross(arm_b));
    } else {
      row.m_angularComponentB.setZero();
    }
    speed_b = row.m_contactNormal2.dot(m.b.m_linearVelocity + m.b.m_externalForceImpulse) +
              row.m_relpos2CrossNormal.dot(m.b.m_angularVelocity);
  }
  row.m_jacDiagABInv = m.relaxation / (mass_a + mass_b);

  const btScalar relative_speed = speed_a + speed_b;
  const btScalar velocity_impulse = (target - relative_speed) * row.m_jacDiagABInv;
  btScalar anchor_impulse = 0;  // pulls an anchored contact back to where it started
  if (cp.m_contactPointFlags & BT_CONTACT_FLAG_FRICTION_ANCHOR) {
    const btScalar drift = (cp.getPositionWorldOnA() - cp.getPositionWorldOnB()).dot(axis);
    const btScalar error = -drift * m.info.m_frictionERP / m.info.m_timeStep;
    anchor_impulse = error * row.m_jacDiagABInv;
  }
  row.m_rhs = anchor_impulse + velocity_impulse;
  row.m_rhsPenetration = 0;
  row.m_cfm = cfm;
  row.m_lowerLimit = -row.m_friction;
  row.m_upperLimit = row.m_friction;
}

/// A contact point's soft-contact constraint force mixing and error reduction: its own cfm / erp,
/// or both from its stiffness and damping; else the solver's (Bullet's convertContact).
void soft_contact(const btContactSolverInfo& info, const btManifoldPoint& cp, btScalar& cfm,
                  btScalar& erp) {
  cfm = info.m_globalCfm;
  erp = info.m_erp2;
  const int flags = cp.m_contactPointFlags;
  if (flags & (BT_CONTACT_FLAG_HAS_CONTACT_CFM | BT_CONTACT_FLAG_HAS_CONTACT_ERP)) {
    if (flags & BT_CONTACT_FLAG_HAS_CONTACT_CFM) cfm = cp.m_contactCFM;
    if (flags & BT_CONTACT_FLAG_HAS_CONTACT_ERP) erp = cp.m_contactERP;
  } else if (flags & BT_CONTACT_FLAG_CONTACT_STIFFNESS_DAMPING) {
    btScalar denom =
        info.m_timeStep * cp.m_combinedContactStiffness1 + cp.m_combinedContactDamping1;
    if (denom < SIMD_EPSILON) denom = SIMD_EPSILON;
    cfm = btScalar(1) / denom;
    erp = (info.m_timeStep * cp.m_combinedContactStiffness1) / denom;
  }
}

/// The Jacobian of a contact's normal row: A pushed along the normal, B against it (lever arms
/// arm_a, arm_b; cfm already divided by the time step): the angular components, the inverse
/// effective mass (with Bullet's relaxation) and the contact normals and torque arms.
template <Side kA, Side kB>
void set_normal_jacobian(const ManifoldRows& m, btSolverConstraint& row, const btVector3& normal,
                         const btVector3& arm_a, const btVector3& arm_b, btScalar cfm) {
  const btVector3 zero(0, 0, 0);
  btScalar mass_a = 0, mass_b = 0;
  btVector3 torque_a = zero, torque_b = zero;  // arm × normal
  if constexpr (kA != Side::kFixed) torque_a = arm_a.cross(normal);
  if constexpr (kB != Side::kFixed) torque_b = arm_b.cross(normal);
  if constexpr (kA == Side::kMoving) {
    const btRigidBody& rb = *m.a.m_originalBody;
    row.m_angularComponentA = rb.getInvInertiaTensorWorld() * torque_a * rb.getAngularFactor();
    mass_a = rb.getInvMass() + normal.dot(row.m_angularComponentA.cross(arm_a));
  } else {
    row.m_angularComponentA.setZero();
  }
  if constexpr (kB == Side::kMoving) {
    const btRigidBody& rb = *m.b.m_originalBody;
    row.m_angularComponentB = rb.getInvInertiaTensorWorld() * -torque_b * rb.getAngularFactor();
    mass_b = rb.getInvMass() + normal.dot((-row.m_angularComponentB).cross(arm_b));
  } else {
    row.m_angularComponentB.setZero();
  }
  row.m_jacDiagABInv = m.relaxation / (mass_a + mass_b + cfm);
  if constexpr (kA != Side::kFixed) {
    row.m_contactNormal1 = normal;
    row.m_relpos1CrossNormal = torque_a;
  } else {
    row.m_contactNormal1.setZero();
    row.m_relpos1CrossNormal.setZero();
  }
  if constexpr (kB != Side::kFixed) {
    row.m_contactNormal2 = -normal;
    row.m_relpos2CrossNormal = -torque_b;
  } else {
    row.m_contactNormal2.setZero();
    row.m_relpos2CrossNormal.setZero();
  }
}

/// Restitution: the approach speed (bodies' own velocities) times the restitution, if above the
/// threshold; 0 otherwise. A zero restitution gives a zero target for any finite speed, so the
/// speed is only computed for a bouncing contact.
template <Side kA, Side kB>
btScalar bounce_speed(const ManifoldRows& m, const btManifoldPoint& cp, const btVector3& arm_a,
                      const btVector3& arm_b) {
  if (cp.m_combinedRestitution == 0) return 0;
  const btVector3 zero(0, 0, 0);
  const btVector3& normal = cp.m_normalWorldOnB;
  const btVector3 velocity_a =
      kA != Side::kFixed ? m.a.m_originalBody->getVelocityInLocalPoint(arm_a) : zero;
  const btVector3 velocity_b =
      kB != Side::kFixed ? m.b.m_originalBody->getVelocityInLocalPoint(arm_b) : zero;
  const btScalar approach = normal.dot(velocity_a - velocity_b);
  btScalar bounce = 0;
  if (!(btFabs(approach) < m.info.m_restitutionVelocityThreshold)) {
    bounce = cp.m_combinedRestitution * -approach;
  }
  if (bounce <= btScalar(0)) bounce = 0;
  return bounce;
}

/// Warm start: last step's impulse, scaled, applied to the moving bodies now (a still body's
/// velocity changes would stay +0: it adds products of its zero inverse mass and inertia).
template <Side kA, Side kB>
void warm_start(const ManifoldRows& m, const btManifoldPoint& cp, btSolverConstraint& row) {
  if (m.info.m_solverMode & SOLVER_USE_WARMSTARTING) {
    row.m_appliedImpulse = cp.m_appliedImpulse * m.info.m_warmstartingFactor;
    if constexpr (kA == Side::kMoving) {
      m.a.internalApplyImpulse(row.m_contactNormal1 * m.a.internalGetInvMass(),
                               row.m_angularComponentA, row.m_appliedImpulse);
    }
    if constexpr (kB == Side::kMoving) {
      m.b.internalApplyImpulse(-row.m_contactNormal2 * m.b.internalGetInvMass(),
                               -row.m_angularComponentB, -btScalar(row.m_appliedImpulse));
    }
  } else {
    row.m_appliedImpulse = 0;
  }
  row.m_appliedPushImpulse = 0;
}

/// Target of a normal row: the relative normal velocity (with this step's external impulses)
/// brought to `bounce`, less the penetration; the position error (erp: error reduction) either
/// goes into the same right-hand side or, with split impulse for shallow contacts, into a
/// separate one. Also the row's cfm and impulse bounds.
template <Side kA, Side kB>
void set_normal_target(const ManifoldRows& m, const btManifoldPoint& cp, btSolverConstraint& row,
                       btScalar bounce, btScalar cfm, btScalar erp) {
  const btContactSolverInfo& info = m.info;
  btScalar speed_a = 0, speed_b = 0;
  if constexpr (kA != Side::kFixed) {
    speed_a = row.m_contactNormal1.dot(m.a.m_linearVelocity + m.a.m_externalForceImpulse) +
              row.m_relpos1CrossNormal.dot(m.a.m_angularVelocity + m.a.m_externalTorqueImpulse);
  }
  if constexpr (kB != Side::kFixed) {
    speed_b = row.m_contactNormal2.dot(m.b.m_linearVelocity + m.b.m_externalForceImpulse) +
              row.m_relpos2CrossNormal.dot(m.b.m_angularVelocity + m.b.m_externalTorqueImpulse);
  }
  const btScalar relative_speed = speed_a + speed_b;
  btScalar position_error = 0;
  btScalar velocity_error = bounce - relative_speed;
  const btScalar penetration = cp.getDistance() + info.m_linearSlop;
  if (penetration > 0) {
    velocity_error -= penetration * m.inv_dt;  // apart (or within the slop): close the gap
  } else {
    position_error = -penetration * erp * m.inv_dt;
  }
  const btScalar position_impulse = position_error * row.m_jacDiagABInv;
  const btScalar velocity_impulse = velocity_error * row.m_jacDiagABInv;
  if (!info.m_splitImpulse || penetration > info.m_splitImpulsePenetrationThreshold) {
    row.m_rhs = position_impulse + velocity_impulse;
    row.m_rhsPenetration = 0;
  } else {
    row.m_rhs = velocity_impulse;
    row.m_rhsPenetration = position_impulse;
  }
  row.m_cfm = cfm * row.m_jacDiagABInv;
  row.m_lowerLimit = 0;
  row.m_upperLimit = 1e10f;
}

/// The friction rows of contact point cp (row contact_index of the contact pool): along cached
/// directions (with their target velocities) if the point has them and caching is on; else
/// along the sliding velocity (its part in the contact plane) when it is not negligible, the
/// second one across it; else any two in the plane. Updates the point's friction directions and
/// flags as Bullet's convertContact does. The rows' impulses start at zero (add_friction_row;
/// Bullet's convertContact zeroes them once more).
template <Side kA, Side kB>
void add_friction_rows(const ManifoldRows& m, btManifoldPoint& cp, int contact_index,
                       const btVector3& arm_a, const btVector3& arm_b) {
  const int mode = m.info.m_solverMode;
  const bool two_directions = (mode & SOLVER_USE_2_FRICTION_DIRECTIONS) != 0;
  const btVector3& normal = cp.m_normalWorldOnB;
  if ((mode & SOLVER_ENABLE_FRICTION_DIRECTION_CACHING) &&
      (cp.m_contactPointFlags & BT_CONTACT_FLAG_LATERAL_FRICTION_INITIALIZED)) {
    add_friction_row<kA, kB>(m, cp.m_lateralFrictionDir1, contact_index, cp, arm_a, arm_b,
                             cp.m_contactMotion1, cp.m_frictionCFM);
    if (two_directions) {
      add_friction_row<kA, kB>(m, cp.m_lateralFrictionDir2, contact_index, cp, arm_a, arm_b,
                               cp.m_contactMotion2, cp.m_frictionCFM);
    }
    return;
  }
  bool sliding = false;
  if (!(mode & SOLVER_DISABLE_VELOCITY_DEPENDENT_FRICTION_DIRECTION)) {
    const btVector3 zero(0, 0, 0);
    btVector3 velocity_a = zero, velocity_b = zero;
    if constexpr (kA != Side::kFixed) m.a.getVelocityInLocalPointNoDelta(arm_a, velocity_a);
    if constexpr (kB != Side::kFixed) m.b.getVelocityInLocalPointNoDelta(arm_b, velocity_b);
    const btVector3 relative = velocity_a - velocity_b;
    const btScalar along_normal = normal.dot(relative);
    cp.m_lateralFrictionDir1 = relative - normal * along_normal;
    const btScalar slide2 = cp.m_lateralFrictionDir1.length2();
    sliding = slide2 > SIMD_EPSILON;
    if (sliding) cp.m_lateralFrictionDir1 *= 1.f / btSqrt(slide2);
  }
  if (sliding) {
    add_friction_row<kA, kB>(m, cp.m_lateralFrictionDir1, contact_index, cp, arm_a, arm_b, 0, 0);
    if (two_directions) {
      cp.m_lateralFrictionDir2 = cp.m_lateralFrictionDir1.cross(normal);
      cp.m_lateralFrictionDir2.normalize();
      add_friction_row<kA, kB>(m, cp.m_lateralFrictionDir2, contact_index, cp, arm_a, arm_b, 0, 0);
    }
    return;
  }
  btPlaneSpace1(normal, cp.m_lateralFrictionDir1, cp.m_lateralFrictionDir2);
  add_friction_row<kA, kB>(m, cp.m_lateralFrictionDir1, contact_index, cp, arm_a, arm_b, 0, 0);
  if (two_directions) {
    add_friction_row<kA, kB>(m, cp.m_lateralFrictionDir2, contact_index, cp, arm_a, arm_b, 0, 0);
    if (mode & SOLVER_DISABLE_VELOCITY_DEPENDENT_FRICTION_DIRECTION) {
      cp.m_contactPointFlags |= BT_CONTACT_FLAG_LATERAL_FRICTION_INITIALIZED;
    }
  }
}

/// The rows of every contact point of one manifold within its processing threshold: the normal
/// row (non-penetration, with Baumgarte or split-impulse position correction, restitution, soft
/// contact cfm/erp, warm start) into the contact pool, then its friction rows into the friction
/// pool. Same fields, operations, side effects and order as Bullet's convertContact without
/// rolling friction and anisotropic friction (its stages in the functions above, in its order).
template <Side kA, Side kB>
void convert_points(const ManifoldRows& m, btPersistentManifold& manifold) {
  const btVector3& origin_a = manifold.getBody0()->getWorldTransform().getOrigin();
  const btVector3& origin_b = manifold.getBody1()->getWorldTransform().getOrigin();
  const btScalar threshold = manifold.getContactProcessingThreshold();
  const btVector3 zero(0, 0, 0);

  for (int j = 0; j < manifold.getNumContacts(); ++j) {
    btManifoldPoint& cp = manifold.getContactPoint(j);
    if (!(cp.getDistance() <= threshold)) continue;
    const int contact_index = m.contacts.size();
    btSolverConstraint& row = m.contacts.expandNonInitializing();
    row.m_solverBodyIdA = m.id_a;
    row.m_solverBodyIdB = m.id_b;
    row.m_originalContactPoint = &cp;
    // Lever arms from each body's origin to its contact point (none for the fixed body: every
    // product with it would be zeroed).
    btVector3 arm_a = zero, arm_b = zero;
    if constexpr (kA != Side::kFixed) arm_a = cp.getPositionWorldOnA() - origin_a;
    if constexpr (kB != Side::kFixed) arm_b = cp.getPositionWorldOnB() - origin_b;

    btScalar cfm, erp;
    soft_contact(m.info, cp, cfm, erp);
    cfm *= m.inv_dt;
    set_normal_jacobian<kA, kB>(m, row, cp.m_normalWorldOnB, arm_a, arm_b, cfm);
    row.m_friction = cp.m_combinedFriction;
    const btScalar bounce = bounce_speed<kA, kB>(m, cp, arm_a, arm_b);
    warm_start<kA, kB>(m, cp, row);
    set_normal_target<kA, kB>(m, cp, row, bounce, cfm, erp);
    row.m_frictionIndex = m.frictions.size();
    add_friction_rows<kA, kB>(m, cp, contact_index, arm_a, arm_b);
  }
}

}  // namespace

bool OneSidedContactSolver::covered(int numConstraints, const btContactSolverInfo& info) {
  return enabled && numConstraints == 0 && m_tmpSolverNonContactConstraintPool.size() == 0 &&
         m_tmpSolverContactRollingFrictionConstraintPool.size() == 0 &&
         (info.m_solverMode &
          (SOLVER_RANDMIZE_ORDER | SOLVER_INTERLEAVE_CONTACT_AND_FRICTION_CONSTRAINTS)) == 0 &&
         m_resolveSingleConstraintRowGeneric == getScalarConstraintRowSolverGeneric() &&
         m_resolveSingleConstraintRowLowerLimit == getScalarConstraintRowSolverLowerLimit();
}

void OneSidedContactSolver::classify_rows() {
  // A body is still for this solve if no row can move it: Bullet's fixed body (impulses are
  // not applied to it) or a kinematic one (no inverse mass or inertia: every row's linear and
  // angular component for it is zero; the setup's own classification, side_of()), starting from
  // zero velocity changes. Its velocity changes then stay zero through every iteration, and its
  // half of each row only adds zeros.
  const int num_bodies = m_tmpSolverBodyPool.size();
  std::vector<std::uint8_t>& still = still_bodies_;  // kept: no allocation per solve
  still.assign(static_cast<std::size_t>(num_bodies), 0);
  for (int i = 0; i < num_bodies; ++i) {
    const btSolverBody& body = m_tmpSolverBodyPool[i];
    const Side side = side_of(body);
    still[i] = (side == Side::kFixed || side == Side::kStill) &&
               is_zero(body.m_deltaLinearVelocity) && is_zero(body.m_deltaAngularVelocity);
  }
  auto sides = [&](const btConstraintArray& pool, std::vector<std::uint8_t>& out) {
    out.resize(static_cast<std::size_t>(pool.size()));
    for (int j = 0; j < pool.size(); ++j) {
      const btSolverConstraint& c = pool[j];
      out[j] = static_cast<std::uint8_t>((still[c.m_solverBodyIdA] ? 0 : kSideA) |
                                         (still[c.m_solverBodyIdB] ? 0 : kSideB));
      (out[j] == (kSideA | kSideB) ? two_sided_rows : one_sided_rows) += 1;
    }
  };
  sides(m_tmpSolverContactConstraintPool, contact_sides_);
  sides(m_tmpSolverContactFrictionConstraintPool, friction_sides_);

  // One moving body for every row: pack the rows.
  packed_body_ = -1;
  int body = -1;
  auto one_body = [&](const btConstraintArray& pool, const std::vector<std::uint8_t>& side) {
    for (int j = 0; j < pool.size(); ++j) {
      if (side[j] != kSideA && side[j] != kSideB) return false;
      const int id = side[j] == kSideA ? pool[j].m_solverBodyIdA : pool[j].m_solverBodyIdB;
      if (body >= 0 && id != body) return false;
      body = id;
    }
    return true;
  };
  if (!one_body(m_tmpSolverContactConstraintPool, contact_sides_) ||
      !one_body(m_tmpSolverContactFrictionConstraintPool, friction_sides_) || body < 0) {
    return;
  }
  const btSolverBody& moving = m_tmpSolverBodyPool[body];
  auto pack = [&](btConstraintArray& pool, const std::vector<std::uint8_t>& side,
                  std::vector<PackedRow>& rows, std::vector<btScalar>& applied) {
    rows.resize(static_cast<std::size_t>(pool.size()));
    applied.resize(static_cast<std::size_t>(pool.size()));
    for (int j = 0; j < pool.size(); ++j) {
      btSolverConstraint& c = pool[j];
      PackedRow& p = rows[j];
      const bool a = side[j] == kSideA;
      p.normal = a ? c.m_contactNormal1 : c.m_contactNormal2;
      p.relpos_cross_normal = a ? c.m_relpos1CrossNormal : c.m_relpos2CrossNormal;
      p.linear = p.normal * moving.m_invMass;
      p.angular = a ? c.m_angularComponentA : c.m_angularComponentB;
      p.rhs = c.m_rhs;
      p.cfm = c.m_cfm;
      p.jac = c.m_jacDiagABInv;
      p.lower = c.m_lowerLimit;
      p.inverse_jac = 1. / c.m_jacDiagABInv;
      p.source = &c;
      applied[j] = c.m_appliedImpulse;
    }
  };
  pack(m_tmpSolverContactConstraintPool, contact_sides_, packed_contacts_, applied_contacts_);
  pack(m_tmpSolverContactFrictionConstraintPool, friction_sides_, packed_frictions_,
       applied_frictions_);
  packed_body_ = body;
}

template <bool kUnitFactors>
btScalar OneSidedContactSolver::solve_packed() {
  btSolverBody& body = m_tmpSolverBodyPool[packed_body_];
  btVector3 dv = body.m_deltaLinearVelocity;
  btVector3 dw = body.m_deltaAngularVelocity;
  const btVector3 linear_factor = body.m_linearFactor;
  const btVector3 angular_factor = body.m_angularFactor;
  btScalar residual = 0;
  // solve_row() for a row of the one moving body, its velocity changes held in dv, dw.
  auto solve = [&](const PackedRow& p, btScalar& applied, btScalar lower, btScalar upper,
                   bool has_upper) {
    btScalar delta = p.rhs - applied * p.cfm;
    const btScalar v = p.normal.dot(dv) + p.relpos_cross_normal.dot(dw);
    delta -= v * p.jac;
    delta = has_upper ? clamp_impulse<true>(delta, applied, lower, upper)
                      : clamp_impulse<false>(delta, applied, lower, upper);
    if (kUnitFactors) {  // x·1 = x: the same bits without the factors' multiplications
      dv += p.linear * delta;
      dw += p.angular * delta;
    } else {
      dv += p.linear * delta * linear_factor;
      dw += p.angular * (delta * angular_factor);
    }
    const btScalar d = btScalar(delta * p.inverse_jac);
    residual = btMax(residual, d * d);
  };
  const int num_contacts = m_tmpSolverContactConstraintPool.size();
  const int num_frictions = m_tmpSolverContactFrictionConstraintPool.size();
  for (int j = 0; j < num_contacts; ++j) {
    const int r = m_orderTmpConstraintPool[j];
    const PackedRow& p = packed_contacts_[r];
    solve(p, applied_contacts_[r], p.lower, 0, false);
  }
  for (int j = 0; j < num_frictions; ++j) {
    const int r = m_orderFrictionConstraintPool[j];
    const PackedRow& p = packed_frictions_[r];
    const btScalar normal = applied_contacts_[p.source->m_frictionIndex];
    if (normal > btScalar(0)) {
      btSolverConstraint& c = *p.source;
      c.m_lowerLimit = -(c.m_friction * normal);
      c.m_upperLimit = c.m_friction * normal;
      solve(p, applied_frictions_[r], c.m_lowerLimit, c.m_upperLimit, true);
    }
  }
  body.m_deltaLinearVelocity = dv;
  body.m_deltaAngularVelocity = dw;
  for (int r = 0; r < num_contacts; ++r)
    packed_contacts_[r].source->m_appliedImpulse = applied_contacts_[r];
  for (int r = 0; r < num_frictions; ++r) {
    packed_frictions_[r].source->m_appliedImpulse = applied_frictions_[r];
  }
  return residual;
}

btScalar OneSidedContactSolver::solve_packed() {
  ++packed_iterations;
  const btSolverBody& body = m_tmpSolverBodyPool[packed_body_];
  const btVector3 one(1, 1, 1);
  return body.m_linearFactor == one && body.m_angularFactor == one ? solve_packed<true>()
                                                                   : solve_packed<false>();
}

btScalar OneSidedContactSolver::solveSingleIteration(
    int iteration, btCollisionObject** bodies, int numBodies, btPersistentManifold** manifolds,
    int numManifolds, btTypedConstraint** constraints, int numConstraints,
    const btContactSolverInfo& info, btIDebugDraw* debugDrawer) {
  if (!covered(numConstraints, info)) {
    ++bullet_iterations;
    return btSequentialImpulseConstraintSolver::solveSingleIteration(
        iteration, bodies, numBodies, manifolds, numManifolds, constraints, numConstraints, info,
        debugDrawer);
  }
  ++own_iterations;
  // Past m_numIterations Bullet solves only non-contact rows (there are none here).
  if (iteration >= info.m_numIterations) return 0;
  const int num_contacts = m_tmpSolverContactConstraintPool.size();
  const int num_frictions = m_tmpSolverContactFrictionConstraintPool.size();
  if (iteration == 0 || contact_sides_.size() != static_cast<std::size_t>(num_contacts) ||
      friction_sides_.size() != static_cast<std::size_t>(num_frictions)) {
    classify_rows();
  }

  if (packed_body_ >= 0) return solve_packed();
  btScalar residual = 0;
  // Normal rows first (impulse >= 0), then the friction rows, bounded by the friction
  // coefficient times their contact's normal impulse of this iteration (Bullet's order when the
  // rows are not interleaved).
  for (int j = 0; j < num_contacts; ++j) {
    const int r = m_orderTmpConstraintPool[j];
    const btSolverConstraint& c = m_tmpSolverContactConstraintPool[r];
    const btScalar d = solve_row<false>(contact_sides_[r], m_tmpSolverBodyPool[c.m_solverBodyIdA],
                                        m_tmpSolverBodyPool[c.m_solverBodyIdB], c);
    residual = btMax(residual, d * d);
  }
  for (int j = 0; j < num_frictions; ++j) {
    const int r = m_orderFrictionConstraintPool[j];
    btSolverConstraint& c = m_tmpSolverContactFrictionConstraintPool[r];
    const btScalar normal = m_tmpSolverContactConstraintPool[c.m_frictionIndex].m_appliedImpulse;
    if (normal > btScalar(0)) {
      c.m_lowerLimit = -(c.m_friction * normal);
      c.m_upperLimit = c.m_friction * normal;
      const btScalar d = solve_row<true>(friction_sides_[r], m_tmpSolverBodyPool[c.m_solverBodyIdA],
                                         m_tmpSolverBodyPool[c.m_solverBodyIdB], c);
      residual = btMax(residual, d * d);
    }
  }
  return residual;
}

bool OneSidedContactSolver::convert_manifold(btPersistentManifold& manifold,
                                             const btContactSolverInfo& info) {
  btCollisionObject& object_a = *const_cast<btCollisionObject*>(manifold.getBody0());
  btCollisionObject& object_b = *const_cast<btCollisionObject*>(manifold.getBody1());
  // Anisotropic friction rescales the friction directions, rolling and spinning friction add
  // rows of their own: Bullet's setup.
  const int anisotropic = btCollisionObject::CF_ANISOTROPIC_FRICTION |
                          btCollisionObject::CF_ANISOTROPIC_ROLLING_FRICTION;
  if (object_a.hasAnisotropicFriction(anisotropic) ||
      object_b.hasAnisotropicFriction(anisotropic)) {
    return false;
  }
  const btScalar threshold = manifold.getContactProcessingThreshold();
  for (int j = 0; j < manifold.getNumContacts(); ++j) {
    const btManifoldPoint& cp = manifold.getContactPoint(j);
    if (cp.getDistance() <= threshold && cp.m_combinedRollingFriction > 0) return false;
  }

  // The solver bodies in Bullet's order (Bullet's convertContact would create them here too;
  // for a manifold handed to it, it finds them created).
  const int id_a = getOrInitSolverBody(object_a, info.m_timeStep);
  const int id_b = getOrInitSolverBody(object_b, info.m_timeStep);
  btSolverBody& a = m_tmpSolverBodyPool[id_a];
  btSolverBody& b = m_tmpSolverBodyPool[id_b];
  // No rows between two bodies that cannot be pushed (Bullet's test).
  if (a.m_invMass.fuzzyZero() && b.m_invMass.fuzzyZero()) return true;

  const ManifoldRows rows{m_tmpSolverContactConstraintPool,
                          m_tmpSolverContactFrictionConstraintPool,
                          a,
                          b,
                          id_a,
                          id_b,
                          info,
                          info.m_sor,
                          btScalar(1) / info.m_timeStep};
  const Side side_a = side_of(a);
  const Side side_b = side_of(b);
  if (side_a == Side::kMoving) {
    switch (side_b) {
      case Side::kMoving:
        convert_points<Side::kMoving, Side::kMoving>(rows, manifold);
        return true;
      case Side::kStill:
        convert_points<Side::kMoving, Side::kStill>(rows, manifold);
        return true;
      case Side::kFixed:
        convert_points<Side::kMoving, Side::kFixed>(rows, manifold);
        return true;
      default:
        return false;
    }
  }
  if (side_b == Side::kMoving) {
    switch (side_a) {
      case Side::kStill:
        convert_points<Side::kStill, Side::kMoving>(rows, manifold);
        return true;
      case Side::kFixed:
        convert_points<Side::kFixed, Side::kMoving>(rows, manifold);
        return true;
      default:
        return false;
    }
  }
  return false;
}

void OneSidedContactSolver::convertContacts(btPersistentManifold** manifolds, int numManifolds,
                                            const btContactSolverInfo& info) {
  for (int i = 0; i < numManifolds; ++i) {
    if (enabled && convert_manifold(*manifolds[i], info)) {
      ++own_manifolds;
    } else {
      ++bullet_manifolds;
      convertContact(manifolds[i], info);
    }
  }
}

}  // namespace mgn::physics
