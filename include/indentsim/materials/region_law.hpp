#pragma once
// Material regions (docs/MODEL.md §14.1): a specimen of layers on a substrate has one point law
// per region, and the region laws here hand each Gauss point of the mesh (index 4 * element + g)
// to its region's law, as MFEM's piecewise coefficients hand each element to its attribute's.
// Each region's law numbers only its own points (in the mesh's order), so its history holds
// those points alone; a specimen of one region never builds these (its law is the region's own).
#include <cstddef>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "indentsim/materials/finite_strain_law.hpp"
#include "indentsim/materials/point_law.hpp"

namespace indentsim {

/// Linear elasticity as a point law without history: a region that never yields, inside a bulk
/// that is inelastic elsewhere.  Its points are always elastic, so the inelastic element loops
/// leave its elements to the assembled elastic stiffness.
class ElasticPointLaw final : public PointLaw {
public:
  explicit ElasticPointLaw(const ElasticMaterial& material) : stiffness_(isotropic_stiffness(material.lame())) {}
  bool elastic(std::size_t, const VoigtVector&) const override { return true; }
  PointResponse respond(std::size_t point, const VoigtVector& strain) const override;
  void commit(std::size_t, const VoigtVector&) override {}
  bool has_yielded(std::size_t) const override { return false; }
  std::vector<double> history() const override { return {}; }
  void restore(const std::vector<double>& history) override;
  std::optional<std::string> history_violation(std::size_t, const VoigtVector&) const override { return std::nullopt; }

private:
  ConstitutiveMatrix stiffness_;
};

/// Which region each Gauss point of the mesh belongs to, and its number among its region's points.
class PointRegions {
public:
  /// `point_region[p]`: the region of Gauss point p, in [0, regions).
  PointRegions(std::vector<int> point_region, int regions);
  int regions() const { return static_cast<int>(count_.size()); }
  int region(std::size_t point) const { return point_region_[point]; }
  std::size_t local(std::size_t point) const { return local_[point]; }
  /// The number of points in `region`: what its law is sized for.
  std::size_t points(int region) const { return count_[static_cast<std::size_t>(region)]; }

private:
  std::vector<int> point_region_;
  std::vector<std::size_t> local_, count_;
};

/// The history of several regions' laws as one vector: the number of regions, each region's
/// length, then their histories in region order.
std::vector<double> join_region_histories(const std::vector<std::vector<double>>& histories);
/// Its inverse; throws std::invalid_argument when `joined` is not of `regions` regions.
std::vector<std::vector<double>> split_region_histories(const std::vector<double>& joined, int regions);

/// What a law per region shares, whatever the strain measure (`Law` is PointLaw or
/// FiniteStrainPointLaw): a point's law and its number there, the load-history flags sent to every
/// region, and the regions' histories joined.
template <class Law>
class RegionLaws {
public:
  RegionLaws(PointRegions regions, std::vector<std::unique_ptr<Law>> laws)
      : regions_(std::move(regions)), laws_(std::move(laws)) {
    if (static_cast<int>(laws_.size()) != regions_.regions()) throw std::invalid_argument("one law per region");
  }

protected:
  const Law& law(std::size_t point) const { return *laws_[static_cast<std::size_t>(regions_.region(point))]; }
  Law& law(std::size_t point) { return *laws_[static_cast<std::size_t>(regions_.region(point))]; }
  std::size_t local(std::size_t point) const { return regions_.local(point); }
  void set_loading_of_all(bool beyond_previous_peak) {
    for (auto& law : laws_) law->set_loading(beyond_previous_peak);
  }
  void set_time_step_of_all(double seconds) {
    for (auto& law : laws_) law->set_time_step(seconds);
  }
  std::vector<double> joined_history() const {
    std::vector<std::vector<double>> histories;
    for (const auto& law : laws_) histories.push_back(law->history());
    return join_region_histories(histories);
  }
  void restore_all(const std::vector<double>& history) {
    const auto histories = split_region_histories(history, regions_.regions());
    for (std::size_t r = 0; r < laws_.size(); ++r) laws_[r]->restore(histories[r]);
  }
  const std::vector<std::unique_ptr<Law>>& laws() const { return laws_; }

private:
  PointRegions regions_;
  std::vector<std::unique_ptr<Law>> laws_;
};

/// A point law per region, behind one PointLaw.  Parameter derivatives are not given (nullopt):
/// with several materials the sensitivities are taken by finite differences (MODEL.md §14.1).
class RegionPointLaw final : public PointLaw, private RegionLaws<PointLaw> {
public:
  /// laws[r] is region r's law, sized for regions.points(r).
  RegionPointLaw(PointRegions regions, std::vector<std::unique_ptr<PointLaw>> laws)
      : RegionLaws(std::move(regions), std::move(laws)) {}
  bool elastic(std::size_t point, const VoigtVector& strain) const override { return law(point).elastic(local(point), strain); }
  PointResponse respond(std::size_t point, const VoigtVector& strain) const override {
    return law(point).respond(local(point), strain);
  }
  void commit(std::size_t point, const VoigtVector& strain) override { law(point).commit(local(point), strain); }
  bool has_yielded(std::size_t point) const override { return law(point).has_yielded(local(point)); }
  void set_loading(bool beyond_previous_peak) override { set_loading_of_all(beyond_previous_peak); }
  void set_time_step(double seconds) override { set_time_step_of_all(seconds); }
  std::vector<double> history() const override { return joined_history(); }
  void restore(const std::vector<double>& history) override { restore_all(history); }
  std::optional<std::string> history_violation(std::size_t point, const VoigtVector& strain) const override {
    return law(point).history_violation(local(point), strain);
  }
};

/// A finite-strain point law per region, behind one FiniteStrainPointLaw.
class RegionFiniteStrainLaw final : public FiniteStrainPointLaw, private RegionLaws<FiniteStrainPointLaw> {
public:
  RegionFiniteStrainLaw(PointRegions regions, std::vector<std::unique_ptr<FiniteStrainPointLaw>> laws)
      : RegionLaws(std::move(regions), std::move(laws)) {}
  FiniteStrainResponse respond(std::size_t point, const Deformation& F) const override {
    return law(point).respond(local(point), F);
  }
  NominalTangent unloading_tangent(std::size_t point, const Deformation& F) const override {
    return law(point).unloading_tangent(local(point), F);
  }
  void commit(std::size_t point, const Deformation& F) override { law(point).commit(local(point), F); }
  bool has_yielded(std::size_t point) const override { return law(point).has_yielded(local(point)); }
  void set_loading(bool beyond_previous_peak) override { set_loading_of_all(beyond_previous_peak); }
  void set_time_step(double seconds) override { set_time_step_of_all(seconds); }
  std::vector<double> history() const override { return joined_history(); }
  void restore(const std::vector<double>& history) override { restore_all(history); }
  /// Symmetric when every region's is.
  bool symmetric_tangent() const override {
    for (const auto& law : laws())
      if (!law->symmetric_tangent()) return false;
    return true;
  }
};

}  // namespace indentsim
