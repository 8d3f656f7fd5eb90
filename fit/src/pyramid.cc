#include "pyramid.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "skycal/core/latlong.h"

namespace skycal::fit {

namespace {

// One row of samples feeding the level: uniform references give their own rows; a
// reference with horizon-biased rows gives one row per level node row, read at the node's
// elevation t = Row(e) through the mapping's exact inverse. Each mapped row holds the mean
// of its band (skycal resample), so the point value at t is the derivative of the cubic
// through the running integral P at the four band edges around t (exact for a quadratic
// sky in t): a combination of three rows. Above the horizon only sky rows are read.
// Measured (tests/row_mapping_test.cc): binning each mapped row to its nearest node
// displaced it by up to half a node and left 1% errors at mid elevations; linear
// interpolation of the band means left 0.17% between the fits; this reading, less.
struct SourceRow {
  std::array<int, 3> r{};         // reference rows
  std::array<double, 3> a{};      // their weights (sum 1; may be negative)
  int node_y = 0;                 // level row
  int grid_height = 0;            // height of the grid whose PixelSolidAngle weights the samples
};

std::vector<SourceRow> SourceRows(const Reference& ref, int h) {
  const int H = ref.radiance.height;
  std::vector<SourceRow> rows;
  if (!ref.row_mapping) {
    for (int y = 0; y < H; ++y) {
      const int node = static_cast<int>(std::lround(static_cast<double>(y) * (h - 1) / (H - 1)));
      rows.push_back({{y, y, y}, {1.0, 0.0, 0.0}, node, H});
    }
    return rows;
  }
  const RowMapping& m = *ref.row_mapping;
  const int cells = static_cast<int>(std::ceil(m.HorizonRow()));  // sky rows 0 .. cells - 1
  // Band edges: 0 (the pole), then i + 0.5.
  auto edge = [](int j) { return j == 0 ? 0.0 : j - 0.5; };
  for (int y = 0; y < h; ++y) {
    const double e = latlong::Latitude(y, h);
    if (e <= 0.0) continue;  // not fitted at any level
    const double t = std::clamp(m.Row(e), 0.0, cells - 1.0);
    SourceRow row;
    row.node_y = y;
    row.grid_height = h;
    if (cells < 3) {
      const int r0 = std::min(static_cast<int>(std::lround(t)), cells - 1);
      row.r = {r0, r0, r0};
      row.a = {1.0, 0.0, 0.0};
    } else {
      const int cell = std::min(static_cast<int>(t + 0.5), cells - 1);
      const int j0 = std::clamp(cell - 1, 0, cells - 3);  // edges j0..j0+3, cells j0..j0+2
      double x[4];
      for (int k = 0; k < 4; ++k) x[k] = edge(j0 + k);
      x[3] = std::min(x[3], static_cast<double>(cells) - 0.5);
      // L_k'(t) of the Lagrange basis on x[0..3].
      double dl[4];
      for (int k = 0; k < 4; ++k) {
        double denom = 1.0, sum = 0.0;
        for (int j = 0; j < 4; ++j)
          if (j != k) denom *= x[k] - x[j];
        for (int skip = 0; skip < 4; ++skip) {
          if (skip == k) continue;
          double prod = 1.0;
          for (int j = 0; j < 4; ++j)
            if (j != k && j != skip) prod *= t - x[j];
          sum += prod;
        }
        dl[k] = sum / denom;
      }
      // P(x[k]) = sum of (width x mean) of the cells below edge k: cell j0 + i weighs
      // width_i x sum_{k > i} L_k'(t).
      for (int i = 0; i < 3; ++i) {
        double s = 0.0;
        for (int k = i + 1; k < 4; ++k) s += dl[k];
        row.r[i] = j0 + i;
        row.a[i] = (x[i + 1] - x[i]) * s;
      }
    }
    rows.push_back(row);
  }
  return rows;
}

}  // namespace

FitLevel BuildLevel(const Reference& ref, int width) {
  const int W = ref.radiance.width, H = ref.radiance.height;
  FitLevel level;
  level.width = std::min(width, W);
  level.height = level.width / 2;
  // The reference itself (2:1 checked at load); horizon-biased rows always go to uniform nodes.
  if (level.width == W && !ref.row_mapping) level.height = H;
  const int w = level.width, h = level.height;
  const size_t n = static_cast<size_t>(w) * h;
  std::vector<double> sum(3 * n, 0.0), fitted(n, 0.0), assigned(n, 0.0);
  for (const SourceRow& row : SourceRows(ref, h)) {
    const int grid_y = ref.row_mapping ? row.node_y : row.r[0];
    for (int x = 0; x < W; ++x) {
      const int cx = static_cast<int>(std::lround(static_cast<double>(x) * (w - 1) / (W - 1)));
      const size_t ci = static_cast<size_t>(row.node_y) * w + cx;
      const double omega = latlong::PixelSolidAngle(x, grid_y, W, row.grid_height);
      assigned[ci] += omega;
      bool sky = true;
      double v[3] = {0.0, 0.0, 0.0};
      for (int k = 0; k < 3 && sky; ++k) {
        if (row.a[k] == 0.0) continue;
        const size_t fi = static_cast<size_t>(row.r[k]) * W + x;
        sky = ref.pixel_class[fi] == PixelClass::kSky;
        for (int c = 0; c < 3; ++c) v[c] += row.a[k] * ref.radiance.pixels[3 * fi + c];
      }
      if (!sky || !(v[0] > 0.0 && v[1] > 0.0 && v[2] > 0.0)) continue;
      fitted[ci] += omega;
      for (int c = 0; c < 3; ++c) sum[3 * ci + c] += omega * v[c];
    }
  }
  level.radiance.assign(3 * n, 0.0f);
  level.weight.assign(n, 0.0);
  for (size_t i = 0; i < n; ++i) {
    // The node must be above the horizon too: the model is evaluated at the node.
    const int y = static_cast<int>(i / w);
    if (fitted[i] <= 0.0 || fitted[i] < 0.5 * assigned[i] || latlong::Latitude(y, h) <= 0.0) continue;
    level.weight[i] = fitted[i];
    level.total_weight += fitted[i];
    for (int c = 0; c < 3; ++c) level.radiance[3 * i + c] = static_cast<float>(sum[3 * i + c] / fitted[i]);
  }
  return level;
}

std::vector<int> AutomaticPyramid(int reference_width) {
  const int top = std::min(reference_width, 512);
  std::vector<int> widths;
  for (int w = 64; w < top; w *= 2) widths.push_back(w);
  widths.push_back(top);
  return widths;
}

}  // namespace skycal::fit
