#pragma once
// Where the wall-clock time of a run goes, phase by phase (planning with the pilot run, building
// the model, stepping the load path, writing output): counters reported at the end of a run and
// in summary.json, as SUNDIALS' examples report theirs.
#include <chrono>
#include <string>
#include <utility>
#include <vector>

namespace indentsim {

class PhaseTimes {
public:
  /// Adds the time until its destruction to `phase` (created on first use, in order of first use).
  class Scope {
  public:
    Scope(PhaseTimes& times, std::string phase) : times_(times), phase_(std::move(phase)), start_(clock::now()) {}
    ~Scope() { times_.add(phase_, std::chrono::duration<double>(clock::now() - start_).count()); }
    Scope(const Scope&) = delete;
    Scope& operator=(const Scope&) = delete;

  private:
    using clock = std::chrono::steady_clock;
    PhaseTimes& times_;
    std::string phase_;
    clock::time_point start_;
  };

  Scope measure(std::string phase) { return Scope(*this, std::move(phase)); }
  void add(const std::string& phase, double seconds) {
    for (auto& [name, total] : phases_)
      if (name == phase) {
        total += seconds;
        return;
      }
    phases_.emplace_back(phase, seconds);
  }
  /// (phase, seconds) in order of first use.
  const std::vector<std::pair<std::string, double>>& phases() const { return phases_; }

private:
  std::vector<std::pair<std::string, double>> phases_;
};

}  // namespace indentsim
