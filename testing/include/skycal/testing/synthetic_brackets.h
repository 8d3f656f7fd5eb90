// Synthetic exposure brackets with known truth, shared by tests/hdr_merge_test.cc and
// benchmarks: a real HDR sky (datasets/real/sunset.exr, from datasets/fetch_real_skies.sh;
// else the bundled preset rendered by the CPU reference) photographed by a simulated camera:
// exposure factor k = t * ISO/100 / N^2, sensor value x = gain * L * k, photon (Poisson,
// Gaussian approximation) and read noise in electrons, clipping at full scale, a known tone
// curve, quantisation to 8 (or 16) bits. The merge's expected output is gain * L.
#pragma once
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "skycal/capture/hdr_merge.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/latlong.h"
#include "skycal/core/luminance.h"
#include "skycal/core/png_io.h"
#include "skycal/render/renderer.h"

namespace skycal::synthetic {

enum class CameraCurve {
  kLinear,  // x (a raw developer's linear output)
  kSrgb,    // sRGB OETF (IEC 61966-2-1)
  kFilmic,  // x^(1/2.2), then the contrast S-curve y^a / (y^a + (1-y)^a), a = 1.3 (a JPEG-like tone curve)
};

constexpr double kFilmicContrast = 1.3;

// Linear sensor value in [0, 1] -> normalised code in [0, 1].
inline double CameraEncode(CameraCurve c, double x) {
  x = std::clamp(x, 0.0, 1.0);
  switch (c) {
    case CameraCurve::kLinear: return x;
    case CameraCurve::kSrgb: return x <= 0.0031308 ? 12.92 * x : 1.055 * std::pow(x, 1.0 / 2.4) - 0.055;
    case CameraCurve::kFilmic: {
      const double y = std::pow(x, 1.0 / 2.2), a = std::pow(y, kFilmicContrast), b = std::pow(1.0 - y, kFilmicContrast);
      return a / (a + b);
    }
  }
  return x;
}

// The inverse: normalised code -> linear sensor value.
inline double CameraDecode(CameraCurve c, double v) {
  v = std::clamp(v, 0.0, 1.0);
  switch (c) {
    case CameraCurve::kLinear: return v;
    case CameraCurve::kSrgb: return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
    case CameraCurve::kFilmic: {
      if (v <= 0.0) return 0.0;
      if (v >= 1.0) return 1.0;
      const double r = std::pow(v / (1.0 - v), 1.0 / kFilmicContrast);
      return std::pow(r / (1.0 + r), 2.2);
    }
  }
  return v;
}

struct BracketSpec {
  CameraCurve curve = CameraCurve::kFilmic;
  // 7 brackets 2 stops apart (nominal camera values: 1/60, 1/15 ...), shortest first.
  std::vector<double> exposure_times_s = {1.0 / 4000, 1.0 / 1000, 1.0 / 250, 1.0 / 60, 1.0 / 15, 1.0 / 4, 1.0};
  double f_number = 8.0;   // FH3's rig shot at f/8
  double iso = 100.0;
  // Scene radiance -> linear sensor value per unit exposure factor: x = gain * L * k.
  // 0: automatic, the scene's median luminance reaches 0.18 of full scale in the middle bracket.
  double gain = 0.0;
  double full_well_e = 10000.0;  // electrons at full scale: photon noise sigma(x) = sqrt(x / full_well)
  double read_noise_e = 3.0;     // electrons RMS
  bool noise = true;
  int bits = 8;
  unsigned seed = 1;
  // Thresholds that define "well exposed" for the truth mask (MergeOptions' defaults).
  double low_threshold = 0.02;
  double high_threshold = 0.98;
};

struct SyntheticBrackets {
  std::vector<capture::Bracket> brackets;  // shortest first; path "synthetic_<i>" (in memory)
  ImageRGB truth;                          // expected merge output: gain * L
  std::vector<float> truth_response;       // per code and channel (levels * 3): CameraDecode(code / max)
  std::vector<uint8_t> truth_well;         // per pixel: every channel well exposed (noise-free) in >= 1 bracket
  long long truth_well_pixels = 0;
  double gain = 0.0;
  std::string scene_source;
};

// The scene: datasets/real/sunset.exr (nearest-neighbour resampled to width x height) when
// present, else the bundled preset rendered with the sun 4 degrees up. Non-finite and
// non-positive pixels are raised to the smallest positive value (DWAB ringing).
inline ImageRGB LoadBracketScene(int width, int height, std::string* source) {
  ImageRGB scene;
  const std::string real = std::string(SKYCAL_SOURCE_DIR) + "/datasets/real/sunset.exr";
  if (std::filesystem::exists(real)) {
    const ImageRGB src = ReadExrRGB(real).image;
    scene = ImageRGB(width, height);
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x) {
        const int sx = std::min(src.width - 1, x * src.width / width), sy = std::min(src.height - 1, y * src.height / height);
        for (int c = 0; c < 3; ++c) scene.at(x, y, c) = src.at(sx, sy, c);
      }
    *source = "datasets/real/sunset.exr";
  } else {
    const render::Preset preset = render::LoadPreset(std::string(SKYCAL_SOURCE_DIR) + "/datasets/presets/default_clear.json");
    render::RenderRequest req;
    req.sun_dir = latlong::DirectionFromElevationAzimuthDeg(4.0, 0.0);
    req.width = width;
    req.height = height;
    scene = render::CreateRenderer(render::Backend::kCpu)->Render(preset, req);
    *source = "rendered default_clear preset, sun at 4 deg";
  }
  float floor_value = INFINITY;
  for (float v : scene.pixels)
    if (std::isfinite(v) && v > 0.0f) floor_value = std::min(floor_value, v);
  for (float& v : scene.pixels)
    if (!std::isfinite(v) || v <= 0.0f) v = floor_value;
  return scene;
}

