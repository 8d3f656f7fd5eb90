// The order in which a dispatch's workgroup rows cover a lat-long image, so that a CPU
// Vulkan driver's threads get equal shares of the work.
//
// Why: Mesa's llvmpipe (lavapipe's compute path; Mesa 22.3 on Debian 12) hands each of its
// T compute threads one contiguous block of about N/T workgroup indices (its compute thread
// pool splits statically; no work stealing). A lat-long image's rows are not equal work:
// the upper half (sky, clouds) costs nearly everything, the lower half (ground) almost
// nothing. With workgroup row r drawing tile row r, the thread holding the lower block was
// done at once and the dispatch ran on one core — measured per thread (/proc/PID/task/*/stat)
// during a 2048x1024 cloud render: one compute thread took all the CPU time, the other none.
//
// The fix: workgroup row r draws tile row (r * stride) mod rows, stride coprime with rows (a
// bijection: every pixel is still computed once, with the same value — only which thread
// computes it changes). The stride is chosen so that every contiguous block of rows / T
// workgroup rows, for every thread count T = 2..16, draws as close to half of its rows from
// the upper half as any stride near rows / 2 can (for even rows this is usually rows/2 + 1,
// which alternates upper and lower rows). A GPU schedules workgroups dynamically and does not
// care about the order.
#pragma once
#include <cstdint>

namespace skycal::gpu {

// Worst |share of upper-half tile rows - 1/2| over the contiguous blocks of rows / T
// workgroup rows (T = 2..16, blocks of at least 4 rows) under `stride`.
double WorkgroupRowImbalance(uint32_t rows, uint32_t stride);

// The stride for `rows` workgroup rows (1 for rows < 3): coprime with rows, the least
// WorkgroupRowImbalance among the candidates nearest rows / 2 + 1. Memoised per rows
// (thread-safe): a few milliseconds at 2048 rows the first time.
uint32_t WorkgroupRowStride(uint32_t rows);

// The tile row workgroup row r draws; the shaders compute the same expression in uint32.
inline uint32_t WorkgroupTileRow(uint32_t r, uint32_t rows, uint32_t stride) {
  return static_cast<uint32_t>((static_cast<uint64_t>(r) * stride) % rows);
}

}  // namespace skycal::gpu
