#include "indentsim/input/profile_csv.hpp"

#include <fmt/format.h>

#include "indentsim/input/csv_table.hpp"
#include "indentsim/base/error.hpp"

namespace indentsim {

std::vector<std::pair<double, double>> read_profile_csv(const std::filesystem::path& file, const std::string& source,
                                                        const std::string& key) {
  return read_two_column_csv(file, source, key, "r", "g", "a profile");
}

std::vector<std::pair<double, double>> read_two_column_csv(const std::filesystem::path& file, const std::string& source,
                                                           const std::string& key, const std::string& first,
                                                           const std::string& second, const std::string& what) {
  const auto fail = [&](const std::string& problem) {
    throw InputError(source, key, fmt::format("{}: {}", printable(file.string(), 200), problem));
  };
  const CsvTable table = read_csv_table(file, 64u << 20, fail);

  std::vector<std::pair<double, double>> points;
  std::size_t line = 0;
  for (const auto& row : table.rows) {
    ++line;
    if (row.empty()) continue;
    double r = 0.0, g = 0.0;
    const bool numbers = row.size() == 2 && parse_csv_number(row[0], r) && parse_csv_number(row[1], g);
    if (!numbers) {
      if (points.empty() && line == 1) continue;  // a header row
      if (row.size() != 2)
        fail(fmt::format("row {} is not two numbers {}, {} (got {} field{}: \"{}\")", line, first, second, row.size(),
                         row.size() == 1 ? "" : "s", printable(row[0], 40)));
      // Quote the field that is wrong, not its good neighbour.
      const bool r_bad = !parse_csv_number(row[0], r);
      fail(fmt::format("row {}: {} = \"{}\" is not a finite number", line, r_bad ? first : second,
                       printable(trim_csv_field(row[r_bad ? 0 : 1]), 40)));
    }
    points.emplace_back(r, g);
  }
  if (points.size() < 2) fail(fmt::format("holds {} point{}; {} needs at least 2", points.size(),
                                          points.size() == 1 ? "" : "s", what));
  return points;
}

}  // namespace indentsim
