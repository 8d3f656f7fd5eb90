#include "fit_cloud_stats.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>

#include "fit_report.h"
#include "render_clouds.h"
#include "skycal/capture/cloud_mask.h"
#include "skycal/capture/sky_segmentation.h"
#include "skycal/cloudfit/cloud_stats.h"
#include "skycal/cloudfit/cloud_sun_scale.h"
#include "skycal/cloudfit/lighting_basis_renderer.h"
#include "skycal/cloudfit/photo_sun.h"
#include "skycal/clouds/cloud_noise.h"
#include "skycal/clouds/weather_map.h"
#include "skycal/core/error.h"
#include "skycal/core/format_number.h"
#include "skycal/core/latlong.h"
#include "skycal/render/irradiance.h"
#include "skycal/render/preset.h"
#include "skycal/render/renderer.h"
#include "verb_common.h"

namespace skycal::cli {
namespace fs = std::filesystem;

bool FitCloudStatsOptions::IsValid(std::string* why) const {
  if (width < 16 || width > 1024 || width % 2 != 0) {
    *why = "--cloud-stats-width " + std::to_string(width) + " (expected an even number of pixels in [16, 1024])";
    return false;
  }
  if (maps < 1 || maps > 16) {
    *why = "--cloud-stats-maps " + std::to_string(maps) + " (expected an integer in [1, 16])";
    return false;
  }
  if (renders < maps || renders > 64) {
    *why = "cloud stats renders per evaluation " + std::to_string(renders) + " (expected [maps, 64])";
    return false;
  }
  if (sun != "photo" && sun != "model") {
    *why = "--cloud-stats-sun '" + sun + "' (expected photo or model)";
    return false;
  }
  if (probability != "fitted" && probability != "initial") {
    *why = "--cloud-stats-probability '" + probability + "' (expected fitted or initial)";
    return false;
  }
  if (sun_scale != "fit" && sun_scale != "off") {
    *why = "--cloud-stats-sun-scale '" + sun_scale + "' (expected fit or off)";
    return false;
  }
  if (max_iterations < 0 || max_iterations > 200) {
    *why = "--cloud-stats-iterations " + std::to_string(max_iterations) + " (expected an integer in [0, 200])";
    return false;
  }
  return true;
}

namespace {

// Box average by an integer factor (a lat-long keeps its 2:1 shape and pixel centres).
ImageRGB BoxDown(const ImageRGB& in, int f) {
  ImageRGB out(in.width / f, in.height / f);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x)
      for (int c = 0; c < 3; ++c) {
        double s = 0.0;
        for (int j = 0; j < f; ++j)
          for (int i = 0; i < f; ++i) s += in.at(x * f + i, y * f + j, c);
        out.at(x, y, c) = static_cast<float>(s / (f * f));
      }
  return out;
}
std::vector<float> BoxDown(const std::vector<float>& in, int w, int h, int f) {
  std::vector<float> out(static_cast<size_t>(w / f) * (h / f));
  for (int y = 0; y < h / f; ++y)
    for (int x = 0; x < w / f; ++x) {
      double s = 0.0;
      for (int j = 0; j < f; ++j)
        for (int i = 0; i < f; ++i) s += in[static_cast<size_t>(y * f + j) * w + x * f + i];
      out[static_cast<size_t>(y) * (w / f) + x] = static_cast<float>(s / (f * f));
    }
  return out;
}

// Solid-angle weighted mean opacity over sky pixels above `min_elevation_deg`.
double MeanOpacity(const std::vector<float>& opacity, const std::vector<float>& sky, int w, int h,
                   double min_elevation_deg) {
  double s = 0.0, n = 0.0;
  for (int y = 0; y < h; ++y) {
    if (latlong::Latitude(y, h) * 180.0 / M_PI < min_elevation_deg) continue;
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      if (!sky.empty() && !(sky[i] >= 0.5f)) continue;
      const double om = latlong::PixelSolidAngle(x, y, w, h);
      s += om * opacity[i];
      n += om;
    }
  }
  return n > 0.0 ? s / n : 0.0;
}

clouds::WeatherMap StatsWeather(uint64_t seed, double extent_m, double mean_coverage) {
  clouds::WeatherNoiseOptions w;  // default_cloudy's statistics of shapes, the coverage matched
  w.mean_coverage = mean_coverage;
  w.coverage_contrast = 3.0;
  w.coverage_cells = 8;
  return clouds::NoiseWeatherMap(seed, 256, extent_m, w);
}

nlohmann::json ErrorsJson(const fit::ImageErrors& e) {
  return {{"pixels", e.pixels}, {"rel_rmse", e.rel_rmse}, {"log_rmse", e.log_rmse}};
}

struct PhotoData {
  cloudfit::CloudStatsReference stats_ref;
  fit::Reference whole;  // the reference with every sky pixel (clear and cloud) of the segmentation as kSky
  fit::Reference clear, cloud;  // the same restricted to probability < 0.5 / >= 0.5
  long long non_sky_segmented = 0;
  nlohmann::json sun_check;
  std::vector<float> probability;  // the cloud probability the statistics use
  nlohmann::json probability_json;
};

