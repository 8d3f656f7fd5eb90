// The Pareto front of time against error, both minimised: a case is on the front unless
// another is at least as fast and at least as accurate, and strictly better in one.
#pragma once
#include <vector>

namespace skycal::bench {

struct TimeError {
  double time = 0.0;   // any unit, smaller is better
  double error = 0.0;  // any unit, smaller is better
};

// Indices of the non-dominated points, in input order. Points with a non-finite time or
// error are never on the front and dominate nothing. Exact ties are all on the front.
std::vector<int> ParetoFront(const std::vector<TimeError>& points);

}  // namespace skycal::bench
