// `skycal fit --clouds` and `skycal export` through the binary (docs/cloud-fitting.md): a clear reference
// never marches clouds and holds every cloud parameter; --clouds on on a clear reference
// and a cloud preset with an out-of-bounds field fail with a clear message and write
// nothing; a cloudy reference rendered with the bundled cloudy preset's shapes and
// lighting is fitted (its lighting recovered, the preset gains the fitted clouds section)
// and exported as cloud keyframes with units in the header.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <vector>
#include <nlohmann/json.hpp>

#include "run_binary.h"
#include "skycal/core/json_file.h"
#include "test_util.h"

namespace skycal {
namespace {
namespace fs = std::filesystem;
using testing::ScratchDir;

const std::string kPresets = std::string(SKYCAL_SOURCE_DIR) + "/datasets/presets/";
const std::string kCloudy = kPresets + "default_cloudy.json";

testing::ProcessResult Skycal(const std::string& args) {
  const std::string cache = (fs::temp_directory_path() / "skycal-clouds-cli-test-cache").string();
  return testing::RunSkycal(SKYCAL_BINARY, args, "XDG_CACHE_HOME=" + cache);
}

// 64x32 references from the bundled cloudy preset, with and without its clouds.
std::string Reference(const ScratchDir& dir, bool clouds) {
  const std::string out = dir / (clouds ? "cloudy.exr" : "clear.exr");
  const auto r = Skycal("render --preset " + kCloudy + " --sun-elevation 30 --sun-azimuth 40 --size 64x32 " +
                        (clouds ? "--clouds " : "") + "--out " + out);
  EXPECT_EQ(r.rc, 0) << r.err;
  return out;
}

TEST(CloudLightingCli, ClearReferenceNeverMarchesAndHoldsEveryCloudParameter) {
  ScratchDir dir("cloudfit-cli-clear");
  const std::string ref = Reference(dir, false);
  const std::string out = dir / "fit";
  const auto r = Skycal("fit --reference " + ref + " --cloud-preset " + kCloudy + " --quiet --out " + out);
  ASSERT_EQ(r.rc, 0) << r.err;
  const nlohmann::json c = ReadJsonFile(out + "/fit.json")["clouds"];
  EXPECT_EQ(c["mode"], "auto");
  EXPECT_FALSE(c["fitted"].get<bool>());
  EXPECT_NE(c["decision"].get<std::string>().find("clear"), std::string::npos) << c["decision"];
  EXPECT_FALSE(c.contains("solve"));  // no render, no Jet march
  ASSERT_EQ(c["parameters"].size(), 15u);  // cloudfit::kCloudLightingParameters
  for (const auto& [name, p] : c["parameters"].items()) {
    EXPECT_TRUE(p["held"].get<bool>()) << name;
    EXPECT_EQ(p["value"], p["initial"]) << name;
  }
}

TEST(CloudLightingCli, CloudsOnWithoutCloudPixelsFailsAndWritesNothing) {
  ScratchDir dir("cloudfit-cli-on-clear");
  const std::string ref = Reference(dir, false);
  const std::string out = dir / "fit";
  const auto r = Skycal("fit --reference " + ref + " --clouds on --cloud-preset " + kCloudy + " --quiet --out " + out);
  EXPECT_EQ(r.rc, 1);
  EXPECT_NE(r.err.find("no cloud pixels"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(ref), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

TEST(CloudLightingCli, CloudMaskAndCloudsOnAreRefusedTogether) {
  ScratchDir dir("cloudfit-cli-mask-and-on");
  const std::string ref = Reference(dir, true);
  const std::string out = dir / "fit";
  const auto r = Skycal("fit --reference " + ref + " --clouds on --cloud-mask --cloud-preset " + kCloudy + " --quiet --out " + out);
  EXPECT_EQ(r.rc, 1);
  EXPECT_NE(r.err.find("--cloud-mask"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--clouds on"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

TEST(CloudLightingCli, OutOfBoundsCloudPresetFieldIsNamed) {
  ScratchDir dir("cloudfit-cli-bounds");
  for (const char* f : {"mie", "rayleigh", "sun_transmittance", "weather"}) {
    fs::copy_file(kPresets + "default_cloudy." + f + ".exr", dir / (std::string("default_cloudy.") + f + ".exr"));
  }
  nlohmann::json j = ReadJsonFile(kCloudy);
  j["clouds"]["extinction"] = 5.0;  // bounds [0, 1] 1/m
  const std::string preset = dir / "default_cloudy.json";
  testing::WriteText(preset, j.dump(1));
  const std::string ref = Reference(dir, true);
  const std::string out = dir / "fit";
  const auto r = Skycal("fit --reference " + ref + " --clouds on --cloud-preset " + preset + " --quiet --out " + out);
  EXPECT_NE(r.rc, 0);
  EXPECT_NE(r.err.find("clouds.extinction"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

// The reference's sky and clouds are the bundled cloudy preset's, so with --init on that
// preset, its model (ffxv) and --absolute the truth is the preset's lighting: the separable
// parameters come back within 0.1%, the held ones stay exactly at it (measured 6e-5 at
// most; 0.1% leaves room for the float renders). With the default ffxv-iso at this size the
// isotropic table, free where the clouds hide the sky, changes the light the clouds
// receive: 2.9% log error at the true lighting and free parameters up to 5% off
// (docs/cloud-fitting.md, regime 1).
TEST(CloudLightingCli, CloudyReferenceFitsAndExportsCloudKeyframes) {
  ScratchDir dir("cloudfit-cli-cloudy");
  const std::string ref = Reference(dir, true);
  const std::string out = dir / "fit";
  const auto r = Skycal("fit --reference " + ref + " --clouds on --cloud-preset " + kCloudy + " --init " + kCloudy +
                        " --model ffxv --absolute --time 14 --cloud-samples 96 --quiet --out " + out);
  ASSERT_EQ(r.rc, 0) << r.err;
  const nlohmann::json c = ReadJsonFile(out + "/fit.json")["clouds"];
  ASSERT_TRUE(c["fitted"].get<bool>());
  EXPECT_GT(c["cloud_pixels"]["count"].get<int>(), 50);
  EXPECT_EQ(c["parameters"]["extinction"]["unit"], "1/m");
  int free = 0;
  for (const auto& [name, p] : c["parameters"].items()) {
    const double v = p["value"].get<double>(), v0 = p["initial"].get<double>();
    if (p["held"].get<bool>()) {
      EXPECT_EQ(v, v0) << name;
      EXPECT_FALSE(p["why"].get<std::string>().empty()) << name;
    } else {
      ++free;
      EXPECT_NEAR(v / v0, 1.0, 1e-3) << name;
    }
  }
  EXPECT_GE(free, 2);
  EXPECT_EQ(c["singular_values"].size(), 14u);  // of 15: rain_absorption unobserved (no rain in the bundled map)
  const nlohmann::json preset = ReadJsonFile(out + "/preset.json");
  ASSERT_TRUE(preset.contains("clouds"));
  EXPECT_TRUE(fs::exists(out + "/preset.weather.exr"));

  const std::string game = dir / "game";
  const auto e = Skycal("export --preset " + out + "/preset.json --backend cpu --out " + game);
  ASSERT_EQ(e.rc, 0) << e.err;
  std::ifstream csv(game + "/cloud_keyframes.csv");
  std::string header, row;
  std::getline(csv, header);
  std::getline(csv, row);
  EXPECT_EQ(header.rfind("time_of_day_h,preset,extinction [1/m],scattering_albedo [1],", 0), 0u) << header;
  EXPECT_EQ(row.rfind("14,fit,", 0), 0u) << row;
  const nlohmann::json keys = ReadJsonFile(game + "/cloud_keyframes.json");
  EXPECT_NEAR(keys["keys"][0]["extinction"].get<double>(), c["parameters"]["extinction"]["value"].get<double>(), 1e-9);
  EXPECT_TRUE(fs::exists(game + "/fit/clouds.json"));
  EXPECT_TRUE(fs::exists(game + "/fit/weather.exr"));
}

// A day: three cloudy references at 8, 10 and 12 h (sun 15, 25, 40 deg; each carries its
// time of day) fitted as one day with clouds: one lighting per reference with the prior
// over time of day (14 prior residuals: one middle key), preset.cloud_keyframes.json beside
// the preset, and export's cloud_keyframes.csv with one row per time of day. Two references
// at one time are refused naming both, writing nothing.
TEST(CloudLightingCli, ADayOfCloudyReferencesExportsOneKeyPerTimeOfDay) {
  ScratchDir dir("cloudfit-cli-day");
  std::string refs;
  const double hours[] = {10.0, 8.0, 12.0}, elevations[] = {25.0, 15.0, 40.0};  // out of time order on purpose
  for (int k = 0; k < 3; ++k) {
    const std::string out = dir / ("f" + std::to_string(k) + ".exr");
    const auto r = Skycal("render --preset " + kCloudy + " --clouds --size 64x32 --sun-azimuth 40 --sun-elevation " +
                          std::to_string(elevations[k]) + " --time-of-day " + std::to_string(hours[k]) + " --out " + out);
    ASSERT_EQ(r.rc, 0) << r.err;
    refs += " --reference " + out;
  }
  const std::string out = dir / "fit";
  const auto r = Skycal("fit" + refs + " --clouds on --cloud-preset " + kCloudy + " --init " + kCloudy +
                        " --model ffxv --absolute --cloud-samples 32 --quiet --out " + out);
  ASSERT_EQ(r.rc, 0) << r.err;
  const nlohmann::json c = ReadJsonFile(out + "/fit.json")["clouds"];
  ASSERT_TRUE(c["fitted"].get<bool>());
  EXPECT_EQ(c["day"]["references"], 3);
  EXPECT_EQ(c["day"]["prior_residuals"], 15);  // one middle key x 15 parameters
  ASSERT_EQ(c["keyframes"].size(), 3u);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(c["keyframes"][k]["time_of_day_h"].get<double>(), 8.0 + 2.0 * k);
  // The truth is the preset's lighting at every time: each key's free parameters within 1%.
  for (const auto& key : c["keyframes"]) {
    for (const auto& [name, p] : c["parameters"].items()) {
      if (p["held"].get<bool>()) continue;
      EXPECT_NEAR(key["lighting"][name].get<double>() / p["initial"].get<double>(), 1.0, 0.01) << name;
    }
  }
  EXPECT_TRUE(fs::exists(out + "/preset.cloud_keyframes.json"));
  const std::string game = dir / "game";
  const auto e = Skycal("export --preset " + out + "/preset.json --backend cpu --out " + game);
  ASSERT_EQ(e.rc, 0) << e.err;
  std::ifstream csv(game + "/cloud_keyframes.csv");
  std::string line;
  std::vector<std::string> rows;
  while (std::getline(csv, line)) rows.push_back(line);
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows[1].rfind("8,fit,", 0), 0u) << rows[1];
  EXPECT_EQ(rows[2].rfind("10,fit,", 0), 0u) << rows[2];
  EXPECT_EQ(rows[3].rfind("12,fit,", 0), 0u) << rows[3];

  const std::string twice = dir / "twice";
  fs::copy_file(dir / "f0.exr", dir / "g0.exr");  // another name, the same time of day
  const auto t = Skycal("fit --reference " + dir / "f0.exr" + " --reference " + dir / "g0.exr" + " --reference " +
                        dir / "f1.exr" + " --clouds on --cloud-preset " + kCloudy + " --quiet --out " + twice);
  EXPECT_EQ(t.rc, 1);
  EXPECT_NE(t.err.find("f0 and g0 have the same time of day 10 h"), std::string::npos) << t.err;
  EXPECT_FALSE(fs::exists(twice));
}

}  // namespace
}  // namespace skycal
