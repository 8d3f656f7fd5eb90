// `skycal render --clouds` through the binary: a render writes the composite and its
// cloudTransmittance channel; bad cloud input (weather map of the wrong size or channels
// or with a NaN, a layer bottom at or above its top, step counts 0 or 10^6, an unknown
// cloud field) exits non-zero with a message naming the field, and writes nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>

#include "run_binary.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/json_file.h"
#include "test_util.h"

namespace skycal {
namespace {
namespace fs = std::filesystem;
using testing::ScratchDir;

const std::string kPresets = std::string(SKYCAL_SOURCE_DIR) + "/datasets/presets/";

testing::ProcessResult Skycal(const std::string& args) {
  // The noise cache lives beside the other test temporaries, shared between runs.
  const std::string cache = (fs::temp_directory_path() / "skycal-clouds-cli-test-cache").string();
  return testing::RunSkycal(SKYCAL_BINARY, args, "XDG_CACHE_HOME=" + cache);
}

// A copy of the bundled cloudy preset in `dir` whose clouds section is edited by `edit`.
std::string CloudyPresetCopy(const ScratchDir& dir, const std::function<void(nlohmann::json&)>& edit) {
  for (const char* f : {"mie", "rayleigh", "sun_transmittance", "weather"}) {
    fs::copy_file(kPresets + "default_cloudy." + f + ".exr", dir / (std::string("default_cloudy.") + f + ".exr"));
  }
  nlohmann::json j = ReadJsonFile(kPresets + "default_cloudy.json");
  edit(j["clouds"]);
  const std::string path = dir / "default_cloudy.json";
  testing::WriteText(path, j.dump(1));
  return path;
}

const char* kRender = "render --sun-elevation 20 --sun-azimuth 40 --size 64x32 --clouds ";

TEST(CloudsCli, RenderWritesCompositeAndTransmittance) {
  ScratchDir dir("clouds-cli-ok");
  for (const char* backend : {"cpu", "vulkan"}) {
    const std::string out = dir / (std::string(backend) + ".exr");
    const auto r = Skycal(std::string(kRender) + "--backend " + backend + " --cloud-time 30 --out " + out + " --json");
    if (std::string(backend) == "vulkan" && r.rc != 0 && r.err.find("Vulkan") != std::string::npos) continue;  // no device
    ASSERT_EQ(r.rc, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_TRUE(j["time_ms"].contains("render"));
    const double t_mean = j["clouds"]["transmittance_mean"].get<double>();
    EXPECT_GT(t_mean, 0.3);  // a partly cloudy sky: some cloud, mostly clear
    EXPECT_LT(t_mean, 0.999);
    int w = 0, h = 0;
    const std::vector<float> t = ReadExrChannel(out, "cloudTransmittance", &w, &h);
    EXPECT_EQ(w, 64);
    EXPECT_EQ(h, 32);
    double mean = 0.0;
    for (float v : t) mean += v / t.size();
    EXPECT_NEAR(mean, t_mean, 1e-6);
  }
}

struct BadCase {
  std::string name, args, expected;  // expected: a piece of the error message (the field)
};

TEST(CloudsCli, BadCloudInputNamesTheFieldAndWritesNothing) {
  ScratchDir dir("clouds-cli-bad");
  // Weather maps: not square, an extra channel, a NaN texel.
  ImageRGB oblong(8, 4);
  WriteExrRGB(dir / "oblong.exr", oblong, {});
  ImageRGB square(8, 8);
  WriteExrRGBWithPlanes(dir / "channels.exr", square, {{"Z", std::vector<float>(64, 0.0f)}}, {});
  square.pixels[7] = std::numeric_limits<float>::quiet_NaN();
  WriteExrRGB(dir / "nan.exr", square, {});
  ScratchDir presets_a("clouds-cli-bad-a"), presets_b("clouds-cli-bad-b"), presets_c("clouds-cli-bad-c");
  const std::string inverted = CloudyPresetCopy(presets_a, [](nlohmann::json& c) {
    c["layer_bottom"]["value"] = 4000.0;
    c["layer_top"]["value"] = 3000.0;
  });
  const std::string negative = CloudyPresetCopy(presets_b, [](nlohmann::json& c) { c["layer_bottom"]["value"] = -10.0; });
  const std::string misspelt = CloudyPresetCopy(presets_c, [](nlohmann::json& c) { c["extintion"] = 0.1; });
  const std::vector<BadCase> cases = {
      {"oblong map", "--weather-map " + (dir / "oblong.exr"), "oblong.exr"},
      {"extra channel", "--weather-map " + (dir / "channels.exr"), "channel"},
      {"NaN texel", "--weather-map " + (dir / "nan.exr"), "nan.exr"},
      {"bottom above top", "--preset " + inverted, "clouds.layer_bottom"},
      {"negative bottom", "--preset " + negative, "clouds.layer_bottom"},
      {"unknown field", "--preset " + misspelt, "did you mean 'extinction'"},
      {"zero steps", "--cloud-steps 0,128", "steps_zenith"},
      {"a million steps", "--cloud-steps 64,1000000", "steps_horizon"},
      {"cheap light opacity 2", "--cloud-cheap-light-opacity 2", "cheap_light_opacity = 2"},
      {"cheap light opacity not a number", "--cloud-cheap-light-opacity half", "--cloud-cheap-light-opacity"},
      {"map without --clouds", "--weather-map x.exr", "need --clouds"},
  };
  for (const BadCase& c : cases) {
    std::string args = std::string(kRender) + c.args + " --backend cpu --out " + (dir / "out.exr") + " --png " + (dir / "out.png");
    if (c.name == "map without --clouds") {
      args = "render --sun-elevation 20 --sun-azimuth 0 --size 64x32 " + c.args + " --out " + (dir / "out.exr");
    }
    const auto r = Skycal(args);
    EXPECT_NE(r.rc, 0) << c.name;
    EXPECT_NE(r.err.find(c.expected), std::string::npos) << c.name << ": " << r.err;
    EXPECT_FALSE(fs::exists(dir / "out.exr")) << c.name;
    EXPECT_FALSE(fs::exists(dir / "out.png")) << c.name;
  }
  EXPECT_EQ(dir.CountEntries(), 3);  // the three maps: no temporaries left
}

}  // namespace
}  // namespace skycal

namespace skycal {
namespace {

// `skycal weather`: the same settings make the same texels (a map is reproducible from its
// command line), the means asked for are met to the remap's stated 1e-4, and bad options
// name the option and write nothing.
TEST(WeatherVerb, SameSettingsSameMapAndTheMeansAskedFor) {
  ScratchDir dir("weather-verb");
  const std::string args = "weather --seed 11 --size 64 --mean-coverage 0.32 --coverage-contrast 3 --coverage-cells 8 "
                           "--mean-precipitation 0.05 --mean-type 0.3 --json --out ";
  const testing::ProcessResult a = Skycal(args + (dir / "a.exr")), b = Skycal(args + (dir / "b.exr"));
  ASSERT_EQ(a.rc, 0) << a.err;
  ASSERT_EQ(b.rc, 0) << b.err;
  const ExrRGB ma = ReadExrRGB(dir / "a.exr"), mb = ReadExrRGB(dir / "b.exr");
  ASSERT_EQ(ma.image.width, 64);
  ASSERT_EQ(ma.image.height, 64);
  EXPECT_EQ(ma.image.pixels, mb.image.pixels);
  double mean[3] = {0, 0, 0};
  const size_t n = ma.image.pixels.size() / 3;
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) mean[c] += ma.image.pixels[i * 3 + c] / static_cast<double>(n);
  EXPECT_NEAR(mean[0], 0.32, 1e-4);
  EXPECT_NEAR(mean[1], 0.05, 1e-4);
  EXPECT_NEAR(mean[2], 0.3, 1e-4);
  const nlohmann::json j = nlohmann::json::parse(a.out);
  EXPECT_NEAR(j["channels"]["coverage"]["mean"].get<double>(), mean[0], 1e-6);
  // Another seed, another map.
  ASSERT_EQ(Skycal("weather --seed 12 --size 64 --out " + (dir / "c.exr")).rc, 0);
  EXPECT_NE(ReadExrRGB(dir / "c.exr").image.pixels, ma.image.pixels);
}

TEST(WeatherVerb, BadOptionsNameTheOptionAndWriteNothing) {
  ScratchDir dir("weather-verb-bad");
  const std::string out = dir / "w.exr";
  for (const std::string& bad : {"--size 100", "--size 8 --coverage-cells 8", "--mean-coverage 1.5", "--octaves 0",
                                 "--extent -5", "--coverage-contrast nan"}) {
    const testing::ProcessResult r = Skycal("weather " + bad + " --out " + out);
    EXPECT_NE(r.rc, 0) << bad;
    const std::string option = bad.substr(0, bad.find(' ', 2));
    EXPECT_NE(r.err.find(bad.find("coverage-cells") != std::string::npos ? "--size" : option), std::string::npos)
        << bad << ": " << r.err;
    EXPECT_FALSE(fs::exists(out)) << bad;
  }
}

}  // namespace
}  // namespace skycal
