// core/sort_pairs.h: the radix sort gives std::sort's order, pair for pair.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "skycal/core/sort_pairs.h"

namespace skycal {
namespace {

using Pairs = std::vector<std::pair<double, double>>;

// Values drawn so that some repeat exactly (ties sorted by the weight), both signs, both
// zeros, and magnitudes far apart (every byte of the keys varies somewhere).
Pairs Draw(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-3.0, 3.0), w(0.0, 1.0);
  std::uniform_int_distribution<int> pick(0, 9);
  Pairs v(n);
  for (auto& p : v) {
    const int k = pick(rng);
    p.first = k == 0 ? 0.5 : k == 1 ? -0.0 : k == 2 ? 0.0 : k == 3 ? 1e-300 * u(rng) : k == 4 ? 1e200 * u(rng) : u(rng);
    p.second = pick(rng) < 3 ? 0.25 : w(rng);
  }
  return v;
}

// Equal as std::sort orders them: the same pairs at every position (the two zeros compare equal).
void ExpectSameOrder(const Pairs& got, const Pairs& want) {
  ASSERT_EQ(got.size(), want.size());
  for (size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(got[i].first, want[i].first) << i;
    EXPECT_EQ(got[i].second, want[i].second) << i;
  }
}

TEST(SortPairs, GivesStdSortsOrderAtEverySize) {
  for (size_t n : {0u, 1u, 7u, 255u, 256u, 257u, 1000u, 20000u}) {
    for (uint32_t seed : {1u, 2u, 3u}) {
      Pairs v = Draw(n, seed), want = v;
      std::sort(want.begin(), want.end());
      SortPairs(&v);
      ExpectSameOrder(v, want);
    }
  }
}

TEST(SortPairs, SortedSortedAndReversedInputs) {
  Pairs v = Draw(5000, 9);
  std::sort(v.begin(), v.end());
  const Pairs want = v;
  SortPairs(&v);
  ExpectSameOrder(v, want);
  std::reverse(v.begin(), v.end());
  SortPairs(&v);
  ExpectSameOrder(v, want);
  // Control: the comparison sees a misplaced pair.
  Pairs wrong = want;
  std::swap(wrong[10], wrong[4000]);
  bool differs = false;
  for (size_t i = 0; i < want.size(); ++i) differs |= wrong[i] != want[i];
  EXPECT_TRUE(differs);
}

}  // namespace
}  // namespace skycal
