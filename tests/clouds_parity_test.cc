// Parity of the cloud backends. A march with data-dependent branches (is the base density
// zero? has the opacity passed 0.3 or ~1?) can flip a branch between float and double, so
// parity is defined in two tiers:
//   1. float CPU path vs Vulkan, per pixel: the same source, the same float parameters,
//      direction tables and textures, so the same decisions except where a comparison sits
//      within float rounding of its threshold. Per pixel, with L_max the image's largest
//      cloud radiance: |dT| <= kPixelT and |dL| <= kPixelL * (|L| + 1e-3 L_max) for all but
//      a fraction kFlipFraction of the pixels (the branch flips), and no pixel worse than
//      kPixelWorst of L_max or in T (a flip changes one sample, not the picture).
//   2. double reference vs Vulkan, on image statistics: mean cloud radiance per channel,
//      mean transmittance and the fraction of cloud pixels (T < 0.99), relative to the
//      reference, within kStatRel (float rounding over ~10^2 samples, plus branch flips on
//      the image's edges of clouds).
// The sweep: sun -10..90 deg, coverage 0..1, the three cloud types, the game's march and
// the naive one, octaves 0-2, both integrations, the cirrus sheet on and off (128 x 64
// images keep it cheap).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <cstdio>
#include <memory>
#include <numbers>

#include "cloud_test_scenes.h"
#include "skycal/clouds/cloud_noise.h"
#include "skycal/clouds/cloud_renderer.h"
#include "skycal/clouds/cloud_renderer_stats.h"
#include "skycal/clouds/weather_map.h"

