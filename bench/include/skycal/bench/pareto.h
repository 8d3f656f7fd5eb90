// The Pareto front of time against error, both minimised: a case is on the front unless
// another is at least as fast and at least as accurate, and strictly better in one.
#pragma once
#include <vector>

namespace skycal::bench {

struct TimeError {
  double time = 0.0;   // any unit, smaller is better
  double error = 0.0;  // any unit, smaller is better
};

// Relative tolerances: within them two numbers count as equal, so a case is not dominated
// by one that is faster only by the machine's noise (these machines are shared), or more
// accurate only in digits that do not matter. Zero: exact comparison.
struct ParetoTolerance {
  double time = 0.0;   // e.g. 0.10: 10% faster is needed to count as faster
  double error = 0.0;  // e.g. 0.01
};

// Indices of the non-dominated points, in input order. a dominates b when a is no worse in
// both (within tolerance) and better beyond the tolerance in at least one. Points with a
// non-finite time or error are never on the front and dominate nothing. Exact ties are
// all on the front.
std::vector<int> ParetoFront(const std::vector<TimeError>& points, const ParetoTolerance& tolerance = {});

}  // namespace skycal::bench
