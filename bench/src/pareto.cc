#include "skycal/bench/pareto.h"

#include <cmath>

namespace skycal::bench {
namespace {

bool Finite(const TimeError& p) { return std::isfinite(p.time) && std::isfinite(p.error); }

// a dominates b: no worse in both, better in one, each beyond its relative tolerance.
bool Dominates(const TimeError& a, const TimeError& b, const ParetoTolerance& tol) {
  const bool time_no_worse = a.time <= b.time * (1.0 + tol.time);
  const bool error_no_worse = a.error <= b.error * (1.0 + tol.error);
  const bool time_better = a.time * (1.0 + tol.time) < b.time || (tol.time == 0.0 && a.time < b.time);
  const bool error_better = a.error * (1.0 + tol.error) < b.error || (tol.error == 0.0 && a.error < b.error);
  return time_no_worse && error_no_worse && (time_better || error_better);
}

}  // namespace

std::vector<int> ParetoFront(const std::vector<TimeError>& points, const ParetoTolerance& tol) {
  // O(n^2): suites have tens of cases.
  std::vector<int> front;
  for (size_t i = 0; i < points.size(); ++i) {
    if (!Finite(points[i])) continue;
    bool dominated = false;
    for (size_t j = 0; j < points.size() && !dominated; ++j)
      dominated = j != i && Finite(points[j]) && Dominates(points[j], points[i], tol);
    if (!dominated) front.push_back(static_cast<int>(i));
  }
  return front;
}

}  // namespace skycal::bench
