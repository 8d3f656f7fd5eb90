// The sun that lights a photograph's clouds, fitted (fit --clouds stats): a scale s on the
// photo's measured sun (photo_sun.h). The albedo is held at its physical value, so the
// statistics' direct light is s x the disc and the ambient k is fitted at each s: the cost's
// profile over s is minimised here (a grid over ln s, then successive parabolas around the
// best grid point). One dimension, a handful of evaluations, each a statistics fit on cached renders.
#pragma once
#include <functional>
#include <string>
#include <vector>

namespace skycal::cloudfit {

struct SunScaleSearchOptions {
  double lower = 0.1, upper = 30.0;  // bounds of s (lower 1 where the disc is a lower bound)
  int grid_points = 5;               // over ln s, bounds included (>= 3)
  double tolerance_ln = 0.05;        // stop when the next vertex is this close (ln s) to a known point
  int max_evaluations = 10;
  bool IsValid(std::string* why) const;
};

struct SunScaleSearch {
  double scale = 1.0, cost = 0.0;
  std::vector<double> scales, costs;  // every evaluation, in order
  bool at_lower = false, at_upper = false;  // the minimum is a bound
};

// `cost(s)` is the profile cost at scale s (the other parameters fitted). Throws skycal::Error
// on invalid options.
SunScaleSearch MinimizeOverSunScale(const std::function<double(double)>& cost, const SunScaleSearchOptions& o);

}  // namespace skycal::cloudfit
