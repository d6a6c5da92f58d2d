#include "indentsim/solvers/unloading_stiffness.hpp"

#include <stdexcept>
#include <vector>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <Eigen/SparseLU>

namespace indentsim {

namespace {

// A matrix in the pattern's CSC layout as an Eigen sparse matrix.
Eigen::SparseMatrix<double> sparse_matrix(const StiffnessPattern& pattern, const std::vector<double>& values) {
  const auto n = static_cast<Eigen::Index>(pattern.size());
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(values.size());
  const auto& start = pattern.column_start();
  const auto& row = pattern.row_index();
  for (Eigen::Index j = 0; j < n; ++j)
    for (std::int64_t p = start[static_cast<std::size_t>(j)]; p < start[static_cast<std::size_t>(j) + 1]; ++p)
      entries.emplace_back(static_cast<Eigen::Index>(row[static_cast<std::size_t>(p)]), j,
                           values[static_cast<std::size_t>(p)]);
  Eigen::SparseMatrix<double> matrix(n, n);
  matrix.setFromTriplets(entries.begin(), entries.end());
  return matrix;
}

// Rows that do not pin unknowns: the bulk's unloading operator T (K, or finite strain's tangent)
// with the contact's own Jacobian rows, J w = -dF/d(alpha), and dP/d(alpha) = -f sum_k (T w)_k
// over the candidates' vertical rows (an open one holds (T w)_k = 0).
double linearized_unloading_stiffness(const StiffnessPattern& pattern, const std::vector<double>& tangent,
                                      const ContactDiscretization& contact, const double* u,
                                      const double* internal_force, double alpha) {
  const auto n = static_cast<Eigen::Index>(pattern.size());
  const auto& rows = contact.row_equations();
  std::vector<double> row_force(rows.size());
  std::vector<std::vector<std::int64_t>> row_positions;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    row_force[i] = internal_force[rows[i]];
    row_positions.push_back(pattern.row_positions(rows[i]));
  }
  std::vector<double> jacobian = tangent;
  contact.write_jacobian_rows(u, alpha, row_force.data(), pattern, row_positions, jacobian.data());
  std::vector<double> d_alpha(static_cast<std::size_t>(n), 0.0);
  contact.write_depth_derivative_rows(u, alpha, row_force.data(), d_alpha.data());

  const Eigen::SparseMatrix<double> J = sparse_matrix(pattern, jacobian);
  Eigen::VectorXd rhs(n);
  for (Eigen::Index i = 0; i < n; ++i) rhs[i] = -d_alpha[static_cast<std::size_t>(i)];
  Eigen::VectorXd w;
  if (contact.rows_keep_symmetry()) {
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> factor(J);
    if (factor.info() != Eigen::Success) throw std::runtime_error("the elastic unloading stiffness could not be factored");
    w = factor.solve(rhs);
  } else {
    Eigen::SparseLU<Eigen::SparseMatrix<double>> factor(J);
    if (factor.info() != Eigen::Success) throw std::runtime_error("the elastic unloading stiffness could not be factored");
    w = factor.solve(rhs);
  }
  std::vector<double> reaction(static_cast<std::size_t>(n));
  pattern.multiply(tangent, w.data(), reaction.data());
  double rate = 0.0;
  for (const ContactCandidate& c : contact.candidates()) rate -= reaction[static_cast<std::size_t>(c.equation)];
  return contact.symmetry_factor() * rate;
}

// Rows that carry history (friction): the one-sided derivative of an increment from the state to
// alpha - delta on the unloading operator T (K, or finite strain's tangent): r(u + w) = r(u) + T w
// on the contact nodes' rows, T w elsewhere.  Its equations are piecewise linear in w (up to the
// current surface's O(delta^2) in finite strain), so semi-smooth Newton reaches their solution in
// a few steps: it
// stops when the branches at the new w are those the step was solved with.  On a fixed set of
// branches w is proportional to delta, so S = f sum_k (K w)_k / delta, without a difference of
// forces.  The sum runs over the nodes in contact at the state or after the increment: a contact
// node that opens within it loses all its force, lambda_k = (K w)_k on its free row.
// `operator_values`, on `pattern`, is the bulk's unloading operator: K, or finite strain's tangent
// at the state (whose contact rows are nonlinear in w: the step's error is O(delta^2) then).
double incremental_unloading_stiffness(const StiffnessPattern& pattern, const std::vector<double>& operator_values,
                                       const ContactDiscretization& at_state, const double* u,
                                       const double* internal_force, double alpha, const ContactResult& state) {
  if (!(alpha > 0.0)) return 0.0;
  const std::unique_ptr<ContactDiscretization> reversed = at_state.at_load_reversal(u);
  const ContactDiscretization& contact = reversed ? *reversed : at_state;
  const auto n = static_cast<std::size_t>(pattern.size());
  const auto& rows = contact.row_equations();
  std::vector<std::vector<std::int64_t>> row_positions;
  for (int equation : rows) row_positions.push_back(pattern.row_positions(equation));
  const double delta = 1e-6 * alpha, target = alpha - delta;
  // The state's force on the rows of the nodes in contact (the contact forces); every other row
  // is in equilibrium at the state, and is taken so: what the state leaves of them (Newton's
  // tolerance, and in finite strain the condensed far field's linearization, 1e-5 N at far
  // surface nodes of the shipped cone) would otherwise load the increment, whose own forces are
  // only S delta.
  std::vector<double> state_force(n, 0.0);
  for (std::size_t k = 0; k < contact.candidates().size() && k < state.in_contact.size(); ++k) {
    if (!state.in_contact[k]) continue;
    const ContactCandidate& c = contact.candidates()[k];
    state_force[static_cast<std::size_t>(c.equation)] = internal_force[c.equation];
    if (c.tangential_equation >= 0)
      state_force[static_cast<std::size_t>(c.tangential_equation)] = internal_force[c.tangential_equation];
  }
  std::vector<double> w(n, 0.0), x(n), kw(n), f(n), row_force(rows.size()), jacobian;
  const auto evaluate = [&] {
    pattern.multiply(operator_values, w.data(), kw.data());
    for (std::size_t i = 0; i < n; ++i) {
      x[i] = u[i] + w[i];
      f[i] = state_force[i] + kw[i];
    }
    for (std::size_t i = 0; i < rows.size(); ++i) row_force[i] = f[static_cast<std::size_t>(rows[i])];
    jacobian = operator_values;
    return contact.write_jacobian_rows(x.data(), target, row_force.data(), pattern, row_positions, jacobian.data());
  };
  std::uint64_t branches = evaluate();
  constexpr int max_steps = 50;
  for (int step = 0;; ++step) {
    if (step == max_steps)
      throw std::runtime_error("the unloading stiffness's increment found no consistent contact branches");
    contact.write_residual_rows(x.data(), target, row_force.data(), f.data());
    const Eigen::SparseMatrix<double> J = sparse_matrix(pattern, jacobian);
    Eigen::SparseLU<Eigen::SparseMatrix<double>> factor(J);
    if (factor.info() != Eigen::Success) throw std::runtime_error("the elastic unloading stiffness could not be factored");
    const Eigen::VectorXd dw = factor.solve(-Eigen::Map<const Eigen::VectorXd>(f.data(), static_cast<Eigen::Index>(n)));
    for (std::size_t i = 0; i < n; ++i) w[i] += dw[static_cast<Eigen::Index>(i)];
    const std::uint64_t next = evaluate();
    if (next == branches) break;  // w solves the equations of its own branches
    branches = next;
  }
  const ContactResult after = contact.evaluate(x.data(), f.data(), target);
  double rate = 0.0;
  for (std::size_t k = 0; k < contact.candidates().size(); ++k)
    if (after.in_contact[k] || (k < state.in_contact.size() && state.in_contact[k]))
      rate += kw[static_cast<std::size_t>(contact.candidates()[k].equation)];
  return contact.symmetry_factor() * rate / delta;
}

}  // namespace

