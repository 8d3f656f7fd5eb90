#include "args.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "skycal/core/error.h"

namespace skycal::cli {

Args::Args(int argc, char** argv, const std::vector<std::string>& value_options, const std::vector<std::string>& flags) {
  for (int i = 0; i < argc; ++i) {
    std::string a = argv[i];
    if (a.rfind("--", 0) != 0) throw Error("unexpected argument '" + a + "' (options start with --; see --help)");
    const std::string name = a.substr(2);
    if (std::find(flags.begin(), flags.end(), name) != flags.end()) {
      flags_[name] = true;
    } else if (std::find(value_options.begin(), value_options.end(), name) != value_options.end()) {
      if (i + 1 >= argc) throw Error("--" + name + ": expected a value");
      values_[name].push_back(argv[++i]);
    } else {
      throw Error("unknown option '--" + name + "' (see --help)");
    }
  }
}

bool Args::Has(const std::string& name) const { return values_.count(name) || flags_.count(name); }

std::optional<std::string> Args::Value(const std::string& name) const {
  auto it = values_.find(name);
  if (it == values_.end()) return std::nullopt;
  return it->second.back();
}

std::vector<std::string> Args::Values(const std::string& name) const {
  auto it = values_.find(name);
  return it == values_.end() ? std::vector<std::string>{} : it->second;
}

double ParseNumber(const std::string& text, const std::string& option) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(v)) {
    throw Error("--" + option + ": expected a finite number, got '" + text + "'");
  }
  return v;
}

std::optional<double> Args::Number(const std::string& name) const {
  auto v = Value(name);
  if (!v) return std::nullopt;
  return ParseNumber(*v, name);
}

std::optional<std::array<double, 3>> Args::Vec3(const std::string& name) const {
  auto v = Value(name);
  if (!v) return std::nullopt;
  std::array<double, 3> out{};
  size_t start = 0;
  for (int i = 0; i < 3; ++i) {
    const size_t comma = v->find(',', start);
    if ((i < 2) != (comma != std::string::npos)) throw Error("--" + name + ": expected X,Y,Z, got '" + *v + "'");
    out[i] = ParseNumber(v->substr(start, i < 2 ? comma - start : std::string::npos), name);
    start = comma + 1;
  }
  return out;
}

std::optional<std::array<int, 2>> Args::Size(const std::string& name) const {
  auto v = Value(name);
  if (!v) return std::nullopt;
  const size_t x = v->find('x');
  if (x == std::string::npos) throw Error("--" + name + ": expected WIDTHxHEIGHT, got '" + *v + "'");
  const double w = ParseNumber(v->substr(0, x), name), h = ParseNumber(v->substr(x + 1), name);
  if (w != std::floor(w) || h != std::floor(h) || w < 1 || h < 1 || w > 1e6 || h > 1e6) {
    throw Error("--" + name + ": expected positive integers WIDTHxHEIGHT, got '" + *v + "'");
  }
  return std::array<int, 2>{static_cast<int>(w), static_cast<int>(h)};
}

}  // namespace skycal::cli
