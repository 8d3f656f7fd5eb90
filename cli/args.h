// A small, strict command-line parser for the verbs: `--name value` and `--flag`.
// Unknown options, missing values and malformed numbers are errors that name the option.
#pragma once
#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace skycal::cli {

class Args {
 public:
  // `flags` take no value; every other --option takes exactly one (repeatable ones collect).
  Args(int argc, char** argv, const std::vector<std::string>& value_options, const std::vector<std::string>& flags);

  bool Has(const std::string& name) const;
  std::optional<std::string> Value(const std::string& name) const;     // last occurrence
  std::vector<std::string> Values(const std::string& name) const;      // all occurrences
  std::optional<double> Number(const std::string& name) const;         // finite double or throws
  std::optional<std::array<double, 3>> Vec3(const std::string& name) const;  // "x,y,z"
  std::optional<std::array<int, 2>> Size(const std::string& name) const;     // "WxH"

 private:
  std::map<std::string, std::vector<std::string>> values_;
  std::map<std::string, bool> flags_;
};

// Parses a finite double; throws skycal::Error("--<option>: expected a number, got '...'").
double ParseNumber(const std::string& text, const std::string& option);

}  // namespace skycal::cli