inline SyntheticBrackets MakeSyntheticBrackets(const ImageRGB& scene, const BracketSpec& spec) {
  SyntheticBrackets out;
  const int n = static_cast<int>(spec.exposure_times_s.size());
  const int max_code = spec.bits == 16 ? 65535 : 255;
  const size_t pixels = static_cast<size_t>(scene.width) * scene.height;
  std::vector<double> k(n);
  for (int i = 0; i < n; ++i) k[i] = spec.exposure_times_s[i] * (spec.iso / 100.0) / (spec.f_number * spec.f_number);
  out.gain = spec.gain;
  if (!(out.gain > 0.0)) {
    std::vector<float> lum(pixels);
    for (size_t p = 0; p < pixels; ++p)
      lum[p] = Rec709Luminance(scene.pixels[3 * p], scene.pixels[3 * p + 1], scene.pixels[3 * p + 2]);
    std::nth_element(lum.begin(), lum.begin() + pixels / 2, lum.end());
    std::vector<double> sorted_k = k;
    std::sort(sorted_k.begin(), sorted_k.end());
    out.gain = 0.18 / (lum[pixels / 2] * sorted_k[(n - 1) / 2]);
  }
  out.truth = ImageRGB(scene.width, scene.height);
  for (size_t i = 0; i < scene.pixels.size(); ++i) out.truth.pixels[i] = static_cast<float>(out.gain * scene.pixels[i]);

  out.truth_response.resize(static_cast<size_t>(max_code + 1) * 3);
  for (int z = 0; z <= max_code; ++z)
    for (int c = 0; c < 3; ++c)
      out.truth_response[static_cast<size_t>(z) * 3 + c] = static_cast<float>(CameraDecode(spec.curve, double(z) / max_code));

  // Brackets (one thread each, seeds seed + i: deterministic whatever the scheduling).
  out.brackets.resize(n);
  std::vector<std::thread> pool;
  for (int i = 0; i < n; ++i) {
    pool.emplace_back([&, i] {
      capture::Bracket& b = out.brackets[i];
      b.path = "synthetic_" + std::to_string(i);
      b.exposure_time_s = spec.exposure_times_s[i];
      b.f_number = spec.f_number;
      b.iso = spec.iso;
      b.image.width = scene.width;
      b.image.height = scene.height;
      b.image.bits = spec.bits;
      b.image.rgb.resize(scene.pixels.size());
      std::mt19937 rng(spec.seed * 7919u + static_cast<unsigned>(i));
      std::normal_distribution<double> gauss(0.0, 1.0);
      for (size_t s = 0; s < scene.pixels.size(); ++s) {
        double x = out.gain * scene.pixels[s] * k[i];
        if (spec.noise) {
          const double e = std::min(x, 2.0) * spec.full_well_e;  // beyond 2x full scale it clips anyway
          x = (e + std::sqrt(e) * gauss(rng) + spec.read_noise_e * gauss(rng)) / spec.full_well_e;
        }
        const double v = CameraEncode(spec.curve, std::clamp(x, 0.0, 1.0));
        b.image.rgb[s] = static_cast<uint16_t>(std::lround(v * max_code));
      }
    });
  }
  for (auto& t : pool) t.join();

  // Truth mask from the noise-free codes, with the merge's code thresholds.
  const int low_code = static_cast<int>(std::floor(spec.low_threshold * max_code));
  const int high_code = static_cast<int>(std::ceil(spec.high_threshold * max_code));
  out.truth_well.assign(pixels, 0);
  for (size_t p = 0; p < pixels; ++p) {
    bool all = true;
    for (int c = 0; c < 3 && all; ++c) {
      bool any = false;
      for (int i = 0; i < n && !any; ++i) {
        const long z = std::lround(CameraEncode(spec.curve, out.gain * scene.pixels[3 * p + c] * k[i]) * max_code);
        any = z > low_code && z < high_code;
      }
      all = any;
    }
    out.truth_well[p] = all;
    out.truth_well_pixels += all;
  }
  return out;
}

