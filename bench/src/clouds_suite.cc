// Suite `clouds`: run time against error of the Horizon Zero Dawn cloud march (docs/benchmarks.md's
// benchmark). Scene: the bundled default_cloudy preset (its clouds section and weather
// map), noise seed 1, sun 25 deg elevation. Error: solid-angle weighted rel RMSE of the
// composite (clear sky x T + clouds) above the horizon against a converged reference —
// the double CPU renderer with every optimisation off, 1,024 primary steps at every
// elevation and the light integral taken along the sun ray itself (64 samples over 8 km,
// no cone, no far sample) — so every approximation of the game's march is measured: its
// primary step, its 6-sample cone of 720 m with the far sample standing in for the rest
// of the light path, and each optimisation. The error is taken at 256x128 (per-pixel error
// does not depend on the image size; the reference is the costly part); time is one
// render at 512x256. Grid: backend x march (the game's settings, the naive march, each HZD
// optimisation switched off alone) x primary steps x light samples, one axis away from the
// game's settings at a time; the CPU reference is timed at the game's and the naive
// settings only.
#include <time.h>

#include <algorithm>
#include <filesystem>
#include <memory>

#include "cloud_scene.h"
#include "image_compare.h"
#include "skycal/clouds/cloud_noise.h"
#include "skycal/clouds/cloud_params.h"
#include "skycal/clouds/cloud_renderer.h"
#include "skycal/clouds/composite.h"
#include "skycal/clouds/weather_map.h"
#include "skycal/core/data_dir.h"
#include "skycal/core/error.h"
#include "skycal/core/latlong.h"
#include "skycal/render/preset.h"
#include "skycal/render/renderer.h"
#include "suite_util.h"
#include "skycal/bench/timing.h"
#include "suites_internal.h"

