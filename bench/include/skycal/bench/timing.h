// Wall-clock timing of one benchmark case: warm-up runs (not kept), then repeats; the
// median is the number reported, min and max its spread (the noise `bench --compare` uses).
// Milliseconds throughout. Medians of repeats, ratios in one run (docs/benchmarks.md).
#pragma once
#include <functional>
#include <vector>

#include <nlohmann/json_fwd.hpp>

namespace skycal::bench {

struct Timing {
  double median_ms = 0.0, min_ms = 0.0, max_ms = 0.0;
  int runs = 0;
  nlohmann::json ToJson() const;
};

// Runs `fn` `warmup` times untimed, then `runs` (>= 1) times timed with steady_clock.
Timing Measure(const std::function<void()>& fn, int warmup, int runs);

// The statistics of given samples (ms); empty: all zero.
Timing FromSamples(std::vector<double> samples_ms);

}  // namespace skycal::bench
