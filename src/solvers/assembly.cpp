#include "indentsim/solvers/assembly.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace indentsim {

StiffnessPattern::StiffnessPattern(const Mesh& mesh) : size_(mesh.equations()) {
  // Column lists: each free unknown couples to the free unknowns of the (up to 4) elements
  // around its node.  Collect, sort, deduplicate per column.
  std::vector<std::vector<std::int64_t>> columns(static_cast<std::size_t>(size_));
  for (auto& c : columns) c.reserve(18);
  for (int ei = 0; ei < mesh.elements_x(); ++ei)
    for (int ej = 0; ej < mesh.elements_y(); ++ej) {
      const auto dofs = mesh.element_dofs(ei, ej);
      for (int b = 0; b < 8; ++b) {
        const int col = mesh.equation(dofs[b]);
        if (col < 0) continue;
        for (int a = 0; a < 8; ++a) {
          const int row = mesh.equation(dofs[a]);
          if (row >= 0) columns[col].push_back(row);
        }
      }
    }
  column_start_.assign(static_cast<std::size_t>(size_) + 1, 0);
  for (std::int64_t c = 0; c < size_; ++c) {
    auto& rows = columns[c];
    std::sort(rows.begin(), rows.end());
    rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
    column_start_[c + 1] = column_start_[c] + static_cast<std::int64_t>(rows.size());
  }
  if (column_start_.back() > std::numeric_limits<std::int32_t>::max())
    throw std::length_error("stiffness pattern exceeds 2^31 entries");
  row_index_.reserve(static_cast<std::size_t>(column_start_.back()));
  diagonal_.assign(static_cast<std::size_t>(size_), -1);
  for (std::int64_t c = 0; c < size_; ++c) {
    for (std::int64_t r : columns[c]) {
      if (r == c) diagonal_[c] = static_cast<std::int64_t>(row_index_.size());
      row_index_.push_back(r);
    }
    std::vector<std::int64_t>().swap(columns[c]);
  }

  element_position_.assign(64 * static_cast<std::size_t>(mesh.elements()), -1);
  for (int ei = 0; ei < mesh.elements_x(); ++ei)
    for (int ej = 0; ej < mesh.elements_y(); ++ej) {
      const auto dofs = mesh.element_dofs(ei, ej);
      std::int32_t* pos = &element_position_[64 * static_cast<std::size_t>(mesh.element(ei, ej))];
      for (int a = 0; a < 8; ++a) {
        const int row = mesh.equation(dofs[a]);
        if (row < 0) continue;
        for (int b = 0; b < 8; ++b) {
          const int col = mesh.equation(dofs[b]);
          if (col < 0) continue;
          const auto first = row_index_.begin() + column_start_[col];
          const auto last = row_index_.begin() + column_start_[col + 1];
          pos[8 * a + b] = static_cast<std::int32_t>(std::lower_bound(first, last, row) - row_index_.begin());
        }
      }
    }
}

StiffnessPattern::StiffnessPattern(std::vector<std::int64_t> column_start, std::vector<std::int64_t> row_index,
                                   std::vector<std::int64_t> dense_block)
    : size_(static_cast<std::int64_t>(column_start.size()) - 1),
      column_start_(std::move(column_start)),
      row_index_(std::move(row_index)),
      dense_block_(std::move(dense_block)) {
  if (size_ < 0 || column_start_.back() != static_cast<std::int64_t>(row_index_.size()))
    throw std::invalid_argument("inconsistent compressed-column pattern");
  for (std::size_t k = 0; k < dense_block_.size(); ++k)
    if (dense_block_[k] < 0 || dense_block_[k] >= size_ || (k > 0 && dense_block_[k] <= dense_block_[k - 1]))
      throw std::invalid_argument("dense block: unknowns out of range or not increasing");
  diagonal_.assign(static_cast<std::size_t>(size_), -1);
  for (std::int64_t c = 0; c < size_; ++c) {
    const auto first = row_index_.begin() + column_start_[c];
    const auto last = row_index_.begin() + column_start_[c + 1];
    const auto d = std::lower_bound(first, last, c);
    if (d == last || *d != c) throw std::invalid_argument("compressed-column pattern without its diagonal");
    diagonal_[c] = d - row_index_.begin();
  }
}

std::vector<std::int64_t> StiffnessPattern::row_positions(int equation) const {
  std::vector<std::int64_t> positions;
  // Symmetric pattern: the columns holding row `equation` are the rows of column `equation`.
  for (std::int64_t p = column_start_[equation]; p < column_start_[equation + 1]; ++p) {
    const std::int64_t col = row_index_[p];
    const auto first = row_index_.begin() + column_start_[col];
    const auto last = row_index_.begin() + column_start_[col + 1];
    positions.push_back(std::lower_bound(first, last, equation) - row_index_.begin());
  }
  return positions;
}

void StiffnessPattern::scatter(int element, const ElementMatrix& ke, std::vector<double>& values) const {
  const std::int32_t* pos = element_positions(element);
  for (int a = 0; a < 8; ++a)
    for (int b = 0; b < 8; ++b)
      if (pos[8 * a + b] >= 0) values[pos[8 * a + b]] += ke(a, b);
}

