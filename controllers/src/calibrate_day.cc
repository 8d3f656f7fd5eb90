#include "calibrate_day.h"

#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <memory>
#include <optional>

#include "calibrate_plan.h"
#include "calibrate_weather.h"
#include "fit_cloud_mask.h"
#include "skycal/capture/latlong_frame.h"
#include "skycal/capture/solar_position.h"
#include "skycal/capture/time_place.h"
#include "skycal/cloudfit/weather_inversion.h"
#include "skycal/cloudfit/weather_wind.h"
#include "skycal/clouds/cloud_noise.h"
#include "skycal/clouds/cloud_params.h"
#include "skycal/clouds/cloud_renderer.h"
#include "skycal/clouds/weather_map.h"
#include "skycal/controllers/game_clouds.h"
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

namespace skycal::controllers {
namespace {

namespace fs = std::filesystem;
constexpr int kWidth = 256, kHeight = 128;  // the prediction's renders and comparison (as the inversion's)

// Seconds since 1970-01-01 UTC of an ISO 8601 time with its offset (glibc's timegm reads the
// fields as UTC; the offset is then taken off).
double EpochSeconds(const std::string& iso) {
  const capture::SpaInput t = capture::ParseIso8601(iso);
  std::tm tm{};
  tm.tm_year = t.year - 1900;
  tm.tm_mon = t.month - 1;
  tm.tm_mday = t.day;
  tm.tm_hour = t.hour;
  tm.tm_min = t.minute;
  return static_cast<double>(timegm(&tm)) + t.second - t.timezone_h * 3600.0;
}

// One qualifying frame: its directory, time, preset, map and what the photo constrained.
struct DayFrame {
  std::string photo, dir, time_source;
  double time_s = 0.0;
  render::Preset preset;
  clouds::CloudParams params;
  clouds::WeatherMap map;
  std::vector<float> constrained;  // what the photo constrained within resolved_radius_m
  double resolved_radius_m = 0.0;
};

// The frame's time and its source from photo.exr (capDate + utcOffset) or the photo as given
// (skycalCloudTimeS); nullopt without either.
std::optional<std::pair<double, std::string>> FrameTime(const PhotoCalibration& p) {
  const std::string photo_exr = (fs::path(p.dir) / "photo.exr").string();
  const capture::TimePlace t = capture::TimePlaceFromExrAttributes(ReadExrHeader(photo_exr).attributes, photo_exr);
  if (!t.time_iso8601.empty()) return std::pair(EpochSeconds(t.time_iso8601), std::string("capDate + utcOffset"));
  std::error_code ec;
  // An earlier run's photo, moved since, or a Radiance picture (no attributes to carry a time).
  if (!fs::is_regular_file(p.photo, ec) || !IsOpenExrFile(p.photo)) return std::nullopt;
  const ExrAttributes given = ReadExrHeader(p.photo).attributes;
  if (const auto it = given.floats.find("skycalCloudTimeS"); it != given.floats.end())
    return std::pair(static_cast<double>(it->second), std::string("skycalCloudTimeS"));
  return std::nullopt;
}

// Every photo calibrated in `out_dir`, this run's and earlier runs' (photos may be added one
// command at a time, as the tables are): DIR/<stem>/ with fit.json, in name order.
std::vector<PhotoCalibration> CalibratedInDir(const std::string& out_dir) {
  std::vector<fs::path> dirs;
  for (const auto& e : fs::directory_iterator(out_dir))
    if (e.is_directory() && !e.path().filename().string().starts_with(".") && fs::is_regular_file(e.path() / "fit.json"))
      dirs.push_back(e.path());
  std::sort(dirs.begin(), dirs.end());
  std::vector<PhotoCalibration> photos;
  for (const fs::path& d : dirs) {
    PhotoCalibration p;
    p.dir = d.string();
    const fit::FitResultFile f = fit::ReadFitResultFile(d / "fit.json");
    p.photo = f.calibration ? f.calibration->photo : (d / "photo.exr").string();
    photos.push_back(std::move(p));
  }
  return photos;
}

// Texels farther than this from the camera are left out of the wind: beyond it a pixel's
// footprint on the layer (radially d^2 x the pixel's angle / the layer's mid height, the
// ray grazing the layer) exceeds a texel, and the inverted map there is the horizon's smear,
// which does not move as the clouds do.
double ResolvedRadiusM(const clouds::CloudParams& p, const clouds::WeatherMap& map, int photo_width) {
  const double pixel_rad = 2.0 * kPi / photo_width, texel_m = map.extent_m / map.width;
  return std::sqrt(texel_m * 0.5 * (p.layer_bottom_m + p.layer_top_m) / pixel_rad);
}

void KeepResolvedTexels(double radius_m, const clouds::WeatherMap& map, std::vector<float>* constrained) {
  const double texel_m = map.extent_m / map.width;
  for (int y = 0; y < map.height; ++y)
    for (int x = 0; x < map.width; ++x) {  // texel centres about the camera at the map's centre
      const double dx = (x + 0.5) * texel_m - 0.5 * map.extent_m, dz = (y + 0.5) * texel_m - 0.5 * map.extent_m;
      if (std::hypot(dx, dz) > radius_m) (*constrained)[static_cast<size_t>(y) * map.width + x] = 0.0f;
    }
}

DayFrame LoadDayFrame(const PhotoCalibration& p, const std::pair<double, std::string>& time) {
  DayFrame f;
  f.photo = p.photo;
  f.dir = p.dir;
  f.time_s = time.first;
  f.time_source = time.second;
  const fs::path preset_json = fs::path(p.dir) / "preset.json";
  f.preset = render::LoadPreset(preset_json);
  f.params = clouds::ParseCloudSectionText(f.preset.clouds_json, preset_json);
  f.map = clouds::LoadWeatherMap(fs::path(p.dir) / "preset.weather.exr", f.params.weather_extent_m);
  int w = 0, h = 0;
  f.constrained = ReadExrChannel((fs::path(p.dir) / kConstrainedTexelsFile).string(), "R", &w, &h);
  f.resolved_radius_m = ResolvedRadiusM(f.params, f.map, ReadExrHeader((fs::path(p.dir) / "photo.exr").string()).width);
  KeepResolvedTexels(f.resolved_radius_m, f.map, &f.constrained);
  return f;
}

// The photo's cloud probability and its compared pixels (sky, above the horizon) at the
// prediction's size: as calibrate's analysis (the clear preset at the photo's sun).
struct PhotoClouds {
  std::vector<float> probability, sky;
};
PhotoClouds PhotoCloudsOf(const DayFrame& f) {
  const capture::LatLongFrame photo = capture::ReadLatLongFrame((fs::path(f.dir) / "photo.exr").string());
  if (!photo.sun_direction) throw Error(f.dir + "/photo.exr: no sunDirection attribute");
  const int w = photo.radiance.width, h = photo.radiance.height;
  int mw = 0, mh = 0;
  const std::vector<float> mask = ReadExrChannel((fs::path(f.dir) / "mask.exr").string(), "R", &mw, &mh);
  const std::vector<float> p = EstimatedCloudProbability(photo.radiance, *photo.sun_direction, DefaultPresetPath());
  PhotoClouds c{AreaDownsampleLatLong(p, w, h, 1, kWidth, kHeight), AreaDownsampleLatLong(mask, w, h, 1, kWidth, kHeight)};
  for (int y = 0; y < kHeight; ++y)
    if (latlong::Latitude(y, kHeight) <= 0.0)
      for (int x = 0; x < kWidth; ++x) c.sky[static_cast<size_t>(y) * kWidth + x] = 0.0f;
  return c;
}

// How far a render's clouds (opacity, 1 - transmittance) agree with the photo's: RMS of the
// opacity against the cloud probability, and the IoU of transmittance < 0.5 with
// probability >= 0.5, over the compared pixels.
struct Agreement {
  double opacity_rms = 0.0, iou = 0.0;
};
Agreement Agree(const std::vector<float>& transmittance, const PhotoClouds& c) {
  double sum = 0.0, n = 0.0;
  for (size_t i = 0; i < transmittance.size(); ++i) {
    if (!(c.sky[i] >= 0.5f)) continue;
    const double d = (1.0 - transmittance[i]) - c.probability[i];
    sum += d * d;
    ++n;
  }
  return {n > 0.0 ? std::sqrt(sum / n) : 0.0, CloudIou(transmittance, c.probability, c.sky).value_or(1.0)};
}

nlohmann::json AgreementJson(const Agreement& a) {
  return {{"opacity_rms", a.opacity_rms}, {"cloud_iou", a.iou}};
}

// One pair's prediction: frame `from`'s map moved by the day's wind to the time of `to`,
// against `to`'s photo; the unmoved map (the control) and `to`'s own map (the floor).
nlohmann::json PredictPair(const DayFrame& from, const DayFrame& to, const cloudfit::DayWind& wind,
                           const cloudfit::MapShift& shift, clouds::CloudRenderer& renderer, const clouds::CloudNoise& noise) {
  const PhotoClouds photo = PhotoCloudsOf(to);
  clouds::CloudRenderRequest q = OpacityRequest(kWidth, kHeight);
  const auto transmittance = [&](const DayFrame& f, const clouds::CloudParams& p, double t) {
    q.time_s = t;
    return renderer.Render({&f.preset, &p, &noise, &f.map}, q).transmittance;
  };
  clouds::CloudParams moved = from.params;
  moved.wind_speed_m_s = wind.speed_m_s;
  moved.wind_direction_deg = wind.direction_deg;
  const double dt = to.time_s - from.time_s;
  const Agreement predicted = Agree(transmittance(from, moved, dt), photo);
  const Agreement unmoved = Agree(transmittance(from, from.params, 0.0), photo);
  const Agreement own = Agree(transmittance(to, to.params, 0.0), photo);
  return {{"from", from.photo}, {"to", to.photo}, {"dt_s", dt},
          {"shift_m", {shift.dx_m, shift.dz_m}}, {"correlation_peak", shift.response},
          {"predicted_by_the_moved_map", AgreementJson(predicted)},
          {"unmoved_map", AgreementJson(unmoved)}, {"own_inverted_map", AgreementJson(own)}};
}

// The wind into the frame's preset.json (clouds.wind_speed, clouds.wind_direction).
void WriteWind(const DayFrame& f, const cloudfit::DayWind& wind) {
  const fs::path preset_json = fs::path(f.dir) / "preset.json";
  nlohmann::json j = ReadJsonFile(preset_json.string());
  j.at("clouds").at("wind_speed")["value"] = wind.speed_m_s;
  j.at("clouds").at("wind_direction")["value"] = wind.direction_deg;
  WriteJsonFileAtomically(preset_json.string(), j);
}

// The qualifying frames, or why there are fewer than two (empty when not a day at all).
std::vector<DayFrame> DayFrames(const std::string& out_dir, std::string* why_not) {
  std::vector<DayFrame> frames;
  int cloudy = 0;
  std::string source;
  for (const PhotoCalibration& p : CalibratedInDir(out_dir)) {
    if (p.dir.empty() || !fs::exists(fs::path(p.dir) / kConstrainedTexelsFile)) continue;
    ++cloudy;
    const auto t = FrameTime(p);
    if (!t) continue;
    if (!source.empty() && t->second != source) {
      *why_not = "the frames' times come from different sources (" + source + ", " + t->second + ")";
      return {};
    }
    source = t->second;
    frames.push_back(LoadDayFrame(p, *t));
  }
  if (frames.size() < 2 && cloudy >= 2)
    *why_not = std::to_string(cloudy) + " frames with inverted weather maps, " + std::to_string(frames.size()) +
               " with a time (capDate + utcOffset, or skycalCloudTimeS): the wind needs two";
  std::sort(frames.begin(), frames.end(), [](const DayFrame& a, const DayFrame& b) { return a.time_s < b.time_s; });
  return frames.size() >= 2 ? std::move(frames) : std::vector<DayFrame>{};
}

nlohmann::json DayJson(const std::vector<DayFrame>& frames, const cloudfit::DayWind& wind, const CalibrateOptions& o) {
  const auto noise = clouds::SharedCloudNoise(kCloudNoiseSeed, clouds::UsableCloudNoiseCacheDir());
  const std::unique_ptr<clouds::CloudRenderer> renderer = OpacityRenderer(o.backend);
  nlohmann::json pairs = nlohmann::json::array(), list = nlohmann::json::array();
  for (const DayFrame& f : frames) list.push_back({{"photo", f.photo}, {"time_s", f.time_s}});
  for (size_t k = 1; k < frames.size(); ++k)
    pairs.push_back(PredictPair(frames[k - 1], frames[k], wind, wind.pairs[k - 1], *renderer, *noise));
  return {{"wind", {{"speed_m_s", wind.speed_m_s}, {"direction_deg", wind.direction_deg},
                    {"from_texels_within_m", frames.front().resolved_radius_m},
                    {"convention", "the azimuth the wind blows toward (lat-long: 0 -> +z, 90 -> +x), as clouds.wind_direction"}}},
          {"time_source", frames.front().time_source}, {"frames", list}, {"pairs", pairs},
          {"comparison", "each pair: the earlier frame's inverted map moved by the day's wind to the later frame's time, "
                         "against the later photo's cloud probability (opacity RMS, cloud IoU at " +
                         std::to_string(kWidth) + "x" + std::to_string(kHeight) + "); the unmoved map is the control, "
                         "the later frame's own map the floor"}};
}

}  // namespace

void FitTheDaysWind(const CalibrateOptions& o, CalibrateResult* r) {
  std::string why_not;
  try {
    const std::vector<DayFrame> frames = DayFrames(o.out_dir, &why_not);
    if (frames.empty()) {
      std::error_code ec;  // an earlier run's wind no longer stands on two frames
      fs::remove(fs::path(o.out_dir) / kDayWindFile, ec);
      if (!why_not.empty()) {
        r->warnings.push_back("no wind for the day: " + why_not);
        CalibrateLog(o, "warning: " + r->warnings.back());
      }
      return;
    }
    std::vector<cloudfit::TimedWeatherMap> maps;
    for (const DayFrame& f : frames) maps.push_back({&f.map, &f.constrained, f.time_s});
    const cloudfit::DayWind wind = cloudfit::FitDayWind(maps);
    CalibrateLog(o, "the day's wind from " + std::to_string(frames.size()) + " partly cloudy frames: " +
                        FormatNumber(std::round(wind.speed_m_s * 100.0) / 100.0) + " m/s toward azimuth " +
                        FormatNumber(std::round(wind.direction_deg * 10.0) / 10.0) + " deg");
    const nlohmann::json day = DayJson(frames, wind, o);
    for (const DayFrame& f : frames) WriteWind(f, wind);
    WriteJsonFileAtomically((fs::path(o.out_dir) / kDayWindFile).string(), day);
    for (const auto& p : day["pairs"])
      CalibrateLog(o, "  " + fs::path(p["to"].get<std::string>()).filename().string() + " predicted from " +
                          fs::path(p["from"].get<std::string>()).filename().string() + " moved by the wind: cloud IoU " +
                          FormatNumber(std::round(p["predicted_by_the_moved_map"]["cloud_iou"].get<double>() * 100.0) / 100.0) +
                          " (unmoved " + FormatNumber(std::round(p["unmoved_map"]["cloud_iou"].get<double>() * 100.0) / 100.0) +
                          ", its own map " + FormatNumber(std::round(p["own_inverted_map"]["cloud_iou"].get<double>() * 100.0) / 100.0) + ")");
  } catch (const std::exception& e) {  // the frames' calibrations stand
    r->warnings.push_back(std::string("no wind for the day: ") + e.what());
    CalibrateLog(o, "warning: " + r->warnings.back());
  }
}

}  // namespace skycal::controllers
