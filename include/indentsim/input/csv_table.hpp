#pragma once
// A CSV file as rows of text fields, read with libcsv (RFC 4180 quoting, any line ending).
// The delimiter is a comma, or a tab or a semicolon when the file's first line holds one of
// those and no comma (instruments export all three).  Shared by the tip-profile and the
// load-depth-curve readers, which give the fields their meaning.
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace indentsim {

struct CsvTable {
  /// The rows in file order (libcsv skips blank lines: "row k" in messages counts rows, from 1).
  std::vector<std::vector<std::string>> rows;
  char delimiter = ',';
};

/// Reads `file`; on any failure calls `fail(problem)`, which must throw (the callers name the
/// file and the key in their own InputError).
CsvTable read_csv_table(const std::filesystem::path& file, std::size_t max_bytes,
                        const std::function<void(const std::string&)>& fail);

/// A field without its surrounding blanks (spaces, tabs, line ends).
std::string trim_csv_field(const std::string& text);

/// A field as a finite number (surrounding blanks allowed); false for text, NaN or infinity.
bool parse_csv_number(const std::string& text, double& value);

/// `text` as one field of a comma-separated line: as it is, or quoted (RFC 4180, by libcsv's
/// csv_write) when it holds a comma, a quote or a line end.
std::string csv_field(const std::string& text);

}  // namespace indentsim
