#include "calibrate_weather.h"

#include <chrono>
#include <filesystem>
#include <memory>
#include <utility>

#include "skycal/capture/cloud_mask.h"
#include "skycal/capture/cloud_opacity.h"
#include "skycal/capture/latlong_frame.h"
#include "skycal/cloudfit/cloud_lighting_params.h"
#include "skycal/cloudfit/weather_inversion.h"
#include "skycal/clouds/cloud_noise.h"
#include "skycal/clouds/cloud_params.h"
#include "skycal/clouds/cloud_renderer.h"
#include "skycal/clouds/weather_map.h"
#include "skycal/controllers/fit_controller.h"
#include "skycal/controllers/game_render.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/format_number.h"
#include "skycal/core/json_file.h"
#include "skycal/core/latlong.h"
#include "skycal/core/latlong_resample.h"
#include "skycal/core/math_constants.h"
#include "skycal/fit/fit_result_file.h"
#include "skycal/render/preset.h"
#include "skycal/render/renderer.h"

namespace skycal::controllers {
namespace {

std::vector<float> Opacity(const std::vector<float>& transmittance) {
  std::vector<float> o(transmittance.size());
  for (size_t i = 0; i < o.size(); ++i) o[i] = 1.0f - transmittance[i];
  return o;
}

// The horizon rule puts cumulus at a fixed coverage beyond 15 km whatever the map says: below
// about 20 degrees it would draw a bank of cloud where the photo shows the sky. The photo's
// horizon is the truth, so the inverted map draws it.
void TurnOffHorizonRule(const std::filesystem::path& preset_json) {
  nlohmann::json j = ReadJsonFile(preset_json.string());
  j.at("clouds").at("horizon_rule")["value"] = false;
  WriteJsonFileAtomically(preset_json.string(), j);
}

// Which texels the photo constrained (1) and which kept the statistics fit's coverage (0),
// on the map's grid (EXR row 0 is map row 0, as the weather map).
void WriteConstrainedTexels(const cloudfit::WeatherTexelView& v, const std::filesystem::path& path) {
  ImageRGB image(v.map_width, v.map_height);
  for (size_t t = 0; t < v.linked.size(); ++t)
    for (int c = 0; c < 3; ++c) image.pixels[3 * t + c] = v.linked[t] ? 1.0f : 0.0f;
  ExrAttributes attributes;
  attributes.strings["skycalContent"] = "weather-map texels the photo constrained (1) or left to the statistics (0)";
  WriteExrRGB(path.string(), image, attributes, ExrPixelType::kHalf);
}

// A sun hidden by a cloud carved a hole through it (its glare read as clear sky), where the
// game then drew the disc. Within kSunGlareDeg of the sun the photo's opacity is taken from
// the ring around it (kSunGlareDeg to 1.5x), where the colour is trusted.
void FillSunGlare(std::vector<float>* opacity, const std::vector<float>& sky, int width, int height,
                  const std::array<double, 3>& sun) {
  const double inner = std::cos(kSunGlareDeg * kRadiansPerDegree), outer = std::cos(1.5 * kSunGlareDeg * kRadiansPerDegree);
  std::vector<size_t> glare;
  double sum = 0.0, n = 0.0;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const auto d = latlong::PixelDirection(x, y, width, height);
      const double c = d[0] * sun[0] + d[1] * sun[1] + d[2] * sun[2];
      const size_t i = static_cast<size_t>(y) * width + x;
      if (c > inner) glare.push_back(i);
      else if (c > outer && sky[i] >= 0.5f) sum += (*opacity)[i], n += 1.0;
    }
  if (n > 0.0)
    for (size_t i : glare) (*opacity)[i] = static_cast<float>(sum / n);
}

// The object `key` of a fit record's clouds.solve (the refit's second solves), or null.
const nlohmann::json* SolveRecord(const nlohmann::json& clouds, const char* key) {
  if (!clouds.is_object() || !clouds.contains("solve") || !clouds["solve"].is_object()) return nullptr;
  const nlohmann::json& solve = clouds["solve"];
  return solve.contains(key) && solve[key].is_object() ? &solve[key] : nullptr;
}

// The photo's cloud opacity at the inversion's width (`sky`: the sky mask there): its colour
// unmixed into the statistics fit's clear sky (times its exposure) and the clouds' light
// (capture/cloud_opacity.h), the cloud probability standing in where the two colours are
// alike, 0 outside the sky, the sun's glare filled from around it.
std::vector<float> PhotoOpacity(const PhotoAnalysis& a, const StagedDirectory& out, const render::Preset& preset,
                                const std::vector<float>& sky, int rw, int rh, WeatherInversionRecord* r,
                                ImageRGB* photo_small) {
  const int w = a.frame.radiance.width, h = a.frame.radiance.height;
  std::vector<float> probability(a.cloud_probability.size());
  for (size_t i = 0; i < probability.size(); ++i)
    probability[i] = a.mask.sky[i] >= 0.5f ? a.cloud_probability[i] : 0.0f;
  ImageRGB photo(rw, rh);
  photo.pixels = AreaDownsampleLatLongOfPositive(a.frame.radiance.pixels, w, h, 3, rw, rh);
  const double exposure = fit::ReadFitResultFile(out / "fit.json").references.at(0).exposure;
  capture::CloudOpacity o = capture::EstimateCloudOpacity(photo, ClearSkyInPhotoUnits(a, preset, exposure, rw, rh),
                                                          AreaDownsampleLatLong(probability, w, h, 1, rw, rh), sky, {});
  FillSunGlare(&o.opacity, sky, rw, rh, *a.sun.direction);
  r->cloud_colour = o.cloud_colour;
  r->colour_pixels = o.colour_pixels;
  r->opacity_from_probability = o.unmixed + o.from_probability > 0
                                    ? static_cast<double>(o.from_probability) / static_cast<double>(o.unmixed + o.from_probability)
                                    : 0.0;
  *photo_small = std::move(photo);
  return std::move(o.opacity);
}

}  // namespace

