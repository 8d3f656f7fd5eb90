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
#include "skycal/controllers/fit_controller.h"
#include "skycal/core/data_dir.h"
#include "skycal/core/error.h"
#include "skycal/core/json_file.h"
#include "skycal/core/latlong.h"
#include "skycal/render/preset.h"
#include "skycal/render/renderer.h"

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

}  // namespace
}  // namespace skycal::controllers
