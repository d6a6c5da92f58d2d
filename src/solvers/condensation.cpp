#include "indentsim/solvers/condensation.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include <cholmod.h>
#include <fmt/format.h>

#include "cholmod_common.hpp"

namespace indentsim {

PlasticExtent PlasticZoneGrowth::at(double depth) const {
  if (depths.empty() || depth <= 0.0) return {};
  if (depth <= depths.front()) {
    const double scale = std::sqrt(depth / depths.front());
    return {scale * extents.front().width, scale * extents.front().depth};
  }
  for (std::size_t k = 1; k < depths.size(); ++k)
    if (depth <= depths[k]) {
      const double t = (depth - depths[k - 1]) / (depths[k] - depths[k - 1]);
      const auto mix = [t](double lo, double hi) { return lo + t * (hi - lo); };
      return {mix(extents[k - 1].width, extents[k].width), mix(extents[k - 1].depth, extents[k].depth)};
    }
  return extents.back();
}

// K_FF's factor lives as long as the condensation: every increment recovers u_F with it.
struct FarFieldCondensation::FarFactor : CholmodCommon {
  cholmod_sparse* matrix = nullptr;  // K_FF, lower triangle
  cholmod_factor* factor = nullptr;
  // The solution and CHOLMOD's workspace, kept between solves (cholmod_l_solve2): a block of the
  // Schur complement is 64 far-field columns, 16 MB for a far field of 32 000 unknowns, and
  // allocating it afresh for each solve cost a page fault per 4 kB.
  cholmod_dense *solution = nullptr, *work_y = nullptr, *work_e = nullptr;

  FarFactor() = default;
  ~FarFactor() {
    if (work_e) cholmod_l_free_dense(&work_e, &common);
    if (work_y) cholmod_l_free_dense(&work_y, &common);
    if (solution) cholmod_l_free_dense(&solution, &common);
    if (factor) cholmod_l_free_factor(&factor, &common);
    if (matrix) cholmod_l_free_sparse(&matrix, &common);
  }
  FarFactor(const FarFactor&) = delete;
  FarFactor& operator=(const FarFactor&) = delete;

