#include "skycal/core/appearance.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "skycal/core/error.h"
#include "skycal/core/format_number.h"
#include "skycal/core/latlong.h"
#include "skycal/core/luminance.h"
#include "skycal/core/math_constants.h"
#include "skycal/core/parallel_chunks.h"
#include "skycal/core/sort_pairs.h"

namespace skycal::appearance {
namespace {

// A value and its weight (a pixel's solid angle, steradians).
using Weighted = std::vector<std::pair<double, double>>;

// The weighted q-quantile of a population sorted by value: the smallest value whose
// cumulative weight reaches q of the total.
double WeightedQuantileOfSorted(const Weighted& v, double q) {
  double total = 0.0;
  for (const auto& p : v) total += p.second;
  double acc = 0.0;
  for (const auto& p : v) {
    acc += p.second;
    if (acc >= q * total) return p.first;
  }
  return v.back().first;
}

// Each population sorted once (a band's luminance serves three quantiles), on up to four
// threads: at 2048x1024 a band holds ~200,000 pixels, and a calibration compares two images.
void SortEach(std::vector<Weighted*>& populations) {
  const int n = static_cast<int>(populations.size());
  ParallelChunks(n, std::min(ResolveThreads(0), 4), [&](int begin, int end, int) {
    for (int k = begin; k < end; ++k) SortPairs(populations[k]);
  });
}

bool Counts(const std::vector<float>& sky, size_t i) { return sky.empty() || sky[i] > 0.5f; }

double ElevationDeg(int y, int height) { return latlong::Latitude(y, height) * kDegreesPerRadian; }

// The photo's median sky luminance (unweighted: only the scale of the floor depends on it).
double MedianSkyLuminance(const ImageRGB& im, const std::vector<float>& sky, const Options& o) {
  std::vector<double> y;
  for (int r = 0; r < im.height; ++r) {
    if (ElevationDeg(r, im.height) < o.min_elevation_deg) continue;
    for (int x = 0; x < im.width; ++x) {
      const size_t i = static_cast<size_t>(r) * im.width + x;
      if (!Counts(sky, i)) continue;
      const double v = Rec709Luminance<double>(im.pixels[3 * i], im.pixels[3 * i + 1], im.pixels[3 * i + 2]);
      if (std::isfinite(v)) y.push_back(v);
    }
  }
  if (y.empty()) return 0.0;
  std::nth_element(y.begin(), y.begin() + y.size() / 2, y.end());
  return y[y.size() / 2];
}

double LnFloored(double v, double floor) { return std::log(std::isfinite(v) && v > floor ? v : floor); }

}  // namespace

std::string Options::IsValid() const {
  if (!(band_deg > 0.0 && band_deg <= 90.0))
    return "Options::band_deg = " + FormatNumber(band_deg) + ": must be in (0, 90] degrees";
  if (!(min_elevation_deg >= -90.0 && min_elevation_deg < 90.0))
    return "Options::min_elevation_deg = " + FormatNumber(min_elevation_deg) + ": must be in [-90, 90) degrees";
  if (!(floor_fraction > 0.0 && floor_fraction < 1.0))
    return "Options::floor_fraction = " + FormatNumber(floor_fraction) + ": must be in (0, 1)";
  if (min_band_pixels < 1) return "Options::min_band_pixels = " + std::to_string(min_band_pixels) + ": must be >= 1";
  return "";
}

std::vector<BandStats> BandStatistics(const ImageRGB& im, const std::vector<float>& sky, double floor,
                                      const Options& o) {
  const int bands = static_cast<int>(std::ceil((90.0 - o.min_elevation_deg) / o.band_deg - 1e-9));
  std::vector<Weighted> ly(bands), rg(bands), bg(bands);
  for (int r = 0; r < im.height; ++r) {
    const double elev = ElevationDeg(r, im.height);
    if (elev < o.min_elevation_deg) continue;
    const int b = std::min(bands - 1, static_cast<int>((elev - o.min_elevation_deg) / o.band_deg));
    for (int x = 0; x < im.width; ++x) {
      const size_t i = static_cast<size_t>(r) * im.width + x;
      if (!Counts(sky, i)) continue;
      const double w = latlong::PixelSolidAngle(x, r, im.width, im.height);
      const double red = im.pixels[3 * i], green = im.pixels[3 * i + 1], blue = im.pixels[3 * i + 2];
      const double lg = LnFloored(green, floor);
      ly[b].emplace_back(LnFloored(Rec709Luminance(red, green, blue), floor), w);
      rg[b].emplace_back(LnFloored(red, floor) - lg, w);
      bg[b].emplace_back(LnFloored(blue, floor) - lg, w);
    }
  }
  std::vector<Weighted*> populations;
  for (int b = 0; b < bands; ++b)
    for (Weighted* v : {&ly[b], &rg[b], &bg[b]}) populations.push_back(v);
  SortEach(populations);
  std::vector<BandStats> out;
  for (int b = 0; b < bands; ++b) {
    BandStats s;
    s.elevation_lo_deg = o.min_elevation_deg + b * o.band_deg;
    s.elevation_hi_deg = std::min(90.0, s.elevation_lo_deg + o.band_deg);
    s.pixels = static_cast<int>(ly[b].size());
    if (s.pixels > 0) {
      s.ln_y_q10 = WeightedQuantileOfSorted(ly[b], 0.1);
      s.ln_y_q50 = WeightedQuantileOfSorted(ly[b], 0.5);
      s.ln_y_q90 = WeightedQuantileOfSorted(ly[b], 0.9);
      s.ln_r_over_g = WeightedQuantileOfSorted(rg[b], 0.5);
      s.ln_b_over_g = WeightedQuantileOfSorted(bg[b], 0.5);
    }
    out.push_back(s);
  }
  return out;
}

namespace {

// Solid-angle-weighted RMS of ln(game / photo) over the counted pixels and channels.
double PerPixelLogRmse(const ImageRGB& photo, const ImageRGB& game, const std::vector<float>& sky,
                       double floor, const Options& o, int* pixels) {
  double sum = 0.0, wsum = 0.0;
  *pixels = 0;
  for (int r = 0; r < photo.height; ++r) {
    if (ElevationDeg(r, photo.height) < o.min_elevation_deg) continue;
    for (int x = 0; x < photo.width; ++x) {
      const size_t i = static_cast<size_t>(r) * photo.width + x;
      if (!Counts(sky, i)) continue;
      const double w = latlong::PixelSolidAngle(x, r, photo.width, photo.height);
      for (int c = 0; c < 3; ++c) {
        const double d = LnFloored(game.pixels[3 * i + c], floor) - LnFloored(photo.pixels[3 * i + c], floor);
        sum += w * d * d;
      }
      wsum += 3.0 * w;
      ++*pixels;
    }
  }
  return wsum > 0.0 ? std::sqrt(sum / wsum) : 0.0;
}

}  // namespace

Comparison Compare(const ImageRGB& photo, const ImageRGB& game, const std::vector<float>& sky,
                   const Options& o, const std::string& photo_name, const std::string& game_name) {
  if (const std::string e = o.IsValid(); !e.empty()) throw Error("appearance comparison: " + e);
  if (photo.empty() || photo.width != game.width || photo.height != game.height)
    throw Error(game_name + ": " + std::to_string(game.width) + " x " + std::to_string(game.height) +
                " pixels, expected the size of " + photo_name + " (" + std::to_string(photo.width) + " x " +
                std::to_string(photo.height) + ")");
  if (!sky.empty() && sky.size() != static_cast<size_t>(photo.width) * photo.height)
    throw Error(photo_name + ": the sky mask has " + std::to_string(sky.size()) + " weights, expected one per pixel (" +
                std::to_string(static_cast<size_t>(photo.width) * photo.height) + ")");
  const double median = MedianSkyLuminance(photo, sky, o);
  if (!(median > 0.0))
    throw Error(photo_name + ": no sky pixel with a positive luminance at or above " +
                FormatNumber(o.min_elevation_deg) + " degrees of elevation; nothing to compare");
  const double floor = o.floor_fraction * median;
  Comparison c;
  c.per_pixel_log_rmse = PerPixelLogRmse(photo, game, sky, floor, o, &c.sky_pixels);
  const std::vector<BandStats> p = BandStatistics(photo, sky, floor, o), g = BandStatistics(game, sky, floor, o);
  double sum = 0.0;
  for (size_t b = 0; b < p.size(); ++b) {
    if (p[b].pixels < o.min_band_pixels || g[b].pixels < o.min_band_pixels) continue;
    const double d[5] = {g[b].ln_y_q10 - p[b].ln_y_q10, g[b].ln_y_q50 - p[b].ln_y_q50, g[b].ln_y_q90 - p[b].ln_y_q90,
                         g[b].ln_r_over_g - p[b].ln_r_over_g, g[b].ln_b_over_g - p[b].ln_b_over_g};
    for (double v : d) sum += v * v;
    c.photo.push_back(p[b]);
    c.game.push_back(g[b]);
  }
  c.bands_compared = static_cast<int>(c.photo.size());
  c.appearance_error = c.bands_compared > 0 ? std::sqrt(sum / (5.0 * c.bands_compared)) : 0.0;
  return c;
}

CloudLayerAgreement CompareCloudLayers(const std::vector<float>& photo_t, const std::vector<float>& game_t, int width,
                                       int height, const std::vector<float>& sky, const Options& o,
                                       const std::string& game_name) {
  if (const std::string e = o.IsValid(); !e.empty()) throw Error("cloud layer comparison: " + e);
  const size_t n = static_cast<size_t>(width) * height;
  if (photo_t.size() != n || game_t.size() != n || (!sky.empty() && sky.size() != n))
    throw Error(game_name + ": cloud transmittance of " + std::to_string(game_t.size()) + " pixels against " +
                std::to_string(photo_t.size()) + " (and a sky mask of " + std::to_string(sky.size()) +
                "), expected " + std::to_string(n));
  CloudLayerAgreement a;
  double sum = 0.0, wsum = 0.0, both = 0.0, either = 0.0;
  for (int r = 0; r < height; ++r) {
    if (ElevationDeg(r, height) < o.min_elevation_deg) continue;
    for (int x = 0; x < width; ++x) {
      const size_t i = static_cast<size_t>(r) * width + x;
      if (!Counts(sky, i)) continue;
      const double w = latlong::PixelSolidAngle(x, r, width, height), d = game_t[i] - photo_t[i];
      sum += w * d * d;
      wsum += w;
      const bool p = photo_t[i] < 0.5f, g = game_t[i] < 0.5f;
      both += w * (p && g);
      either += w * (p || g);
      ++a.pixels;
    }
  }
  a.opacity_rms = wsum > 0.0 ? std::sqrt(sum / wsum) : 0.0;
  if (either > 0.0) a.iou = both / either;
  return a;
}

std::vector<float> WithoutSunCone(std::vector<float> sky, int width, int height, const std::array<double, 3>& sun,
                                  double cone_deg) {
  if (sky.empty()) sky.assign(static_cast<size_t>(width) * height, 1.0f);
  const double cos_cone = std::cos(cone_deg * kPi / 180.0);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const auto d = latlong::PixelDirection(x, y, width, height);
      if (d[0] * sun[0] + d[1] * sun[1] + d[2] * sun[2] >= cos_cone) sky[static_cast<size_t>(y) * width + x] = 0.0f;
    }
  return sky;
}

}  // namespace skycal::appearance
