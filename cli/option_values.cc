#include "option_values.h"

#include <cmath>
#include <cstdlib>
#include <limits>

#include "skycal/core/error.h"

namespace skycal::cli {

double ParseNumber(const std::string& text, const std::string& option) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(v)) {
    throw Error(option + ": expected a finite number, got '" + text + "'");
  }
  return v;
}

std::array<double, 3> ParseVec3(const std::string& text, const std::string& option) {
  std::array<double, 3> out{};
  size_t start = 0;
  for (int i = 0; i < 3; ++i) {
    const size_t comma = text.find(',', start);
    if ((i < 2) != (comma != std::string::npos)) throw Error(option + ": expected X,Y,Z, got '" + text + "'");
    out[i] = ParseNumber(text.substr(start, i < 2 ? comma - start : std::string::npos), option);
    start = comma + 1;
  }
  return out;
}

std::array<int, 2> ParseSize(const std::string& text, const std::string& option) {
  const size_t x = text.find('x');
  if (x == std::string::npos) throw Error(option + ": expected WIDTHxHEIGHT, got '" + text + "'");
  const double w = ParseNumber(text.substr(0, x), option), h = ParseNumber(text.substr(x + 1), option);
  if (w != std::floor(w) || h != std::floor(h) || w < 1 || h < 1 || w > 1e6 || h > 1e6) {
    throw Error(option + ": expected positive integers WIDTHxHEIGHT, got '" + text + "'");
  }
  return {static_cast<int>(w), static_cast<int>(h)};
}

std::vector<double> ParseNumberList(const std::string& text, const std::string& option) {
  std::vector<double> values;
  size_t start = 0;
  while (true) {
    const size_t comma = text.find(',', start);
    values.push_back(ParseNumber(text.substr(start, comma == std::string::npos ? std::string::npos : comma - start), option));
    if (comma == std::string::npos) return values;
    start = comma + 1;
  }
}

int ParseInteger(const std::string& text, const std::string& option) {
  const double v = ParseNumber(text, option);
  // int's range, so the cast below is defined; callers check their own, tighter ranges.
  if (v != std::floor(v) || std::abs(v) > std::numeric_limits<int>::max()) {
    throw Error(option + ": expected an integer, got '" + text + "'");
  }
  return static_cast<int>(v);
}

}  // namespace skycal::cli
