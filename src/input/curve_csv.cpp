#include "indentsim/input/curve_csv.hpp"

#include <algorithm>
#include <cctype>
#include <optional>
#include <tuple>

#include <fmt/format.h>

#include "indentsim/input/csv_table.hpp"
#include "indentsim/base/error.hpp"

namespace indentsim {

namespace {

std::string trim(const std::string& text) { return trim_csv_field(text); }

std::string lower(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

/// "Depth (nm)" -> {"Depth", "nm"}; "Load [mN]" -> {"Load", "mN"}; "alpha" -> {"alpha", ""}.
std::pair<std::string, std::string> name_and_unit(const std::string& field) {
  const std::string f = trim(field);
  if (!f.empty() && (f.back() == ')' || f.back() == ']')) {
    const char open = f.back() == ')' ? '(' : '[';
    const auto at = f.rfind(open);
    if (at != std::string::npos) return {trim(f.substr(0, at)), trim(f.substr(at + 1, f.size() - at - 2))};
  }
  return {f, ""};
}

/// A blank line, or a comment: instruments' exports start lines of notes with '#'.
bool blank_or_comment(const std::vector<std::string>& row) {
  if (row.empty()) return true;
  const std::string first = trim(row[0]);
  return (row.size() == 1 && first.empty()) || (!first.empty() && first[0] == '#');
}

bool all_numbers(const std::vector<std::string>& row) {
  double v = 0.0;
  return !row.empty() && std::all_of(row.begin(), row.end(), [&](const std::string& f) { return parse_csv_number(f, v); });
}

std::string join_fields(const std::vector<std::string>& row) {
  std::string out;
  for (const auto& f : row) out += (out.empty() ? "\"" : ", \"") + printable(trim(f), 40) + "\"";
  return out;
}

}  // namespace

double depth_unit_factor(const std::string& unit) {
  if (unit == "m") return 1.0;
  if (unit == "mm") return 1e-3;
  if (unit == "um" || unit == "µm" || unit == "μm") return 1e-6;
  if (unit == "nm") return 1e-9;
  return 0.0;
}

double force_unit_factor(const std::string& unit) {
  if (unit == "N") return 1.0;
  if (unit == "mN") return 1e-3;
  if (unit == "uN" || unit == "µN" || unit == "μN") return 1e-6;
  if (unit == "nN") return 1e-9;
  return 0.0;
}

double time_unit_factor(const std::string& unit) {
  if (unit == "s") return 1.0;
  if (unit == "ms") return 1e-3;
  if (unit == "min") return 60.0;
  return 0.0;
}

bool is_per_length_force_unit(const std::string& unit) {
  return unit.size() > 2 && unit.compare(unit.size() - 2, 2, "/m") == 0 && force_unit_factor(unit.substr(0, unit.size() - 2)) != 0.0;
}

double force_or_per_length_unit_factor(const std::string& unit) {
  return is_per_length_force_unit(unit) ? force_unit_factor(unit.substr(0, unit.size() - 2)) : force_unit_factor(unit);
}

LoadDepthCurve read_curve_csv(const std::filesystem::path& file, const CurveColumns& columns) {
  const std::string name = file.string();
  const auto fail = [&](const std::string& key, const std::string& problem) {
    throw InputError(name, key, problem);
  };
  const CsvTable table = read_csv_table(file, std::size_t{1} << 30, [&](const std::string& p) { fail("curve", p); });
  const auto& rows = table.rows;
  if (rows.empty()) fail("curve", "is empty");

  // The header: the row naming both columns, or the last row before the first row of numbers.
  const bool named = !columns.depth_column.empty() || !columns.force_column.empty();
  if (named && (columns.depth_column.empty() || columns.force_column.empty()))
    fail(columns.depth_column.empty() ? "curve.depth_column" : "curve.force_column",
         "name both columns (curve.depth_column and curve.force_column), or neither for a two-column file");
  if (!columns.time_column.empty() && !named)
    fail("curve.time_column", "a time column is read beside named depth and force columns: name them too "
                              "(curve.depth_column and curve.force_column)");
  const auto find_column = [&](const std::vector<std::string>& header, const std::string& wanted) -> std::optional<std::size_t> {
    for (std::size_t c = 0; c < header.size(); ++c)
      if (lower(trim(header[c])) == lower(trim(wanted)) || lower(name_and_unit(header[c]).first) == lower(trim(wanted)))
        return c;
    return std::nullopt;
  };
  std::optional<std::size_t> header_row;
  std::size_t depth_col = 0, force_col = 1;
  if (named) {
    for (std::size_t k = 0; k < rows.size() && !header_row; ++k) {
      const auto d = find_column(rows[k], columns.depth_column), f = find_column(rows[k], columns.force_column);
      if (d && f) {
        header_row = k;
        depth_col = *d;
        force_col = *f;
      }
    }
    if (!header_row) {
      const auto& first = rows.front();
      fail(find_column(first, columns.depth_column) ? "curve.force_column" : "curve.depth_column",
           fmt::format("no header row names both \"{}\" and \"{}\" (the first row holds {})",
                       printable(columns.depth_column, 40), printable(columns.force_column, 40), join_fields(first)));
    }
  } else {
    std::size_t first_numbers = 0;
    while (first_numbers < rows.size() && !all_numbers(rows[first_numbers])) ++first_numbers;
    if (first_numbers == rows.size()) fail("curve", "holds no row of numbers");
    // The header is the last line before the numbers that is neither blank nor a comment.
    for (std::size_t k = first_numbers; k > 0 && !header_row; --k)
      if (!blank_or_comment(rows[k - 1])) header_row = k - 1;
    if (rows[first_numbers].size() != 2)
      fail("curve.depth_column",
           fmt::format("has {} columns: name the depth and the force column (curve.depth_column and "
                       "curve.force_column, or --depth-column and --force-column){}",
                       rows[first_numbers].size(),
                       header_row ? fmt::format("; the header holds {}", join_fields(rows[*header_row])) : ""));
  }

  std::optional<std::size_t> time_col;
  if (!columns.time_column.empty()) {
    time_col = find_column(rows[*header_row], columns.time_column);
    if (!time_col)
      fail("curve.time_column", fmt::format("the header row (row {}) has no column \"{}\": it holds {}", *header_row + 1,
                                            printable(columns.time_column, 40), join_fields(rows[*header_row])));
  }

  if (header_row)
    for (const auto& field : rows[*header_row])
      if (std::any_of(field.begin(), field.end(), [](char c) { return static_cast<unsigned char>(c) < 0x20 && c != '\t'; }))
        fail(fmt::format("row {}", *header_row + 1),
             fmt::format("the header field \"{}\" holds a control character (NUL or another byte below 0x20): is this "
                         "a text file?",
                         printable(trim(field), 40)));

  // The units: given, or from the header.
  LoadDepthCurve curve;
  bool declared = false;  // the last unit_of's unit was given or in the header
  const auto unit_of = [&](const std::string& given, std::size_t column, const char* key, const char* what,
                           double (*factor)(const std::string&), const char* accepted, const std::string& fallback) {
    std::string unit = trim(given);
    if (unit.empty() && header_row && column < rows[*header_row].size())
      unit = name_and_unit(rows[*header_row][column]).second;
    declared = !unit.empty();
    if (unit.empty()) unit = fallback;
    if (unit.empty())
      fail(key, fmt::format("the {} unit is missing: give {} ({}) or write it in the header, e.g. \"{} ({})\"",
                            what, key, accepted, what, std::string(accepted).substr(0, std::string(accepted).find(','))));
    if (factor(unit) == 0.0)
      fail(key, fmt::format("\"{}\" is not a {} unit (accepted: {})", printable(unit, 20), what, accepted));
    return unit;
  };
  curve.depth_unit = unit_of(columns.depth_unit, depth_col, "curve.depth_unit", "depth", depth_unit_factor,
                             "nm, um, mm, m", columns.default_depth_unit);
  curve.force_unit = columns.force_per_length
                         ? unit_of(columns.force_unit, force_col, "curve.force_unit", "force",
                                   force_or_per_length_unit_factor, "mN, uN, nN, N, or per length N/m, mN/m, uN/m, nN/m",
                                   columns.default_force_unit)
                         : unit_of(columns.force_unit, force_col, "curve.force_unit", "force", force_unit_factor,
                                   "mN, uN, nN, N", columns.default_force_unit);
  curve.force_unit_declared = declared;
  if (time_col)
    curve.time_unit = unit_of(columns.time_unit, *time_col, "curve.time_unit", "time", time_unit_factor, "s, ms, min",
                              columns.default_time_unit);
  const double depth_scale = depth_unit_factor(curve.depth_unit),
               force_scale = force_or_per_length_unit_factor(curve.force_unit),
               time_scale = time_col ? time_unit_factor(curve.time_unit) : 0.0;

  // The numbers: every row after the header, both columns finite numbers.
  const std::string depth_name = header_row ? printable(trim(rows[*header_row][depth_col]), 40) : "1";
  const std::string force_name = header_row ? printable(trim(rows[*header_row][force_col]), 40) : "2";
  const std::string time_name = time_col ? printable(trim(rows[*header_row][*time_col]), 40) : "";
  for (std::size_t k = header_row ? *header_row + 1 : 0; k < rows.size(); ++k) {
    const auto& row = rows[k];
    if (blank_or_comment(row)) continue;
    double h = 0.0, P = 0.0, t = 0.0;
    std::vector<std::tuple<std::size_t, std::string, double*>> wanted{{depth_col, depth_name, &h},
                                                                      {force_col, force_name, &P}};
    if (time_col) wanted.emplace_back(*time_col, time_name, &t);
    for (const auto& [col, column_name, value] : wanted) {
      if (col >= row.size())
        fail(fmt::format("row {}", k + 1),
             fmt::format("has {} fields; column \"{}\" is missing", row.size(), column_name));
      if (!parse_csv_number(row[col], *value))
        fail(fmt::format("row {}", k + 1), fmt::format("column \"{}\": \"{}\" is not a finite number", column_name,
                                                       printable(trim(row[col]), 40)));
    }
    if (time_col) {
      // A hold's time goes on while its depth or force stands still: time never runs back.
      if (!curve.time.empty() && t * time_scale < curve.time.back())
        fail(fmt::format("row {}", k + 1),
             fmt::format("column \"{}\": time {:g} {} comes before the row above it ({:g} {}): the rows are not in "
                         "the order of time",
                         time_name, t, curve.time_unit, curve.time.back() / time_scale, curve.time_unit));
      curve.time.push_back(t * time_scale);
    }
    curve.depth.push_back(h * depth_scale);
    curve.force.push_back(P * force_scale);
    curve.rows.push_back(k + 1);
  }
  if (curve.depth.size() < 2)
    fail("curve", fmt::format("holds {} point{} of depth and force", curve.depth.size(), curve.depth.size() == 1 ? "" : "s"));
  return curve;
}

}  // namespace indentsim
