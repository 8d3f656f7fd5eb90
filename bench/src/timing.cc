#include "skycal/bench/timing.h"

#include <algorithm>
#include <chrono>

#include <nlohmann/json.hpp>

#include "skycal/core/device_stats.h"

namespace skycal::bench {

nlohmann::json Timing::ToJson() const {
  return {{"median_ms", median_ms},
          {"min_ms", min_ms},
          {"max_ms", max_ms},
          {"runs", runs},
          {"gpu_median_ms", gpu_median_ms ? nlohmann::json(*gpu_median_ms) : nlohmann::json(nullptr)}};
}

Timing FromSamples(std::vector<double> ms) {
  Timing t;
  if (ms.empty()) return t;
  std::sort(ms.begin(), ms.end());
  const size_t n = ms.size();
  t.runs = static_cast<int>(n);
  t.median_ms = n % 2 ? ms[n / 2] : 0.5 * (ms[n / 2 - 1] + ms[n / 2]);
  t.min_ms = ms.front();
  t.max_ms = ms.back();
  return t;
}

Timing Measure(const std::function<void()>& fn, int warmup, int runs) {
  for (int i = 0; i < warmup; ++i) fn();
  std::vector<double> ms, gpu_ms;
  bool all_timed = true;
  for (int i = 0; i < std::max(runs, 1); ++i) {
    const DeviceTimeTotals d0 = DeviceTimeSoFar();
    const auto t0 = std::chrono::steady_clock::now();
    fn();
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    const DeviceTimeTotals d1 = DeviceTimeSoFar();
    if (d1.timed_submits == d0.timed_submits || d1.untimed_submits != d0.untimed_submits) all_timed = false;
    gpu_ms.push_back(d1.gpu_ms - d0.gpu_ms);
  }
  Timing t = FromSamples(std::move(ms));
  if (all_timed) t.gpu_median_ms = FromSamples(std::move(gpu_ms)).median_ms;
  return t;
}

}  // namespace skycal::bench