namespace skycal::bench {
namespace {

// The light_step axis value of the game's default march (MarchOptions::light_step_m), in m.
const std::string kDefaultLightStep = std::to_string(static_cast<int>(clouds::MarchOptions().light_step_m));

// "64/128" -> zenith and horizon primary steps.
void SetSteps(clouds::MarchOptions& m, const std::string& steps) {
  const size_t slash = steps.find('/');
  m.steps_zenith = std::stoi(steps.substr(0, slash));
  m.steps_horizon = std::stoi(steps.substr(slash + 1));
}

// Light samples with the cone's length kept (samples x step = the game's 6 x 240 m).
void SetLightSamples(clouds::MarchOptions& m, int samples) {
  const clouds::MarchOptions game;
  m.light_step_m = game.light_step_m * game.light_samples / samples;
  m.light_samples = samples;
}

}  // namespace

double ProcessCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

clouds::MarchOptions CloudMarchVariant(const std::string& name) {
  clouds::MarchOptions m;
  if (name == "game") return m;
  if (name == "naive") return clouds::MarchOptions::Naive();
  if (name.rfind("naive+", 0) == 0) {  // one optimisation on top of the naive march
    clouds::MarchOptions n = clouds::MarchOptions::Naive();
    const std::string on = name.substr(6);
    if (on == "cheap-march") {  // the whole cheap march, as the game runs it
      n.cheap_march = true;
      n.step_back = m.step_back;
      n.empty_to_cheap = m.empty_to_cheap;
    } else if (on == "cheap-march-no-step-back") {
      n.cheap_march = true;
      n.empty_to_cheap = m.empty_to_cheap;
    } else if (on == "opacity-stop") {
      n.opacity_stop = true;
    } else if (on == "cheap-light") {
      n.cheap_light = true;
    } else if (on == "far-light") {
      n.far_light = true;
    } else {
      throw Error("clouds suite: unknown march setting '" + name + "'");
    }
    return n;
  }
  // Candidates for less added error, the game's march with one number changed:
  // "cheap-light-X" (cheap light samples from opacity X, HZD: 0.3), "far-light-Xm" (the far
  // light sample X metres away), "no-cheap-no-far-light" (both light shortcuts off).
  if (name.rfind("cheap-light-", 0) == 0) {
    m.cheap_light_opacity = std::stod(name.substr(12));
    return m;
  }
  if (name.rfind("far-light-", 0) == 0 && name.back() == 'm') {
    m.far_light_distance_m = std::stod(name.substr(10, name.size() - 11));
    return m;
  }
  if (name == "no-cheap-no-far-light") {
    m.cheap_light = m.far_light = false;
    return m;
  }
  if (name == "no-cheap-march") m.cheap_march = false;
  else if (name == "no-step-back") m.step_back = false;
  else if (name == "no-return-to-cheap") m.empty_to_cheap = 0;
  else if (name == "no-opacity-stop") m.opacity_stop = false;
  else if (name == "no-cheap-light") m.cheap_light = false;
  else if (name == "no-far-light") m.far_light = false;
  else throw Error("clouds suite: unknown march setting '" + name + "'");
  return m;
}

ConvergedCloudReference MakeConvergedCloudReference(const CloudBenchScene& scene, const clouds::CloudRenderRequest& error_req,
                                                    const SuiteOptions& o) {
  // The light integral along the sun ray itself (no cone), in full density, out to 8 km
  // (the layer's far side for a sun >= 18 deg; samples outside the layer add nothing),
  // with no far sample; 1,024 primary steps at every elevation.
  clouds::MarchOptions converged = clouds::MarchOptions::Naive();
  converged.steps_zenith = converged.steps_horizon = o.quick ? 256 : 1024;
  converged.light_samples = o.quick ? 16 : 64;
  converged.light_step_m = 8000.0 / converged.light_samples;
  converged.far_light = false;
  converged.cone_spread = 0.0;

  ConvergedCloudReference ref;
  auto sky_renderer = render::CreateRenderer(render::Backend::kCpu);
  render::RenderRequest sky_req;
  sky_req.sun_dir = error_req.sun_dir;
  sky_req.width = error_req.width;
  sky_req.height = error_req.height;
  sky_req.sun_disc = false;  // the disc would dominate the rel error where clouds leave it visible
  ref.sky = sky_renderer->Render(scene.preset, sky_req);
  std::unique_ptr<clouds::CloudRenderer> cpu = clouds::CreateCpuCloudRenderer(clouds::CloudPrecision::kDouble);
  o.Log("[clouds] reference: cpu double, " + std::to_string(converged.steps_zenith) + " steps, " +
        std::to_string(converged.light_samples) + " light samples, " + std::to_string(error_req.width) + "x" +
        std::to_string(error_req.height));
  clouds::CloudRenderRequest ref_req = error_req;
  ref_req.march = converged;
  ref.clouds = cpu->Render(scene.View(), ref_req);
  ref.truth = clouds::CompositeClouds(ref.sky, ref.clouds);
  return ref;
}

clouds::CloudRenderRequest CloudSuiteRequest(int width) {
  clouds::CloudRenderRequest r;
  r.sun_dir = latlong::DirectionFromElevationAzimuthDeg(25.0, 40.0);
  r.width = width;
  r.height = width / 2;
  return r;
}

void TimeCloudRender(clouds::CloudRenderer& renderer, const CloudBenchScene& scene, const clouds::CloudRenderRequest& request,
                     const SuiteOptions& o, int repeats, CaseResult& c) {
  std::vector<double> cpu_ms;
  c.time = Measure(
      [&] {
        const double cpu0 = ProcessCpuMs();
        renderer.Render(scene.View(), request);
        cpu_ms.push_back(ProcessCpuMs() - cpu0);
      },
      o.warmup, repeats);
  cpu_ms.erase(cpu_ms.begin(), cpu_ms.begin() + std::min<size_t>(cpu_ms.size() - 1, static_cast<size_t>(o.warmup)));
  c.extra["cpu_time_ms"] = FromSamples(cpu_ms).median_ms;
}

CloudBenchScene LoadDefaultCloudyScene() {
  const std::string path = DataPath("datasets/presets/default_cloudy.json");
  CloudBenchScene s;
  s.preset = render::LoadPreset(path);
  s.params = clouds::ParseCloudSectionText(s.preset.clouds_json, path);
  const std::string map = (std::filesystem::path(path).parent_path() / s.params.weather_map).string();
  s.weather = clouds::LoadWeatherMap(map, s.params.weather_extent_m);
  s.noise = clouds::LoadOrGenerateCloudNoise(1, clouds::DefaultCloudNoiseCacheDir());
  return s;
}

namespace {

// Backend x march variant x steps x light samples x light step, one setting away from the
// game's at a time; the CPU reference at the game's and the naive settings only.
Grid CloudsGrid(bool quick) {
  Grid grid;
  grid.axes = {{"backend", {"vulkan", "cpu"}, "vulkan"},
               {"march", quick ? std::vector<std::string>{"game", "naive"}
                               : std::vector<std::string>{"game", "naive", "no-cheap-march", "no-step-back",
                                                          "no-return-to-cheap", "no-opacity-stop", "no-cheap-light",
                                                          "no-far-light"},
                "game"},
               {"steps", quick ? std::vector<std::string>{"32/64", "64/128"}
                               : std::vector<std::string>{"16/32", "32/64", "64/128", "96/192", "128/256", "256/512"},
                "64/128"},
               {"light_samples", quick ? std::vector<std::string>{"6"} : std::vector<std::string>{"3", "6", "12"}, "6"},
               // Metres between the 6 light samples (the cone's length / 6): 120 m covers only
               // 720 m toward the sun, less than a cumulus is deep at low sun (the old default).
               {"light_step", quick ? std::vector<std::string>{kDefaultLightStep} : std::vector<std::string>{"120", "240", "400"},
                kDefaultLightStep}};
  grid.skip = [](const Settings& c) -> std::string {
    const int off_default = (Get(c, "march") != "game") + (Get(c, "steps") != "64/128") +
                            (Get(c, "light_samples") != "6") + (Get(c, "light_step") != kDefaultLightStep);
    if (off_default > 1) return "one setting away from the game's at a time";
    const bool game_or_naive = off_default == 0 || (Get(c, "march") == "naive");
    if (Get(c, "backend") == "cpu" && !game_or_naive) return "the CPU reference is timed at the game's and the naive settings";
    return "";
  };
  return grid;
}

}  // namespace

Suite CloudsSuite() {
  Suite s;
  s.name = "clouds";
  s.summary = "HZD cloud march of the bundled cloudy preset (sun 25 deg): backend x march x steps x light samples x light step";
  s.error_metric = "rel RMSE of the composite above the horizon vs a converged double reference (1,024 steps, light integral on the sun ray: 64 samples over 8 km)";
  s.error_axis = "rel RMSE vs converged clouds";
  s.run = [](const SuiteOptions& o) {
    const CloudBenchScene scene = LoadDefaultCloudyScene();
    const Grid grid = CloudsGrid(o.quick);

    const clouds::CloudRenderRequest error_req = CloudSuiteRequest(o.quick ? 64 : 256);
    const clouds::CloudRenderRequest time_req = CloudSuiteRequest(o.quick ? 128 : 512);

    const ConvergedCloudReference ref = MakeConvergedCloudReference(scene, error_req, o);
    const ImageRGB& sky = ref.sky;
    const clouds::CloudImage& reference = ref.clouds;
    const ImageRGB& truth = ref.truth;
    std::unique_ptr<clouds::CloudRenderer> cpu = clouds::CreateCpuCloudRenderer(clouds::CloudPrecision::kDouble);
    std::unique_ptr<clouds::CloudRenderer> vulkan = clouds::CreateVulkanCloudRenderer();

    const int repeats = o.Repeats(o.quick ? 3 : 5);
    return RunGrid("clouds", grid, o, [&](CaseResult& c) {
      clouds::CloudRenderer& r = Get(c.settings, "backend") == "cpu" ? *cpu : *vulkan;
      clouds::MarchOptions m = CloudMarchVariant(Get(c.settings, "march"));
      SetSteps(m, Get(c.settings, "steps"));
      SetLightSamples(m, std::stoi(Get(c.settings, "light_samples")));
      if (Get(c.settings, "light_step") != kDefaultLightStep)  // the cone's length scaled, the sample count kept
        m.light_step_m = std::stod(Get(c.settings, "light_step")) * clouds::MarchOptions().light_samples / m.light_samples;
      clouds::CloudRenderRequest er = error_req, tr = time_req;
      er.march = tr.march = m;
      const clouds::CloudImage at_error_size = r.Render(scene.View(), er);
      const ImageRGB composite = clouds::CompositeClouds(sky, at_error_size);
      // Wall time, and the process's CPU time per render (all threads, lavapipe's included):
      // on a machine shared with other jobs the CPU time measures the work where the wall
      // time measures the share of the cores the process got (bench_cloud_march's second
      // column, now here).
      TimeCloudRender(r, scene, tr, o, repeats, c);
      if (!AllFinite(composite)) {
        c.outcome = Outcome::kNonFinite;
        c.message = "non-finite composite";
      }
      c.error = RelRmse(truth, composite, 0.0);
      // The same above 10 deg: near the horizon a ray crosses up to 35 km of layer, where
      // the primary step (270 m at the game's 128) undersamples the 22 m detail texels.
      c.extra["rel_rmse_above_10deg"] = RelRmse(truth, composite, 10.0);
      // Transmittance error over the reference's cloud pixels (T < 0.99), the clouds alone.
      double sum = 0.0;
      int n = 0;
      for (size_t i = 0; i < reference.transmittance.size(); ++i) {
        if (reference.transmittance[i] < 0.99f) {
          sum += std::abs(at_error_size.transmittance[i] - reference.transmittance[i]);
          ++n;
        }
      }
      c.extra["transmittance_mae_cloud_pixels"] = n ? sum / n : 0.0;
      c.extra["cloud_pixels"] = n;
      c.extra["size_timed"] = std::to_string(time_req.width) + "x" + std::to_string(time_req.height);
      c.extra["device"] = r.Describe();
    });
  };
  return s;
}

}  // namespace skycal::bench
