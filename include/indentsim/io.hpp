#pragma once
// Output files of a run.
#include <cstdio>
#include <filesystem>
#include <string>

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

}  // namespace indentsim
