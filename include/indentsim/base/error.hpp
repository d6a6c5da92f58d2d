#pragma once
// Errors the library reports to its callers.  Input problems are the user's to fix
// (the CLI turns them into exit status 2); solver failures are the model's.
#include <stdexcept>
#include <string>

namespace indentsim {

/// `text` as it can be shown in one line of a message: control characters escaped (\n, \t,
/// \x00, ...) and anything beyond `max_length` bytes cut with an ellipsis and the count cut.
std::string printable(const std::string& text, std::size_t max_length = 200);

/// Bad input: names the file, the key and what is wrong with it.  The message shows all three
/// through printable(), so a hostile value cannot cut or flood it.
class InputError : public std::runtime_error {
public:
  InputError(std::string file, std::string key, std::string problem);
  const std::string& file() const { return file_; }
  const std::string& key() const { return key_; }
  const std::string& problem() const { return problem_; }

private:
  std::string file_, key_, problem_;
};

/// A file that could not be read or written: names the file and the operating system's reason
/// ("No space left on device", "Permission denied", ...).  The CLI exits with status 4.
class IoError : public std::runtime_error {
public:
  IoError(std::string file, std::string action, std::string reason);
  const std::string& file() const { return file_; }
  const std::string& reason() const { return reason_; }

private:
  std::string file_, reason_;
};

/// A nonlinear solve that could not be completed (after every allowed cutback).
class SolverError : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

}  // namespace indentsim
