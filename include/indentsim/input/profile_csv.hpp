#pragma once
// A measured tip profile from a CSV file: rows r, g(r) in metres, an optional header row; and any
// two-column table of numbers read the same way (a hardening table's eps_p, sigma).
// Read with libcsv (RFC 4180 quoting, any line ending); the shape checks (r from 0 increasing,
// g not decreasing) are validate()'s, which names the point.
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace indentsim {

/// The (r, g) rows of `file`; throws InputError(source, key, ...) naming the file and the row
/// when it cannot be read or a row is not two numbers.
std::vector<std::pair<double, double>> read_profile_csv(const std::filesystem::path& file, const std::string& source,
                                                        const std::string& key);

/// The rows of a two-column CSV file of numbers named `first`, `second` ("eps_p", "sigma"), at
/// least two of them, for `what` ("a hardening table"); the same reading and messages.
std::vector<std::pair<double, double>> read_two_column_csv(const std::filesystem::path& file, const std::string& source,
                                                           const std::string& key, const std::string& first,
                                                           const std::string& second, const std::string& what);

}  // namespace indentsim
