// The contact edge resolved inside an element (contact_half_width, include/indentsim/solvers/contact.hpp):
// against Hertz's and Sneddon's edges under refinement, never a node's position, and converging
// with an observed order on two plastic cases, whose edge has no closed form.
#include <algorithm>
#include <cmath>
#include <iostream>
#include <numbers>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "indentsim/simulation/simulation.hpp"
#include "test_support.hpp"

using namespace indentsim;
using indentsim::testing::contact_modulus;
using indentsim::testing::shipped_case;

namespace {

/// The loading curve's (P, a), how often a sat on a node of the top surface, and how often it was
/// the fallback, the middle of the edge's element (an extrapolation the active set contradicts).
struct EdgeRun {
  std::vector<double> force, half_width;
  int on_a_node = 0;
  int fallbacks = 0;
};

EdgeRun run_edges(const LoadCase& lc) {
  Simulation sim(lc);
  EdgeRun run;
  sim.run([&](const IncrementRecord& r) {
    if (!(r.force > 0.0)) return;
    run.force.push_back(r.force);
    run.half_width.push_back(r.half_width);
    const auto& cs = sim.contact_boundary().candidates();
    const double spacing = cs[1].x - cs[0].x;
    for (const auto& c : cs)
      if (std::abs(c.x - r.half_width) <= 1e-9 * spacing) ++run.on_a_node;
    const int n = sim.contact().outermost;
    if (n + 1 < static_cast<int>(cs.size()) && std::abs(0.5 * (cs[n].x + cs[n + 1].x) - r.half_width) <= 1e-9 * spacing)
      ++run.fallbacks;
  });
  return run;
}

/// The largest relative error of a against theory a(P) over the last two thirds of the loading.
template <class Theory>
double largest_edge_error(const EdgeRun& run, Theory theory) {
  double worst = 0.0;
  for (std::size_t k = run.force.size() / 3; k < run.force.size(); ++k)
    worst = std::max(worst, std::abs(run.half_width[k] / theory(run.force[k]) - 1.0));
  return worst;
}

/// The mean relative difference of a between two resolutions of the same load steps over the last
/// two thirds of the loading (the edge's position within its element varies from step to step, so
/// one step alone says little about the order).
double mean_difference(const EdgeRun& coarse, const EdgeRun& fine) {
  EXPECT_EQ(coarse.half_width.size(), fine.half_width.size());
  const std::size_t n = std::min(coarse.half_width.size(), fine.half_width.size());
  double sum = 0.0;
  int count = 0;
  for (std::size_t k = n / 3; k < n; ++k, ++count)
    sum += std::abs(coarse.half_width[k] - fine.half_width[k]) / fine.half_width[k];
  return sum / count;
}

}  // namespace

TEST(ContactEdge, ElasticEdgesConvergeToHertzAndSneddon) {
  // Sphere (Hertz): a = (3 P R / 4 E*)^(1/3).  Cone (Sneddon): P = pi E* a^2 / (2 tan theta).
  // The plane-strain Hertz edge is tests/test_elastic_contact.cpp's P(a).
  const auto sphere = [](int nodes) {
    const LoadCase lc = shipped_case("axisymmetric/elastic_sphere.toml", {fmt::format("mesh.contact_nodes={}", nodes)});
    const double e_star = contact_modulus(lc), radius = lc.punch.radius;
    const EdgeRun run = run_edges(lc);
    EXPECT_EQ(run.on_a_node, 0);
    EXPECT_EQ(run.fallbacks, 0);
    return largest_edge_error(run, [&](double P) { return std::cbrt(3 * P * radius / (4 * e_star)); });
  };
  const auto cone = [](int nodes) {
    const LoadCase lc = shipped_case("axisymmetric/berkovich_cone.toml",
                                     {fmt::format("mesh.contact_nodes={}", nodes), "material.model=\"elastic\"",
                                      "load.path=[0, 1e-6]", "load.increments=10"});
    const double e_star = contact_modulus(lc), tan_theta = std::tan(lc.punch.half_angle * std::numbers::pi / 180);
    const EdgeRun run = run_edges(lc);
    EXPECT_EQ(run.on_a_node, 0);
    EXPECT_EQ(run.fallbacks, 0);
    return largest_edge_error(run, [&](double P) { return std::sqrt(2 * P * tan_theta / (std::numbers::pi * e_star)); });
  };
  const double s10 = sphere(10), s20 = sphere(20), s40 = sphere(40);
  const double c10 = cone(10), c20 = cone(20), c40 = cone(40);
  std::cout << fmt::format("edge error, sphere (Hertz) at 10/20/40 contact nodes: {:.4f} {:.4f} {:.4f}; "
                           "cone (Sneddon): {:.4f} {:.4f} {:.4f}\n", s10, s20, s40, c10, c20, c40);
  RecordProperty("sphere_10_20_40", fmt::format("{:.4f} {:.4f} {:.4f}", s10, s20, s40));
  RecordProperty("cone_10_20_40", fmt::format("{:.4f} {:.4f} {:.4f}", c10, c20, c40));
  EXPECT_LT(s20, s10);
  EXPECT_LT(s40, s20);
  EXPECT_LT(s40, 0.003);
  EXPECT_LT(c20, c10);
  EXPECT_LT(c40, c20);
  EXPECT_LT(c40, 0.01);
}

TEST(ContactEdge, PlasticEdgeIsNeverANodeAndConvergesWithAnObservedOrder) {
  // Ilyushin's deformation theory with linear (kappa = 0.95) and power (n = 0.2) hardening, on a
  // fixed fine zone refined twice.  Path independent on monotone loading (tests/
  // test_plastic_contact.cpp), so each step's a compares across meshes at the same depth.
  for (const char* name : {"deep_plastic.toml", "power_law.toml"}) {
    SCOPED_TRACE(name);
    const auto run = [&](int nodes) {
      const EdgeRun r = run_edges(shipped_case(name, {"mesh.contact_half_width=0.6e-3",
                                                      fmt::format("mesh.contact_nodes={}", nodes)}));
      EXPECT_EQ(r.on_a_node, 0) << nodes << " nodes";
      EXPECT_EQ(r.fallbacks, 0) << nodes << " nodes";
      return r;
    };
    const EdgeRun r10 = run(10), r20 = run(20), r40 = run(40);
    const double d1 = mean_difference(r10, r20), d2 = mean_difference(r20, r40);
    const double order = std::log2(d1 / d2);
    std::cout << fmt::format("{}: mean |a_h - a_h/2| / a: {:.4f} (10-20 nodes), {:.4f} (20-40); observed order {:.2f}\n",
                             name, d1, d2, order);
    RecordProperty(std::string(name) + "_order", fmt::format("{:.2f}", order));
    EXPECT_GT(order, 0.3);
    EXPECT_LT(d2, 0.01);
  }
}
