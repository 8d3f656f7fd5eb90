#include "skycal/bench/grid.h"

#include <algorithm>
#include <set>

#include "skycal/core/error.h"

namespace skycal::bench {

bool Grid::IsValid(std::string* why) const {
  std::set<std::string> names;
  for (const Axis& a : axes) {
    if (a.name.empty() || !names.insert(a.name).second) {
      *why = "grid: axis names must be non-empty and distinct ('" + a.name + "')";
      return false;
    }
    if (a.values.empty()) {
      *why = "grid: axis '" + a.name + "' has no values";
      return false;
    }
    if (std::set<std::string>(a.values.begin(), a.values.end()).size() != a.values.size()) {
      *why = "grid: axis '" + a.name + "' repeats a value";
      return false;
    }
    if (std::find(a.values.begin(), a.values.end(), a.default_value) == a.values.end()) {
      *why = "grid: axis '" + a.name + "': default '" + a.default_value + "' is not one of its values";
      return false;
    }
  }
  return true;
}

std::vector<Settings> Grid::Expand() const {
  std::string why;
  if (!IsValid(&why)) throw Error(why);
  std::vector<Settings> out;
  if (axes.empty()) return out;
  std::vector<size_t> index(axes.size(), 0);
  while (true) {
    Settings s;
    for (size_t k = 0; k < axes.size(); ++k) s.emplace_back(axes[k].name, axes[k].values[index[k]]);
    if (!skip || skip(s).empty()) out.push_back(std::move(s));
    // Odometer, last axis fastest.
    size_t k = axes.size();
    while (k > 0) {
      --k;
      if (++index[k] < axes[k].values.size()) break;
      index[k] = 0;
      if (k == 0) return out;
    }
  }
}

Settings Grid::Defaults() const {
  Settings s;
  for (const Axis& a : axes) s.emplace_back(a.name, a.default_value);
  return s;
}

const std::string& Get(const Settings& s, const std::string& name) {
  for (const auto& [k, v] : s)
    if (k == name) return v;
  throw Error("bench: setting '" + name + "' missing from case '" + Label(s) + "'");
}

std::string Label(const Settings& s) {
  std::string out;
  for (const auto& [k, v] : s) out += (out.empty() ? "" : " ") + k + "=" + v;
  return out;
}

}  // namespace skycal::bench
