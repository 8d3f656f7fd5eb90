// Synthetic stars over a rendered sky (tests/star_removal_test.cc, bench_chart_stars): point
// sources with a Gaussian spread (sigma 0.5 px, the lens), at least `min_separation_px`
// apart, between rows y_lo and y_hi, each with a peak of `contrast` x the sky under it,
// contrast log-uniform in [contrast_lo, contrast_hi]. Deterministic for a seed.
#pragma once
#include <cmath>
#include <random>
#include <vector>

#include "skycal/core/image.h"

namespace skycal::testing {

struct SyntheticStar {
  double x, y;      // centre, pixel-centre coordinates
  double contrast;  // peak / sky
};

inline std::vector<SyntheticStar> AddStars(ImageRGB* img, int count, int y_lo, int y_hi, double contrast_lo,
                                           double contrast_hi, int min_separation_px, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(3.0, img->width - 4.0), uy(y_lo, y_hi), uc(std::log(contrast_lo), std::log(contrast_hi));
  std::vector<SyntheticStar> stars;
  for (int tries = 0; static_cast<int>(stars.size()) < count && tries < 100 * count; ++tries) {
    const SyntheticStar s{ux(rng), uy(rng), std::exp(uc(rng))};
    bool far = true;
    for (const auto& o : stars) far = far && std::max(std::abs(o.x - s.x), std::abs(o.y - s.y)) >= min_separation_px;
    if (far) stars.push_back(s);
  }
  const ImageRGB sky = *img;
  for (const auto& s : stars) {
    const int cx = static_cast<int>(std::lround(s.x)), cy = static_cast<int>(std::lround(s.y));
    for (int dy = -2; dy <= 2; ++dy)
      for (int dx = -2; dx <= 2; ++dx) {
        const int x = cx + dx, y = cy + dy;
        if (x < 0 || y < 0 || x >= img->width || y >= img->height) continue;
        const double g = std::exp(-((x - s.x) * (x - s.x) + (y - s.y) * (y - s.y)) / (2 * 0.25));
        for (int c = 0; c < 3; ++c) img->at(x, y, c) += static_cast<float>(s.contrast * sky.at(cx, cy, c) * g);
      }
  }
  return stars;
}

}  // namespace skycal::testing