// --cloud-stats-probability fitted applies when the sky fit's clear pixels are within this
// relative RMSE (`sky` 0.17 and `dawn` 0.38 are; the overcast `city`'s 5.4 is not, and against
// its sky fit the overcast lost 84% of its cloud pixels).
constexpr double kMaxSkyFitRelForProbability = 0.5;

// Cloud pixels (probability >= 0.5, above the horizon) per bin of angle from the sun.
nlohmann::json CloudPixelsBySunAngle(const std::vector<float>& p, const fit::Reference& ref,
                                     const std::vector<double>& edges_deg) {
  const int w = ref.radiance.width, h = ref.radiance.height;
  std::vector<long long> n(edges_deg.size() - 1, 0);
  for (int y = 0; y < h; ++y) {
    if (latlong::Latitude(y, h) <= 0.0) continue;
    for (int x = 0; x < w; ++x) {
      if (!(p[static_cast<size_t>(y) * w + x] >= 0.5f)) continue;
      const auto v = latlong::PixelDirection(x, y, w, h);
      const double a =
          std::acos(std::clamp(v[0] * ref.sun_dir[0] + v[1] * ref.sun_dir[1] + v[2] * ref.sun_dir[2], -1.0, 1.0)) * 180.0 / M_PI;
      for (size_t b = 0; b + 1 < edges_deg.size(); ++b)
        if (a >= edges_deg[b] && a < edges_deg[b + 1]) ++n[b];
    }
  }
  return n;
}

// The cloud probability against `rendered` (a sky fit's render) as well: a pixel is cloud
// where both clear-sky expectations say so (the minimum).
std::vector<float> AlsoAgainst(const fit::Reference& ref, const ImageRGB& rendered, const std::vector<float>& p) {
  const capture::CloudMask m = capture::EstimateCloudProbability(ref.radiance, rendered, ref.sun_dir, {});
  std::vector<float> q(p.size());
  for (size_t i = 0; i < p.size(); ++i) q[i] = std::min(p[i], m.probability[i]);
  return q;
}

// The photo's sun against the model's, in model units (the photo divided by the sky fit's
// exposure): the clouds' direct light is the model's sun x transmittance, and a sky fit
// without the disc does not pin it (the exposure x LUT gauge keeps the initial preset's
// sun-to-sky ratio).
nlohmann::json SunCheck(const fit::Reference& ref, const render::Preset& preset, double exposure) {
  const cloudfit::PhotoSun ps = cloudfit::MeasurePhotoSun(ref.radiance, ref.sun_dir);
  const render::Rgb model = render::SunIlluminanceAtGround(preset, ref.sun_dir);
  nlohmann::json photo = nlohmann::json::array(), ratio = nlohmann::json::array();
  for (int c = 0; c < 3; ++c) {
    photo.push_back(ps.illuminance[c] / exposure);
    ratio.push_back(ps.illuminance[c] / exposure / model[c]);
  }
  return {{"photo_lux_model_units", photo},
          {"model_lux", {model[0], model[1], model[2]}},
          {"photo_over_model", ratio},
          {"disc_pixels", ps.disc_pixels},
          {"peak_over_background", ps.peak / std::max(ps.background[1], 1e-30)},
          {"clipped", ps.clipped()},
          {"direct_to_diffuse", ps.direct_to_diffuse()},
          {"clean_disc", ps.clean_disc()},
          {"saturated", ps.saturated()},
          {"note", "the photo's disc + blur within 3 deg above the median of a 4-6 deg ring, divided by the exposure; "
                   "clipped: more than 2 disc pixels within 0.1% of the peak at the frame's own resolution; "
                   "direct_to_diffuse: the disc's light on a horizontal surface over the sky's outside it (green); "
                   "saturated (the disc a lower bound): clipped, or a clean disc (peak >= 100x its ring) with "
                   "direct_to_diffuse < 0.5, which an unveiled sun does not give"}};
}

}  // namespace

