#include "indentsim/geometry/mesh.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <unistd.h>

#include <fmt/format.h>

#include "indentsim/base/error.hpp"
#include "indentsim/geometry/punch.hpp"
#include "indentsim/materials/material.hpp"

namespace indentsim {

namespace {

struct AxisLayout {
  std::int64_t fine_elements = 0;
  double spacing = 0.0;  // uniform spacing actually used in the fine zone
  double fine_length = 0.0;
  std::int64_t graded_elements = 0;
  double ratio = 1.0;  // growth ratio actually used (<= requested)
  bool graded_uniform = false;
  double graded_uniform_size = 0.0;
};

AxisLayout layout_axis(double length, double fine_length, double spacing, double growth) {
  AxisLayout a;
  a.fine_length = std::min(fine_length, length);
  const double fine_count = std::ceil(a.fine_length / spacing - 1e-9);
  if (!(fine_count < 1e12)) throw std::length_error("axis has too many elements");
  a.fine_elements = std::max<std::int64_t>(1, static_cast<std::int64_t>(fine_count));
  a.spacing = a.fine_length / static_cast<double>(a.fine_elements);
  const double rest = length - a.fine_length;
  if (rest <= 1e-12 * length) return a;

  const double h = a.spacing;
  if (growth <= 1.0 + 1e-12) {
    a.graded_elements = std::max<std::int64_t>(1, static_cast<std::int64_t>(std::ceil(rest / h - 1e-9)));
    a.graded_uniform = true;
    a.graded_uniform_size = rest / static_cast<double>(a.graded_elements);
    return a;
  }
  // Sizes h r, h r^2, ..., h r^m with h r (r^m - 1)/(r - 1) >= rest.
  const double m = std::ceil(std::log1p(rest * (growth - 1.0) / (h * growth)) / std::log(growth) - 1e-9);
  a.graded_elements = std::max<std::int64_t>(1, static_cast<std::int64_t>(m));
  const auto count = static_cast<double>(a.graded_elements);
  if (h * count >= rest) {
    a.graded_uniform = true;
    a.graded_uniform_size = rest / count;
    return a;
  }
  // Solve h sum_{k=1..m} r^k = rest for r in (1, growth] so that the last element closes exactly.
  const auto series = [&](double r) { return h * r * (std::pow(r, count) - 1.0) / (r - 1.0); };
  double lo = 1.0 + 1e-15, hi = growth;
  for (int it = 0; it < 200 && hi - lo > 1e-15; ++it) {
    const double mid = 0.5 * (lo + hi);
    (series(mid) < rest ? lo : hi) = mid;
  }
  a.ratio = hi;
  return a;
}

std::vector<int> classify_sizes(const std::vector<double>& coords, int& classes) {
  std::vector<int> cls(coords.size() - 1);
  std::vector<double> representatives;
  for (std::size_t e = 0; e + 1 < coords.size(); ++e) {
    const double size = coords[e + 1] - coords[e];
    int found = -1;
    // Sizes come in runs (uniform zone) and then grow, so look at recent classes first.
    for (int c = static_cast<int>(representatives.size()) - 1; c >= 0; --c)
      if (std::abs(representatives[c] - size) <= 1e-10 * size) {
        found = c;
        break;
      }
    if (found < 0) {
      found = static_cast<int>(representatives.size());
      representatives.push_back(size);
    }
    cls[e] = found;
  }
  classes = static_cast<int>(representatives.size());
  return cls;
}

}  // namespace

std::vector<double> graded_axis(double length, double fine_length, double spacing, double growth) {
  const AxisLayout a = layout_axis(length, fine_length, spacing, growth);
  std::vector<double> x;
  x.reserve(static_cast<std::size_t>(a.fine_elements + a.graded_elements + 1));
  for (std::int64_t i = 0; i <= a.fine_elements; ++i) x.push_back(static_cast<double>(i) * a.spacing);
  x.back() = a.fine_length;
  double size = a.spacing;
  for (std::int64_t k = 1; k <= a.graded_elements; ++k) {
    size = a.graded_uniform ? a.graded_uniform_size : size * a.ratio;
    x.push_back(x.back() + size);
  }
  x.back() = length;
  return x;
}

std::int64_t graded_axis_count(double length, double fine_length, double spacing, double growth) {
  const AxisLayout a = layout_axis(length, fine_length, spacing, growth);
  return a.fine_elements + a.graded_elements + 1;
}

std::vector<double> lay_interfaces(std::vector<double> d, const std::vector<double>& interfaces, int min_rows,
                                   double ratio_limit) {
  std::vector<char> fixed(d.size(), 0);
  fixed.front() = fixed.back() = 1;
  std::vector<std::size_t> lines{0};  // the interfaces' nodes, found after each insertion below
  for (const double depth : interfaces) {
    const auto above = std::lower_bound(d.begin(), d.end(), depth);
    std::size_t j = static_cast<std::size_t>(above - d.begin());
    if (j > 0 && (j == d.size() || depth - d[j - 1] < d[j] - depth)) --j;
    if (!fixed[j]) {
      d[j] = depth;  // on the node already, or the nearest free node moved onto it (within half an element)
      fixed[j] = 1;
    } else {
      const auto at = static_cast<std::size_t>(std::upper_bound(d.begin(), d.end(), depth) - d.begin());
      d.insert(d.begin() + static_cast<std::ptrdiff_t>(at), depth);
      fixed.insert(fixed.begin() + static_cast<std::ptrdiff_t>(at), 1);
    }
  }
  // Each layer's band (surface to first interface, then interface to interface) divided into at
  // least min_rows rows.
  std::vector<double> laid{0.0};
  double top = 0.0;
  for (const double bottom : interfaces) {
    std::vector<double> inside;
    for (const double x : d)
      if (x > top && x < bottom) inside.push_back(x);
    if (static_cast<int>(inside.size()) + 1 < min_rows) {
      inside.clear();
      for (int r = 1; r < min_rows; ++r) inside.push_back(top + (bottom - top) * r / min_rows);
    }
    laid.insert(laid.end(), inside.begin(), inside.end());
    laid.push_back(bottom);
    top = bottom;
  }
  for (const double x : d)
    if (x > top) laid.push_back(x);
  // The 2:1 rule: halve any element more than ratio_limit times a neighbour, until none is.
  for (bool halved = true; halved;) {
    halved = false;
    std::vector<double> next{laid.front()};
    for (std::size_t i = 0; i + 1 < laid.size(); ++i) {
      const double size = laid[i + 1] - laid[i];
      double neighbour = size;
      if (i > 0) neighbour = std::min(neighbour, laid[i] - laid[i - 1]);
      if (i + 2 < laid.size()) neighbour = std::min(neighbour, laid[i + 2] - laid[i + 1]);
      // (validate() keeps interfaces apart: every element has a height, and the halving ends)
      if (size > ratio_limit * neighbour && neighbour > 0.0) {
        next.push_back(laid[i] + 0.5 * size);
        halved = true;
      }
      next.push_back(laid[i + 1]);
    }
    laid = std::move(next);
  }
  return laid;
}

double default_growth(int contact_nodes) {
  return std::clamp(1.0 + 2.5 / static_cast<double>(contact_nodes), 1.02, 1.5);
}

double MeshPlan::estimated_bytes() const {
  const double n = static_cast<double>(unknowns());
  const double elements = static_cast<double>((nodes_x - 1) * (nodes_y - 1));
  // Matrix pattern and values (~18 entries per row, a few copies), element positions
  // (64 int32 per element), sparse LU factors of a 2-D grid (~12 n log2 n entries with
  // their indices) and a dozen vectors.
  return n * 18.0 * 12.0 * 3.0 + elements * 64.0 * 4.0 + 12.0 * n * std::log2(std::max(2.0, n)) * 12.0 +
         n * 8.0 * 12.0;
}

/// A refusal of the mesh with the values that most likely caused it: a key given outside the
/// magnitudes of its kind (a cone of half-angle 1e-300, a depth in nm written as m).
static std::string with_implausible_values(const LoadCase& lc, std::string message) {
  for (const auto& w : implausible_values(lc)) message += "; note: " + w;
  return message;
}

/// The depths of the mesh's node rows, surface (0) to base (ly): the graded axis, with the layers'
/// interfaces laid into it (docs/MODEL.md §14.3).
static std::vector<double> depth_axis(const LoadCase& lc, const MeshPlan& plan) {
  std::vector<double> depth = graded_axis(lc.geometry.ly, plan.fine_depth, plan.fine_spacing, plan.growth);
  if (lc.layers.empty()) return depth;
  return lay_interfaces(std::move(depth), lc.interface_depths(), min_rows_per_layer, std::max(2.0, plan.growth));
}

MeshPlan plan_mesh(const LoadCase& lc, std::optional<double> measured_half_width) {
  const auto& m = lc.mesh;
  MeshPlan plan;
  // The contact estimate of the punch's shape (Hertz, Sneddon; docs/MODEL.md §6.1).  A flat punch's
  // contact radius is its own: the mesh puts a node on its rim.
  const auto punch = make_punch(lc.punch);
  plan.contact_half_width_estimate =
      punch->rim() ? *punch->rim()
                   : m.contact_half_width.value_or(measured_half_width.value_or(
                         punch->contact_estimate(lc.geometry.kind, lc.max_depth(), lc.geometry.ly, lc.surface_material().nu)));
  const double a_star = plan.contact_half_width_estimate;
  plan.fine_spacing = a_star / static_cast<double>(m.contact_nodes);
  // The fine zone holds the contact with a margin for the estimate, and the layer below it
  // where the Hertz stresses are largest (max shear at depth 0.78 a).
  plan.fine_width = std::min(lc.geometry.lx, m.fine_width.value_or(1.5 * a_star));
  plan.fine_depth = std::min(lc.geometry.ly, m.fine_depth.value_or(1.5 * a_star));
  plan.growth = m.growth.value_or(default_growth(m.contact_nodes));
  const std::string size_key = m.contact_half_width ? "mesh.contact_half_width" : "mesh.contact_nodes";
  if (!(plan.fine_spacing > 0.0))
    throw InputError(lc.source, size_key, "gives a zero mesh spacing");
  const double limit_per_axis = 1e8;
  if (plan.fine_width / plan.fine_spacing > limit_per_axis || plan.fine_depth / plan.fine_spacing > limit_per_axis)
    throw InputError(lc.source, size_key,
                     fmt::format("asks for a fine spacing of {:.3g} m: more than 1e8 elements along an edge",
                                 plan.fine_spacing));
  // What double precision resolves: the uniform zone holds at least one element (an override
  // below the spacing, or a specimen narrower than it, leaves none), and the specimen is at most
  // 1e9 fine spacings across -- beyond, the far field's coordinates swallow the contact's and the
  // stiffness cannot be factored (or, worse, factors into P = 0).
  const auto zone_key = [&](const char* override_key, const std::optional<double>& given, const char* size_key_name,
                            double size) -> std::string {
    return given && *given <= size ? override_key : size_key_name;
  };
  if (!(plan.fine_width >= plan.fine_spacing))
    throw InputError(lc.source, zone_key("mesh.fine_width", m.fine_width, "geometry.lx", lc.geometry.lx),
                     fmt::format("the uniform zone ({:.3g} m wide) is narrower than one fine element ({:.3g} m = a* / "
                                 "contact_nodes, a* = {:.3g} m): it must hold the contact",
                                 plan.fine_width, plan.fine_spacing, a_star));
  if (!(plan.fine_depth >= plan.fine_spacing))
    throw InputError(lc.source, zone_key("mesh.fine_depth", m.fine_depth, "geometry.ly", lc.geometry.ly),
                     fmt::format("the uniform zone ({:.3g} m deep) is shallower than one fine element ({:.3g} m = a* / "
                                 "contact_nodes, a* = {:.3g} m): it must hold the contact",
                                 plan.fine_depth, plan.fine_spacing, a_star));
  constexpr double max_spacings_across = 1e9;
  for (const auto& [key, size] : {std::pair<const char*, double>{"geometry.lx", lc.geometry.lx}, {"geometry.ly", lc.geometry.ly}})
    if (!(size / plan.fine_spacing <= max_spacings_across))
      throw InputError(lc.source, key,
                       with_implausible_values(
                           lc, fmt::format("{} m is {:.3g} fine elements ({:.3g} m) across: beyond {:g}, double "
                                           "precision cannot resolve the contact against the specimen (is it in "
                                           "metres? else use a smaller specimen or a larger mesh.contact_half_width)",
                                           size, size / plan.fine_spacing, plan.fine_spacing, max_spacings_across)));
  try {
    plan.nodes_x = graded_axis_count(lc.geometry.lx, plan.fine_width, plan.fine_spacing, plan.growth);
    plan.nodes_y = graded_axis_count(lc.geometry.ly, plan.fine_depth, plan.fine_spacing, plan.growth);
  } catch (const std::length_error&) {
    throw InputError(lc.source, size_key, "gives a mesh with too many elements");
  }
  // The interfaces' lines and the layers' rows (a 1-D axis: cheap once its graded count is sane).
  if (!lc.layers.empty() && plan.unknowns() <= lc.mesh.max_unknowns)
    plan.nodes_y = static_cast<std::int64_t>(depth_axis(lc, plan).size());

  if (plan.unknowns() > lc.mesh.max_unknowns)
    throw InputError(lc.source, size_key,
                     with_implausible_values(
                         lc, fmt::format("the mesh would have {} x {} nodes ({} unknowns), more than "
                                         "mesh.max_unknowns = {}: lower contact_nodes, check the lengths and the "
                                         "angle, or raise mesh.max_unknowns",
                                         plan.nodes_x, plan.nodes_y, plan.unknowns(), lc.mesh.max_unknowns)));
  const double pages = static_cast<double>(sysconf(_SC_PHYS_PAGES));
  const double page_size = static_cast<double>(sysconf(_SC_PAGE_SIZE));
  const double memory = pages > 0 && page_size > 0 ? pages * page_size : 8.0 * (1ull << 30);
  const double needed = plan.estimated_bytes();
  const double nnz_estimate = 18.0 * static_cast<double>(plan.unknowns());
  if (needed > 0.75 * memory || nnz_estimate > 2.0e9)
    throw InputError(lc.source, size_key,
                     fmt::format("the mesh would have {} x {} nodes ({} unknowns) and need about {:.1f} GiB, "
                                 "more than this machine can hold ({:.1f} GiB); lower contact_nodes",
                                 plan.nodes_x, plan.nodes_y, plan.unknowns(), needed / (1ull << 30),
                                 memory / (1ull << 30)));
  return plan;
}

Mesh Mesh::from_plan(const LoadCase& lc, const MeshPlan& plan) {
  std::vector<double> x = graded_axis(lc.geometry.lx, plan.fine_width, plan.fine_spacing, plan.growth);
  const std::vector<double> depth = depth_axis(lc, plan);
  std::vector<double> y(depth.size());
  for (std::size_t k = 0; k < depth.size(); ++k) y[k] = -depth[depth.size() - 1 - k];
  y.back() = 0.0;
  y.front() = -lc.geometry.ly;
  Mesh mesh(std::move(x), std::move(y));
  mesh.set_scene(lc.geometry.kind);
  if (!lc.layers.empty()) {
    std::vector<int> row_region(static_cast<std::size_t>(mesh.elements_y()));
    for (int ej = 0; ej < mesh.elements_y(); ++ej)
      row_region[static_cast<std::size_t>(ej)] =
          static_cast<int>(lc.region_at_depth(-0.5 * (mesh.y(ej) + mesh.y(ej + 1))));
    mesh.set_row_regions(std::move(row_region), static_cast<int>(lc.regions()));
  }
  return mesh;
}

void Mesh::set_row_regions(std::vector<int> row_region, int regions) {
  if (static_cast<int>(row_region.size()) != elements_y() || regions < 1 ||
      std::any_of(row_region.begin(), row_region.end(), [&](int r) { return r < 0 || r >= regions; }))
    throw std::invalid_argument("set_row_regions: one region in [0, regions) per element row");
  row_region_ = std::move(row_region);
  regions_ = regions;
}

Mesh::Mesh(std::vector<double> x, std::vector<double> y) : x_(std::move(x)), y_(std::move(y)) {
  if (x_.size() < 2 || y_.size() < 2) throw std::invalid_argument("a mesh needs at least 2 nodes per axis");
  equation_.assign(2 * static_cast<std::size_t>(nodes()), -1);
  for (int i = 0; i < nodes_x(); ++i)
    for (int j = 0; j < nodes_y(); ++j) {
      const int n = node(i, j);
      const bool base = (j == 0);
      const bool axis = (i == 0);
      if (!base && !axis) equation_[dof_u(n)] = equations_++;
      if (!base) equation_[dof_v(n)] = equations_++;
    }
  width_class_ = classify_sizes(x_, width_classes_);
  height_class_ = classify_sizes(y_, height_classes_);
}

std::array<int, 8> Mesh::element_dofs(int ei, int ej) const {
  const auto n = element_nodes(ei, ej);
  return {dof_u(n[0]), dof_u(n[1]), dof_u(n[2]), dof_u(n[3]),
          dof_v(n[0]), dof_v(n[1]), dof_v(n[2]), dof_v(n[3])};
}

std::vector<Rectangle> Mesh::class_rectangles() const {
  // A graded tensor mesh has few distinct rectangles (in axisymmetry every column differs, the
  // rows still repeat).
  std::vector<Rectangle> columns(static_cast<std::size_t>(column_classes()));
  std::vector<double> heights(static_cast<std::size_t>(height_classes()));
  for (int ei = 0; ei < elements_x(); ++ei) columns[static_cast<std::size_t>(column_class(ei))] = rectangle(ei, 0);
  for (int ej = 0; ej < elements_y(); ++ej) heights[static_cast<std::size_t>(height_class(ej))] = rectangle(0, ej).height;
  std::vector<Rectangle> classes;
  classes.reserve(columns.size() * heights.size());
  for (const Rectangle& column : columns)
    for (const double height : heights) {
      Rectangle rect = column;
      rect.height = height;
      classes.push_back(rect);
    }
  return classes;
}

}  // namespace indentsim