ImageRGB ClearSkyInPhotoUnits(const PhotoAnalysis& a, const render::Preset& preset, double exposure, int width,
                              int height) {
  render::RenderRequest req;
  req.sun_dir = *a.sun.direction;
  req.width = width;
  req.height = height;
  req.sun_disc = false;
  ImageRGB clear = render::CreateRenderer(render::Backend::kCpu)->Render(preset, req);
  for (float& v : clear.pixels) v = static_cast<float>(v * exposure);
  return clear;
}

// 512 for a photo at least that wide (a texel near the zenith is about a pixel there), else
// 256; the photo averaged down to it (core/latlong_resample.h for a size that is no multiple).
// At 256 for a 512-wide photo every other column of the game's image fell between the rays the
// refinement followed, and the clouds near the horizon hung in vertical streaks
// (bench/results/weather_inversion.md).
int InversionRenderWidth(int width, int height) {
  constexpr int kRenderWidths[] = {512, 256};
  for (int rw : kRenderWidths)
    if (width >= rw && height >= rw / 2) return rw;
  return 0;
}

// "; solved again from the far side of a bound 1 time(s), ..." from the refit's record, or "".
std::string BoundRestartsText(const nlohmann::json& clouds) {
  const nlohmann::json* record = SolveRecord(clouds, "bound_restarts");
  if (!record) return "";
  const nlohmann::json& r = *record;
  const std::string kept = r.value("kept", std::string());
  return "; solved again from the far side of a bound " + std::to_string(r.value("tried", 0)) + " time(s), " +
         (kept.empty() ? std::string("the first solve kept (lower cost)")
                       : "the restart in " + kept + " kept (lower cost)");
}

std::string ReleasedHoldsText(const nlohmann::json& clouds) {
  const nlohmann::json* record = SolveRecord(clouds, "released_holds");
  if (!record) return "";
  const nlohmann::json& r = *record;
  std::string names;
  for (const auto& n : r.value("freed", nlohmann::json::array())) names += (names.empty() ? "" : ", ") + n.get<std::string>();
  const auto cost = [&](const char* key) { return FormatNumber(std::round(r.value(key, 0.0) * 1e4) / 1e4); };
  return "; then the holds of the separability rule released (" + names + ") and the solve continued: cost " +
         cost("cost_before") + " -> " + cost("cost_after") +
         (r.value("kept", false) ? std::string(", kept (the freed values are the image's best, not determined ones)")
                                 : std::string(", not kept (no lower)"));
}

