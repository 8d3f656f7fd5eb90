#include "skycal/bench/timing.h"

#include <algorithm>
#include <chrono>

#include <nlohmann/json.hpp>

namespace skycal::bench {

nlohmann::json Timing::ToJson() const {
  return {{"median_ms", median_ms}, {"min_ms", min_ms}, {"max_ms", max_ms}, {"runs", runs}};
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
  std::vector<double> ms;
  for (int i = 0; i < std::max(runs, 1); ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    fn();
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  return FromSamples(std::move(ms));
}

}  // namespace skycal::bench
