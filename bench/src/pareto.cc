#include "skycal/bench/pareto.h"

#include <cmath>

namespace skycal::bench {
namespace {

bool Finite(const TimeError& p) { return std::isfinite(p.time) && std::isfinite(p.error); }

// a dominates b: no worse in both, strictly better in one.
bool Dominates(const TimeError& a, const TimeError& b) {
  return a.time <= b.time && a.error <= b.error && (a.time < b.time || a.error < b.error);
}

}  // namespace

std::vector<int> ParetoFront(const std::vector<TimeError>& points) {
  // O(n^2): suites have tens of cases.
  std::vector<int> front;
  for (size_t i = 0; i < points.size(); ++i) {
    if (!Finite(points[i])) continue;
    bool dominated = false;
    for (size_t j = 0; j < points.size() && !dominated; ++j)
      dominated = j != i && Finite(points[j]) && Dominates(points[j], points[i]);
    if (!dominated) front.push_back(static_cast<int>(i));
  }
  return front;
}

}  // namespace skycal::bench
