// The studies' (bench_fit, bench_cie, bench_probe_fit) timing and machine block: the same
// code as `skycal bench` (skycal_bench), so there is one way to measure.
#pragma once
#include <nlohmann/json.hpp>

#include "skycal/bench/results.h"
#include "skycal/bench/timing.h"

namespace skycal::bench {

// The machine block of results.json plus the keys these studies' files always had.
inline nlohmann::json MachineJson() {
  nlohmann::json j = DescribeMachine("").ToJson();
  j["hardware_threads"] = j["cores"];
  return j;
}

}  // namespace skycal::bench