nlohmann::json RefineCloudMaskAndRefitSky(const FitCloudStatsOptions& o, bool user_mask, std::vector<fit::Reference>* refs,
                                          std::vector<std::vector<float>>* probability, const fit::FitResult& sky,
                                          const std::function<void()>& refit) {
  nlohmann::json j = {{"threshold_released_fraction", kSkyRefitReleasedFraction}, {"refitted", false}};
  if (o.probability != "fitted") {
    j["why"] = "--cloud-stats-probability initial: the first mask stays";
    return j;
  }
  if (user_mask) {
    j["why"] = "a --mask is given: its pixels and the cloud mask's are both user-masked, none released";
    return j;
  }
  bool any = false;
  nlohmann::json per_ref = nlohmann::json::array();
  for (size_t r = 0; r < refs->size(); ++r) {
    fit::Reference& ref = (*refs)[r];
    std::vector<float>& p = (*probability)[r];
    const double rel = sky.references[r].errors.rel_rmse;
    nlohmann::json rj = {{"name", ref.name}, {"sky_fit_clear_rel_rmse", rel}};
    if (!(rel <= kMaxSkyFitRelForProbability)) {
      rj["released_pixels"] = 0;
      rj["why"] = "the sky fit misses its clear pixels by more than 50%: no clear-sky expectation";
      per_ref.push_back(rj);
      continue;
    }
    const std::vector<float> refined = AlsoAgainst(ref, sky.references[r].rendered, p);
    const std::vector<double> angle_edges = {0.0, 20.0, 45.0, 90.0, 180.0};
    rj["sun_angle_edges_deg"] = angle_edges;
    rj["initial_cloud_pixels_by_sun_angle"] = CloudPixelsBySunAngle(p, ref, angle_edges);
    long long released = 0;
    const long long sky_before = ref.counts.sky + ref.counts.user_masked;
    for (size_t i = 0; i < p.size(); ++i) {
      const float q = refined[i];
      if (ref.pixel_class[i] == fit::PixelClass::kUserMasked && p[i] >= 0.5f && q < 0.5f) {
        ref.pixel_class[i] = fit::PixelClass::kSky;
        ++released;
      }
      p[i] = q;
    }
    ref.counts.sky += released;
    ref.counts.user_masked -= released;
    const double fraction = sky_before > 0 ? static_cast<double>(released) / sky_before : 0.0;
    rj["cloud_pixels_by_sun_angle"] = CloudPixelsBySunAngle(p, ref, angle_edges);
    rj["released_pixels"] = released;
    rj["released_fraction"] = fraction;
    any = any || fraction > kSkyRefitReleasedFraction;
    per_ref.push_back(rj);
  }
  j["references"] = per_ref;
  if (!any) {
    j["why"] = "no reference's mask changed by more than the threshold";
    return j;
  }
  const auto t0 = std::chrono::steady_clock::now();
  refit();
  j["refitted"] = true;
  j["time_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  j["why"] = "the cloud mask against the sky fit's own render released more than the threshold of a reference's sky "
             "pixels: the atmosphere fitted once more on them (from the first fit's preset)";
  Log("fit", "clouds stats: the refined cloud mask released pixels to the sky fit: refitted the atmosphere in " +
                 FormatNumber(j["time_s"].get<double>()) + " s");
  return j;
}

nlohmann::json RunCloudStatsOnPhotos(const FitCloudStatsOptions& o, const std::vector<CloudStatsPhoto>& photos,
                                     const fit::FitResult& sky, const fs::path& fit_dir, CloudStatsPresetUpdate* update) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  cloudfit::CloudStatsOptions so;
  so.render_width = o.width;
  so.render_height = o.width / 2;
  so.model_renders = o.renders;
  so.max_iterations = o.max_iterations;
  so.fitted = o.fitted;
  // A bin the photo fills and the render empties costs as much as a 2-log-unit (7x) miss
  // of each quantile: more than any bin's start is off on the three photos.
  so.empty_bin_log_residual = 2.0;
  const render::Preset cloudy = render::LoadPreset(DefaultCloudyPresetPath());
  const clouds::CloudParams initial = clouds::ParseCloudSectionText(cloudy.clouds_json, DefaultCloudyPresetPath());
  auto sky_renderer = render::CreateRenderer(render::Backend::kCpu);
  std::vector<PhotoData> data(photos.size());
  for (size_t r = 0; r < photos.size(); ++r) {
    const fit::Reference& ref = *photos[r].ref;
    const int w = ref.radiance.width, h = ref.radiance.height;
    if (w % o.width != 0 || w / o.width < 1)
      throw Error(ref.path + ": --clouds stats: the frame is " + std::to_string(w) + " wide, not a multiple of " +
                  "--cloud-stats-width " + std::to_string(o.width));
    const int f = w / o.width;
    // Sky: what the sky fit used or left out as cloud, minus what the automatic segmentation
    // finds is not sky (buildings, trees, terrain: grey like cloud in the colour test).
    const capture::SkyMask seg = capture::EstimateSkyMask(ref.radiance, ref.sun_dir, capture::SkyMaskOptions{});
    std::vector<float> skymask(static_cast<size_t>(w) * h, 0.0f);
    PhotoData& d = data[r];
    const double exposure = sky.references[r].exposure;
    d.sun_check = SunCheck(ref, sky.preset, exposure);
    d.probability = photos[r].cloud_probability;
    const std::vector<double> angle_edges = {0.0, 20.0, 45.0, 90.0, 180.0};
    d.probability_json = {{"expectation", o.probability},
                          {"sun_angle_edges_deg", angle_edges},
                          {"initial_cloud_pixels_by_sun_angle", CloudPixelsBySunAngle(d.probability, ref, angle_edges)}};
    // A sky fit that misses its own clear pixels by more than half (an overcast frame: `city`,
    // 536% on the few it had) is no clear-sky expectation: the initial probability stays.
    const double sky_fit_rel = sky.references[r].errors.rel_rmse;
    const bool refine = o.probability == "fitted" && sky_fit_rel <= kMaxSkyFitRelForProbability && !photos[r].refined;
    d.probability_json["sky_fit_clear_rel_rmse"] = sky_fit_rel;
    d.probability_json["refined"] = refine || photos[r].refined;
    if (photos[r].refined) d.probability_json["refined_against"] = "the first sky fit (before the sky refit: sky_refit)";
    if (refine) {
      d.probability = AlsoAgainst(ref, sky.references[r].rendered, d.probability);
      d.probability_json["cloud_pixels_by_sun_angle"] = CloudPixelsBySunAngle(d.probability, ref, angle_edges);
    }
    d.whole = ref;
    d.clear = ref;
    d.cloud = ref;
    for (size_t i = 0; i < skymask.size(); ++i) {
      const fit::PixelClass c = ref.pixel_class[i];
      const bool candidate = c == fit::PixelClass::kSky || c == fit::PixelClass::kUserMasked;
      const bool is_sky = candidate && seg.sky[i] >= 0.5f;
      d.non_sky_segmented += candidate && !is_sky;
      skymask[i] = is_sky ? 1.0f : 0.0f;
      const bool cloudy = d.probability[i] >= 0.5f;
      const auto keep = fit::PixelClass::kSky, drop = fit::PixelClass::kUserMasked;
      if (candidate) {
        d.whole.pixel_class[i] = is_sky ? keep : drop;
        d.clear.pixel_class[i] = is_sky && !cloudy ? keep : drop;
        d.cloud.pixel_class[i] = is_sky && cloudy ? keep : drop;
      }
    }
    Log("fit", "clouds stats: " + ref.name + ": the photo's sun / the model's (green) " +
                   FormatNumber(d.sun_check["photo_over_model"][1].get<double>()) +
                   (d.sun_check["clipped"].get<bool>() ? " (clipped: a lower bound)" : ""));
    cloudfit::CloudStatsReference& sr = d.stats_ref;
    sr.name = ref.name;
    sr.radiance = BoxDown(ref.radiance, f);
    for (float& v : sr.radiance.pixels) v = static_cast<float>(v / exposure);  // model units
    sr.opacity = BoxDown(d.probability, w, h, f);
    sr.sky = BoxDown(skymask, w, h, f);
    for (float& v : sr.sky) v = v >= 0.99f ? 1.0f : 0.0f;  // a mixed pixel is not a cloud sample
    sr.sun_dir = ref.sun_dir;
    // Before any march: a photo with no cloud the statistics can use (after the refinement
    // too) is refused here, naming the file.
    {
      const cloudfit::CloudStatistics st = cloudfit::ComputeCloudStatistics(sr.radiance, sr.opacity, sr.sky, sr.sun_dir, so);
      if (std::none_of(st.weight.begin(), st.weight.end(), [&](double w) { return w >= so.min_bin_sr; }))
        throw Error(ref.path + ": --clouds stats: no cloud pixels to fit (no bin of angle from the sun x elevation x " +
                    "opacity holds " + FormatNumber(so.min_bin_sr) + " sr of cloud" +
                    (refine ? "; against the sky fit's render too: --cloud-stats-probability initial uses --cloud-mask's alone)"
                            : ")"));
    }
    render::RenderRequest req;
    req.sun_dir = ref.sun_dir;
    req.width = o.width;
    req.height = o.width / 2;
    req.sun_disc = false;
    sr.clear_sky = sky_renderer->Render(sky.preset, req);
  }

  // The sun that lights the model's clouds (FitCloudStatsOptions::sun). One preset lights
  // every reference: with several, the photos' suns are averaged (per channel, geometric).
  render::Preset cloud_preset = sky.preset;
  if (o.sun == "photo") {
    std::array<double, 3> log_ratio{};
    for (const PhotoData& d : data)
      for (int c = 0; c < 3; ++c)
        log_ratio[c] += std::log(std::max(d.sun_check["photo_over_model"][c].get<double>(), 1e-6)) / data.size();
    const double g = std::exp(log_ratio[1]);
    cloud_preset.sun_illuminance_lux = std::clamp(sky.preset.sun_illuminance_lux * g, 1.0, 2.0e5);
    for (int c = 0; c < 3; ++c)
      cloud_preset.sun_tint_rgb[c] = std::clamp(sky.preset.sun_tint_rgb[c] * std::exp(log_ratio[c]) / g, 0.0, 10.0);
    Log("fit", "clouds stats: the clouds lit by the photo's sun: " + FormatNumber(cloud_preset.sun_illuminance_lux) +
                   " lux (the fitted preset's " + FormatNumber(sky.preset.sun_illuminance_lux) + ")");
  }

  std::unique_ptr<clouds::CloudRenderer> renderer;
  try {
    renderer = clouds::CreateVulkanCloudRenderer(false);
  } catch (const Error& e) {
    Log("fit", std::string("clouds stats: no Vulkan device (") + e.what() + "): the float CPU march renders");
    renderer = clouds::CreateCpuCloudRenderer(clouds::CloudPrecision::kFloat, 2);
  }
  const clouds::CloudNoise noise = clouds::LoadOrGenerateCloudNoise(kCloudNoiseSeed, clouds::DefaultCloudNoiseCacheDir());

  // Coverage first: match the weather maps' mean coverage until the model's mean opacity
  // (pooled over the ensemble, at the starting lighting) equals the photos' mean cloud
  // probability over their sky above the lowest elevation bin.
  const double min_el = so.elevation_edges_deg.front();
  // Opacity only: the transmittance depends on the extinction and the shapes, never on the
  // light samples (cloud_march.glsl.h: the light march feeds the source term alone), so the
  // match marches without them.
  cloudfit::CloudStatsOptions opacity_only = so;
  opacity_only.march.light_samples = 0;
  double target = 0.0;
  for (const PhotoData& d : data)
    target += MeanOpacity(d.stats_ref.opacity, d.stats_ref.sky, o.width, o.width / 2, min_el) / data.size();
  auto model_opacity = [&](double coverage, std::vector<clouds::WeatherMap>* maps) {
    maps->clear();
    for (int m = 0; m < o.maps; ++m) maps->push_back(StatsWeather(o.weather_seed + m, initial.weather_extent_m, coverage));
    cloudfit::CloudStatsScene scene{&cloud_preset, initial, &noise, &(*maps)[0]};
    double mean = 0.0;
    for (const PhotoData& d : data)
      for (int m = 0; m < o.maps; ++m)
        mean += MeanOpacity(cloudfit::RenderForCloudStats(d.stats_ref, scene, initial, *renderer, opacity_only, 0.0, &(*maps)[m]).opacity,
                            d.stats_ref.sky, o.width, o.width / 2, min_el) /
                (data.size() * o.maps);
    return mean;
  };
  std::vector<clouds::WeatherMap> maps;
  const auto coverage_t0 = std::chrono::steady_clock::now();
  // The Illinois variant of regula falsi on f(c) = opacity(c) - photo: the opacity rises
  // monotonically with the coverage from 0 (no cloud) toward 1, the anchors' assumed values
  // until evaluated points replace them; it stops within 0.005 of the photo (3-4 steps on
  // the real skies, where 8 halvings took 8) or after 8 steps.
  double lo = 0.0, hi = 1.0, f_lo = -target, f_hi = 1.0 - target, coverage = 0.5, achieved = 0.0;
  int side = 0;
  nlohmann::json coverage_steps = nlohmann::json::array();
  for (int step = 0; step < 8; ++step) {
    coverage = std::clamp((lo * f_hi - hi * f_lo) / (f_hi - f_lo), 1e-3, 1.0);
    achieved = model_opacity(coverage, &maps);
    coverage_steps.push_back({{"mean_coverage", coverage}, {"model_mean_opacity", achieved}});
    Log("fit", "clouds stats: coverage " + FormatNumber(coverage) + " -> model mean opacity " + FormatNumber(achieved) +
                   " (photo " + FormatNumber(target) + ")");
    const double f = achieved - target;
    if (std::abs(f) < 0.005) break;
    if (f < 0.0) {
      lo = coverage;
      f_lo = f;
      if (side == -1) f_hi *= 0.5;
      side = -1;
    } else {
      hi = coverage;
      f_hi = f;
      if (side == 1) f_lo *= 0.5;
      side = 1;
    }
  }
  const double coverage_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - coverage_t0).count();

  std::vector<cloudfit::CloudStatsReference> refs;
  for (const PhotoData& d : data) refs.push_back(d.stats_ref);
  cloudfit::CloudStatsScene scene{&cloud_preset, initial, &noise, &maps[0]};
  for (const auto& m : maps) scene.weather_ensemble.push_back(&m);
  const bool fit_sun = o.sun_scale == "fit";
  if (fit_sun) {  // the albedo held physical; the sun's scale takes its place (below)
    so.fitted.erase(std::remove(so.fitted.begin(), so.fitted.end(), "scattering_albedo"), so.fitted.end());
    scene.initial.scattering_albedo = kPhysicalCloudAlbedo;
  }
  Log("fit", "clouds stats: fitting " + std::to_string(so.fitted.size()) + " lighting parameters" +
                 (fit_sun ? " and the sun's scale" : "") + " (" + std::to_string(o.renders) + " renders of " +
                 std::to_string(o.maps) + " weather maps per evaluation, " + std::to_string(o.width) + "x" +
                 std::to_string(o.width / 2) + ", at most " + std::to_string(o.max_iterations) + " iterations)");
  // When only the linear lighting (albedo, ambient) is fitted, each draw of shapes is
  // marched three times (four with a sun scale) and every evaluation after that is a weighted
  // sum of those (lighting_basis_renderer.h); otherwise every evaluation marches.
  const bool linear = std::all_of(so.fitted.begin(), so.fitted.end(), [](const std::string& n) {
    return n == "scattering_albedo" || n == "ambient_strength";
  });
  if (fit_sun && !linear) throw Error("--cloud-stats-sun-scale fit needs the linear lighting alone (albedo, ambient)");
  cloudfit::LightingBasisCloudRenderer basis(*renderer, static_cast<int>(refs.size()) * o.renders + 1);
  clouds::CloudRenderer& fit_renderer = linear ? static_cast<clouds::CloudRenderer&>(basis) : *renderer;
  cloudfit::CloudStatsResult res;
  nlohmann::json sun_scale_json;
  if (!fit_sun) {
    res = cloudfit::FitCloudStats(refs, scene, fit_renderer, so);
  } else {
    // The profile over s: at each s the ambient fitted from the best ambient so far. The disc
    // bounds s from below where every photo's disc is a lower bound (saturated).
    const bool saturated =
        o.sun == "photo" && std::all_of(data.begin(), data.end(), [](const PhotoData& d) { return d.sun_check["saturated"].get<bool>(); });
    cloudfit::SunScaleSearchOptions ss;
    ss.lower = saturated ? 1.0 : 0.1;
    ss.upper = std::min(sky.preset.sun_illuminance_lux, 2.0e5) / cloud_preset.sun_illuminance_lux;
    if (!(ss.upper > ss.lower)) ss.upper = ss.lower * 1.5;
    std::vector<double> iterations;
    const auto t0 = std::chrono::steady_clock::now();
    double best_cost = INFINITY;
    const cloudfit::SunScaleSearch found = cloudfit::MinimizeOverSunScale(
        [&](double sc) {
          basis.set_sun_scale(sc);
          cloudfit::CloudStatsScene at = scene;
          if (best_cost < INFINITY) at.initial.ambient_strength = res.params.ambient_strength;
          cloudfit::CloudStatsResult r = cloudfit::FitCloudStats(refs, at, fit_renderer, so);
          iterations.push_back(r.iterations);
          Log("fit", "clouds stats: sun scale " + FormatNumber(sc) + ": ambient " + FormatNumber(r.params.ambient_strength) +
                         ", cost " + FormatNumber(r.final_cost) + " (" + std::to_string(r.iterations) + " iterations)");
          const double cost = r.final_cost;
          if (cost < best_cost) {
            best_cost = cost;
            res = std::move(r);
          }
          return cost;
        },
        ss);
    const double search_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    basis.set_sun_scale(found.scale);
    res.time_s = search_s;
    const double measured = cloud_preset.sun_illuminance_lux;
    cloud_preset.sun_illuminance_lux = measured * found.scale;
    nlohmann::json profile = nlohmann::json::array();
    for (size_t i = 0; i < found.scales.size(); ++i)
      profile.push_back({{"scale", found.scales[i]}, {"cost", found.costs[i]}, {"iterations", iterations[i]}});
    nlohmann::json model_sun = nlohmann::json::array();
    for (const PhotoData& d : data) model_sun.push_back(d.sun_check["model_lux"][1]);
    sun_scale_json = {
        {"measured_lux", measured},
        {"scale", found.scale},
        {"fitted_lux", cloud_preset.sun_illuminance_lux},
        {"sky_fit_sun_lux_green", model_sun},
        {"lower_bound", ss.lower},
        {"upper_bound", ss.upper},
        {"at_lower_bound", found.at_lower},
        {"at_upper_bound", found.at_upper},
        {"scattering_albedo_held", kPhysicalCloudAlbedo},
        {"evaluations", found.scales.size()},
        {"time_s", search_s},
        {"profile", profile},
        {"why",
         std::string("the albedo of cloud water droplets is ~1 in the visible (Hansen & Travis 1974): held at ") +
             FormatNumber(kPhysicalCloudAlbedo) + "; the statistics then fit the clouds' direct light as a scale on the " +
             (o.sun == "photo" ? "photo's measured sun" : "fitted preset's sun") + " (the ambient fitted at each scale, "
             "the cost's minimum over the scale found by a grid over ln s and golden sections)" +
             (saturated ? "; the disc is saturated (sun_check), a lower bound: s >= 1" : "; s >= 0.1") +
             "; s <= the sky fit's own sun over the measured one (upper_bound)"}};
    Log("fit", "clouds stats: the clouds' sun " + FormatNumber(found.scale) + " x the measured " + FormatNumber(measured) +
                   " lux = " + FormatNumber(cloud_preset.sun_illuminance_lux) + " lux (" +
                   std::to_string(found.scales.size()) + " statistics fits, " + FormatNumber(search_s) + " s)");
  }
  const long long marches = linear ? basis.marches() : res.renders;
  Log("fit", "clouds stats: cost " + FormatNumber(res.initial_cost) + " -> " + FormatNumber(res.final_cost) + ", " +
                 std::to_string(res.renders) + " evaluations' renders (" + std::to_string(marches) + " marched), " +
                 FormatNumber(res.time_s) + " s");

  nlohmann::json params = nlohmann::json::object();
  for (const auto& p : res.parameters) {
    params[p.name] = {{"value", p.value}, {"unit", p.unit}, {"initial", p.initial}, {"held", p.held}};
    if (p.held) params[p.name]["why"] = p.why_held;
  }
  if (fit_sun)
    params["scattering_albedo"]["why"] = "water droplets' physical single-scattering albedo in the visible (Hansen & Travis 1974); "
                                         "the sun's scale is fitted instead (sun_scale)";
  nlohmann::json per_ref = nlohmann::json::array();
  const int nq = static_cast<int>(so.quantiles.size());
  const int mid = nq / 2;  // the median of the default {0.25, 0.5, 0.75}
  std::vector<fit::Reference> panel_refs;
  fit::FitResult panels = sky;
  panels.references.clear();
  for (size_t r = 0; r < data.size(); ++r) {
    const PhotoData& d = data[r];
    const cloudfit::CloudStatistics& photo = res.reference_stats[r];
    const cloudfit::CloudStatistics& model = res.final_stats.empty() ? photo : res.final_stats[r];
    // The statistical fit image: each sky pixel is the atmosphere's fit where clear and, by
    // its cloud membership, the model's median radiance of its (sun angle, elevation,
    // opacity) bin where cloud. The photo's own cloud map places the clouds; the lighting is
    // the fitted one. It shows how well the bins' lighting predicts the photo, pixel by pixel.
    const fit::Reference& ref = *photos[r].ref;
    const double exposure = sky.references[r].exposure;
    ImageRGB pred = sky.references[r].rendered;
    const int w = ref.radiance.width, h = ref.radiance.height;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const size_t i = static_cast<size_t>(y) * w + x;
        if (d.whole.pixel_class[i] != fit::PixelClass::kSky) continue;
        const auto v = latlong::PixelDirection(x, y, w, h);
        const double c = std::clamp(v[0] * ref.sun_dir[0] + v[1] * ref.sun_dir[1] + v[2] * ref.sun_dir[2], -1.0, 1.0);
        int sb = 0, eb = 0;
        if (!cloudfit::FindCloudBin(so, std::acos(c) * 180.0 / M_PI, latlong::Latitude(y, h) * 180.0 / M_PI, &sb, &eb)) continue;
        double thin = 0.0, thick = 0.0;
        cloudfit::OpacityClassWeights(so, d.probability[i], &thin, &thick);
        const double weights[2] = {thin, thick};
        double clear_share = 1.0;
        double acc[3] = {0.0, 0.0, 0.0};
        for (int k = 0; k < 2; ++k) {
          const int bin = model.Bin(sb, eb, k);
          if (weights[k] <= 0.0 || model.weight[bin] <= 0.0) continue;
          clear_share -= weights[k];
          for (int ch = 0; ch < 3; ++ch)
            acc[ch] += weights[k] * exposure * std::exp(model.log_quantile[(static_cast<size_t>(bin) * 3 + ch) * nq + mid]);
        }
        for (int ch = 0; ch < 3; ++ch) pred.at(x, y, ch) = static_cast<float>(clear_share * pred.at(x, y, ch) + acc[ch]);
      }
    const ImageRGB& atmosphere = sky.references[r].rendered;
    nlohmann::json errors = {
        {"atmosphere_only", {{"whole_sky", ErrorsJson(fit::CompareToReference(d.whole, atmosphere))},
                             {"clear", ErrorsJson(fit::CompareToReference(d.clear, atmosphere))},
                             {"cloud", ErrorsJson(fit::CompareToReference(d.cloud, atmosphere))}}},
        {"with_cloud_statistics", {{"whole_sky", ErrorsJson(fit::CompareToReference(d.whole, pred))},
                                   {"clear", ErrorsJson(fit::CompareToReference(d.clear, pred))},
                                   {"cloud", ErrorsJson(fit::CompareToReference(d.cloud, pred))}}}};
    nlohmann::json bins = nlohmann::json::array();
    for (int sb = 0; sb < photo.sun_bins; ++sb)
      for (int eb = 0; eb < photo.elevation_bins; ++eb)
        for (int k = 0; k < 2; ++k) {
          const int bin = photo.Bin(sb, eb, k);
          if (photo.weight[bin] < so.min_bin_sr) continue;
          auto medians = [&](const cloudfit::CloudStatistics& s) {
            nlohmann::json m = nlohmann::json::array();
            for (int ch = 0; ch < 3; ++ch) m.push_back(s.log_quantile[(static_cast<size_t>(bin) * 3 + ch) * nq + mid]);
            return m;
          };
          bins.push_back({{"sun_angle_deg", {so.sun_angle_edges_deg[sb], so.sun_angle_edges_deg[sb + 1]}},
                          {"elevation_deg", {so.elevation_edges_deg[eb], so.elevation_edges_deg[eb + 1]}},
                          {"opacity_class", k == 0 ? "thin" : "thick"},
                          {"photo_sr", photo.weight[bin]},
                          {"model_sr", model.weight[bin] / o.renders},
                          {"photo_log_median_rgb", medians(photo)},
                          {"fit_log_median_rgb", medians(model)},
                          {"initial_log_median_rgb", res.initial_stats.empty() ? nlohmann::json() : medians(res.initial_stats[r])}});
        }
    per_ref.push_back({{"name", ref.name},
                       {"non_sky_pixels_segmented", d.non_sky_segmented},
                       {"sun_check", d.sun_check},
                       {"cloud_probability", d.probability_json},
                       {"photo_mean_cloud_probability",
                        MeanOpacity(d.stats_ref.opacity, d.stats_ref.sky, o.width, o.width / 2, min_el)},
                       {"errors", errors},
                       {"bins", bins},
                       {"images", {{"reference", "fit/" + ref.name + ".clouds.reference.png"},
                                   {"fit", "fit/" + ref.name + ".clouds.fit.png"},
                                   {"error", "fit/" + ref.name + ".clouds.error.png"}}}});
    fit::Reference pr = d.whole;
    pr.name = ref.name + ".clouds";
    panel_refs.push_back(std::move(pr));
    fit::ReferenceFit rf = sky.references[r];
    rf.rendered = std::move(pred);
    panels.references.push_back(std::move(rf));
  }
  WriteFitPanels(fit_dir.string(), panel_refs, panels);
  if (update) {
    update->params = res.params;
    update->weather = maps[0];
    update->sun_illuminance_lux = cloud_preset.sun_illuminance_lux;
    update->sun_tint_rgb = cloud_preset.sun_tint_rgb;
    // A visible disc peaks thousands of times above the sky around it (`sky` 4,700x, `city`
    // 5,200x through overcast); a sun behind terrain leaves a glow (`dawn` 8x).
    constexpr double kVisibleDiscPeakOverSky = 100.0;
    double weakest = INFINITY;
    for (const PhotoData& d : data) weakest = std::min(weakest, d.sun_check["peak_over_background"].get<double>());
    const bool seen = weakest >= kVisibleDiscPeakOverSky;
    // The preset takes the sun that lit the clouds when it is a measurement (the disc seen)
    // or a fit (--cloud-stats-sun-scale fit: the clouds' brightness sets it, within bounds
    // from the disc): either way it is the sun this fit stands for.
    update->sun_measured = o.sun == "photo" && (seen || fit_sun);
    const std::string disc = "the photo's disc " + std::string(seen ? "seen" : "not seen") + " (peak " +
                             FormatNumber(weakest) + "x the sky ring around it; seen from " +
                             FormatNumber(kVisibleDiscPeakOverSky) + "x)";
    update->sun_why = o.sun != "photo" ? "--cloud-stats-sun model: the clouds were lit by the sky fit's sun"
                      : fit_sun        ? disc + "; the sun's scale fitted to the clouds (sun_scale)"
                      : seen           ? disc + ": its measured sun"
                                       : disc + ": what lit the clouds is no measurement of the sun; the preset keeps "
                                                "the sky fit's, and its clouds, lit by it, render brighter than fitted";
  }
  return {{"term", "cloud statistics (unknown shapes): weighted quantiles of log radiance per (sun angle x elevation x "
                   "opacity) bin, model pooled over an ensemble of weather maps"},
          {"shared_with_atmosphere", o.sun == "photo"
                                         ? "the sky's SH-9 ambient and the sun's transmittance come from the fitted preset; "
                                           "the sun's illuminance and tint from the photo's disc (sun_check)"
                                         : "the sun's illuminance, tint and transmittance and the sky's SH-9 ambient come "
                                           "from the fitted preset"},
          {"sun", o.sun},
          {"cloud_sun_illuminance_lux", cloud_preset.sun_illuminance_lux},
          {"cloud_sun_tint_rgb", cloud_preset.sun_tint_rgb},
          {"direct_light_lux_at_albedo_1", res.params.scattering_albedo * cloud_preset.sun_illuminance_lux},
          {"sun_scale", fit_sun ? sun_scale_json : nlohmann::json(nullptr)},
          {"render_size", {o.width, o.width / 2}},
          {"weather_maps", o.maps},
          {"renders_per_evaluation", o.renders},
          {"coverage", {{"photo_mean_cloud_probability", target},
                        {"matched_mean_coverage", coverage},
                        {"model_mean_opacity", achieved},
                        {"time_s", coverage_s},
                        {"steps", coverage_steps}}},
          {"parameters", params},
          {"initial_cost", res.initial_cost},
          {"final_cost", res.final_cost},
          {"iterations", res.iterations},
          {"renders", res.renders},
          {"marched_renders", marches},
          {"renderer", fit_renderer.Describe()},
          {"singular_values", res.singular_values},
          {"whitening", {{"covariance", res.noise_covariance},
                         {"draws", res.noise_draws},
                         {"shrinkage", res.noise_shrinkage},
                         {"median_noise_sd", res.median_noise_sd}}},
          {"termination", res.termination},
          {"time_s", res.time_s},
          {"notes", {{"fit image", "clear pixels: the atmosphere's fit; cloud pixels: by their cloud membership, the "
                                   "fitted model's median radiance of their bin (the photo's cloud map places them)"},
                     {"model_sr", "per render (the pooled weight divided by the renders)"}}},
          {"references", per_ref}};
}

