#include "calibrate_plan.h"

#include "calibrate_weather.h"

#include <filesystem>
#include <functional>

#include "skycal/capture/solar_position.h"
#include "skycal/controllers/game_render.h"
#include "skycal/core/error.h"
#include "skycal/core/format_number.h"
#include "skycal/render/preset.h"

namespace skycal::controllers {
namespace {

// The share of an overcast sky the CIE standard overcast term carries (render/model: L =
// mix(L_lut, L_z (1 + 2 sin el) / 3, w)); the LUT keeps the rest, the deck's colour and any
// azimuthal structure the thin parts let through.
constexpr double kOvercastWeight = 0.7;

fit::FitDecision Decision(const std::string& what, const std::string& why) {
  fit::FitDecision d;
  d.what = what;
  d.why = why;
  d.saved_ms_basis = "not measured in this run";
  return d;
}

// The cloud statistics' render width (pixels): the default 128, halved down to 32 until the
// photo is at least as wide (the statistics average the photo down to it); 0: it is narrower.
int StatsWidth(int photo_width) {
  for (int w = FitCloudStatsOptions{}.width; w >= 32; w /= 2)
    if (photo_width >= w) return w;
  return 0;
}

std::string KindWhy(const PhotoAnalysis& a) {
  return std::string(capture::ToString(a.kind.kind)) + ": " + a.kind.reason;
}

}  // namespace

void RefuseWhatCannotBeCalibrated(const std::string& path, const PhotoAnalysis& a) {
  if (a.kind.kind == capture::SkyKind::kNight)
    throw Error(path + ": not calibrated: a night sky (" + a.kind.reason + "); the sky model has no night sky");
  if (a.kind.kind == capture::SkyKind::kNotSky)
    throw Error(path + ": not calibrated: not a sky (" + a.kind.reason + ")");
  if (!a.sun.direction)  // an overcast sky gets a nominal sun (NominalOvercastSun); others need one
    throw Error(path + ": not calibrated: the sun is not placed: " + a.sun.refusal +
                " (give CalibrateOptions::time_iso8601 with latitude_deg and longitude_deg, or sun_elevation_deg and "
                "sun_azimuth_deg)");
}

namespace fs = std::filesystem;

// The records' name for a file the fits read from the staging directory: where it will be once
// committed, or, for the refit's inputs that are not kept (the inverted shapes' preset, the photo
// averaged to the inversion's width), its name in the directory and that it was not kept.
std::function<std::string(const std::string&)> FinalPaths(const StagedDirectory& out, const std::string& final_dir) {
  return [staging = out.staging().lexically_normal(), final_dir](const std::string& path) {
    const fs::path rel = fs::path(path).lexically_normal().lexically_relative(staging);
    if (rel.empty() || *rel.begin() == "..") return path;
    const std::string first = rel.begin()->string();
    if (first == kInvertedShapesDir || first == kRefitInputsDir)
      return rel.generic_string() + " (an intermediate of the refit, not kept)";
    return (fs::path(final_dir) / rel).string();
  };
}

FitPlan PlanFit(const PhotoAnalysis& a, const StagedDirectory& out, const std::string& final_dir, const CalibrateOptions& o) {
  FitPlan p;
  p.fit.record_path = FinalPaths(out, final_dir);
  p.fit.references = {out / "photo.exr"};
  p.fit.out_dir = final_dir;
  p.fit.fit.mask_path = out / "mask.exr";
  p.fit.fit.sun_dir = a.sun.direction;
  p.fit.fit.verbose = false;
  p.fit.log = [o](const std::string& line) { CalibrateLog(o, "  fit: " + line); };  // quiet with calibrate
  p.fit.fit.backend = o.backend;
  p.fit.init_preset = o.init_preset;
  p.fit.report = false;  // written after the game's image, over everything
  p.decisions.push_back(Decision("sky pixels: the automatic segmentation (mask.exr)",
                                 "buildings, trees and terrain kept out of the sky terms; " +
                                     FormatNumber(static_cast<double>(a.mask.non_sky_above_horizon)) +
                                     " pixels above the horizon are not sky"));
  p.decisions.push_back(Decision("sun from " + a.sun.source, a.sun.uncertainty_deg
                                     ? "uncertainty " + FormatNumber(*a.sun.uncertainty_deg) + " deg"
                                     : std::string("measured or given")));
  if (!o.init_preset.empty() && a.kind.kind != capture::SkyKind::kOvercast) {
    const double w = render::LoadPreset(o.init_preset).overcast_weight;
    if (w > 0.0) {  // an overcast frame's preset: its CIE term would carry part of a clear sky
      p.fit.init_preset.clear();
      p.decisions.push_back(Decision("start: the bundled default preset, not " + o.init_preset,
                                     "it carries the overcast term (weight " + FormatNumber(w) + ") and this photo is " +
                                         capture::ToString(a.kind.kind)));
    }
  }
  const bool cloudy = a.kind.kind == capture::SkyKind::kPartlyCloudy ||
                      (a.kind.kind == capture::SkyKind::kTwilight && capture::HasCloudEdges(a.features, {}));
  if (a.kind.kind == capture::SkyKind::kOvercast) {
    render::Preset start = render::LoadPreset(DefaultPresetPath());
    start.overcast_weight = kOvercastWeight;
    render::SavePreset(start, out / "overcast_start.json");
    p.fit.init_preset = out / "overcast_start.json";
    p.fit.fit.hold_inseparable_overcast = false;
    p.draw_sun_disc = a.sun.uncertainty_deg.value_or(0.0) < 90.0;  // a nominal sun: no disc to draw
    p.decisions.push_back(Decision("overcast: the CIE overcast term carries the sky (weight " + FormatNumber(kOvercastWeight) +
                                       "), no cloud layer drawn",
                                   KindWhy(a) + "; a uniform deck has no cloud shapes to place, so the cloud statistics were skipped"));
  } else if (cloudy && StatsWidth(a.frame.radiance.width) == 0) {
    p.fit.clouds.mode = "off";
    p.decisions.push_back(Decision("no cloud layer: the photo is too small for the cloud statistics",
                                   KindWhy(a) + "; its width " + std::to_string(a.frame.radiance.width) +
                                       " px is under the statistics' smallest width, 32 (PhotoCloudStatsOptions::width)"));
  } else if (cloudy) {
    p.fit.cloud_mask = true;
    p.fit.cloud_stats.enabled = true;
    p.fit.cloud_stats.width = StatsWidth(a.frame.radiance.width);
    p.fit.clouds.mode = "off";
    p.draw_clouds = true;
    // The refit on the placed clouds (calibrate_weather.h) replaces the statistics fit's
    // outputs: its previews would be drawn and deleted.
    const int w = a.frame.radiance.width, h = a.frame.radiance.height;
    p.fit.previews = o.weather_map.empty() && !(o.invert_weather && InversionRenderWidth(w, h) != 0);
    std::string why = KindWhy(a);
    if (!p.fit.previews) {
      // The statistics' lighting only starts that refit (their coverage fills the texels the
      // photo does not see): one render per weather map, not two. What it moved:
      // bench/results/weather_inversion.md, stop 51.
      p.fit.cloud_stats.renders = p.fit.cloud_stats.maps;
      why += "; one statistics render per weather map (" + std::to_string(p.fit.cloud_stats.renders) +
             "): the refit on the placed clouds replaces their lighting, which only starts it";
    }
    p.decisions.push_back(
        Decision("clouds: clear pixels fit the atmosphere, cloud pixels the cloud lighting (statistics)", why));
  } else {
    p.fit.clouds.mode = "off";
    p.decisions.push_back(Decision("no cloud layer: the atmosphere alone", KindWhy(a) + "; the cloud statistics were skipped"));
  }
  if (o.time_of_day_h) {  // the preset's time of day orders the exported keyframes
    p.fit.fit.time_of_day_h = o.time_of_day_h;
  } else if (a.time_iso8601) {
    const capture::SpaInput t = capture::ParseIso8601(*a.time_iso8601, "the photo's time (" + a.time_source + ")");
    p.fit.fit.time_of_day_h = t.hour + t.minute / 60.0 + t.second / 3600.0;
  }
  return p;
}

}  // namespace skycal::controllers
