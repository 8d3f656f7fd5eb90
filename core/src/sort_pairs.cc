#include "skycal/core/sort_pairs.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>

namespace skycal {
namespace {

// The bits of `v` as an unsigned integer in the same order as the doubles (the sign bit
// flipped for positives, every bit for negatives; both zeros as +0).
uint64_t OrderedBits(double v) {
  if (v == 0.0) v = 0.0;
  uint64_t u = 0;
  std::memcpy(&u, &v, sizeof u);
  return (u >> 63) != 0 ? ~u : (u | (uint64_t{1} << 63));
}

// Below this many pairs std::sort is as fast.
constexpr size_t kRadixMinimum = 256;

}  // namespace

void SortPairs(std::vector<std::pair<double, double>>* v) {
  const size_t n = v->size();
  if (n < kRadixMinimum) {
    std::sort(v->begin(), v->end());
    return;
  }
  std::vector<uint64_t> keys(n), keys_tmp(n);
  std::vector<std::pair<double, double>> tmp(n);
  for (size_t i = 0; i < n; ++i) keys[i] = OrderedBits((*v)[i].first);
  for (int shift = 0; shift < 64; shift += 8) {
    std::array<size_t, 257> count{};
    for (uint64_t k : keys) ++count[((k >> shift) & 0xFF) + 1];
    if (std::any_of(count.begin() + 1, count.end(), [n](size_t c) { return c == n; })) continue;  // one byte value
    for (int b = 0; b < 256; ++b) count[b + 1] += count[b];
    for (size_t i = 0; i < n; ++i) {
      const size_t to = count[(keys[i] >> shift) & 0xFF]++;
      keys_tmp[to] = keys[i];
      tmp[to] = (*v)[i];
    }
    keys.swap(keys_tmp);
    v->swap(tmp);
  }
  for (size_t i = 0; i < n;) {  // runs of equal firsts, by the second
    size_t j = i + 1;
    while (j < n && keys[j] == keys[i]) ++j;
    if (j - i > 1) std::sort(v->begin() + i, v->begin() + j);
    i = j;
  }
}

}  // namespace skycal
