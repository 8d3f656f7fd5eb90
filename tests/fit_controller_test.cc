// The fit controller (skycal/controllers/fit_controller.h): its options' check names the field
// and its value; RunFitInto writes the fit beside a caller's own files in the caller's staged
// directory (the calibrate pipeline's use), report.html included, and fits what
// RunFitController fits.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <unistd.h>

#include "skycal/capture/latlong_frame.h"
#include "skycal/clouds/weather_map.h"
#include "skycal/controllers/game_render.h"
#include "skycal/core/exr_io.h"
#include "skycal/controllers/fit_controller.h"
#include "skycal/core/data_dir.h"
#include "skycal/core/error.h"
#include "skycal/core/json_file.h"
#include "skycal/core/latlong.h"
#include "skycal/core/math_constants.h"
#include "skycal/render/preset.h"
#include "skycal/render/renderer.h"
#include "fit_cloud_mask.h"

namespace skycal::controllers {
namespace {

namespace fs = std::filesystem;

std::string WhyInvalid(const FitControllerOptions& o) {
  std::string why;
  return o.IsValid(&why) ? "(valid)" : why;
}

TEST(FitController, IsValidNamesTheFieldAndItsValue) {
  FitControllerOptions o;
  o.references = {"a.exr"};
  o.out_dir = "d";
  EXPECT_EQ(WhyInvalid(o), "(valid)");  // control
  FitControllerOptions bad = o;
  bad.references.clear();
  EXPECT_EQ(WhyInvalid(bad), "FitControllerOptions::references is empty (expected at least one lat-long EXR)");
  bad = o;
  bad.clouds.time_s = 2.0e7;
  EXPECT_EQ(WhyInvalid(bad), "FitCloudOptions::time_s = 2e+07 (expected seconds, finite, within 1e7)");
  bad = o;
  bad.clouds.mode = "off";
  bad.clouds.preset = "p.json";
  EXPECT_EQ(WhyInvalid(bad), "FitCloudOptions::preset has no effect with FitCloudOptions::mode = off");
  bad = o;
  bad.cloud_stats.enabled = true;
  EXPECT_EQ(WhyInvalid(bad),
            "FitCloudStatsOptions::enabled = true fits the atmosphere to the clear pixels: it needs "
            "FitControllerOptions::cloud_mask = true");
  bad.cloud_mask = true;
  EXPECT_EQ(WhyInvalid(bad), "(valid)");
  bad.cloud_stats.width = 65;
  EXPECT_NE(WhyInvalid(bad).find("PhotoCloudStatsOptions::width = 65"), std::string::npos) << WhyInvalid(bad);
  bad = o;
  bad.clouds.sky_pixels_sun_boost = -0.1;
  EXPECT_EQ(WhyInvalid(bad), "FitCloudOptions::sky_pixels_sun_boost = -0.1 (expected [0, 5], as capture::CloudMaskOptions::sun_boost)");
  bad.clouds.sky_pixels_sun_boost = 0.0;
  EXPECT_EQ(WhyInvalid(bad), "(valid)");
  bad = o;
  bad.fit.sun_cone_deg = 90.0;
  EXPECT_EQ(WhyInvalid(bad), "FitOptions::sun_cone_deg = 90 (expected degrees in [0, 45])");
}

// A 128x64 reference rendered from the bundled clear preset, sun 25 deg up: the fit matches it.
std::string SmallReference(const fs::path& dir) {
  const render::Preset p = render::LoadPreset(DataPath("datasets/presets/default_clear.json"));
  render::RenderRequest req;
  req.sun_dir = latlong::DirectionFromElevationAzimuthDeg(25.0, 30.0);
  req.width = 128;
  req.height = 64;
  capture::LatLongFrame f;
  f.radiance = render::CreateRenderer(render::Backend::kCpu)->Render(p, req);
  f.sun_direction = req.sun_dir;
  const std::string path = (dir / "small.exr").string();
  capture::WriteLatLongFrame(path, f);
  return path;
}

TEST(FitController, RunFitIntoWritesBesideTheCallersFilesAndMatchesRunFitController) {
  const fs::path dir = fs::temp_directory_path() / ("skycal-fit-controller-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  FitControllerOptions o;
  o.references = {SmallReference(dir)};
  o.fit.backend = render::Backend::kCpu;
  o.fit.verbose = false;
  o.out_dir = (dir / "photo").string();
  nlohmann::json into;
  {
    StagedDirectory out(o.out_dir, "test out", "calibrate", FitControllerInputs(o));
    std::ofstream(out / "mask.txt") << "the caller's own file";
    into = RunFitInto(o, out);
    EXPECT_FALSE(fs::exists(o.out_dir));  // nothing committed before the caller commits
    out.Commit();
  }
  for (const char* f : {"mask.txt", "preset.json", "fit.json", "report.png", "report.html", "fit/small.exr"}) {
    EXPECT_TRUE(fs::exists(fs::path(o.out_dir) / f)) << f;
  }
  EXPECT_EQ(into["out"], o.out_dir);
  EXPECT_LT(into["references"][0]["rel_rmse"].get<double>(), 0.01);
  EXPECT_GT(into["references"][0]["pixels"]["sky_fitted"].get<long long>(), 1000);
  EXPECT_EQ(ReadJsonFile((fs::path(o.out_dir) / "fit.json").string())["references"][0]["rel_rmse"], into["references"][0]["rel_rmse"]);
  // The controller that stages its own directory fits the same (the CPU objective is deterministic).
  FitControllerOptions own = o;
  own.out_dir = (dir / "own").string();
  own.report = false;
  const nlohmann::json j = RunFitController(own);
  EXPECT_DOUBLE_EQ(j["references"][0]["rel_rmse"].get<double>(), into["references"][0]["rel_rmse"].get<double>());
  EXPECT_TRUE(fs::exists(dir / "own/preset.json"));
  EXPECT_FALSE(fs::exists(dir / "own/report.html"));  // report = false
  // Invalid options: named, nothing written.
  own.out_dir = (dir / "bad").string();
  own.fit.sun_cone_deg = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(RunFitController(own), Error);
  EXPECT_FALSE(fs::exists(dir / "bad"));
  fs::remove_all(dir);
}

// A shape refinement that rains 0.5 on every texel (or keeps the map) and records what the fit
// handed it.
class RainEverywhere : public cloudfit::ShapeRefinement {
 public:
  explicit RainEverywhere(bool rain) : rain_(rain) {}
  std::optional<clouds::WeatherMap> Refine(const render::Preset&, const clouds::CloudParams& lit, double exposure,
                                           const clouds::WeatherMap& map) override {
    ++calls;
    exposure_seen = exposure;
    sun_scale_seen = lit.sun_scale;
    if (!rain_) return std::nullopt;
    clouds::WeatherMap m = map;
    for (size_t t = 1; t < m.rgb.size(); t += 3) m.rgb[t] = 0.5f;
    return m;
  }
  int calls = 0;
  double exposure_seen = 0.0, sun_scale_seen = 0.0;

 private:
  bool rain_;
};

// The mean of the exported weather map's precipitation (G).
double MeanPrecipitation(const fs::path& exr) {
  const ImageRGB m = ReadExrRGB(exr.string()).image;
  double sum = 0.0;
  for (size_t i = 1; i < m.pixels.size(); i += 3) sum += m.pixels[i];
  return sum / static_cast<double>(m.pixels.size() / 3);
}

// The known-shapes fit with a refinement (CloudLightingOptions::refine_shapes): called once,
// after the solve, with its lighting and exposure; the map it returns is the exported one and
// the report's (a rain the reference does not have leaves the cloud pixels further from it
// than the kept map, whose control is the refinement that keeps the map: no rain exported).
TEST(FitController, TheMapRefinedAfterTheLightingSolveIsTheFits) {
  const fs::path dir = fs::temp_directory_path() / ("skycal-fit-refine-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  GameRenderOptions g;
  g.preset_path = DefaultCloudyPresetPath();
  g.sun_dir = latlong::DirectionFromElevationAzimuthDeg(30.0, 40.0);
  g.width = 64;
  g.height = 32;
  g.backend = render::Backend::kCpu;
  g.clouds.enabled = true;
  g.verbose = false;
  capture::LatLongFrame f;
  f.radiance = RenderGameImage(g).radiance;
  f.sun_direction = g.sun_dir;
  capture::WriteLatLongFrame((dir / "cloudy.exr").string(), f);
  const double kept_rain = MeanPrecipitation(fs::path(DefaultCloudyPresetPath()).parent_path() / "default_cloudy.weather.exr");
  auto fit = [&](RainEverywhere* refine, const std::string& name) {
    FitControllerOptions o;
    o.references = {(dir / "cloudy.exr").string()};
    o.init_preset = DefaultCloudyPresetPath();
    o.fit.backend = render::Backend::kCpu;
    o.fit.absolute = true;
    o.fit.verbose = false;
    o.clouds.mode = "on";
    o.clouds.preset = DefaultCloudyPresetPath();
    o.clouds.samples = 64;
    o.clouds.max_iterations = 3;
    o.clouds.values_from_renderer = false;
    o.clouds.refine_shapes = refine;
    o.report = false;
    o.out_dir = (dir / name).string();
    return RunFitController(o);
  };
  RainEverywhere rain(true), keep(false);
  const nlohmann::json rained = fit(&rain, "rained"), kept = fit(&keep, "kept");
  EXPECT_EQ(rain.calls, 1);
  EXPECT_EQ(keep.calls, 1);
  EXPECT_NEAR(rain.exposure_seen, 1.0, 1e-12);  // absolute: the exposure fixed at 1
  EXPECT_GT(rain.sun_scale_seen, 0.0);
  EXPECT_NEAR(MeanPrecipitation(dir / "rained/preset.weather.exr"), 0.5, 1e-3);  // half floats
  EXPECT_NEAR(MeanPrecipitation(dir / "kept/preset.weather.exr"), kept_rain, 1e-3);
  EXPECT_GT(std::abs(kept_rain - 0.5), 0.1);
  const double after_rain = rained["clouds"]["cloud_pixels"]["final"]["log_rmse"].get<double>();
  const double without = kept["clouds"]["cloud_pixels"]["final"]["log_rmse"].get<double>();
  EXPECT_GT(after_rain, without + 0.01) << "the report is on the rained map";
  EXPECT_LT(without, 0.05);  // the reference's own shapes and lighting
  fs::remove_all(dir);
}

// The cloud mask's ramp options reach the estimate (FitCloudOptions::sky_pixels_sun_boost,
// calibrate's refit): a clear sky with two equal whitish patches (ln R/B raised by 0.45, a
// thin cloud), one 10 deg above the sun, one 90 deg of azimuth away. The ramp's allowance for the haze
// round the sun lets the near one pass for clear sky; without it both are cloud.
TEST(FitCloudMask, TheRampsAllowanceByTheSunIsTheCallers) {
  const fs::path dir = fs::temp_directory_path() / ("skycal-fit-cloud-mask-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string path = SmallReference(dir);  // sun 25 deg up, azimuth 30
  capture::LatLongFrame f = capture::ReadLatLongFrame(path);
  const latlong::Vec3d near = latlong::DirectionFromElevationAzimuthDeg(35.0, 30.0);
  const latlong::Vec3d far = latlong::DirectionFromElevationAzimuthDeg(35.0, 120.0);
  std::vector<size_t> near_px, far_px;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 128; ++x) {
      const latlong::Vec3d d = latlong::PixelDirection(x, y, 128, 64);
      const size_t i = static_cast<size_t>(y) * 128 + x;
      if (d[0] * near[0] + d[1] * near[1] + d[2] * near[2] > std::cos(4.0 * kRadiansPerDegree)) near_px.push_back(i);
      if (d[0] * far[0] + d[1] * far[1] + d[2] * far[2] > std::cos(4.0 * kRadiansPerDegree)) far_px.push_back(i);
    }
  ASSERT_GT(near_px.size(), 3u);
  ASSERT_GT(far_px.size(), 3u);
  for (const auto* px : {&near_px, &far_px})
    for (size_t i : *px) f.radiance.pixels[3 * i] *= static_cast<float>(std::exp(0.45));
  capture::WriteLatLongFrame(path, f);
  const auto masked = [&](const capture::CloudMaskOptions& ramp, const std::vector<size_t>& px) {
    fit::FitOptions fo;
    fit::Reference r = fit::LoadReference(path, fo);
    ApplyCloudMask(&r, DataPath("datasets/presets/default_clear.json"), ramp);
    int n = 0;
    for (size_t i : px) n += r.pixel_class[i] == fit::PixelClass::kUserMasked;
    return n;
  };
  capture::CloudMaskOptions strict;
  strict.sun_boost = 0.0;
  EXPECT_EQ(masked({}, near_px), 0);                                   // the allowance: clear
  EXPECT_EQ(masked(strict, near_px), static_cast<int>(near_px.size()));  // without it: cloud
  EXPECT_EQ(masked({}, far_px), static_cast<int>(far_px.size()));       // control: cloud either way
  EXPECT_EQ(masked(strict, far_px), static_cast<int>(far_px.size()));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace skycal::controllers
