#pragma once
// A converged state as the output layer reads it.  The stepping loop (driver/run_driver.cpp) hands
// one to the writers after every increment (Simulation::snapshot), so no writer sees the
// Simulation: they read the row, the surface, and views of the mesh, the displacement, the bulk
// model and the contact boundary.  What costs a pass over the mesh is computed on first use and
// only once: the contact (it sums the internal forces) and the exact unloading stiffness (it
// factors the elastic stiffness with the contact rows).
#include <functional>
#include <optional>
#include <vector>

#include "indentsim/geometry/mesh.hpp"
#include "indentsim/simulation/load_stepping.hpp"
#include "indentsim/solvers/assembly.hpp"
#include "indentsim/solvers/contact_discretization.hpp"

namespace indentsim {

class IncrementSnapshot {
public:
  IncrementSnapshot(const IncrementRecord& record, double alpha, double free_surface_depth, const Mesh& mesh,
                    const std::vector<double>& displacement, const BulkModel& bulk,
                    const ContactDiscretization& contact_boundary, std::function<ContactResult()> evaluate_contact,
                    std::function<double(const ContactResult&)> evaluate_unloading_stiffness)
      : record(record),
        alpha(alpha),
        free_surface_depth(free_surface_depth),
        mesh(mesh),
        displacement(displacement),
        bulk(bulk),
        contact_boundary(contact_boundary),
        evaluate_contact_(std::move(evaluate_contact)),
        evaluate_unloading_stiffness_(std::move(evaluate_unloading_stiffness)) {}

  const IncrementRecord record;     ///< the row of curve.csv
  const double alpha;               ///< the state's depth [m]
  const double free_surface_depth;  ///< max_k (-v_k - g(x_k)): the imprint's depth once separated [m]
  const Mesh& mesh;
  const std::vector<double>& displacement;
  const BulkModel& bulk;
  const ContactDiscretization& contact_boundary;

  const ContactResult& contact() const {
    if (!contact_) contact_ = evaluate_contact_();
    return *contact_;
  }
  /// -dP/d(alpha) of the elastic unloading tangent at this state (unloading_stiffness.hpp).
  double unloading_stiffness() const { return evaluate_unloading_stiffness_(contact()); }
  /// The contact half-width (radius) of the contact solution [m].
  double contact_half_width() const { return contact().half_width; }

private:
  std::function<ContactResult()> evaluate_contact_;
  std::function<double(const ContactResult&)> evaluate_unloading_stiffness_;
  mutable std::optional<ContactResult> contact_;
};

}  // namespace indentsim
