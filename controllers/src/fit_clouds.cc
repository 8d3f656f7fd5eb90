#include "skycal/controllers/fit_clouds.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "skycal/cloudfit/cloud_lighting_json.h"
#include "skycal/clouds/cloud_noise.h"
#include "skycal/clouds/weather_map.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/json_file.h"
#include "skycal/core/format_number.h"
#include "fit_cloud_mask.h"
#include "fit_internal.h"

namespace skycal::controllers {
namespace fs = std::filesystem;
namespace {

// fit.json's decision record and the log quote the command line `skycal fit` takes (the
// report shows them to the user as they are): the library's names of the mode and the shapes
// written as the options that set them.
std::string DecisionWording(std::string text) {
  static const std::pair<const char*, const char*> kNames[] = {
      {"CloudMode on", "--clouds on"}, {"CloudMode off", "--clouds off"}, {"CloudMode auto", "--clouds auto"},
      {"KnownCloudShapes", "--cloud-preset"}};
  for (const auto& [name, wording] : kNames) {
    const std::string n = name, w = wording;
    for (size_t at = text.find(n); at != std::string::npos; at = text.find(n, at + w.size())) text.replace(at, n.size(), w);
  }
  return text;
}

}  // namespace

bool FitCloudOptions::IsValid(std::string* why) const {
  try {
    const cloudfit::CloudMode m = cloudfit::ParseCloudMode(mode, "FitCloudOptions::mode");
    if (m == cloudfit::CloudMode::kOff && !preset.empty()) {
      *why = "FitCloudOptions::preset has no effect with FitCloudOptions::mode = off";
      return false;
    }
  } catch (const Error& e) {
    *why = e.what();
    return false;
  }
  if (sky_pixels_sun_boost && !(*sky_pixels_sun_boost >= 0.0 && *sky_pixels_sun_boost <= 5.0)) {
    *why = "FitCloudOptions::sky_pixels_sun_boost = " + FormatNumber(*sky_pixels_sun_boost) +
           " (expected [0, 5], as capture::CloudMaskOptions::sun_boost)";
    return false;
  }
  if (time_s && (!std::isfinite(*time_s) || std::abs(*time_s) > 1.0e7)) {
    *why = "FitCloudOptions::time_s = " + FormatNumber(*time_s) + " (expected seconds, finite, within 1e7)";
    return false;
  }
  cloudfit::CloudLightingOptions co;
  co.samples = samples;
  co.max_iterations = max_iterations;
  co.day_smoothness = day_smoothness;
  co.iterations_after_refinement = iterations_after_refinement;
  co.hold = hold;
  return co.IsValid(why);  // its messages name CloudLightingOptions' fields of the same names
}

std::vector<NamedPath> FitCloudInputs(const FitCloudOptions& o) {
  if (o.preset.empty()) return {};
  return PresetFileInputs("FitCloudOptions::preset", o.preset);
}

std::unique_ptr<LoadedCloudShapes> LoadFitCloudShapes(const FitCloudOptions& o) {
  if (o.preset.empty()) return nullptr;
  const render::Preset p = render::LoadPreset(o.preset);
  if (p.clouds_json.empty()) throw Error(o.preset + ": FitCloudOptions::preset: the preset has no 'clouds' section");
  auto out = std::make_unique<LoadedCloudShapes>();
  out->shapes.params = clouds::ParseCloudSectionText(p.clouds_json, o.preset);  // names the file and field
  out->origin = o.preset;
  if (out->shapes.params.weather_map.empty()) {
    throw Error(o.preset + ": field 'clouds.weather_map' is missing and no --weather-map was given (expected an RGB EXR: "
                "coverage, precipitation, type)");
  }
  out->weather_origin = (fs::path(o.preset).parent_path() / out->shapes.params.weather_map).string();
  out->weather = clouds::LoadWeatherMap(out->weather_origin, out->shapes.params.weather_extent_m);
  out->noise = clouds::SharedCloudNoise(kRenderCloudNoiseSeed, clouds::UsableCloudNoiseCacheDir());
  out->shapes.noise = out->noise.get();
  out->shapes.weather = &out->weather;
  out->shapes.time_s = o.time_s.value_or(0.0);
  return out;
}

cloudfit::SkyCloudFit RunSkyCloudFit(const FitCloudOptions& o, const std::vector<fit::Reference>& refs,
                                     const render::Preset& init, const fit::FitOptions& fo, render::SkyRenderer& renderer,
                                     const std::vector<const fit::ProbeSamples*>& probes, const LoadedCloudShapes* shapes) {
  const cloudfit::CloudMode mode = cloudfit::ParseCloudMode(o.mode, "FitCloudOptions::mode");
  cloudfit::CloudDecision d;
  if (mode == cloudfit::CloudMode::kAuto && !shapes) {
    // No shapes: nothing could be marched, so the mask is not even computed (a clear-sky
    // fit pays nothing for the clouds feature).
    d.why = "--clouds auto: no cloud shapes given (--cloud-preset): clouds off without looking (the cloud mask "
            "was not computed); their pixels, if any, count in the sky terms";
  } else {
    d = cloudfit::DecideClouds(mode, refs, init, shapes != nullptr);  // its errors name CloudMode and KnownCloudShapes
    d.why = DecisionWording(d.why);
  }
  if (fo.verbose) FitLog("clouds: " + d.why);  // fit --quiet and skycal bench: off
  cloudfit::CloudLightingOptions co;
  co.samples = o.samples;
  co.max_iterations = o.max_iterations;
  co.fit_sun_scale = o.fit_sun_scale;
  co.values_from_renderer = o.values_from_renderer;
  co.restart_at_bounds = o.restart_at_bounds;
  co.release_inseparable = o.release_inseparable;
  co.start_prior = o.start_prior;
  co.refine_shapes = o.refine_shapes;
  co.iterations_after_refinement = o.iterations_after_refinement;
  co.hold = o.hold;
  co.day_smoothness = o.day_smoothness;
  co.verbose = fo.verbose;
  cloudfit::KnownCloudShapes known;
  if (shapes) {
    known = shapes->shapes;
    if (!o.time_s) {
      // Each reference's own wind time (a time-lapse's clouds move between frames).
      for (const fit::Reference& r : refs) {
        const ExrAttributes a = ReadExrHeader(r.path).attributes;
        const auto it = a.floats.find("skycalCloudTimeS");
        known.time_s_per_reference.push_back(it != a.floats.end() ? it->second : 0.0);
      }
    }
  }
  std::unique_ptr<clouds::CloudRenderer> cloud_renderer;
  if (d.march) {
    // The values come from the cloud renderer of the sky's backend: Vulkan (the game's
    // path) by default, the double CPU model with --backend cpu.
    cloud_renderer = fo.backend == render::Backend::kVulkan ? clouds::CreateVulkanCloudRenderer()
                                                            : clouds::CreateCpuCloudRenderer(clouds::CloudPrecision::kDouble);
    if (fo.verbose) FitLog("clouds: values from " + cloud_renderer->Describe() + ", derivatives from the Jet march (CPU)");
  }
  std::vector<std::vector<fit::PixelClass>> photo_clear;  // FitCloudOptions::sky_pixels_from_photo
  if (d.march && o.sky_pixels_from_photo) {
    for (const fit::Reference& r : refs) {
      fit::Reference masked = r;
      capture::CloudMaskOptions ramp;
      if (o.sky_pixels_sun_boost) ramp.sun_boost = *o.sky_pixels_sun_boost;
      const CloudMaskApplied cm = ApplyCloudMask(&masked, DefaultClearPresetPath(), ramp);
      if (fo.verbose) FitLog("clouds: the sky stage fits the photo's clear pixels (" + std::to_string(masked.counts.sky) +
                             "; cloud probability < 0.5, " + cm.source + ", the ramp's allowance by the sun " +
                             FormatNumber(ramp.sun_boost) + ")");
      photo_clear.push_back(std::move(masked.pixel_class));
    }
  }
  cloudfit::SkyCloudFit f =
      cloudfit::FitSkyAndClouds(refs, init, fo, renderer, probes, d, cloudfit::CloudTermKind::kKnownShapes,
                                shapes ? &known : nullptr, co, cloud_renderer.get(), photo_clear.empty() ? nullptr : &photo_clear);
  if (d.march) {
    f.clouds.decision = d.why;
    for (cloudfit::CloudLightingReport& r : f.references) r.decision = d.why;
    f.sky.decisions.push_back({"cloud mask for --clouds " + o.mode, d.why, 0.0,
                               "none: the mask cost " + FormatNumber(1000.0 * d.time_s) + " ms", std::nullopt, ""});
  }
  return f;
}

nlohmann::json CloudReportJson(const FitCloudOptions& o, const cloudfit::SkyCloudFit& f) {
  return cloudfit::CloudReportJson({o.mode, o.preset, o.time_s, o.day_smoothness}, f);
}

void AttachFittedClouds(const cloudfit::SkyCloudFit& f, const LoadedCloudShapes& shapes, const fs::path& preset_json,
                        render::Preset* preset) {
  const cloudfit::CloudLightingReport& r = f.clouds;
  if (!r.fitted) return;
  clouds::CloudParams p = r.fitted_params;
  const std::string weather_name = preset_json.stem().string() + ".weather.exr";
  clouds::SaveWeatherMap(f.refined_weather ? *f.refined_weather : shapes.weather,
                         (preset_json.parent_path() / weather_name).string());
  p.weather_map = weather_name;
  preset->clouds_json = clouds::CloudSectionToJson(p).dump();
  if (f.references.size() > 1) {
    WriteJsonFileAtomically(preset_json.parent_path() / (preset_json.stem().string() + ".cloud_keyframes.json"),
                            cloudfit::CloudDayKeyframesJson(f));
  }
}

}  // namespace skycal::controllers
