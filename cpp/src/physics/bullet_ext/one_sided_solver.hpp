#pragma once
// Bullet's sequential-impulse solver with the immovable half of each contact row left out
// (private: Bullet types do not appear in installed headers).
//
// Mirrors Bullet 3.24: btSequentialImpulseConstraintSolver::solveSingleIteration,
// ::convertContacts, ::convertContact, ::setupContactConstraint, ::setFrictionConstraintImpulse,
// ::addFrictionConstraint, ::setupFrictionConstraint, the scalar row solvers behind
// ::resolveSingleConstraintRowGeneric and ::resolveSingleConstraintRowLowerLimit, and
// btSolverBody::internalApplyImpulse.
//
// Bullet's btSequentialImpulseConstraintSolver solves a contact row (one normal or one friction
// direction of one contact point) for both of its bodies: it reads both bodies' velocity
// changes, computes the row's impulse and applies it to both. In the shake test every contact
// pairs the object with a hand body (palm or finger) that is kinematic: it has no inverse mass
// and no inverse inertia, so its half of every row reads zeros and adds zeros. For the drop,
// the tote and the floor are static (Bullet's fixed solver body). The iterations were about
// three quarters of a shake trial's solver instructions, the solver about half of the trial
// (docs/decisions/0012-shake-one-sided-solver.md).
//
// OneSidedContactSolver runs the same Projected Gauss-Seidel iterations (same rows, same order,
// same single-precision operations in the same order, same residual for Bullet's early exit),
// but for a body that cannot move it skips the products that are zero. The result is the same
// simulation bit for bit (tested step by step against Bullet's own solver): a skipped term is
// x - (±0)·k = x, which can differ from Bullet's only in the sign of a zero. Worlds the fast
// path does not cover — joints, rolling friction, randomised or interleaved row order, SIMD row
// solvers — are handed to Bullet's own iteration unchanged.
//
// The rows are set up the same way (convertContacts): Bullet's convertContact builds both halves
// of every contact row and of its one or two friction rows, and a step of the shake test spends
// about an eighth of its instructions there. For a contact between a body that moves and one
// that cannot (Bullet's fixed body, or a kinematic body: no inverse mass, no inverse inertia),
// OneSidedContactSolver skips what only the still body would contribute — its angular
// components (the inverse inertia products), its share of the effective mass, its warm-start
// impulse; for the fixed body also its lever arm — and computes everything else with Bullet's
// operations in Bullet's order: the rows (every field Bullet writes), the bodies' warm-start
// velocity changes, the points' friction directions and flags, and the pools' order are the
// same. The still body's angular components are written as +0 where Bullet's product of a zero
// inertia may give -0 (never read by the iterations above; Bullet's own iteration adds them to a
// body that takes no impulse). Two moving bodies are covered too. Manifolds with rolling or
// spinning friction or anisotropic friction are converted by Bullet's own convertContact.
#include "physics/bullet_ext/version.hpp"

#include <btBulletDynamicsCommon.h>

#include <cstdint>
#include <vector>

namespace mgn::physics {

class OneSidedContactSolver : public btSequentialImpulseConstraintSolver {
 public:
  btScalar solveSingleIteration(int iteration, btCollisionObject** bodies, int numBodies,
                                btPersistentManifold** manifolds, int numManifolds,
                                btTypedConstraint** constraints, int numConstraints,
                                const btContactSolverInfo& info,
                                btIDebugDraw* debugDrawer) override;

  /// Sets up the contact and friction rows of every manifold as Bullet's convertContact does,
  /// without the still body's half where one body cannot move (see above).
  void convertContacts(btPersistentManifold** manifolds, int numManifolds,
                       const btContactSolverInfo& info) override;

  /// false: every iteration and every manifold's setup is Bullet's own (for comparisons).
  bool enabled = true;
  /// Manifolds converted to rows by this solver's own setup / by Bullet's convertContact.
  long own_manifolds = 0;
  long bullet_manifolds = 0;
  /// Iterations run by this solver's own loop / handed to Bullet's (for tests and benchmarks).
  long own_iterations = 0;
  long bullet_iterations = 0;
  /// Rows solved for one body or none / for both, summed over the solves (per solve, not per
  /// iteration; for tests and benchmarks).
  long one_sided_rows = 0;
  long two_sided_rows = 0;
  /// Of own_iterations, those on packed rows (one moving body).
  long packed_iterations = 0;

 private:
  bool covered(int numConstraints, const btContactSolverInfo& info);
  bool convert_manifold(btPersistentManifold& manifold, const btContactSolverInfo& info);
  void classify_rows();

  btScalar solve_packed();
  template <bool kUnitFactors>
  btScalar solve_packed();

  // Per row of the contact and friction pools (computed at iteration 0 of every solve): which
  // of its two bodies take part (bit 0: A, bit 1: B).
  std::vector<std::uint8_t> still_bodies_;  // per solver body: no row can move it
  std::vector<std::uint8_t> contact_sides_;
  std::vector<std::uint8_t> friction_sides_;

  // When every row moves one and the same body (the shake test's object), the rows are packed
  // with what an iteration reads, the body's velocity changes stay in registers through an
  // iteration, and the impulses are written back to Bullet's rows after it.
  struct PackedRow {
    btVector3 normal;               // the moving body's contact normal (or friction direction)
    btVector3 relpos_cross_normal;  // its lever arm × normal
    btVector3 linear;               // normal × the body's inverse mass
    btVector3 angular;              // the row's angular component for the body
    btScalar rhs = 0, cfm = 0, jac = 0;
    btScalar lower = 0;                    // contact rows: the impulse's lower limit
    double inverse_jac = 0;                // 1 / jac in double, as Bullet's residual divides
    btSolverConstraint* source = nullptr;  // the row in Bullet's pool
  };
  std::vector<PackedRow> packed_contacts_;   // by contact pool index
  std::vector<PackedRow> packed_frictions_;  // by friction pool index
  std::vector<btScalar> applied_contacts_;   // accumulated impulses, by pool index
  std::vector<btScalar> applied_frictions_;
  int packed_body_ = -1;  // the one moving solver body, or -1: rows solved one by one
};

}  // namespace mgn::physics
