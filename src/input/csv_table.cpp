#include "indentsim/input/csv_table.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include <csv.h>
#include <fmt/format.h>

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

/// True when `line` split at `delimiter` gives two or more fields that are all numbers.
bool numeric_row(const std::string& line, char delimiter) {
  std::size_t fields = 0, start = 0;
  for (;;) {
    const std::size_t end = line.find(delimiter, start);
    const std::string field = line.substr(start, end == std::string::npos ? std::string::npos : end - start);
    double v = 0.0;
    if (!parse_csv_number(field, v)) return false;
    ++fields;
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return fields >= 2;
}

/// The delimiter of the data, not of a title: an instrument's export begins with comments and
/// metadata lines ("Number of Points = 42", "# ...") that hold no delimiter or another one, so
/// the delimiter is the one that splits the most of the first lines into numbers only; a file
/// without rows of numbers keeps the first line's (its messages then name the header).
char detect_delimiter(const std::string& bytes) {
  const char candidates[] = {',', '\t', ';'};
  std::size_t numeric[3] = {0, 0, 0};
  std::istringstream lines(bytes);
  std::string line;
  for (int n = 0; n < 400 && std::getline(lines, line); ++n) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    for (std::size_t c = 0; c < 3; ++c) numeric[c] += numeric_row(line, candidates[c]) ? 1 : 0;
  }
  const std::size_t best = static_cast<std::size_t>(std::max_element(numeric, numeric + 3) - numeric);
  if (numeric[best] > 0) return candidates[best];
  const std::string first_line = bytes.substr(0, bytes.find_first_of("\r\n"));
  if (first_line.find(',') != std::string::npos) return ',';
  if (first_line.find('\t') != std::string::npos) return '\t';
  if (first_line.find(';') != std::string::npos) return ';';
  return ',';
}

}  // namespace

std::string trim_csv_field(const std::string& text) {
  const auto first = text.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return "";
  return text.substr(first, text.find_last_not_of(" \t\r\n") - first + 1);
}

bool parse_csv_number(const std::string& text, double& value) {
  const std::string trimmed = trim_csv_field(text);
  if (trimmed.empty()) return false;
  char* end = nullptr;
  errno = 0;
  value = std::strtod(trimmed.c_str(), &end);
  return errno == 0 && end == trimmed.c_str() + trimmed.size() && std::isfinite(value);
}

CsvTable read_csv_table(const std::filesystem::path& file, std::size_t max_bytes,
                        const std::function<void(const std::string&)>& fail) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) fail("cannot open: not a readable file");
  std::ifstream in(file, std::ios::binary);
  if (!in) fail("cannot open for reading");
  std::ostringstream text;
  text << in.rdbuf();
  std::string bytes = text.str();
  if (bytes.size() > max_bytes) fail(fmt::format("is larger than {} MiB", max_bytes >> 20));
  // A UTF-8 byte-order mark, which spreadsheet programs and some instruments' software write first:
  // not part of the first header field.
  if (bytes.compare(0, 3, "\xEF\xBB\xBF") == 0) bytes.erase(0, 3);

  CsvTable table;
  table.delimiter = detect_delimiter(bytes);
  CsvParser parser;
  if (!parser.ready()) fail("cannot start the CSV parser");
  csv_set_delim(parser.get(), table.delimiter);
  Rows rows;
  if (csv_parse(parser.get(), bytes.data(), bytes.size(), Rows::field, Rows::end_of_row, &rows) != bytes.size() ||
      csv_fini(parser.get(), Rows::field, Rows::end_of_row, &rows) != 0)
    fail(fmt::format("not valid CSV ({})", csv_strerror(csv_error(parser.get()))));
  if (!rows.rows.empty() && rows.rows.back().empty()) rows.rows.pop_back();  // after the last end of row
  table.rows = std::move(rows.rows);
  return table;
}

std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\r\n") == std::string::npos) return text;
  std::string quoted(text.size() * 2 + 2, '\0');  // csv_write's worst case: every character a quote
  quoted.resize(csv_write(quoted.data(), quoted.size(), text.data(), text.size()));
  return quoted;
}

}  // namespace indentsim