void StiffnessPattern::multiply(const std::vector<double>& values, const double* x, double* y) const {
  std::fill(y, y + size_, 0.0);
  for (std::int64_t c = 0; c < size_; ++c) {
    const double xc = x[c];
    for (std::int64_t p = column_start_[c]; p < column_start_[c + 1]; ++p) y[row_index_[p]] += values[p] * xc;
  }
}

ElementVector gather(const Mesh& mesh, int ei, int ej, const double* u) {
  const auto dofs = mesh.element_dofs(ei, ej);
  ElementVector ue;
  for (int a = 0; a < 8; ++a) {
    const int eq = mesh.equation(dofs[a]);
    ue[a] = eq < 0 ? 0.0 : u[eq];
  }
  return ue;
}

ElasticStiffness::ElasticStiffness(const Mesh& mesh, std::vector<ElasticMaterial> by_region,
                                   const StiffnessPattern& pattern)
    : mesh_(mesh), pattern_(pattern), by_region_(std::move(by_region)) {
  if (static_cast<int>(by_region_.size()) != mesh.regions())
    throw std::invalid_argument("ElasticStiffness: one material per region of the mesh");
  // One representative rectangle per (column class, height class), its quadrature, and a matrix
  // per (column class, row class): each (height class, region) pair the rows have.
  const std::vector<Rectangle> rectangles = mesh.class_rectangles();
  for (const Rectangle& rect : rectangles) quadrature_by_class_.push_back(mesh.kinematics().quadrature(rect, mesh.element_kind()));
  for (int ej = 0; ej < mesh.elements_y(); ++ej) {
    std::size_t c = 0;
    while (c < row_region_.size() && (row_height_class_[c] != mesh.height_class(ej) || row_region_[c] != mesh.region(ej))) ++c;
    if (c == row_region_.size()) {
      row_height_class_.push_back(mesh.height_class(ej));
      row_region_.push_back(mesh.region(ej));
    }
    row_class_.push_back(c);
  }
  for (int column = 0; column < mesh.column_classes(); ++column)
    for (std::size_t c = 0; c < row_region_.size(); ++c)
      by_class_.push_back(mesh.kinematics().elastic_stiffness(
          rectangles[static_cast<std::size_t>(column) * static_cast<std::size_t>(mesh.height_classes()) +
                     static_cast<std::size_t>(row_height_class_[c])],
          by_region_[static_cast<std::size_t>(row_region_[c])].lame(), mesh.element_kind()));

  values_.assign(static_cast<std::size_t>(pattern.nonzeros()), 0.0);
  for (int ei = 0; ei < mesh.elements_x(); ++ei)
    for (int ej = 0; ej < mesh.elements_y(); ++ej) pattern.scatter(mesh.element(ei, ej), cached_matrix(ei, ej), values_);
}

ElementVector ElasticStiffness::element_force(int ei, int ej) const {
  if (committed_u_.empty()) return ElementVector::Zero();
  return cached_matrix(ei, ej) * gather(mesh_, ei, ej, committed_u_.data());
}

void ElasticStiffness::commit(const double* u) {
  committed_u_.assign(u, u + pattern_.size());
  // Reported only (how close the elastic solution comes to a yield limit); no material law here.
  double largest = 0.0;
  for (int ei = 0; ei < mesh_.elements_x(); ++ei)
    for (int ej = 0; ej < mesh_.elements_y(); ++ej)
      for (const VoigtVector& strain : strains(ei, ej, u)) largest = std::max(largest, strain_intensity(strain));
  max_strain_intensity_ = largest;
}

void ElasticStiffness::restore(const std::vector<double>& history, const double* u) {
  if (!history.empty()) throw std::invalid_argument("an elastic model carries no history");
  commit(u);  // elasticity has no history: committing u rebuilds everything
}

std::array<GaussPointState, 4> ElasticStiffness::gauss_point_states(int ei, int ej) const {
  std::array<GaussPointState, 4> states;
  if (committed_u_.empty()) return states;
  const auto eps = strains(ei, ej, committed_u_.data());
  const ConstitutiveMatrix d = isotropic_stiffness(material(ej).lame());
  for (int g = 0; g < 4; ++g) {
    states[g].stress = d * eps[g];
    states[g].strain_intensity = strain_intensity(eps[g]);
  }
  return states;
}

std::array<VoigtVector, 4> ElasticStiffness::strains(int ei, int ej, const double* u) const {
  return quadrature(ei, ej).strains(gather(mesh_, ei, ej, u));
}

std::vector<ElementSlot> whole_mesh_slots(const Mesh& mesh, const StiffnessPattern& pattern) {
  std::vector<ElementSlot> slots;
  slots.reserve(static_cast<std::size_t>(mesh.elements()));
  for (int ei = 0; ei < mesh.elements_x(); ++ei)
    for (int ej = 0; ej < mesh.elements_y(); ++ej) {
      ElementSlot slot;
      slot.ei = ei;
      slot.ej = ej;
      const auto dofs = mesh.element_dofs(ei, ej);
      for (int a = 0; a < 8; ++a) slot.unknowns[a] = mesh.equation(dofs[a]);
      const std::int32_t* pos = pattern.element_positions(mesh.element(ei, ej));
      for (int p = 0; p < 64; ++p) slot.positions[p] = pos[p];
      slots.push_back(slot);
    }
  return slots;
}

}  // namespace indentsim