nlohmann::json AttachCloudStats(const CloudStatsPresetUpdate& update, const fs::path& preset_json, render::Preset* preset) {
  clouds::CloudParams p = update.params;
  const std::string weather_name = preset_json.stem().string() + ".weather.exr";
  clouds::SaveWeatherMap(update.weather, (preset_json.parent_path() / weather_name).string());
  p.weather_map = weather_name;
  preset->clouds_json = clouds::CloudSectionToJson(p).dump();
  const nlohmann::json record = {
      {"clouds_section", "the fitted cloud lighting; weather_map " + weather_name +
                             ": noise at the matched mean coverage (the photo's shapes are unknown, its cover is not)"},
      {"weather_map", weather_name},
      {"sun_illuminance_lux", {{"sky_fit", preset->sun_illuminance_lux}, {"clouds_lit_by", update.sun_illuminance_lux}}},
      {"sun_tint_rgb", {{"sky_fit", preset->sun_tint_rgb}, {"clouds_lit_by", update.sun_tint_rgb}}},
      {"sun_written", update.sun_measured ? "clouds_lit_by" : "sky_fit"},
      {"why", update.sun_why + (update.sun_measured ? std::string(": the preset takes it, so it renders what was fitted "
                                                                  "(the sky's radiance does not depend on the sun's "
                                                                  "illuminance; the disc, the ground and the clouds do)")
                                                    : std::string())}};
  if (update.sun_measured) {
    preset->sun_illuminance_lux = update.sun_illuminance_lux;
    preset->sun_tint_rgb = update.sun_tint_rgb;
  }
  return record;
}

}  // namespace skycal::cli
