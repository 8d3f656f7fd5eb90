// The studies' (bench_fit --decisions; the cloud statistics suites) timing and machine block: the same
// code as `skycal bench` (skycal_bench), so there is one way to measure.
#pragma once
#include <algorithm>
#include <vector>

#include <nlohmann/json.hpp>

#include "skycal/bench/results.h"
#include "skycal/bench/timing.h"

namespace skycal::bench {

inline double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

// The machine block of results.json plus the keys these studies' files always had.
inline nlohmann::json MachineJson() {
  nlohmann::json j = DescribeMachine("").ToJson();
  j["hardware_threads"] = j["cores"];
  return j;
}

}  // namespace skycal::bench