  /// Solves K_FF X = B for a dense block B (column-major, `rows` x `columns`), in place.
  void solve(double* block, std::size_t rows, std::size_t columns) {
    cholmod_dense b{};
    b.nrow = rows;
    b.ncol = columns;
    b.nzmax = rows * columns;
    b.d = rows;
    b.x = block;
    b.xtype = CHOLMOD_REAL;
    b.dtype = CHOLMOD_DOUBLE;
    if (!cholmod_l_solve2(CHOLMOD_A, factor, &b, nullptr, &solution, nullptr, &work_y, &work_e, &common))
      throw std::runtime_error("CHOLMOD could not solve with the far-field factor");
    std::memcpy(block, solution->x, rows * columns * sizeof(double));
  }
};

namespace {

// Column blocks of the Schur complement solved at once: wide enough for CHOLMOD's supernodal
// solve to work on dense blocks, narrow enough that a block of a 10^6-unknown far field stays
// near 128 MB.
std::size_t schur_block_columns(std::size_t far_unknowns) {
  const std::size_t budget = 16'000'000;  // doubles
  return std::clamp<std::size_t>(budget / std::max<std::size_t>(far_unknowns, 1), 4, 64);
}

}  // namespace

std::vector<char> near_field_equations(const Mesh& mesh, const std::vector<int>& candidate_equations,
                                       const NearField& near, const std::vector<int>& tangential_equations) {
  // The near field: all unknowns of the near elements, the vertical unknowns of the candidates.
  std::vector<char> is_near(static_cast<std::size_t>(mesh.equations()), 0);
  const int top = mesh.elements_y() - 1;
  const int columns = std::min(near.elements_x, mesh.elements_x());
  const int rows = std::min(near.elements_y, mesh.elements_y());
  for (int ei = 0; ei < columns; ++ei)
    for (int ej = top - rows + 1; ej <= top; ++ej)
      for (int dof : mesh.element_dofs(ei, ej))
        if (mesh.equation(dof) >= 0) is_near[mesh.equation(dof)] = 1;
  for (std::size_t k = 0; k < candidate_equations.size() && static_cast<int>(k) < near.contact_nodes; ++k)
    is_near[candidate_equations[k]] = 1;
  for (std::size_t k = 0; k < tangential_equations.size() && static_cast<int>(k) < near.contact_nodes; ++k)
    if (tangential_equations[k] >= 0) is_near[tangential_equations[k]] = 1;
  return is_near;
}

FarFieldCondensation::FarFieldCondensation(const ElasticStiffness& stiffness, const ContactDiscretization& contact,
                                           const NearField& near)
    : full_pattern_(stiffness.pattern()), full_values_(stiffness.values()) {
  const Mesh& mesh = stiffness.mesh();
  const auto n = static_cast<std::size_t>(full_pattern_.size());
  const auto& colptr = full_pattern_.column_start();
  const auto& rowind = full_pattern_.row_index();

  std::vector<ContactCandidate> candidates;
  std::vector<int> candidate_equations, tangential_equations;
  for (const ContactCandidate& c : contact.candidates()) {
    if (static_cast<int>(candidates.size()) >= near.contact_nodes) break;  // node i is candidate i
    candidates.push_back(c);
    candidate_equations.push_back(c.equation);
    if (contact.has_tangential_rows()) tangential_equations.push_back(c.tangential_equation);
  }
  const std::vector<char> is_near = near_field_equations(mesh, candidate_equations, near, tangential_equations);
  if (is_near.size() != n) throw std::invalid_argument("the near field's mesh is not the stiffness' mesh");

  near_of_.assign(n, -1);
  far_of_.assign(n, -1);
  for (std::size_t e = 0; e < n; ++e) {
    if (is_near[e]) {
      near_of_[e] = static_cast<std::int32_t>(near_equation_.size());
      near_equation_.push_back(static_cast<int>(e));
    } else {
      far_of_[e] = static_cast<std::int32_t>(far_equation_.size());
      far_equation_.push_back(static_cast<int>(e));
    }
  }
  const std::size_t near_count = near_equation_.size(), far_count = far_equation_.size();

  // The interface: near unknowns whose stiffness column reaches the far field.
  std::vector<std::int32_t> interface_of(near_count, -1);
  for (std::size_t r = 0; r < near_count; ++r) {
    const int e = near_equation_[r];
    for (auto p = colptr[e]; p < colptr[e + 1]; ++p)
      if (far_of_[rowind[p]] >= 0) {
        interface_of[r] = static_cast<std::int32_t>(interface_.size());
        interface_.push_back(static_cast<int>(r));
        break;
      }
  }
  const std::size_t interface_count = interface_.size();

  // The condensed pattern: the near-near stiffness entries, and the dense interface block.
  std::vector<std::int64_t> column_start(near_count + 1, 0), row_index;
  std::vector<std::int64_t> rows_of_column;
  for (std::size_t r = 0; r < near_count; ++r) {
    rows_of_column.clear();
    const int e = near_equation_[r];
    for (auto p = colptr[e]; p < colptr[e + 1]; ++p)
      if (near_of_[rowind[p]] >= 0) rows_of_column.push_back(near_of_[rowind[p]]);
    if (interface_of[r] >= 0) rows_of_column.insert(rows_of_column.end(), interface_.begin(), interface_.end());
    std::sort(rows_of_column.begin(), rows_of_column.end());
    rows_of_column.erase(std::unique(rows_of_column.begin(), rows_of_column.end()), rows_of_column.end());
    row_index.insert(row_index.end(), rows_of_column.begin(), rows_of_column.end());
    column_start[r + 1] = static_cast<std::int64_t>(row_index.size());
  }
  pattern_ = std::make_unique<StiffnessPattern>(std::move(column_start), std::move(row_index),
                                                std::vector<std::int64_t>(interface_.begin(), interface_.end()));
  const auto position = [&](std::int64_t row, std::int64_t col) {
    const auto& cs = pattern_->column_start();
    const auto& ri = pattern_->row_index();
    const auto first = ri.begin() + cs[col], last = ri.begin() + cs[col + 1];
    return static_cast<std::int64_t>(std::lower_bound(first, last, row) - ri.begin());
  };
  values_.assign(static_cast<std::size_t>(pattern_->nonzeros()), 0.0);
  for (std::size_t r = 0; r < near_count; ++r) {
    const int e = near_equation_[r];
    for (auto p = colptr[e]; p < colptr[e + 1]; ++p)
      if (near_of_[rowind[p]] >= 0) values_[position(near_of_[rowind[p]], static_cast<std::int64_t>(r))] += full_values_[p];
  }

  if (far_count > 0 && interface_count > 0) {
    // K_FF, lower triangle, in the far numbering (which keeps the free equations' order).
    far_ = std::make_unique<FarFactor>();
    cholmod_common* cm = &far_->common;
    std::size_t far_nonzeros = 0;
    for (std::size_t f = 0; f < far_count; ++f) {
      const int e = far_equation_[f];
      for (auto p = colptr[e]; p < colptr[e + 1]; ++p)
        if (far_of_[rowind[p]] >= static_cast<std::int32_t>(f)) ++far_nonzeros;
    }
    far_->matrix = cholmod_l_allocate_sparse(far_count, far_count, far_nonzeros, 1, 1, -1, CHOLMOD_REAL, cm);
    if (!far_->matrix) throw std::runtime_error("out of memory for the far-field stiffness");
    auto* fp = static_cast<SuiteSparse_long*>(far_->matrix->p);
    auto* fi = static_cast<SuiteSparse_long*>(far_->matrix->i);
    auto* fx = static_cast<double*>(far_->matrix->x);
    std::size_t k = 0;
    for (std::size_t f = 0; f < far_count; ++f) {
      fp[f] = static_cast<SuiteSparse_long>(k);
      const int e = far_equation_[f];
      for (auto p = colptr[e]; p < colptr[e + 1]; ++p)
        if (far_of_[rowind[p]] >= static_cast<std::int32_t>(f)) {
          fi[k] = far_of_[rowind[p]];
          fx[k++] = full_values_[p];
        }
    }
    fp[far_count] = static_cast<SuiteSparse_long>(k);
    far_->factor = analyze_serialized(far_->matrix, cm);
    if (!far_->factor || !cholmod_l_factorize(far_->matrix, far_->factor, cm) || cm->status != CHOLMOD_OK)
      throw std::runtime_error(fmt::format("the far-field stiffness could not be factored (CHOLMOD status {}): "
                                           "is the far field held by the clamped base?",
                                           cm->status));

    // K_red(B, B) -= K_BF K_FF^{-1} K_FB, a block of interface columns at a time.
    const std::size_t width = std::min(schur_block_columns(far_count), interface_count);
    std::vector<double> block(far_count * width);
    for (std::size_t first = 0; first < interface_count; first += width) {
      const std::size_t count = std::min(width, interface_count - first);
      std::fill(block.begin(), block.begin() + static_cast<std::ptrdiff_t>(far_count * count), 0.0);
      for (std::size_t j = 0; j < count; ++j) {
        const int e = near_equation_[interface_[first + j]];
        for (auto p = colptr[e]; p < colptr[e + 1]; ++p)
          if (far_of_[rowind[p]] >= 0) block[j * far_count + far_of_[rowind[p]]] = full_values_[p];
      }
      far_->solve(block.data(), far_count, count);
      for (std::size_t i = 0; i < interface_count; ++i) {
        const int row = interface_[i];
        const int e = near_equation_[row];
        // Row e of K restricted to the far field = column e (K is symmetric).
        for (std::size_t j = 0; j < count; ++j) {
          double s = 0.0;
          for (auto p = colptr[e]; p < colptr[e + 1]; ++p)
            if (far_of_[rowind[p]] >= 0) s += full_values_[p] * block[j * far_count + far_of_[rowind[p]]];
          values_[position(row, interface_[first + j])] -= s;
        }
      }
    }
  }

  // Candidates renumbered, scaled by the condensed diagonal (the softer Schur diagonal).
  for (ContactCandidate& c : candidates) {
    c.equation = near_of_[c.equation];
    c.scale = values_[pattern_->diagonal_position(c.equation)];
    if (c.tangential_equation >= 0) {
      c.tangential_equation = near_of_[c.tangential_equation];  // -1 when the contact writes no row for it
      c.tangential_scale = c.tangential_equation >= 0 ? values_[pattern_->diagonal_position(c.tangential_equation)] : 0.0;
    }
  }
  contact_ = contact.on_candidates(std::move(candidates));

  // The near elements (near_field_equations' columns and rows), as the near system's slots.
  const int top = mesh.elements_y() - 1;
  const int columns = std::min(near.elements_x, mesh.elements_x());
  const int rows = std::min(near.elements_y, mesh.elements_y());
  for (int ei = 0; ei < columns; ++ei)
    for (int ej = top - rows + 1; ej <= top; ++ej) {
      ElementSlot ne;
      ne.ei = ei;
      ne.ej = ej;
      const auto dofs = mesh.element_dofs(ei, ej);
      for (int a = 0; a < 8; ++a) {
        const int e = mesh.equation(dofs[a]);
        ne.unknowns[a] = e < 0 ? -1 : near_of_[e];
      }
      for (int a = 0; a < 8; ++a)
        for (int b = 0; b < 8; ++b)
          ne.positions[8 * a + b] =
              ne.unknowns[a] < 0 || ne.unknowns[b] < 0 ? -1 : position(ne.unknowns[a], ne.unknowns[b]);
      elements_.push_back(ne);
    }
}

FarFieldCondensation::~FarFieldCondensation() = default;

void FarFieldCondensation::restrict_to_near(const std::vector<double>& u, std::vector<double>& u_near) const {
  u_near.resize(near_equation_.size());
  for (std::size_t r = 0; r < near_equation_.size(); ++r) u_near[r] = u[near_equation_[r]];
}

void FarFieldCondensation::expand(const std::vector<double>& u_near, std::vector<double>& u) const {
  u.assign(static_cast<std::size_t>(full_pattern_.size()), 0.0);
  for (std::size_t r = 0; r < near_equation_.size(); ++r) u[near_equation_[r]] = u_near[r];
  if (!far_) return;
  // Right-hand side -K_FB u_B, solved with the kept factor.
  const auto& colptr = full_pattern_.column_start();
  const auto& rowind = full_pattern_.row_index();
  std::vector<double> far(far_equation_.size(), 0.0);
  for (int r : interface_) {
    const int e = near_equation_[r];
    for (auto p = colptr[e]; p < colptr[e + 1]; ++p)
      if (far_of_[rowind[p]] >= 0) far[far_of_[rowind[p]]] -= full_values_[p] * u_near[r];
  }
  far_->solve(far.data(), far.size(), 1);
  for (std::size_t f = 0; f < far.size(); ++f) u[far_equation_[f]] = far[f];
}

void CondensedBulk::internal_force(const double* u, double* f) {
  condensation_.pattern().multiply(condensation_.values(), u, f);
  if (nonlinear_) nonlinear_->add_force_corrections(condensation_.elements(), u, f);
}

void CondensedBulk::tangent(const double* u, double* values) {
  const auto& k = condensation_.values();
  std::copy(k.begin(), k.end(), values);
  if (nonlinear_) nonlinear_->add_tangent_corrections(condensation_.elements(), u, values);
}

}  // namespace indentsim
