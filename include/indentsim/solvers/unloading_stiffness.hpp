#pragma once
// The exact unloading stiffness S = -dP/d(alpha) at a reversal.
//
// Both plastic models unload elastically from the peak state (Ilyushin's unloading theorem; J2's
// elastic predictor), and at the onset of unloading every node in contact stays in contact (its
// pressure is positive).  So S is the stiffness of the linear elastic body with the peak's
// contact nodes moving with the punch, dv_k/d(alpha) = -1, and the others free:
//   K_ff w_f = -K_fA w_A,   w_A = -1,   S = f sum_{k in A} -(K w)_k   (f the symmetry factor),
// one sparse Cholesky solve (Eigen's SimplicialLDLT) on the whole mesh -- no finite difference,
// no dependence on the increment size.  A flat punch included: its rim node is in A.
//
// A discretization whose rows do not pin unknowns (the integrated gap's penalty) linearizes its
// own rows instead: J w = -dF/d(alpha) with J the elastic stiffness whose contact rows are the
// discretization's Jacobian rows at the state, and S = -f sum_k (K w)_k over the candidates
// (the rows without contact force hold (K w)_k = 0).
//
// Rows that carry history (Coulomb friction) have no single linearization at a reversal: which
// nodes stick and which go on sliding as the punch withdraws is itself the solution of the
// increment.  S is then the one-sided derivative of an increment from the state to alpha - delta
// on the elastic unloading operator, solved exactly (its equations are piecewise linear).
#include "indentsim/solvers/assembly.hpp"
#include "indentsim/solvers/contact_discretization.hpp"

namespace indentsim {

/// S [N/m in axisymmetry, N/m per m in plane strain] for the contact set of `state`.
/// `u` and `internal_force` are the state's displacement and internal force on the whole mesh.
double elastic_unloading_stiffness(const ElasticStiffness& stiffness, const ContactDiscretization& contact,
                                   const double* u, const double* internal_force, double alpha,
                                   const ContactResult& state);
/// The same for a bulk whose unloading operator is not K (finite strain: the tangent at the
/// state, geometric terms included), given as `tangent` on K's pattern: J w = -dF/d(alpha) with
/// the contact's own Jacobian rows, S = -f sum_k (T w)_k over the candidates' vertical rows.
/// Contacts that carry history (friction on the current surface): the one-sided derivative of an
/// increment from the state on T, as above.
double unloading_stiffness_of_tangent(const StiffnessPattern& pattern, const std::vector<double>& tangent,
                                      const ContactDiscretization& contact, const double* u,
                                      const double* internal_force, double alpha, const ContactResult& state);

}  // namespace indentsim