// Writes the brackets as PNG (8 or 16 bit) into dir; returns the paths, shortest first.
inline std::vector<std::string> WriteBracketsPng(const SyntheticBrackets& s, const std::string& dir) {
  std::vector<std::string> paths;
  for (size_t i = 0; i < s.brackets.size(); ++i) {
    const capture::BracketImage& im = s.brackets[i].image;
    Raster r(im.width, im.height, 3, im.bits == 16 ? 16 : 8);
    for (int y = 0; y < im.height; ++y)
      for (int x = 0; x < im.width; ++x)
        for (int c = 0; c < 3; ++c) {
          const uint16_t v = im.rgb[im.index(x, y) + c];
          if (im.bits == 16)
            r.row16(y)[3 * x + c] = v;
          else
            r.row(y)[3 * x + c] = static_cast<uint8_t>(v);
        }
    paths.push_back(dir + "/bracket_" + std::to_string(i) + ".png");
    const std::vector<uint8_t> png = EncodePng(r, paths.back());
    WriteFileAtomically(paths.back(), std::string(png.begin(), png.end()));
  }
  return paths;
}

struct MergeErrors {
  long long pixels = 0;       // pixels well measured by >= 1 bracket (truth mask), 3 channels each
  double median_rel = 0.0;    // |merged - truth| / truth over those channel values
  double p95_rel = 0.0;
  double gauge[3] = {1, 1, 1};  // median merged / truth per channel (divided out when fit_gauge)
  double curve_median_rel = 0.0;  // recovered vs true response over well-exposed codes, 3 channels
  double curve_p95_rel = 0.0;
  double curve_max_rel = 0.0;
  long long mask_mismatch = 0;  // pixels where MergeResult::well_measured != the truth mask
};

inline double Quantile(std::vector<double> v, double q) {
  if (v.empty()) return NAN;
  const size_t i = std::min(v.size() - 1, static_cast<size_t>(q * (v.size() - 1) + 0.5));
  std::nth_element(v.begin(), v.begin() + i, v.end());
  return v[i];
}

// fit_gauge: a recovered curve's scale is a gauge (MergeResult::response_curve); divide the
// median per-channel ratio out before measuring (for kDebevec / kRobertson).
inline MergeErrors EvaluateMerge(const capture::MergeResult& r, const SyntheticBrackets& s, bool fit_gauge,
                                 double low_threshold = 0.02, double high_threshold = 0.98) {
  MergeErrors e;
  const size_t pixels = s.truth_well.size();
  for (size_t p = 0; p < pixels; ++p) e.mask_mismatch += (r.well_measured[p] > 0.5f) != (s.truth_well[p] != 0);
  for (int c = 0; c < 3; ++c) {
    std::vector<double> ratio;
    for (size_t p = 0; p < pixels; ++p)
      if (s.truth_well[p]) ratio.push_back(r.radiance.pixels[3 * p + c] / s.truth.pixels[3 * p + c]);
    e.gauge[c] = Quantile(ratio, 0.5);
  }
  std::vector<double> rel;
  rel.reserve(pixels * 3);
  for (size_t p = 0; p < pixels; ++p) {
    if (!s.truth_well[p]) continue;
    ++e.pixels;
    for (int c = 0; c < 3; ++c) {
      const double m = r.radiance.pixels[3 * p + c] / (fit_gauge ? e.gauge[c] : 1.0);
      rel.push_back(std::fabs(m - s.truth.pixels[3 * p + c]) / s.truth.pixels[3 * p + c]);
    }
  }
  e.median_rel = Quantile(rel, 0.5);
  e.p95_rel = Quantile(rel, 0.95);
  // Response: compare at the brackets' codes (a 256-level curve is interpolated for 16 bits).
  const int levels = static_cast<int>(s.truth_response.size() / 3), max_code = levels - 1;
  const int low_code = static_cast<int>(std::floor(low_threshold * max_code)) + 1;
  const int high_code = static_cast<int>(std::ceil(high_threshold * max_code)) - 1;
  std::vector<double> crel;
  for (int z = low_code; z <= high_code; ++z)
    for (int c = 0; c < 3; ++c) {
      double rec;
      if (r.response_levels == levels) {
        rec = r.response_curve[static_cast<size_t>(z) * 3 + c];
      } else {  // 256-level curve, 16-bit codes
        const double u = z / 257.0;
        const int i = std::min(254, static_cast<int>(u));
        rec = r.response_curve[i * 3 + c] * (1.0 - (u - i)) + r.response_curve[(i + 1) * 3 + c] * (u - i);
      }
      const double truth = s.truth_response[static_cast<size_t>(z) * 3 + c];
      if (truth > 0.0) crel.push_back(std::fabs(rec - truth) / truth);
    }
  e.curve_median_rel = Quantile(crel, 0.5);
  e.curve_p95_rel = Quantile(crel, 0.95);
  e.curve_max_rel = crel.empty() ? NAN : *std::max_element(crel.begin(), crel.end());
  return e;
}

}  // namespace skycal::synthetic