std::string ParametersAtBounds(const nlohmann::json& clouds) {
  std::string out;
  const auto p = clouds.is_object() ? clouds.find("parameters") : clouds.end();
  if (p == clouds.end() || !p->is_object()) return out;
  for (int k = 0; k < cloudfit::kCloudLightingParameters; ++k) {
    const auto e = p->find(cloudfit::CloudLightingNames()[k]);
    if (e == p->end() || !e->is_object() || e->value("held", true) || !(*e)["value"].is_number()) continue;
    const double v = (*e)["value"].get<double>();
    const int end = cloudfit::CloudLightingRangeEnd(k, v);
    if (end == 0) continue;
    out += (out.empty() ? "" : ", ") + std::string(cloudfit::CloudLightingNames()[k]) + " " + FormatNumber(v) +
           (end > 0 ? " (its maximum)" : " (its minimum)");
  }
  return out;
}

fit::FitDecision WeatherInversionRecord::Decision() const {
  fit::FitDecision d;
  d.saved_ms_basis = "not measured in this run";
  if (!done) {
    d.what = "weather map: the statistical one kept";
    d.why = why_not;
    return d;
  }
  d.what = "weather map inverted from the photo: the clouds where the photo has them";
  d.why = std::to_string(constrained) + " of " + std::to_string(texels) + " texels seen by the photo (" +
          kConstrainedTexelsFile + "; the rest keep the statistics fit's coverage); rendered vs photo cloud opacity RMS";
  for (double r : rms) d.why += " " + FormatNumber(std::round(r * 1000.0) / 1000.0);
  d.why += " over " + std::to_string(rms.size()) + " renders at " + std::to_string(render_width) + " px wide";
  const auto f3 = [](double v) { return FormatNumber(std::round(v * 1000.0) / 1000.0); };
  d.why += "; the photo's opacity unmixed from its colour (the statistics fit's clear sky behind, the clouds' colour";
  for (double c : cloud_colour) d.why += " " + f3(c);
  if (colour_pixels > 0) d.why += " from " + std::to_string(colour_pixels) + " sure cloud pixels";
  else d.why += " (grey: too few sure cloud pixels)";
  d.why += "; the cloud probability stood in for " + f3(100.0 * opacity_from_probability) +
           "% of the sky pixels, whose colour matches the clouds')";
  if (horizon_rule_off)
    d.why += "; the horizon rule off (it would draw a bank of cumulus beyond 15 km where the photo shows its own horizon)";
  return d;
}

std::unique_ptr<clouds::CloudRenderer> OpacityRenderer(render::Backend backend) {
  return backend == render::Backend::kVulkan ? clouds::CreateVulkanCloudRenderer()
                                             : clouds::CreateCpuCloudRenderer(clouds::CloudPrecision::kFloat);
}

clouds::CloudRenderRequest OpacityRequest(int width, int height) {
  clouds::CloudRenderRequest r;
  r.width = width;
  r.height = height;
  r.march.light_samples = 0;
  r.march.far_light = false;
  return r;
}

std::optional<double> CloudIou(const std::vector<float>& transmittance, const std::vector<float>& probability,
                               const std::vector<float>& compared) {
  if (transmittance.empty() || probability.size() != transmittance.size()) return std::nullopt;
  double both = 0.0, either = 0.0;
  for (size_t i = 0; i < compared.size(); ++i) {
    if (!(compared[i] >= 0.5f)) continue;
    const bool game = transmittance[i] < 0.5f, photo = probability[i] >= 0.5f;
    both += game && photo;
    either += game || photo;
  }
  if (either == 0.0) return std::nullopt;
  return both / either;
}

