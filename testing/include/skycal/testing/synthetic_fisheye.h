// Synthetic rig views of a lat-long sky, shared by tests/lens_unwrap_test.cc and benchmarks:
// what each camera of a rig (capture/rig.h) would record of a known lat-long, and the
// round-trip error of stitching those views back (capture::UnwrapToLatLong).
#pragma once
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <optional>
#include <thread>
#include <vector>

#include "skycal/capture/lens.h"
#include "skycal/capture/rig.h"
#include "skycal/core/image.h"
#include "skycal/core/latlong.h"
#include "skycal/core/luminance.h"
#include "skycal/core/math_constants.h"

namespace skycal::synthetic {

// Bilinear sample of a lat-long (project convention, core/latlong.h) along a unit world
// direction. Columns 0 and W-1 are the same longitude, so clamping at the seam is exact.
inline void SampleLatLong(const ImageRGB& ll, const std::array<double, 3>& dir, float out[3]) {
  const auto p = latlong::PixelPosition(dir, ll.width, ll.height);
  const double x = std::clamp(p[0], 0.0, ll.width - 1.0), y = std::clamp(p[1], 0.0, ll.height - 1.0);
  const int x0 = std::min(static_cast<int>(x), ll.width - 2), y0 = std::min(static_cast<int>(y), ll.height - 2);
  const double fx = x - x0, fy = y - y0;
  for (int c = 0; c < 3; ++c) {
    const double top = (1 - fx) * ll.at(x0, y0, c) + fx * ll.at(x0 + 1, y0, c);
    const double bottom = (1 - fx) * ll.at(x0, y0 + 1, c) + fx * ll.at(x0 + 1, y0 + 1, c);
    out[c] = static_cast<float>((1 - fy) * top + fy * bottom);
  }
}

// The image `camera` would record of the lat-long sky (camera.width x camera.height): each
// pixel the lat-long's radiance along its ray (bilinear point sample: views are meant to be
// finer than the lat-long), times the lens's vignetting gain; 0 outside the image circle.
// Rows are shared among `threads` threads.
inline ImageRGB RenderCameraView(const ImageRGB& latlong, const capture::RigCamera& camera, int threads = 2) {
  ImageRGB img(camera.width, camera.height);
  const auto& r = camera.rotation;
  std::atomic<int> next{0};
  auto worker = [&] {
    std::vector<capture::Vec2d> pix(camera.width);
    std::vector<capture::Vec3d> rays(camera.width);
    std::vector<unsigned char> valid(camera.width);
    for (int y; (y = next.fetch_add(1)) < camera.height;) {
      for (int x = 0; x < camera.width; ++x) pix[x] = {static_cast<double>(x), static_cast<double>(y)};
      capture::PixelsToRays(camera.lens, pix, rays, valid);
      for (int x = 0; x < camera.width; ++x) {
        if (!valid[x]) continue;
        const auto& v = rays[x];
        const std::array<double, 3> w{r[0] * v[0] + r[1] * v[1] + r[2] * v[2], r[3] * v[0] + r[4] * v[1] + r[5] * v[2],
                                      r[6] * v[0] + r[7] * v[1] + r[8] * v[2]};
        float rgb[3];
        SampleLatLong(latlong, w, rgb);
        const double gain = capture::VignettingGain(camera.lens, pix[x]);
        for (int c = 0; c < 3; ++c) img.at(x, y, c) = static_cast<float>(rgb[c] * gain);
      }
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < std::max(1, threads); ++t) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  return img;
}

// A fisheye lens whose image circle is inscribed in a size x size image.
inline capture::LensParams InscribedLens(capture::LensModel model, double fov_deg, int size,
                                         std::array<double, 4> kb_k = {}, std::array<double, 3> vignetting = {}) {
  capture::LensParams lens;
  lens.model = model;
  lens.fov_deg = fov_deg;
  lens.center_x = lens.center_y = 0.5 * (size - 1);
  lens.radius_px = 0.5 * size;
  lens.kb_k = kb_k;
  lens.vignetting = vignetting;
  return lens;
}

// n cameras with the same lens, optical axes pitch_deg above the horizon and yaw_deg0 +
// i * 360 / n in azimuth (the FH3 rig: three fisheyes 120 degrees apart, tilted up).
inline std::vector<capture::RigCamera> RingRig(const capture::LensParams& lens, int width, int height, int n = 3,
                                               double pitch_deg = 30.0, double yaw_deg0 = 0.0) {
  std::vector<capture::RigCamera> rig;
  for (int i = 0; i < n; ++i) {
    capture::RigCamera c;
    c.lens = lens;
    c.width = width;
    c.height = height;
    c.rotation = capture::RotationFromYawPitchRollDeg(yaw_deg0 + 360.0 * i / n, pitch_deg, 0.0);
    c.name = "cam" + std::to_string(i);
    rig.push_back(c);
  }
  return rig;
}

struct ErrorStats {
  double median = 0.0, p95 = 0.0, max = 0.0;
  long long pixels = 0;
};
struct RoundTripError {
  ErrorStats luminance;      // relative error of Rec.709 luminance
  ErrorStats worst_channel;  // per node, the largest relative error of R, G, B
};

inline ErrorStats Stats(std::vector<double> v) {
  ErrorStats s;
  s.pixels = static_cast<long long>(v.size());
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  auto q = [&](double f) { return v[std::min(v.size() - 1, static_cast<size_t>(f * (v.size() - 1) + 0.5))]; };
  s.median = q(0.5);
  s.p95 = q(0.95);
  s.max = v.back();
  return s;
}

// Relative error of `got` against `truth` (same size) over the nodes that count as covered
// sky: coverage > 0, elevation >= min_elevation_deg, more than sun_exclusion_deg from the
// sun (when given), truth finite and > 0 in every channel, and mask >= 0.5 where a mask
// (width * height values) is given.
inline RoundTripError CompareLatLong(const ImageRGB& truth, const ImageRGB& got, const std::vector<float>& coverage,
                                     double min_elevation_deg, std::optional<std::array<double, 3>> sun,
                                     double sun_exclusion_deg, const std::vector<float>& mask = {}) {
  std::vector<double> lum, worst;
  const double cos_sun = std::cos(sun_exclusion_deg * kPi / 180.0);
  for (int y = 0; y < truth.height; ++y) {
    for (int x = 0; x < truth.width; ++x) {
      const size_t i = static_cast<size_t>(y) * truth.width + x;
      if (!(coverage[i] > 0.0f)) continue;
      if (!mask.empty() && !(mask[i] >= 0.5f)) continue;
      const auto d = latlong::PixelDirection(x, y, truth.width, truth.height);
      if (latlong::ElevationDeg(d) < min_elevation_deg) continue;
      if (sun && d[0] * (*sun)[0] + d[1] * (*sun)[1] + d[2] * (*sun)[2] > cos_sun) continue;
      double t[3], g[3], w = 0.0;
      bool ok = true;
      for (int c = 0; c < 3; ++c) {
        t[c] = truth.at(x, y, c);
        g[c] = got.at(x, y, c);
        ok = ok && std::isfinite(t[c]) && t[c] > 0.0;
        const double e = std::abs(g[c] - t[c]) / t[c];
        if (ok) w = std::max(w, e <= 1e30 ? e : 1e30);  // a non-finite result counts as a huge error
      }
      if (!ok) continue;
      const double lt = Rec709Luminance(t[0], t[1], t[2]);
      const double lg = Rec709Luminance(g[0], g[1], g[2]);
      const double e = std::abs(lg - lt) / lt;
      lum.push_back(e <= 1e30 ? e : 1e30);
      worst.push_back(w);
    }
  }
  return {Stats(std::move(lum)), Stats(std::move(worst))};
}

}  // namespace skycal::synthetic