namespace skycal::clouds {
namespace {

// Thresholds (measured maxima over the sweep in brackets, lavapipe on 2 cores):
//   kPixelT 2e-5 [5.9e-6]: T is a product of ~10^2 float exponentials, each within a few
//     ulp of the CPU's (lavapipe's exp is not correctly rounded): ~100 x 6e-8 ~ 6e-6;
//   kPixelL 3e-4 relative [1.4e-4; < 1e-5 of L_max]: the same rounding on sums of ~10^2
//     terms, largest in thin, faint cloud where the sum cancels least favourably;
//   kFlipFraction 0.5% [0.012%: one pixel of 8,192, itself within 1e-5 of L_max]: a flipped
//     branch touches the pixels where a density sits within rounding of 0 or an opacity
//     within rounding of 0.3 / 0.999, a thin set;
//   kPixelWorst 0.25 of L_max or in T: one flipped decision changes one or a few samples;
//   kStatRel 1e-3 [2.2e-5]: double vs float rounding averages out over an image; the margin
//     allows branch flips on edges of clouds.
struct Tolerances {
  double pixel_t, pixel_l, flip_fraction, pixel_worst, stat_rel;
};
constexpr Tolerances kBuffers{2e-5, 3e-4, 0.005, 0.25, 1e-3};
// The march on sampled images (hardware filter). Lavapipe filters RGBA32F in float
// (tests/sampled_image_test.cc: its error is ~0.2% of the 8-bit weight bound), so texels,
// weights and decisions are the exact filter's up to rounding, and the tiers are the texel
// buffers' except kPixelT 5e-5 [2.0e-5]: the sampler blends by nested lerps, not the
// source's weighted sum, a few more ulp on each of the ~10^2 density reads behind one T.
// A device with 8-bit filter weights moves each density by up to 3 x 2^-8 of its texels'
// spread: there the sampler-level bound of sampled_image_test is the contract, not this sweep.
constexpr Tolerances kImages{5e-5, 3e-4, 0.005, 0.25, 1e-3};

struct Stats {
  double mean_l[3] = {0, 0, 0}, mean_t = 0, cloud_fraction = 0;
};
Stats ImageStats(const CloudImage& c) {
  Stats s;
  const size_t n = c.transmittance.size();
  for (size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) s.mean_l[k] += c.radiance.pixels[3 * i + k] / n;
    s.mean_t += c.transmittance[i] / n;
    s.cloud_fraction += (c.transmittance[i] < 0.99f ? 1.0 : 0.0) / n;
  }
  return s;
}

struct CaseResult {
  double flip_fraction = 0, worst_l = 0, worst_t = 0, tight_t = 0, worst_rel = 0, stat = 0, cloud_fraction = 0;
};

// Tier 1 (a: float CPU vs b: Vulkan, per pixel) and tier 2 (d: double reference vs b, image
// statistics) of one case.
CaseResult Compare(const CloudImage& a, const CloudImage& b, const CloudImage& d, const Tolerances& tol) {
  CaseResult r;
  double l_max = 0.0;
  for (float v : a.radiance.pixels) l_max = std::max(l_max, static_cast<double>(v));
  size_t flips = 0;
  for (size_t p = 0; p < a.transmittance.size(); ++p) {
    const double dt = std::abs(a.transmittance[p] - b.transmittance[p]);
    bool ok = dt <= tol.pixel_t;
    r.worst_t = std::max(r.worst_t, dt);
    for (int k = 0; k < 3; ++k) {
      const double la = a.radiance.pixels[3 * p + k], lb = b.radiance.pixels[3 * p + k];
      ok = ok && std::abs(la - lb) <= tol.pixel_l * (std::abs(la) + 1e-3 * l_max);
      r.worst_l = std::max(r.worst_l, std::abs(la - lb) / std::max(l_max, 1e-30));
      r.worst_rel = std::max(r.worst_rel, std::abs(la - lb) / (std::abs(la) + 1e-3 * l_max + 1e-30));
    }
    if (!ok) ++flips;
    else r.tight_t = std::max(r.tight_t, dt);
  }
  r.flip_fraction = static_cast<double>(flips) / a.transmittance.size();
  const Stats sd = ImageStats(d), sb = ImageStats(b);
  r.stat = std::abs(sb.mean_t - sd.mean_t) / std::max(sd.mean_t, 1e-3);
  r.stat = std::max(r.stat, std::abs(sb.cloud_fraction - sd.cloud_fraction) / std::max(sd.cloud_fraction, 0.01));
  for (int k = 0; k < 3; ++k) r.stat = std::max(r.stat, std::abs(sb.mean_l[k] - sd.mean_l[k]) / std::max(sd.mean_l[k], 1e-3));
  r.cloud_fraction = sd.cloud_fraction;
  return r;
}

// The sweep above, the Vulkan renderer `vk` against the CPU paths.
void RunSweep(CloudRenderer& vk, const Tolerances& tol) {
  const auto cpu_f = CreateCpuCloudRenderer(CloudPrecision::kFloat, 2);
  const auto cpu_d = CreateCpuCloudRenderer(CloudPrecision::kDouble, 2);
  const render::Preset preset = render::LoadPreset(std::string(SKYCAL_SOURCE_DIR) + "/datasets/presets/default_clear.json");
  // Cases 0-9: hand-made sinusoid noise; 10-11: the generator's noise (seed 1, cached beside
  // the other test temporaries) and a procedural weather map, whose Worley edges put more
  // densities near 0 (where a branch can flip).
  const CloudNoise sinusoid = testing::SinusoidCloudNoise();
  const CloudNoise generated =
      LoadOrGenerateCloudNoise(1, (std::filesystem::temp_directory_path() / "skycal-clouds-parity-cache").string());
  const double elevations[] = {-10.0, 3.0, 25.0, 60.0, 90.0};
  const float coverages[] = {0.0f, 0.3f, 0.55f, 0.8f, 1.0f};
  const float types[] = {0.0f, 0.5f, 1.0f};
  double worst_flip = 0.0, worst_stat = 0.0, worst_tight_t = 0.0;
  for (int i = 0; i < 12; ++i) {
    const CloudNoise& noise = i < 10 ? sinusoid : generated;
    const double el = elevations[i % 5] * std::numbers::pi / 180.0;
    const float coverage = coverages[(i * 3) % 5];
    const float type = types[i % 3];
    const bool game = i % 2 == 0;
    WeatherNoiseOptions wo;
    wo.mean_coverage = std::clamp(static_cast<double>(coverage), 0.2, 0.8);
    wo.mean_type = type;
    const WeatherMap weather = i < 10 ? testing::PatchyWeather(coverage, type) : NoiseWeatherMap(11 + i, 64, 60000.0, wo);
    CloudParams params;
    params.ms_octaves = i % 3;
    params.integration = i % 4 == 3 ? 1.0 : 0.0;
    params.cirrus_coverage = i % 2 == 1 ? 0.6 : 0.0;  // the 2D sheet in half the cases
    CloudRenderRequest request;
    request.width = 128;
    request.height = 64;
    request.sun_dir = {0.5 * std::cos(el), std::sin(el), 0.866 * std::cos(el)};
    request.march = game ? MarchOptions{} : MarchOptions::Naive();
    request.time_s = 100.0 * i;
    const CloudScene scene{&preset, &params, &noise, &weather};
    const CloudImage a = cpu_f->Render(scene, request);
    const CloudImage b = vk.Render(scene, request);
    const CloudImage d = cpu_d->Render(scene, request);
    const CaseResult r = Compare(a, b, d, tol);
    std::printf("case %d: sun %5.1f deg coverage %.2f type %.1f %s octaves %d: flips %.4f%%, worst dL/Lmax %.2e, worst dL rel %.2e, worst dT %.2e, "
                "tight dT %.2e, stats rel %.2e, cloud fraction %.3f\n",
                i, elevations[i % 5], coverage, type, game ? "game " : "naive", i % 3, 100.0 * r.flip_fraction, r.worst_l,
                r.worst_rel, r.worst_t, r.tight_t, r.stat, r.cloud_fraction);
    EXPECT_LE(r.flip_fraction, tol.flip_fraction) << "case " << i;
    EXPECT_LE(r.worst_l, tol.pixel_worst) << "case " << i;
    EXPECT_LE(r.worst_t, tol.pixel_worst) << "case " << i;
    EXPECT_LE(r.stat, tol.stat_rel) << "case " << i;
    worst_flip = std::max(worst_flip, r.flip_fraction);
    worst_stat = std::max(worst_stat, r.stat);
    worst_tight_t = std::max(worst_tight_t, r.tight_t);
  }
  std::printf("maxima: flip fraction %.4f%%, tight-pixel dT %.2e, statistics %.2e\n", 100.0 * worst_flip, worst_tight_t, worst_stat);
}

TEST(CloudsParity, FloatCpuVsVulkanPerPixelAndDoubleVsVulkanStatistics) {
  std::unique_ptr<CloudRenderer> vk;
  try {
    vk = CreateVulkanCloudRenderer(false, CloudTextures::kBuffers);
  } catch (const std::exception& e) {
    GTEST_SKIP() << "no Vulkan device: " << e.what();
  }
  EXPECT_FALSE(RendererDeviceStats(*vk).sampled_images);
  RunSweep(*vk, kBuffers);
}

TEST(CloudsParity, SampledImagesAgainstTheCpuPaths) {
  std::unique_ptr<CloudRenderer> vk;
  try {
    vk = CreateVulkanCloudRenderer(false, CloudTextures::kImages);
  } catch (const std::exception& e) {
    GTEST_SKIP() << "no Vulkan device: " << e.what();
  }
  if (!RendererDeviceStats(*vk).sampled_images) GTEST_SKIP() << "the device cannot sample the textures as images";
  RunSweep(*vk, kImages);
}

}  // namespace
}  // namespace skycal::clouds
