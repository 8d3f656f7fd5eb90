// The settings of a benchmark suite as a grid: named axes, each with its values and the
// default (what a user gets without options); a case is one point of the product. A
// suite may drop points where a setting has no effect (Grid::skip says why), so no case
// is measured twice under two names.
#pragma once
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace skycal::bench {

// name=value pairs in the grid's axis order.
using Settings = std::vector<std::pair<std::string, std::string>>;

struct Axis {
  std::string name;
  std::vector<std::string> values;  // non-empty, distinct
  std::string default_value;        // one of values
};

struct Grid {
  std::vector<Axis> axes;
  // Returns a non-empty reason to leave a point out (e.g. "numeric Jacobians only on the
  // Ceres path"); empty keeps it.
  std::function<std::string(const Settings&)> skip;

  bool IsValid(std::string* why) const;
  // Every kept point, the first axis varying slowest. Throws skycal::Error if invalid.
  std::vector<Settings> Expand() const;
  Settings Defaults() const;
};

// The value of `name` in `s`; throws skycal::Error when absent.
const std::string& Get(const Settings& s, const std::string& name);
// "backend=vulkan size=512x256": the case's name within its suite (unique per point).
std::string Label(const Settings& s);

}  // namespace skycal::bench
