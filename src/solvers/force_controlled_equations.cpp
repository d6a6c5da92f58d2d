#include "indentsim/solvers/force_controlled_equations.hpp"

#include <algorithm>
#include <set>
#include <stdexcept>

namespace indentsim {

namespace {

// The column holding value position p of a compressed-column pattern.
std::int64_t column_of(const StiffnessPattern& pattern, std::int64_t p) {
  const auto& start = pattern.column_start();
  return std::upper_bound(start.begin(), start.end(), p) - start.begin() - 1;
}

}  // namespace

ForceControlledEquations::ForceControlledEquations(ContactEquations& depth_controlled,
                                                   const ContactDiscretization& contact, double force_scale,
                                                   double largest_force)
    : depth_controlled_(depth_controlled),
      contact_(contact),
      force_scale_(force_scale),
      largest_force_(largest_force),
      pattern_({0}, {}) {
  if (!(largest_force > 0.0)) throw std::invalid_argument("force control: the largest force must be positive");
  depth_controlled_.keep_bulk_rows(true);
  const StiffnessPattern& inner = depth_controlled_.pattern();
  const std::int64_t n = inner.size();
  // The border's unknowns: every column of a candidate's row (the force row) and every contact
  // row (the depth column), one symmetric set so that the pattern stays symmetric.
  std::set<std::int64_t> border;
  for (const auto& c : contact_.candidates())
    for (std::int64_t p : inner.row_positions(c.equation)) border.insert(column_of(inner, p));
  for (int equation : contact_.row_equations()) border.insert(equation);

  std::vector<std::int64_t> column_start{0}, row_index;
  inner_position_.resize(static_cast<std::size_t>(inner.nonzeros()));
  std::vector<std::int64_t> last_row_position(static_cast<std::size_t>(n), -1);  // (n, j) per column j
  for (std::int64_t j = 0; j < n; ++j) {
    for (std::int64_t p = inner.column_start()[j]; p < inner.column_start()[j + 1]; ++p) {
      inner_position_[static_cast<std::size_t>(p)] = static_cast<std::int64_t>(row_index.size());
      row_index.push_back(inner.row_index()[p]);
    }
    if (border.count(j)) {
      last_row_position[static_cast<std::size_t>(j)] = static_cast<std::int64_t>(row_index.size());
      row_index.push_back(n);
    }
    column_start.push_back(static_cast<std::int64_t>(row_index.size()));
  }
  std::vector<std::int64_t> column_position(static_cast<std::size_t>(n), -1);  // (i, n) per row i
  for (std::int64_t i : border) {
    column_position[static_cast<std::size_t>(i)] = static_cast<std::int64_t>(row_index.size());
    row_index.push_back(i);
  }
  corner_ = static_cast<std::int64_t>(row_index.size());
  row_index.push_back(n);
  column_start.push_back(static_cast<std::int64_t>(row_index.size()));
  // The depth is eliminated last, after any dense block of the depth-controlled system.
  std::vector<std::int64_t> dense = inner.dense_block();
  dense.push_back(n);
  pattern_ = StiffnessPattern(std::move(column_start), std::move(row_index), std::move(dense));
  pattern_.eliminate_last(n);

  for (int equation : contact_.row_equations()) border_column_.push_back(column_position[static_cast<std::size_t>(equation)]);
  for (const auto& c : contact_.candidates()) {
    std::vector<std::pair<std::int64_t, std::int64_t>> row;
    for (std::int64_t p : inner.row_positions(c.equation))
      row.emplace_back(last_row_position[static_cast<std::size_t>(column_of(inner, p))], p);
    force_row_.push_back(std::move(row));
  }
  inner_values_.resize(static_cast<std::size_t>(inner.nonzeros()));
  internal_force_.assign(static_cast<std::size_t>(n), 0.0);
}

double force_control_reference(double target, double largest_force) {
  return std::max(target, 1e-2 * largest_force);
}

void ForceControlledEquations::residual(const double* x, double target, double* f) {
  const std::int64_t n = depth_controlled_.size();
  const double alpha = x[n];
  depth_controlled_.residual(x, alpha, f);
  // The contact's own force of the state, from the internal force on its rows (where the
  // contact state reads it: ContactDiscretization::evaluate).
  const auto& rows = contact_.row_equations();
  const auto& row_force = depth_controlled_.contact_row_forces();
  for (std::size_t i = 0; i < rows.size(); ++i) internal_force_[static_cast<std::size_t>(rows[i])] = row_force[i];
  const ContactResult state = contact_.evaluate(x, internal_force_.data(), alpha);
  residual_x_.assign(x, x + n + 1);
  residual_in_contact_ = state.in_contact;
  f[n] = (state.force - target) * force_scale_ / force_control_reference(target, largest_force_);
}

void ForceControlledEquations::embed(const std::vector<double>& inner, double* values) const {
  std::fill(values, values + pattern_.nonzeros(), 0.0);
  for (std::size_t p = 0; p < inner.size(); ++p) values[inner_position_[p]] = inner[p];
}

void ForceControlledEquations::jacobian(const double* x, double target, double* values) {
  const std::int64_t n = depth_controlled_.size();
  const double alpha = x[n];
  depth_controlled_.jacobian(x, alpha, inner_values_.data());
  embed(inner_values_, values);
  const auto& rows = contact_.row_equations();
  const auto& row_force = depth_controlled_.contact_row_forces();
  // The depth column: how the contact rows move with alpha at fixed u.
  std::fill(internal_force_.begin(), internal_force_.end(), 0.0);
  contact_.write_depth_derivative_rows(x, alpha, row_force.data(), internal_force_.data());
  for (std::size_t i = 0; i < rows.size(); ++i)
    values[border_column_[i]] = internal_force_[static_cast<std::size_t>(rows[i])];
  // The force row: P = -f sum over the candidates in contact of their internal force.
  if (!std::equal(x, x + n + 1, residual_x_.begin(), residual_x_.end())) {
    for (std::size_t i = 0; i < rows.size(); ++i) internal_force_[static_cast<std::size_t>(rows[i])] = row_force[i];
    residual_x_.assign(x, x + n + 1);
    residual_in_contact_ = contact_.evaluate(x, internal_force_.data(), alpha).in_contact;
  }
  const double weight = -contact_.symmetry_factor() * force_scale_ / force_control_reference(target, largest_force_);
  const auto& bulk_rows = depth_controlled_.bulk_rows();
  for (std::size_t k = 0; k < force_row_.size(); ++k) {
    if (!residual_in_contact_[k]) continue;
    for (std::size_t p = 0; p < force_row_[k].size(); ++p) values[force_row_[k][p].first] += weight * bulk_rows[k][p];
  }
}

bool ForceControlledEquations::pivot_reference(double* values) {
  // The depth-controlled reference, and a unit pivot for the depth: it is ordered last, so the
  // reference's pivots for the rest are those of the depth-controlled system.
  if (!depth_controlled_.pivot_reference(inner_values_.data())) return false;
  embed(inner_values_, values);
  values[corner_] = 1.0;
  return true;
}

}  // namespace indentsim