WeatherInversionRecord InvertPhotoWeather(const PhotoAnalysis& a, const StagedDirectory& out, render::Backend backend,
                                          PhotoWeatherView* kept) {
  const auto t0 = std::chrono::steady_clock::now();
  WeatherInversionRecord r;
  const render::Preset preset = render::LoadPreset(out / "preset.json");
  const int w = a.frame.radiance.width, h = a.frame.radiance.height;
  const int rw = InversionRenderWidth(w, h), rh = rw / 2;
  if (preset.clouds_json.empty() || a.cloud_probability.empty() || !std::filesystem::exists(out / "preset.weather.exr")) {
    r.why_not = "no fitted clouds section, cloud probability or weather map to invert";
    return r;
  }
  if (rw == 0) {
    r.why_not = "the photo's size " + std::to_string(w) + "x" + std::to_string(h) +
                " is smaller than 256x128 (the refinement renders')";
    return r;
  }
  clouds::CloudParams params = clouds::ParseCloudSectionText(preset.clouds_json, out / "preset.json");
  r.horizon_rule_off = params.horizon_rule != 0.0;
  if (r.horizon_rule_off) {
    params.horizon_rule = 0.0;
    TurnOffHorizonRule(out / "preset.json");
  }
  clouds::WeatherMap map = clouds::LoadWeatherMap(out / "preset.weather.exr", params.weather_extent_m);
  if (map.width < cloudfit::kInvertedMapSize) map = clouds::ResampleWeatherMap(map, cloudfit::kInvertedMapSize);
  PhotoWeatherView v;
  v.width = rw;
  v.height = rh;
  v.sky = AreaDownsampleLatLong(a.mask.sky, w, h, 1, rw, rh);
  v.opacity = PhotoOpacity(a, out, preset, v.sky, rw, rh, &r, &v.photo);
  v.texels = cloudfit::ProjectWeatherTexels(params, map.width, map.height, rw, rh, v.sky);
  const cloudfit::WeatherTexelView& view = v.texels;
  // The march's transmittance through the map being refined.
  const auto noise = clouds::SharedCloudNoise(kCloudNoiseSeed, clouds::UsableCloudNoiseCacheDir());
  const std::unique_ptr<clouds::CloudRenderer> renderer = OpacityRenderer(backend);
  clouds::CloudRenderRequest request = OpacityRequest(rw, rh);
  request.sun_dir = *a.sun.direction;
  const auto render = [&](const clouds::WeatherMap& m) {
    return Opacity(renderer->Render({&preset, &params, noise.get(), &m}, request).transmittance);
  };
  r.rms = cloudfit::InvertWeatherMap(view, params.weather_extent_m, v.opacity, render, {}, &map);
  clouds::SaveWeatherMap(map, out / "preset.weather.exr");
  WriteConstrainedTexels(view, out / kConstrainedTexelsFile);
  r.done = true;
  r.texels = map.width * map.height;
  r.constrained = view.constrained;
  r.render_width = rw;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (kept) *kept = std::move(v);
  return r;
}

fit::FitDecision HoldWeatherMap(const std::string& weather_map, const StagedDirectory& out) {
  const render::Preset preset = render::LoadPreset(out / "preset.json");
  const clouds::CloudParams params = clouds::ParseCloudSectionText(preset.clouds_json, out / "preset.json");
  clouds::SaveWeatherMap(clouds::LoadWeatherMap(weather_map, params.weather_extent_m), out / "preset.weather.exr");
  fit::FitDecision d;
  d.what = "weather map: the user's, held (not inverted)";
  d.why = "CalibrateOptions::weather_map = " + weather_map + ": the clouds' shapes given; the lighting is fitted on them";
  d.saved_ms_basis = "not measured in this run";
  return d;
}

