// (double, double) pairs sorted as std::sort sorts them (by the first, ties by the second),
// in linear time: a least-significant-digit radix sort on the first (8 bits a pass, a pass
// skipped where every key shares its byte), then each run of equal firsts by the second.
// The cloud statistics sort their bins' (ln radiance, weight) samples hundreds of times a
// fit, where std::sort was the largest single cost. Values must not be NaN; -0.0 and +0.0
// count as equal, as they do for std::sort.
#pragma once
#include <utility>
#include <vector>

namespace skycal {

void SortPairs(std::vector<std::pair<double, double>>* v);

}  // namespace skycal
