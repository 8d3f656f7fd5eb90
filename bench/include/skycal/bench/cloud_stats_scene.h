// The synthetic unknown-shapes scene of the cloud statistics fit (docs/cloud-fitting.md, regime 2),
// shared by its test (tests/cloud_stats_test.cc) and its benchmark suites
// (`skycal bench --suite fit-cloud-stats,cloud-stats-noise`: bench/src/fit_cloud_stats_suite.cc,
// cloud_stats_noise_suite.cc): the bundled default_cloudy preset, a reference rendered with
// one noise seed and weather-map seed, and a model scene with another pair of seeds and
// the same weather statistics (default_cloudy's procedural map: mean coverage 0.32,
// contrast 3, 8 cells). Header-only: the test does not link the bench library.
#pragma once
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <memory>
#include <string>

#include "skycal/cloudfit/cloud_stats.h"
#include "skycal/clouds/cloud_noise.h"
#include "skycal/clouds/cloud_params.h"
#include "skycal/clouds/cloud_renderer.h"
#include "skycal/clouds/weather_map.h"
#include "skycal/core/latlong.h"
#include "skycal/render/preset.h"
#include "skycal/render/renderer.h"

namespace skycal::bench {

struct CloudStatsSeeds {
  uint64_t noise = 1, weather = 11;
};

struct CloudStatsSyntheticScene {
  render::Preset preset;
  clouds::CloudParams truth;
  clouds::CloudNoise noise;        // the model's shapes
  clouds::WeatherMap weather;
  cloudfit::CloudStatsReference reference;
};

// The renderer of the benchmark's fits: Vulkan, else (no device) the float CPU path, said on stderr.
inline std::unique_ptr<clouds::CloudRenderer> CreateCloudStatsRenderer() {
  try {
    return clouds::CreateVulkanCloudRenderer(false);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "no Vulkan device (%s): the float CPU path renders\n", e.what());
    return clouds::CreateCpuCloudRenderer(clouds::CloudPrecision::kFloat, 2);
  }
}

// The scratch folder of the benchmark's and test's noise textures.
inline std::string CloudStatsCacheDir() {
  return (std::filesystem::temp_directory_path() / "skycal-cloud-stats-cache").string();
}

inline clouds::WeatherMap CloudStatsWeather(uint64_t seed, double extent_m) {
  clouds::WeatherNoiseOptions w;
  w.mean_coverage = 0.32;
  w.coverage_contrast = 3.0;
  w.coverage_cells = 8;
  return clouds::NoiseWeatherMap(seed, 256, extent_m, w);
}

// The reference is rendered with `ref_seeds` and the true parameters through `renderer`;
// the model scene carries `model_seeds`. Noise is cached in `cache_dir`.
inline CloudStatsSyntheticScene MakeCloudStatsScene(const std::string& source_dir, CloudStatsSeeds ref_seeds,
                                                    CloudStatsSeeds model_seeds, double sun_elevation_deg,
                                                    double sun_azimuth_deg, const cloudfit::CloudStatsOptions& options,
                                                    clouds::CloudRenderer& renderer, const std::string& cache_dir) {
  CloudStatsSyntheticScene s;
  s.preset = render::LoadPreset(source_dir + "/datasets/presets/default_cloudy.json");
  s.truth = clouds::ParseCloudSectionText(s.preset.clouds_json, "default_cloudy.json");
  s.noise = clouds::LoadOrGenerateCloudNoise(model_seeds.noise, cache_dir);
  s.weather = CloudStatsWeather(model_seeds.weather, s.truth.weather_extent_m);
  const auto sun = latlong::DirectionFromElevationAzimuthDeg(sun_elevation_deg, sun_azimuth_deg);
  render::RenderRequest sky_req;
  sky_req.sun_dir = sun;
  sky_req.width = options.render_width;
  sky_req.height = options.render_height;
  sky_req.sun_disc = false;
  auto& ref = s.reference;
  ref.name = "synthetic";
  ref.sun_dir = sun;
  ref.clear_sky = render::CreateRenderer(render::Backend::kCpu)->Render(s.preset, sky_req);
  const clouds::CloudNoise ref_noise = clouds::LoadOrGenerateCloudNoise(ref_seeds.noise, cache_dir);
  const clouds::WeatherMap ref_weather = CloudStatsWeather(ref_seeds.weather, s.truth.weather_extent_m);
  cloudfit::CloudStatsScene ref_scene{&s.preset, s.truth, &ref_noise, &ref_weather};
  const cloudfit::CloudStatsRender r = cloudfit::RenderForCloudStats(ref, ref_scene, s.truth, renderer, options);
  ref.radiance = r.composite;
  ref.opacity = r.opacity;
  return s;
}

}  // namespace skycal::bench
