#include "indentsim/io.hpp"

#include <stdexcept>

#include <fmt/format.h>

#include "indentsim/simulation.hpp"

namespace indentsim {

CurveWriter::CurveWriter(const std::filesystem::path& file) : file_(std::fopen(file.c_str(), "w")) {
  if (!file_) throw std::runtime_error("cannot write " + file.string());
  const std::string h = header() + "\n";
  std::fputs(h.c_str(), file_);
  std::fflush(file_);
}

CurveWriter::~CurveWriter() {
  if (file_) std::fclose(file_);
}

std::string CurveWriter::header() {
  return "step,alpha,P,a,contact_nodes,newton_iters,factorizations,cutbacks,plastic_points,max_strain_intensity,"
         "wall_s";
}

std::string CurveWriter::format(const IncrementRecord& r) {
  // Full round-trip precision: the curve is data, not a report.
  return fmt::format("{},{:.17g},{:.17g},{:.17g},{},{},{},{},{},{:.17g},{:.6f}", r.step, r.alpha, r.force,
                     r.half_width, r.contact_nodes, r.newton_iterations, r.factorizations, r.cutbacks,
                     r.plastic_points, r.max_strain_intensity, r.wall_seconds);
}

void CurveWriter::write(const IncrementRecord& record) {
  const std::string line = format(record) + "\n";
  if (std::fputs(line.c_str(), file_) < 0 || std::fflush(file_) != 0)
    throw std::runtime_error("writing curve.csv failed");
}

RunOutput::RunOutput(const std::filesystem::path& dir, const LoadCase& load_case)
    : dir_(dir),
      fields_every_(load_case.output.fields_every),
      profile_depths_(load_case.output.profile_depths),
      curve_(dir / "curve.csv"),
      fields_(dir) {
  write_file_atomically(dir_ / "case.toml", to_toml(load_case));
}

void RunOutput::increment(const Simulation& sim, const IncrementRecord& record) {
  curve_.write(record);
  last_step_ = record.step;
  if (fields_every_ > 0 && record.step % fields_every_ == 0) write_fields(sim, record.step);
}

void RunOutput::write_fields(const Simulation& sim, int step) {
  const NodalStresses nodal = average_to_nodes(sim.mesh(), sim.bulk());
  fields_.add(step, sim.alpha(),
              vtu_document(sim.mesh(), sim.displacement().data(), sim.bulk(), nodal, sim.contact_boundary(),
                           sim.contact()));
  last_fields_step_ = step;
}

void RunOutput::finish(const Simulation& sim) {
  if (last_step_ < 0) return;
  if (last_fields_step_ != last_step_) write_fields(sim, last_step_);
  const auto& mesh = sim.mesh();
  const auto layer = nodal_layer_forces(mesh, sim.element_matrices(), sim.displacement().data());
  write_file_atomically(dir_ / "layers.csv", layers_csv(layer_forces(mesh, layer), sim.contact().force));
  write_file_atomically(dir_ / "profiles.csv", profiles_csv(mesh, profile_lines(mesh, profile_depths_), layer,
                                                           average_to_nodes(mesh, sim.bulk())));
}

}  // namespace indentsim