namespace {

namespace fs = std::filesystem;

// Copies the preset's files (preset.json and every preset.* beside it) into `to`.
void CopyPresetFiles(const fs::path& from, const fs::path& to) {
  fs::create_directories(to);
  for (const auto& e : fs::directory_iterator(from))
    if (e.is_regular_file() && e.path().filename().string().starts_with("preset"))
      fs::copy_file(e.path(), to / e.path().filename(), fs::copy_options::overwrite_existing);
}

// Moves every visible entry of `from` over its namesake in `to`.
void MoveUp(const fs::path& from, const fs::path& to) {
  for (const auto& e : fs::directory_iterator(from)) {
    if (e.path().filename().string().starts_with(".")) continue;
    fs::remove_all(to / e.path().filename());
    fs::rename(e.path(), to / e.path().filename());
  }
}

// The refit reads the photo and its sky mask box-averaged to the inversion's width (when the
// photo is wider): a handful of lighting parameters and the sky's LUT need no more pixels,
// and the known-shapes fit prepares and composites every cloud pixel at the references' size
// (at 2048x1024 that was most of the command). The game's image is still rendered and judged
// at the photo's size. The photo is averaged over its positive pixels (import zeroes the
// non-finite ones; the fit reads positive radiance). Returns the (photo, mask) the refit reads.
std::pair<fs::path, fs::path> RefitInputs(const StagedDirectory& out, const fs::path& dir) {
  const fs::path photo = out / "photo.exr", mask = out / "mask.exr";
  capture::LatLongFrame f = capture::ReadLatLongFrame(photo.string());
  const int w = f.radiance.width, h = f.radiance.height, rw = InversionRenderWidth(w, h);
  if (rw == 0 || rw >= w) return {photo, mask};
  const int rh = rw / 2;
  fs::create_directories(dir);
  ImageRGB radiance(rw, rh);  // over the positive pixels: import zeroes the non-finite ones
  radiance.pixels = AreaDownsampleLatLongOfPositive(f.radiance.pixels, w, h, 3, rw, rh);
  f.radiance = std::move(radiance);
  capture::WriteLatLongFrame((dir / "photo.exr").string(), f);
  const ExrRGB m = ReadExrRGB(mask.string());
  ImageRGB small_mask(rw, rh);
  small_mask.pixels = AreaDownsampleLatLong(m.image.pixels, w, h, 3, rw, rh);
  WriteExrRGB((dir / "mask.exr").string(), small_mask, m.attributes, ExrPixelType::kHalf);
  return {dir / "photo.exr", dir / "mask.exr"};
}

std::string CloudPixelsLogRmse(const nlohmann::json& clouds, const char* when) {
  const auto c = clouds.is_object() ? clouds.find("cloud_pixels") : clouds.end();
  if (c == clouds.end() || !c->contains(when) || !(*c)[when].contains("log_rmse")) return "?";
  return FormatNumber(std::round((*c)[when]["log_rmse"].get<double>() * 1000.0) / 1000.0);
}

// The refit's pull toward the statistics fit's lighting, as a clause of its decision.
std::string StartPriorText(double start_prior) {
  if (start_prior <= 0.0) return "";
  return "every parameter pulled weakly toward the statistics fit's lighting (weight " + FormatNumber(start_prior) +
         ": what the image does not determine stays near it instead of landing in another basin with each small "
         "change of the start); ";
}

// The refit's decision, from its record's `clouds`.
fit::FitDecision RefitDecision(const nlohmann::json& clouds, int iterations, double start_prior) {
  fit::FitDecision d;
  d.saved_ms_basis = "not measured in this run";
  d.what = "cloud lighting refitted pixel by pixel on the recovered shapes (known shapes)";
  d.why = "extinction held (the inversion set the coverage for it: the two trade in opacity, and a refitted extinction "
          "would thin or thicken the shapes it placed); the clouds' sun scale fitted with the albedo held physical (one "
          "degree of freedom in the clouds' radiance); the atmosphere on the photo's clear pixels (cloud probability < "
          "0.5, the colour ramp's allowance for the haze round the sun " + FormatNumber(kRefitSkySunBoost) + ": its default " +
          FormatNumber(capture::CloudMaskOptions{}.sun_boost) + " let a thin cloud by the sun pass for clear sky and "
          "brightened the fitted aureole; those clear through the shapes leave LUT columns unseen behind horizon cloud); "
          "at most " +
          std::to_string(iterations) +
          " iterations, values at the Jacobian's samples by the CPU model (the shader's source), the frame rendered "
          "once at the end; " + StartPriorText(start_prior) + "cloud pixels' log RMSE " +
          CloudPixelsLogRmse(clouds, "initial") + " -> " + CloudPixelsLogRmse(clouds, "final") +
          "; the statistics fit's record: fit.statistics.json";
  d.why += BoundRestartsText(clouds) + ReleasedHoldsText(clouds);
  const std::string at_bounds = ParametersAtBounds(clouds);
  if (!at_bounds.empty())
    d.why += "; at the end of its range: " + at_bounds +
             " (making up for the recovered shapes, which are not the photo's 3D clouds: a value to read with care)";
  return d;
}

}  // namespace

