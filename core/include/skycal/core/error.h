// Errors that reach the user. Every message names the file or option at fault, the
// field, and what was expected; the CLI prints it and exits non-zero.
#pragma once
#include <stdexcept>
#include <string>

namespace skycal {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace skycal
