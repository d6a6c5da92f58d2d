#include "indentsim/io.hpp"

#include <stdexcept>

#include <fmt/format.h>

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

}  // namespace indentsim