fit::FitDecision RefitCloudLighting(const FitPlan& plan, const StagedDirectory& out, const std::string& final_dir,
                                    const RefitPass& pass) {
  const fs::path shapes = out.staging() / kInvertedShapesDir, refit_dir = out.staging() / "refit",
                 inputs = out.staging() / kRefitInputsDir;
  fit::FitDecision d;
  d.saved_ms_basis = "not measured in this run";
  try {
    CopyPresetFiles(out.staging(), shapes);
    FitControllerOptions k = plan.fit;
    const auto [photo, mask] = RefitInputs(out, inputs);
    k.references = {photo.string()};
    k.fit.mask_path = mask.string();
    k.init_preset = (shapes / "preset.json").string();
    k.out_dir = final_dir;
    k.cloud_stats.enabled = false;
    k.cloud_mask = false;
    k.previews = true;  // the refit's are the ones kept (the statistics fit drew none)
    k.clouds.mode = "on";
    k.clouds.preset = (shapes / "preset.json").string();
    k.clouds.hold.push_back("extinction");
    k.clouds.max_iterations = pass.iterations;
    k.clouds.sky_pixels_from_photo = true;
    k.clouds.sky_pixels_sun_boost = kRefitSkySunBoost;
    // The solve's values from the model at its samples: a frame's march per trial point cost
    // most of the refit, and the game's image is rendered from the result anyway.
    k.clouds.values_from_renderer = false;
    // Which parameters the conditioning holds flips with small changes of the shapes, and the
    // image then lands in another basin (a lobe or a factor at the far end of its range): the
    // holds released after the solve and the solve continued from there, kept when the cost
    // falls, make it less a matter of which side of the separability line a parameter fell.
    // Not restart_at_bounds as well: over the synthetic sky's sizes and inversion renders it
    // gained little more than this alone, for a solve per parameter at a bound
    // (bench/results/weather_inversion.md).
    k.clouds.release_inseparable = pass.release_holds;
    k.clouds.start_prior = pass.start_prior;
    k.clouds.refine_shapes = pass.refine;
    k.clouds.iterations_after_refinement = kRefitAfterRainIterations;
    // The clouds' sun scale free, the albedo held at the statistics fit's physical value: in
    // the clouds' radiance the two are one degree of freedom (L = C + a s D + a k A), and the
    // scale is the one a photo leaves open (its sky fit does not pin the sun apart from the
    // exposure; water droplets' albedo is known).
    k.clouds.fit_sun_scale = true;
    k.clouds.hold.push_back("scattering_albedo");
    {
      StagedDirectory refit(refit_dir.string(), "CalibrateOptions::out_dir", "calibrate", {});
      RunFitInto(k, refit);
      refit.Commit();
    }
    // The decision from the refit's record before anything moves: a failure here leaves the
    // statistics fit's files in place, as the catch below says.
    d = RefitDecision(fit::ReadFitResultFile((refit_dir / "fit.json").string()).clouds, pass.iterations, pass.start_prior);
    fs::rename(out / "fit.json", out / "fit.statistics.json");
    MoveUp(refit_dir, out.staging());
  } catch (const std::exception& e) {  // the statistics fit's lighting stands
    d.what = "cloud lighting: the statistics fit's kept";
    d.why = std::string("the known-shapes refit failed: ") + e.what() +
            " (the statistics fit wrote no previews, report.png and fit/*.png, expecting the refit's)";
  }
  std::error_code ec;
  fs::remove_all(shapes, ec);
  fs::remove_all(refit_dir, ec);
  fs::remove_all(inputs, ec);
  return d;
}

}  // namespace skycal::controllers
