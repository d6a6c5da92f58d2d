#include "indentsim/materials/region_law.hpp"

#include <stdexcept>

namespace indentsim {

PointResponse ElasticPointLaw::respond(std::size_t, const VoigtVector& strain) const {
  PointResponse r;
  r.stress = stiffness_ * strain;
  r.tangent = stiffness_;
  r.strain_intensity = strain_intensity(strain);
  return r;
}

void ElasticPointLaw::restore(const std::vector<double>& history) {
  if (!history.empty()) throw std::invalid_argument("an elastic region carries no history");
}

PointRegions::PointRegions(std::vector<int> point_region, int regions)
    : point_region_(std::move(point_region)), count_(static_cast<std::size_t>(regions), 0) {
  local_.reserve(point_region_.size());
  for (const int r : point_region_) {
    if (r < 0 || r >= regions) throw std::invalid_argument("PointRegions: a region outside [0, regions)");
    local_.push_back(count_[static_cast<std::size_t>(r)]++);
  }
}

std::vector<double> join_region_histories(const std::vector<std::vector<double>>& histories) {
  std::vector<double> joined{static_cast<double>(histories.size())};
  for (const auto& h : histories) joined.push_back(static_cast<double>(h.size()));
  for (const auto& h : histories) joined.insert(joined.end(), h.begin(), h.end());
  return joined;
}

std::vector<std::vector<double>> split_region_histories(const std::vector<double>& joined, int regions) {
  const auto n = static_cast<std::size_t>(regions);
  if (joined.size() < 1 + n || joined[0] != static_cast<double>(regions))
    throw std::invalid_argument("a history of another number of material regions");
  std::vector<std::vector<double>> histories(n);
  std::size_t at = 1 + n;
  for (std::size_t r = 0; r < n; ++r) {
    const double length = joined[1 + r];
    if (!(length >= 0.0 && length <= static_cast<double>(joined.size() - at)) || length != static_cast<double>(static_cast<std::size_t>(length)))
      throw std::invalid_argument("a region's history is longer than the history holds");
    const auto count = static_cast<std::size_t>(length);
    histories[r].assign(joined.begin() + static_cast<std::ptrdiff_t>(at), joined.begin() + static_cast<std::ptrdiff_t>(at + count));
    at += count;
  }
  if (at != joined.size()) throw std::invalid_argument("a history longer than its regions' histories");
  return histories;
}

}  // namespace indentsim
