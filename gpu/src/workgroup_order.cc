#include "skycal/gpu/workgroup_order.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <numeric>

namespace skycal::gpu {

double WorkgroupRowImbalance(uint32_t rows, uint32_t stride) {
  double worst = 0.0;
  for (uint32_t threads = 2; threads <= 16; ++threads) {
    if (rows / threads < 4) break;
    for (uint32_t k = 0; k < threads; ++k) {
      const uint32_t begin = static_cast<uint32_t>(static_cast<uint64_t>(k) * rows / threads);
      const uint32_t end = static_cast<uint32_t>(static_cast<uint64_t>(k + 1) * rows / threads);
      uint32_t upper = 0;
      for (uint32_t r = begin; r < end; ++r) upper += 2 * WorkgroupTileRow(r, rows, stride) < rows;
      worst = std::max(worst, std::abs(static_cast<double>(upper) / (end - begin) - 0.5));
    }
  }
  return worst;
}

uint32_t WorkgroupRowStride(uint32_t rows) {
  if (rows < 3) return 1;
  static std::mutex mutex;
  static std::map<uint32_t, uint32_t> memo;
  const std::lock_guard<std::mutex> lock(mutex);
  if (const auto it = memo.find(rows); it != memo.end()) return it->second;
  // Candidates: the 64 coprime strides nearest rows / 2 + 1, alternating above and below.
  uint32_t best = rows - 1;  // coprime with rows always
  double best_imbalance = WorkgroupRowImbalance(rows, best);
  const int64_t centre = rows / 2 + 1;
  int tried = 0;
  for (int64_t d = 0; tried < 64 && d < rows; ++d)
    for (const int64_t s : {centre + d, centre - d - 1}) {
      if (s < 1 || s >= rows || std::gcd(static_cast<uint32_t>(s), rows) != 1) continue;
      ++tried;
      const double imbalance = WorkgroupRowImbalance(rows, static_cast<uint32_t>(s));
      if (imbalance < best_imbalance - 1e-12) {
        best_imbalance = imbalance;
        best = static_cast<uint32_t>(s);
      }
    }
  memo.emplace(rows, best);
  return best;
}

}  // namespace skycal::gpu
