#pragma once
// A load-depth curve from a CSV file: a run's own curve.csv or a measured one, as instruments
// export them (metadata lines, then a header row, then numbers; comma, tab or semicolon).
//
// The two columns are picked by their header names (a name matches a header field with or
// without its unit: "depth" matches "Depth (nm)"); a file of exactly two columns needs none.
// The units are given (m, mm, um/µm, nm; N, mN, uN/µN) or read from the header ("Depth (nm)",
// "Load [mN]"); a curve without its units is refused, never guessed.  Depths and forces come
// back in SI (m, N).
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace indentsim {

struct CurveColumns {
  std::string depth_column, force_column;  ///< header names; both "" for a two-column file
  std::string depth_unit, force_unit;      ///< "" : from the header
  /// The time column's header name ("" : the curve is read without time); it needs the depth and
  /// force columns named too.  Its unit (s, ms, min) given, or from the header.
  std::string time_column, time_unit;
  /// Units taken when neither given nor in the header ("" : such a file is refused).  The fit
  /// reads its data in SI by default (m, and the case's force unit).
  std::string default_depth_unit, default_force_unit;
  /// Also accept a force per unit length (N/m, mN/m, uN/m, nN/m): a plane-strain curve, as the fit
  /// reads it.  Off, such a unit is refused as not a force unit.
  bool force_per_length = false;
  /// The time unit taken when neither given nor in the header ("" : refused); the fit's is s.
  std::string default_time_unit;
};

struct LoadDepthCurve {
  std::vector<double> depth, force;  ///< [m], [N] (a plane-strain run's force: N/m)
  std::vector<double> time;          ///< [s], never decreasing; empty without a time column
  std::vector<std::size_t> rows;     ///< the CSV row (from 1) of each point, for messages
  std::string depth_unit, force_unit;  ///< the units the file was read in
  std::string time_unit;               ///< "" without a time column
  /// The force unit was given (CurveColumns::force_unit) or written in the header, not the default.
  bool force_unit_declared = false;
};

/// Scale factor of a depth unit to metres / a force unit to newtons / a time unit to seconds; 0
/// when not a known unit.
double depth_unit_factor(const std::string& unit);
double force_unit_factor(const std::string& unit);
double time_unit_factor(const std::string& unit);
/// A force per unit length ("N/m", "mN/m", ...) to N/m, or a force to N; 0 when neither.
double force_or_per_length_unit_factor(const std::string& unit);
/// True for a force per unit length ("N/m", "mN/m", ...).
bool is_per_length_force_unit(const std::string& unit);

/// Reads the curve; throws InputError(file, key, problem) naming the file, the key (the column
/// or unit setting concerned, e.g. "curve.depth_unit", or "row 12") and what is wrong.
LoadDepthCurve read_curve_csv(const std::filesystem::path& file, const CurveColumns& columns);

}  // namespace indentsim
