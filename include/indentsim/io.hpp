#pragma once
// Output files of a run.
#include <cstdio>
#include <filesystem>
#include <string>

#include <memory>

#include "indentsim/fields.hpp"
#include "indentsim/load_stepping.hpp"

namespace indentsim {

/// DIR/curve.csv: the P-alpha curve, one row per converged increment, written and flushed as
/// the run goes so that a stopped run keeps every converged increment.
class CurveWriter {
public:
  explicit CurveWriter(const std::filesystem::path& file);
  ~CurveWriter();
  CurveWriter(const CurveWriter&) = delete;
  CurveWriter& operator=(const CurveWriter&) = delete;

  void write(const IncrementRecord& record);
  static std::string header();
  static std::string format(const IncrementRecord& record);

private:
  std::FILE* file_ = nullptr;
};

class Simulation;

/// Everything a run writes into its output folder, as the run goes:
///   case.toml      the load case as run (every key explicit);
///   curve.csv      one row per converged increment (CurveWriter);
///   fields.pvd, fields/step_*.vtu   every output.fields_every increments and the final state;
///   layers.csv, profiles.csv        the paper's layer view of the final state.
class RunOutput {
public:
  RunOutput(const std::filesystem::path& dir, const LoadCase& load_case);
  void increment(const Simulation& sim, const IncrementRecord& record);
  void finish(const Simulation& sim);
  std::filesystem::path curve_path() const { return dir_ / "curve.csv"; }

private:
  void write_fields(const Simulation& sim, int step);

  std::filesystem::path dir_;
  int fields_every_ = 0;
  std::vector<double> profile_depths_;
  CurveWriter curve_;
  FieldSeries fields_;
  int last_step_ = -1, last_fields_step_ = -1;
};

}  // namespace indentsim
