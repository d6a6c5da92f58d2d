#include "indentsim/profile_csv.hpp"

#include <cerrno>
#include <cstdlib>
#include <fstream>
#include <cmath>
#include <sstream>

#include <csv.h>
#include <fmt/format.h>

#include "indentsim/error.hpp"

namespace indentsim {

namespace {

/// libcsv's parser: initialised here, its buffer released by csv_free whatever happens.
class CsvParser {
public:
  CsvParser() : ready_(csv_init(&parser_, CSV_APPEND_NULL) == 0) {}
  ~CsvParser() {
    if (ready_) csv_free(&parser_);
  }
  CsvParser(const CsvParser&) = delete;
  CsvParser& operator=(const CsvParser&) = delete;
  bool ready() const { return ready_; }
  csv_parser* get() { return &parser_; }

private:
  csv_parser parser_{};
  bool ready_;
};

struct Rows {
  std::vector<std::vector<std::string>> rows{{}};
  static void field(void* text, std::size_t length, void* self) {
    static_cast<Rows*>(self)->rows.back().emplace_back(static_cast<const char*>(text), length);
  }
  static void end_of_row(int, void* self) { static_cast<Rows*>(self)->rows.emplace_back(); }
};

bool parse_number(const std::string& text, double& value) {
  std::string trimmed = text;
  trimmed.erase(0, trimmed.find_first_not_of(" \t"));
  trimmed.erase(trimmed.find_last_not_of(" \t") + 1);
  if (trimmed.empty()) return false;
  char* end = nullptr;
  errno = 0;
  value = std::strtod(trimmed.c_str(), &end);
  return errno == 0 && end == trimmed.c_str() + trimmed.size() && std::isfinite(value);
}

}  // namespace

std::vector<std::pair<double, double>> read_profile_csv(const std::filesystem::path& file, const std::string& source,
                                                        const std::string& key) {
  const auto fail = [&](const std::string& problem) {
    throw InputError(source, key, fmt::format("{}: {}", printable(file.string(), 200), problem));
  };
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) fail("cannot open: not a readable file");
  std::ifstream in(file, std::ios::binary);
  if (!in) fail("cannot open for reading");
  std::ostringstream text;
  text << in.rdbuf();
  const std::string bytes = text.str();
  if (bytes.size() > (64u << 20)) fail("is larger than 64 MiB: not a tip profile");

  CsvParser parser;
  if (!parser.ready()) fail("cannot start the CSV parser");
  Rows rows;
  if (csv_parse(parser.get(), bytes.data(), bytes.size(), Rows::field, Rows::end_of_row, &rows) != bytes.size() ||
      csv_fini(parser.get(), Rows::field, Rows::end_of_row, &rows) != 0)
    fail(fmt::format("not valid CSV ({})", csv_strerror(csv_error(parser.get()))));

  std::vector<std::pair<double, double>> points;
  std::size_t line = 0;
  for (const auto& row : rows.rows) {
    ++line;
    if (row.empty()) continue;  // blank lines
    double r = 0.0, g = 0.0;
    const bool numbers = row.size() == 2 && parse_number(row[0], r) && parse_number(row[1], g);
    if (!numbers) {
      if (points.empty() && line == 1) continue;  // a header row
      fail(fmt::format("row {} is not two numbers r, g (got {} field{}: \"{}\")", line, row.size(),
                       row.size() == 1 ? "" : "s", printable(row.empty() ? "" : row[0], 40)));
    }
    points.emplace_back(r, g);
  }
  if (points.size() < 2) fail(fmt::format("holds {} point{}; a profile needs at least 2", points.size(),
                                          points.size() == 1 ? "" : "s"));
  return points;
}

}  // namespace indentsim
