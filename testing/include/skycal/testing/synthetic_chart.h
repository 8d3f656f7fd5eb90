// A ColorChecker Classic rendered into a linear image (tests and bench_chart_stars): the
// chart in OpenCV mcc's layout (6 x 4 patches of 2.5 units, gaps and border 0.25 units,
// 16.75 x 11.25 in all), `unit` pixels per unit, its top-left outer corner at (x0, y0) in
// pixel-edge coordinates. Patch radiance = published reflectance (linear Rec.709) x
// `illuminance`; the gaps are the chart's black frame (reflectance 0.03). Pixels are
// covered by their centre (no anti-aliasing: the sampling keeps to patch centres).
#pragma once
#include <array>

#include "skycal/capture/color_chart.h"
#include "skycal/core/image.h"

namespace skycal::testing {

struct ChartPlacement {
  double x0 = 0.0, y0 = 0.0, unit = 5.0;
  double illuminance = 1.0;
};

// Draws the chart; returns its corners for ChartOptions::corners (pixel-centre coordinates,
// as OpenCV's: the top-left pixel's centre is (0, 0)).
inline std::array<double, 8> RenderChart(ImageRGB* img, const ChartPlacement& p) {
  const auto& ref = capture::ColorCheckerLinearRec709();
  const double w = 16.75 * p.unit, h = 11.25 * p.unit;
  for (int y = 0; y < img->height; ++y) {
    for (int x = 0; x < img->width; ++x) {
      const double u = (x + 0.5 - p.x0) / p.unit, v = (y + 0.5 - p.y0) / p.unit;
      if (u < 0 || v < 0 || u >= 16.75 || v >= 11.25) continue;
      const int col = static_cast<int>((u - 0.25) / 2.75), row = static_cast<int>((v - 0.25) / 2.75);
      const double pu = u - 0.25 - col * 2.75, pv = v - 0.25 - row * 2.75;
      const bool in_patch = u >= 0.25 && v >= 0.25 && col < 6 && row < 4 && pu < 2.5 && pv < 2.5;
      for (int c = 0; c < 3; ++c) {
        img->at(x, y, c) = static_cast<float>(p.illuminance * (in_patch ? ref[row * 6 + col][c] : 0.03));
      }
    }
  }
  const double l = p.x0 - 0.5, t = p.y0 - 0.5;
  return {l, t, l + w, t, l + w, t + h, l, t + h};
}

}  // namespace skycal::testing
