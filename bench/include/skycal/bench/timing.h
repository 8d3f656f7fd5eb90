// Wall-clock timing of one benchmark case: warm-up runs (not kept), then repeats; the
// median is the number reported, min and max its spread (the noise `bench --compare` uses).
// Milliseconds throughout. Medians of repeats, ratios in one run (docs/benchmarks.md).
#pragma once
#include <functional>
#include <optional>
#include <vector>

#include <nlohmann/json_fwd.hpp>

namespace skycal::bench {

struct Timing {
  double median_ms = 0.0, min_ms = 0.0, max_ms = 0.0;
  int runs = 0;
  // Beside the wall time: the median device time per timed run (the Vulkan submissions'
  // timestamps, core/device_stats.h); none when the runs submitted nothing to a device or the
  // device wrote no timestamps. JSON: gpu_median_ms, a number or null.
  std::optional<double> gpu_median_ms;
  nlohmann::json ToJson() const;
};

// Runs `fn` `warmup` times untimed, then `runs` (>= 1) times timed with steady_clock, and
// the device time of each timed run (gpu_median_ms) when every run's submissions had one.
Timing Measure(const std::function<void()>& fn, int warmup, int runs);

// The statistics of given samples (ms); empty: all zero.
Timing FromSamples(std::vector<double> samples_ms);

}  // namespace skycal::bench
