#include "physics/one_sided_solver.hpp"

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
  const btScalar sum = btScalar(c.m_appliedImpulse) + delta;
  if (sum < c.m_lowerLimit) {
    delta = c.m_lowerLimit - c.m_appliedImpulse;
    c.m_appliedImpulse = c.m_lowerLimit;
  } else if (kUpper && sum > c.m_upperLimit) {
    delta = c.m_upperLimit - c.m_appliedImpulse;
    c.m_appliedImpulse = c.m_upperLimit;
  } else {
    c.m_appliedImpulse = sum;
  }
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
  // A body is still for this solve if no row can move it: Bullet's fixed body (no original
  // body: impulses are not applied), or a body without inverse mass whose rows carry no angular
  // component (kinematic bodies), starting from zero velocity changes. Its velocity changes then
  // stay zero through every iteration, and its half of each row only adds zeros.
  const int num_bodies = m_tmpSolverBodyPool.size();
  std::vector<std::uint8_t> still(static_cast<std::size_t>(num_bodies));
  for (int i = 0; i < num_bodies; ++i) {
    const btSolverBody& body = m_tmpSolverBodyPool[i];
    still[i] = (body.m_originalBody == nullptr || is_zero(body.m_invMass)) &&
               is_zero(body.m_deltaLinearVelocity) && is_zero(body.m_deltaAngularVelocity);
  }
  auto check = [&](const btConstraintArray& pool) {
    for (int j = 0; j < pool.size(); ++j) {
      const btSolverConstraint& c = pool[j];
      if (m_tmpSolverBodyPool[c.m_solverBodyIdA].m_originalBody != nullptr &&
          !is_zero(c.m_angularComponentA))
        still[c.m_solverBodyIdA] = 0;
      if (m_tmpSolverBodyPool[c.m_solverBodyIdB].m_originalBody != nullptr &&
          !is_zero(c.m_angularComponentB))
        still[c.m_solverBodyIdB] = 0;
    }
  };
  check(m_tmpSolverContactConstraintPool);
  check(m_tmpSolverContactFrictionConstraintPool);
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
    const btScalar sum = applied + delta;
    if (sum < lower) {
      delta = lower - applied;
      applied = lower;
    } else if (has_upper && sum > upper) {
      delta = upper - applied;
      applied = upper;
    } else {
      applied = sum;
    }
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

}  // namespace mgn::physics