double elastic_unloading_stiffness(const ElasticStiffness& stiffness, const ContactDiscretization& contact,
                                   const double* u, const double* internal_force, double alpha,
                                   const ContactResult& state) {
  if (contact.carries_history())
    return incremental_unloading_stiffness(stiffness.pattern(), stiffness.values(), contact, u, internal_force, alpha,
                                           state);
  if (!contact.rows_pin_unknowns())
    return linearized_unloading_stiffness(stiffness.pattern(), stiffness.values(), contact, u, internal_force, alpha);
  const StiffnessPattern& pattern = stiffness.pattern();
  const std::vector<double>& values = stiffness.values();
  const auto n = static_cast<Eigen::Index>(pattern.size());
  const auto& candidates = contact.candidates();

  // The punch's motion: w_A = -1 on the contact nodes' vertical unknowns, 0 elsewhere.
  std::vector<char> active(static_cast<std::size_t>(n), 0);
  Eigen::VectorXd w_A = Eigen::VectorXd::Zero(n);
  for (std::size_t k = 0; k < candidates.size(); ++k)
    if (state.in_contact[k]) {
      active[static_cast<std::size_t>(candidates[k].equation)] = 1;
      w_A[candidates[k].equation] = -1.0;
    }

  // K with the active rows and columns replaced by the identity; their coupling moves to the
  // right-hand side.
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(values.size());
  const auto& start = pattern.column_start();
  const auto& row = pattern.row_index();
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n);
  for (Eigen::Index j = 0; j < n; ++j)
    for (std::int64_t p = start[static_cast<std::size_t>(j)]; p < start[static_cast<std::size_t>(j) + 1]; ++p) {
      const auto i = static_cast<Eigen::Index>(row[static_cast<std::size_t>(p)]);
      const bool row_active = active[static_cast<std::size_t>(i)], column_active = active[static_cast<std::size_t>(j)];
      if (!row_active && !column_active) entries.emplace_back(i, j, values[static_cast<std::size_t>(p)]);
      else if (!row_active) rhs[i] -= values[static_cast<std::size_t>(p)] * w_A[j];
    }
  for (Eigen::Index i = 0; i < n; ++i)
    if (active[static_cast<std::size_t>(i)]) {
      entries.emplace_back(i, i, 1.0);
      rhs[i] = w_A[i];
    }
  Eigen::SparseMatrix<double> K(n, n);
  K.setFromTriplets(entries.begin(), entries.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> factor(K);
  if (factor.info() != Eigen::Success) throw std::runtime_error("the elastic unloading stiffness could not be factored");
  const Eigen::VectorXd w = factor.solve(rhs);

  std::vector<double> reaction(static_cast<std::size_t>(n));
  pattern.multiply(values, w.data(), reaction.data());
  double rate = 0.0;  // dP/d(alpha) along w
  for (std::size_t k = 0; k < candidates.size(); ++k)
    if (state.in_contact[k]) rate -= reaction[static_cast<std::size_t>(candidates[k].equation)];
  return contact.symmetry_factor() * rate;
}

double unloading_stiffness_of_tangent(const StiffnessPattern& pattern, const std::vector<double>& tangent,
                                      const ContactDiscretization& contact, const double* u,
                                      const double* internal_force, double alpha, const ContactResult& state) {
  if (contact.carries_history())
    return incremental_unloading_stiffness(pattern, tangent, contact, u, internal_force, alpha, state);
  return linearized_unloading_stiffness(pattern, tangent, contact, u, internal_force, alpha);
}

}  // namespace indentsim
