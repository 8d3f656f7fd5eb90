// gpu::WorkgroupRowStride (gpu/workgroup_order.h): the row order the sky and cloud shaders
// use so that lavapipe's statically split compute threads share the sky's work. The map
// must be a bijection (every pixel computed exactly once: the render parity tests check the
// values), and every thread's contiguous block of workgroup rows must draw about half its
// rows from the sky. Identity order is the control: one thread gets all the sky.
#include <gtest/gtest.h>

#include <numeric>
#include <vector>

#include "skycal/gpu/workgroup_order.h"

namespace skycal::gpu {
namespace {

TEST(WorkgroupOrder, TheRowMapIsABijectionForEveryRowCount) {
  // Every count up to 300, then the sizes renders use (the stride search costs ~ms each).
  std::vector<uint32_t> counts(300);
  std::iota(counts.begin(), counts.end(), 1u);
  for (uint32_t rows : {384u, 512u, 640u, 1000u, 1024u, 2048u}) counts.push_back(rows);
  for (uint32_t rows : counts) {
    const uint32_t stride = WorkgroupRowStride(rows);
    ASSERT_EQ(std::gcd(stride, rows), 1u) << rows;
    std::vector<int> hit(rows, 0);
    for (uint32_t r = 0; r < rows; ++r) ++hit[WorkgroupTileRow(r, rows, stride)];
    for (uint32_t t = 0; t < rows; ++t) ASSERT_EQ(hit[t], 1) << "rows " << rows << " tile row " << t;
  }
}

TEST(WorkgroupOrder, EveryThreadsBlockDrawsHalfItsRowsFromTheSky) {
  // The row counts skycal dispatches most: cloud tiles of 8 rows at 512x256 (32) and
  // 2048x1024 (128), sky rows at 128x64 ... 2048x1024.
  for (uint32_t rows : {32u, 64u, 128u, 256u, 512u, 1024u}) {
    const uint32_t stride = WorkgroupRowStride(rows);
    // Two threads (this machine, CI): exactly half each.
    uint32_t upper = 0;
    for (uint32_t r = 0; r < rows / 2; ++r) upper += 2 * WorkgroupTileRow(r, rows, stride) < rows;
    EXPECT_EQ(upper, rows / 4) << rows;
    // Any thread count 2..16 (blocks >= 4 rows): within 0.1 of half (measured worst 0.1,
    // at blocks of 5 rows, where one row is 0.2 of the block).
    EXPECT_LE(WorkgroupRowImbalance(rows, stride), 0.1 + 1e-12) << rows;
    // Control: the identity order gives the first thread nothing but sky.
    EXPECT_DOUBLE_EQ(WorkgroupRowImbalance(rows, 1), 0.5) << rows;
  }
}

}  // namespace
}  // namespace skycal::gpu
