#pragma once
// The bulk's departure from linear elasticity, element by element: what the Newton systems add
// to K u, on the whole mesh or on a condensed near field (CondensedBulk), and what the run asks
// of it.  Two implementations behind this seam (docs/DESIGN.md §14):
//   InelasticBulk      small strain: the elements with an inelastic Gauss point, through a
//                      PointLaw of the linearized strain (solvers/inelastic_bulk.hpp);
//   FiniteStrainBulk   finite strain: every element of the system, through a
//                      FiniteStrainPointLaw of the deformation gradient (solvers/finite_strain_bulk.hpp).
#include <cstddef>
#include <optional>
#include <vector>

#include "indentsim/materials/material_parameter.hpp"
#include "indentsim/solvers/assembly.hpp"

namespace indentsim {

class NonlinearBulk : public BulkModel {
public:
  /// Adds to f each slot's element force less its linear elastic one, f_e(u) - K_e u_e (or, to
  /// the tangent's values, d f_e / d u_e - K_e).  An element the kinematics and the law leave
  /// linear elastic adds nothing.
  virtual void add_force_corrections(const std::vector<ElementSlot>& slots, const double* u, double* f) const = 0;
  virtual void add_tangent_corrections(const std::vector<ElementSlot>& slots, const double* u, double* values) const = 0;
  /// True if element (ei, ej) departs from linear elasticity at u (free-equation vector of the
  /// whole mesh): a far-field element that does makes the near field grow.
  virtual bool departs_at(int ei, int ej, const double* u) const = 0;
  /// The point (4 element + g) has yielded at some time.
  virtual bool has_yielded(std::size_t point) const = 0;
  /// Whether the load path is beyond its deepest point so far (PointLaw::set_loading).
  virtual void set_loading(bool beyond_previous_peak) = 0;
  /// The duration [s] of the (sub-)increment being solved (PointLaw::set_time_step).
  virtual void set_time_step(double seconds) = 0;
  /// Whether the tangent is symmetric (F-bar's is not: a Cholesky factorization cannot take it).
  virtual bool symmetric_tangent() const { return true; }
  /// Adds d f_int / d theta at fixed u over the slots' elements to df; false (df then unusable)
  /// when the bulk cannot give it at this state: the run's sensitivities then come from finite
  /// differences of whole runs.
  virtual bool add_parameter_derivative(const std::vector<ElementSlot>& /*slots*/, const double* /*u*/,
                                        MaterialParameter /*parameter*/, double* /*df*/) const {
    return false;
  }
  /// Hands the law d eps / d theta from a displacement sensitivity (InelasticBulk's Ilyushin peak).
  virtual void record_strain_derivatives(const std::vector<ElementSlot>& /*slots*/, const double* /*du*/,
                                         MaterialParameter /*parameter*/) {}
  /// The tangent of the elastic unloading from the committed state u on the whole mesh's pattern,
  /// or nothing where it is the linear elastic stiffness K (small strain: both plastic models
  /// unload elastically), for the exact unloading stiffness (unloading_stiffness.hpp).
  virtual std::optional<std::vector<double>> unloading_tangent(const double* /*u*/) const { return std::nullopt; }
  /// The whole mesh's element slots (its free-equation system).
  virtual const std::vector<ElementSlot>& slots() const = 0;
  /// After commit(u): the elements outside `near` (the Newton system's) are the condensed far
  /// field's, linear elastic in small strain; a bulk whose kinematics are not small strain
  /// measures what that neglects there (far_field_gradient).
  virtual void measure_far_field(const std::vector<ElementSlot>& /*near*/) {}
};

}  // namespace indentsim
