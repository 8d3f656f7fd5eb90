// The skycal binary end to end: exit codes, JSON summaries, outputs, and bad input
// (clear message, non-zero exit, nothing left behind).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "skycal/capture/latlong_frame.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/json_file.h"
#include "skycal/render/preset.h"
#include "test_presets.h"
#include "test_util.h"
#include "run_binary.h"

namespace skycal {
namespace {

using testing::ScratchDir;

using Result = testing::ProcessResult;
using testing::Slurp;

Result Skycal(const std::string& args, const std::string& env = "") { return testing::RunSkycal(SKYCAL_BINARY, args, env); }

TEST(Cli, VersionAndHelp) {
  Result r = Skycal("--version");
  EXPECT_EQ(r.rc, 0);
  EXPECT_NE(r.out.find("skycal 0."), std::string::npos);
  r = Skycal("render --help");
  EXPECT_EQ(r.rc, 0);
  EXPECT_NE(r.out.find("--sun-elevation"), std::string::npos);
  EXPECT_NE(Skycal("no-such-verb").rc, 0);
}

TEST(Cli, RenderDefaultPresetWritesExrPngAndJson) {
  ScratchDir dir("cli-render");
  const Result r = Skycal("render --sun-elevation 30 --sun-azimuth 90 --size 256x128 --out " + (dir / "sky.exr") +
                          " --png " + (dir / "sky.png") + " --json");
  ASSERT_EQ(r.rc, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(j["ok"].get<bool>());
  EXPECT_EQ(j["backend"], "vulkan");
  EXPECT_NEAR(j["sun_elevation_deg"].get<double>(), 30.0, 1e-9);
  EXPECT_NEAR(j["sun_azimuth_deg"].get<double>(), 90.0, 1e-9);
  const capture::LatLongFrame f = capture::ReadLatLongFrame(dir / "sky.exr");
  ASSERT_TRUE(f.sun_direction.has_value());
  EXPECT_NEAR((*f.sun_direction)[0], std::cos(M_PI / 6), 1e-6);  // azimuth 90 deg -> +X
  EXPECT_NEAR((*f.sun_direction)[1], 0.5, 1e-6);
  EXPECT_EQ(f.radiance.width, 256);
  EXPECT_GT(std::filesystem::file_size(dir / "sky.png"), 1000u);
  EXPECT_EQ(dir.CountEntries(), 2);  // no temporaries left
}

TEST(Cli, CpuAndVulkanBackendsAgreeThroughTheBinary) {
  ScratchDir dir("cli-backends");
  ASSERT_EQ(Skycal("render --sun-dir 0.3,0.5,-0.8 --size 128x64 --backend cpu --out " + (dir / "c.exr")).rc, 0);
  ASSERT_EQ(Skycal("render --sun-dir 0.3,0.5,-0.8 --size 128x64 --backend vulkan --out " + (dir / "v.exr")).rc, 0);
  const auto c = capture::ReadLatLongFrame(dir / "c.exr"), v = capture::ReadLatLongFrame(dir / "v.exr");
  double worst = 0.0;
  for (size_t i = 0; i < c.radiance.pixels.size(); ++i) {
    const double a = c.radiance.pixels[i], b = v.radiance.pixels[i];
    if (a > 1e6) continue;  // sun disc pixels (edge pixels may flip): covered by the parity test
    worst = std::max(worst, std::abs(a - b) / std::max(a, 1e-30));
  }
  EXPECT_LT(worst, 2e-5);  // same threshold and reason as render_parity_test
}

// Expects failure: exit code 1, `needle` in stderr, and nothing written in `dir`.
void ExpectFailure(const std::string& args, const std::string& needle, const ScratchDir& dir, const std::string& env = "") {
  const int before = dir.CountEntries();
  const Result r = Skycal(args, env);
  EXPECT_EQ(r.rc, 1) << args << "\n" << r.err;
  EXPECT_NE(r.err.find(needle), std::string::npos) << "expected '" << needle << "' in: " << r.err;
  EXPECT_EQ(dir.CountEntries(), before) << "output left behind by: " << args;
}

TEST(Cli, BadInputIsRefusedClearlyAndLeavesNothing) {
  ScratchDir dir("cli-bad");
  const std::string out = " --out " + (dir / "o.exr");
  const std::string sun = " --sun-elevation 10 --sun-azimuth 0";
  ExpectFailure("render" + sun + " --preset " + (dir / "nope.json") + out, "nope.json", dir);
  testing::WriteText(dir / "corrupt.json", "{ not json");
  ExpectFailure("render" + sun + " --preset " + (dir / "corrupt.json") + out, "not valid JSON", dir);
  // A preset with a NaN parameter and one with an unknown variant.
  render::SavePreset(testing::RandomPreset(4, render::ModelVariant::kFfxv), dir / "p.json");
  auto j = ReadJsonFile(dir / "p.json");
  j["parameters"]["haziness_g"]["value"] = "nan";
  testing::WriteText(dir / "nan.json", j.dump());
  ExpectFailure("render" + sun + " --preset " + (dir / "nan.json") + out, "haziness_g", dir);
  j = ReadJsonFile(dir / "p.json");
  j["parameters"]["sun_angular_radius"]["value"] = 45.0;
  testing::WriteText(dir / "oob.json", j.dump());
  ExpectFailure("render" + sun + " --preset " + (dir / "oob.json") + out, "sun_angular_radius", dir);
  j = ReadJsonFile(dir / "p.json");
  j["model"] = "ffxv-pro";
  testing::WriteText(dir / "variant.json", j.dump());
  ExpectFailure("render" + sun + " --preset " + (dir / "variant.json") + out, "unknown model variant 'ffxv-pro'", dir);
  ExpectFailure("render" + sun + " --backend metal" + out, "unknown backend 'metal'", dir);
  ExpectFailure("render --sun-elevation 100 --sun-azimuth 0" + out, "--sun-elevation", dir);
  ExpectFailure("render --sun-elevation nan --sun-azimuth 0" + out, "--sun-elevation", dir);
  ExpectFailure("render --sun-dir 0,0,0" + out, "--sun-dir", dir);
  ExpectFailure("render" + sun + " --sun-dir 0,1,0" + out, "not both", dir);
  ExpectFailure("render" + out, "sun direction is required", dir);
  ExpectFailure("render" + sun + " --size 0x10" + out, "--size", dir);
  ExpectFailure("render" + sun + " --out " + (dir / "missing-dir/o.exr"), "does not exist", dir);
  ExpectFailure("render" + sun + " --out " + (dir / "o.png"), "--out", dir);
  ExpectFailure("render" + sun + " --frobnicate 3" + out, "unknown option '--frobnicate'", dir);
  // The PNG cannot be written: the EXR must not be left behind either.
  ExpectFailure("render" + sun + out + " --png " + (dir / "missing-dir/o.png"), "does not exist", dir);
  // Inputs are never modified.
  EXPECT_EQ(Slurp(dir / "corrupt.json"), "{ not json");
}

// Option syntax (CLI11, cli/command_line.h): --x=v and --x v, negative values, and the
// mistakes a hand-typed command line makes, each refused with the option named.
TEST(Cli, OptionSyntaxAndStrictness) {
  ScratchDir dir("cli-syntax");
  // --x=v and --x v mix; a negative value after either form is a value, not an option.
  Result r = Skycal("render --sun-elevation=30 --sun-azimuth -20 --size=64x32 --backend=cpu --out=" + (dir / "eq.exr") +
                    " --json");
  ASSERT_EQ(r.rc, 0) << r.err;
  auto j = nlohmann::json::parse(r.out);
  EXPECT_NEAR(j["sun_elevation_deg"].get<double>(), 30.0, 1e-9);
  EXPECT_NEAR(j["sun_azimuth_deg"].get<double>(), -20.0, 1e-9);
  EXPECT_EQ(j["size"], nlohmann::json::array({64, 32}));
  r = Skycal("sun --time=2003-10-17T12:30:30-07:00 --lat=-33.9 --lon -18.4 --json");
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_NEAR(nlohmann::json::parse(r.out)["latitude_deg"].get<double>(), -33.9, 1e-12);
  std::filesystem::remove(dir / "eq.exr");

  const std::string sun = " --sun-elevation 10 --sun-azimuth 0", out = " --out " + (dir / "o.exr");
  // A non-repeatable option (value or flag) given twice names the option.
  ExpectFailure("sun --time 2003-10-17T12:30:30Z --lat 40 --lon 0 --time 2003-10-17T13:30:30Z", "--time: given 2 times",
                dir);
  ExpectFailure("render" + sun + " --half --half" + out, "--half: given 2 times", dir);
  ExpectFailure("render" + sun + out + " --out=" + (dir / "p.exr"), "--out: given 2 times", dir);
  // A missing value is reported as such, at the end of the line or as --x=.
  ExpectFailure("render" + sun + " --out", "--out: expected a value", dir);
  ExpectFailure("render" + sun + " --out=", "--out: expected a value", dir);
  ExpectFailure("sun --time 2003-10-17T12:30:30Z --lat 40 --lon", "--lon: expected a value", dir);
  // Numbers are finite and whole: nan, inf and trailing junk are refused by the parser.
  ExpectFailure("render --sun-elevation nan --sun-azimuth 0" + out, "--sun-elevation: expected a finite number, got 'nan'",
                dir);
  ExpectFailure("render --sun-elevation 10 --sun-azimuth inf" + out, "--sun-azimuth: expected a finite number", dir);
  ExpectFailure("render" + sun + " --exposure=-INF" + out, "--exposure: expected a finite number", dir);
  ExpectFailure("probe-predict --sun-elevation 10deg --sun-azimuth 0", "--sun-elevation: expected a finite number", dir);
  ExpectFailure("bake --haziness 1.5 --out " + (dir / "p.json"), "--haziness: expected g in [0, 0.999]", dir);
  ExpectFailure("bake --n-theta 3.5 --out " + (dir / "p.json"), "--n-theta: expected an integer in [2, 1024]", dir);
  // Unknown options (either form), stray words, flags given a value.
  ExpectFailure("render" + sun + " --frobnicate=3" + out, "unknown option '--frobnicate'", dir);
  ExpectFailure("render" + sun + " stray" + out, "unexpected argument 'stray'", dir);
  ExpectFailure("render" + sun + " --half=1" + out, "--half: takes no value", dir);
  // Repeatable options take one value per occurrence.
  ExpectFailure("fit --reference a.exr b.exr --out " + (dir / "fit"), "unexpected argument 'b.exr'", dir);
  // A parse error with --json is a JSON failure too.
  r = Skycal("render --json" + sun + " --out");
  EXPECT_EQ(r.rc, 1);
  j = nlohmann::json::parse(r.out);
  EXPECT_FALSE(j["ok"].get<bool>());
  EXPECT_EQ(j["error"], "--out: expected a value");
}

// --help is generated from the registered options: every verb lists each of its options
// (all of them, so an option added without help text or dropped from the parser shows here).
TEST(Cli, HelpListsEveryRegisteredOption) {
  const std::map<std::string, std::vector<std::string>> options = {
      {"render", {"--preset", "--sun-elevation", "--sun-azimuth", "--sun-dir", "--time-of-day", "--size", "--backend", "--ground",
                  "--no-sun-disc", "--half", "--out", "--png", "--exposure", "--vulkan-validation", "--json"}},
      {"bake", {"--out", "--name", "--haziness", "--model", "--n-theta", "--n-gamma", "--mie-scattering",
                "--rayleigh-scale-height", "--mie-scale-height", "--observer-altitude", "--json"}},
      {"batch", {"--references", "--out", "--frames-per-job", "--frame-job", "--engine", "--jobs", "--resume", "--cold-start",
                 "--day-frames", "--poll", "--slurm-option", "--model", "--backend", "--mask", "--init", "--absolute",
                 "--sun-cone", "--clip-fraction", "--loss", "--loss-scale", "--no-linear-start", "--linear-width",
                 "--polish", "--pyramid", "--max-iterations", "--smoothness", "--prior-weight", "--no-haziness",
                 "--numeric-derivatives", "--quiet", "--probe-weight", "--probe-quadrature", "--no-ground-albedo",
                 "--worker-chunk", "--reduce", "--json"}},
      {"ceiling", {"--reference", "--init", "--model", "--sun-cone", "--mask", "--json"}},
      {"compare", {"--photo", "--game", "--mask", "--exposure", "--band", "--min-elevation", "--json"}},
      {"capture", {"--brackets", "--exposure-times", "--response", "--lens", "--lens-profile", "--lens-fov-deg", "--lens-center",
                   "--lens-radius", "--kb-k", "--vignetting", "--camera-rotation", "--rig", "--input-colorspace",
                   "--color-correction", "--chart", "--chart-corners", "--chart-label", "--remove-stars", "--star-window",
                   "--star-sigma", "--star-contrast", "--star-max-pixels",
                   "--time", "--lat", "--lon", "--north-longitude", "--size", "--out", "--json"}},
      {"chart", {"--image", "--out", "--response", "--chart-corners", "--label", "--json"}},
      {"stars", {"--reference", "--out", "--mask-out", "--star-window", "--star-sigma", "--star-contrast",
                 "--star-max-pixels", "--json"}},
      {"export", {"--preset", "--out", "--headroom", "--backend", "--fog-sigma-deg", "--json"}},
      {"fit", {"--reference", "--model", "--backend", "--sun-dir", "--sun-elevation", "--sun-azimuth", "--mask",
               "--init", "--absolute", "--sun-cone", "--clip-fraction", "--loss", "--loss-scale", "--no-linear-start",
               "--linear-width", "--polish", "--pyramid", "--max-iterations", "--smoothness", "--prior-weight", "--time",
               "--no-haziness", "--numeric-derivatives", "--quiet", "--probe", "--require-probe", "--probe-weight",
               "--probe-quadrature", "--no-ground-albedo", "--out", "--json"}},
      {"import", {"--in", "--out", "--source-convention", "--sun-dir", "--detect-sun", "--min-sun-contrast", "--half",
                  "--json"}},
      {"mask", {"--reference", "--out", "--horizon-deg", "--darkness", "--texture", "--ground-band-deg",
                "--ground-dark-share", "--lines", "--dilate", "--no-grabcut", "--json"}},
      {"probe-extract", {"--image", "--circle", "--camera-rotation", "--albedo", "--clip-level", "--out", "--json"}},
      {"probe-predict", {"--preset", "--sun-elevation", "--sun-azimuth", "--sun-dir", "--albedo", "--normals",
                         "--sky-width", "--backend", "--ground", "--vulkan-validation", "--json"}},
      {"sun", {"--time", "--lat", "--lon", "--elevation-m", "--pressure", "--temperature", "--delta-t",
               "--north-longitude", "--json"}},
      {"resample", {"--in", "--out", "--nominal-height", "--horizon-density", "--zenith-density", "--nadir-density",
                    "--half", "--json"}},
      {"flow", {"--out", "--scale", "--json"}},
  };
  for (const auto& [verb, names] : options) {
    const Result r = Skycal(verb + " --help");
    EXPECT_EQ(r.rc, 0) << verb;
    EXPECT_EQ(r.out.rfind("skycal " + verb + ": ", 0), 0u) << verb << " help starts with its description:\n" << r.out;
    EXPECT_NE(r.out.find("  skycal " + verb + " "), std::string::npos) << verb << ": usage synopsis missing";
    for (const std::string& name : names) {
      // Listed as an option line: "  --name" starting a line, followed by its metavar or help.
      bool listed = false;
      for (size_t at = r.out.find("\n  " + name); at != std::string::npos && !listed; at = r.out.find("\n  " + name, at + 1)) {
        const char next = at + 3 + name.size() < r.out.size() ? r.out[at + 3 + name.size()] : '\0';
        listed = next == ' ' || next == '\n';
      }
      EXPECT_TRUE(listed) << verb << " --help does not list " << name << ":\n" << r.out;
    }
    // Help wins wherever it appears, even after a bad option; -h is the same.
    EXPECT_EQ(Skycal(verb + " --frobnicate -h").out, r.out) << verb;
  }
}

// `compare` through the binary: a frame against itself is 0 in both numbers, against a frame
// twice as bright ln 2 per pixel and ln 2 * sqrt(3/5) in appearance (core/appearance.h), and
// bad input names the file and writes nothing; the clouds compared when both carry them.
TEST(Cli, CompareGivesBothNumbersAndRefusesBadInput) {
  ScratchDir dir("cli-compare");
  const std::string sun = " --sun-elevation 20 --sun-azimuth 30 --size 64x32 --backend cpu";
  ASSERT_EQ(Skycal("render" + sun + " --out " + (dir / "a.exr")).rc, 0);
  ExrRGB b = ReadExrRGB(dir / "a.exr");
  for (float& v : b.image.pixels) v *= 2.0f;
  WriteExrRGB(dir / "b.exr", b.image, b.attributes);
  const Result same = Skycal("compare --photo " + (dir / "a.exr") + " --game " + (dir / "a.exr") + " --json");
  ASSERT_EQ(same.rc, 0) << same.err;
  const auto js = nlohmann::json::parse(same.out);
  EXPECT_EQ(js["per_pixel_log_rmse"].get<double>(), 0.0);
  EXPECT_EQ(js["appearance_error"].get<double>(), 0.0);
  const Result twice = Skycal("compare --photo " + (dir / "a.exr") + " --game " + (dir / "b.exr") + " --json");
  ASSERT_EQ(twice.rc, 0) << twice.err;
  const auto jt = nlohmann::json::parse(twice.out);
  EXPECT_NEAR(jt["per_pixel_log_rmse"].get<double>(), std::log(2.0), 1e-3);
  EXPECT_NEAR(jt["appearance_error"].get<double>(), std::log(2.0) * std::sqrt(0.6), 1e-3);
  // --exposure 2 on the photo against itself is the same as the frame twice as bright.
  const Result scaled = Skycal("compare --photo " + (dir / "a.exr") + " --game " + (dir / "a.exr") + " --exposure 2 --json");
  ASSERT_EQ(scaled.rc, 0) << scaled.err;
  EXPECT_EQ(nlohmann::json::parse(scaled.out)["per_pixel_log_rmse"].get<double>(), jt["per_pixel_log_rmse"].get<double>());
  ASSERT_EQ(Skycal("render --sun-elevation 20 --sun-azimuth 30 --size 32x16 --backend cpu --out " + (dir / "small.exr")).rc, 0);
  ExpectFailure("compare --photo " + (dir / "a.exr") + " --game " + (dir / "small.exr"),
                "small.exr: 32 x 16 pixels, expected the size of", dir);
  ExpectFailure("compare --photo " + (dir / "a.exr"), "--game G.exr is required", dir);
  ExpectFailure("compare --photo " + (dir / "nope.exr") + " --game " + (dir / "a.exr"), "nope.exr", dir);
  ExpectFailure("compare --photo " + (dir / "a.exr") + " --game " + (dir / "a.exr") + " --band 0", "--band 0", dir);
  // --sun-cone needs the game file's sun, and a cone that leaves a sky.
  WriteExrRGB(dir / "nosun.exr", b.image, {});
  ExpectFailure("compare --photo " + (dir / "a.exr") + " --game " + (dir / "nosun.exr") + " --sun-cone 3",
                "nosun.exr: no sunDirection attribute", dir);
  ExpectFailure("compare --photo " + (dir / "a.exr") + " --game " + (dir / "a.exr") + " --sun-cone 50",
                "--sun-cone 50: expected degrees in [0, 45]", dir);
  // Where the clouds sit, when both files carry their transmittance: none here; a cloudy render
  // against itself agrees exactly.
  EXPECT_TRUE(js["clouds"].is_null());
  ASSERT_EQ(Skycal("render" + sun + " --clouds --out " + (dir / "c.exr")).rc, 0);
  const Result clouds = Skycal("compare --photo " + (dir / "c.exr") + " --game " + (dir / "c.exr") + " --json");
  ASSERT_EQ(clouds.rc, 0) << clouds.err;
  const auto jc = nlohmann::json::parse(clouds.out)["clouds"];
  ASSERT_TRUE(jc.is_object()) << clouds.out;
  EXPECT_EQ(jc["opacity_rms"].get<double>(), 0.0);
  EXPECT_EQ(jc["iou"].get<double>(), 1.0);
}

TEST(Cli, NoVulkanDeviceGivesAClearMessage) {
  ScratchDir dir("cli-novk");
  const std::string env = "VK_DRIVER_FILES=/nonexistent/icd.json VK_ICD_FILENAMES=/nonexistent/icd.json";
  ExpectFailure("render --sun-elevation 10 --sun-azimuth 0 --out " + (dir / "o.exr"), "no Vulkan device", dir, env);
  // The CPU reference still works without a driver.
  const Result r = Skycal("render --sun-elevation 10 --sun-azimuth 0 --size 64x32 --backend cpu --out " + (dir / "o.exr"), env);
  EXPECT_EQ(r.rc, 0) << r.err;
}

TEST(Cli, JsonFailureSummary) {
  ScratchDir dir("cli-json");
  const Result r = Skycal("render --json --sun-elevation 10 --sun-azimuth 0 --backend x --out " + (dir / "o.exr"));
  EXPECT_EQ(r.rc, 1);
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_FALSE(j["ok"].get<bool>());
  EXPECT_NE(j["error"].get<std::string>().find("unknown backend"), std::string::npos);
}

}  // namespace
}  // namespace skycal

namespace skycal {
namespace {

// Golden files: the bundled preset is exactly what `skycal bake` produces today. Update
// path (after a deliberate change to the baker or the defaults):
//   build/skycal bake --out datasets/presets/default_clear.json   and commit the files.
TEST(Cli, BundledPresetMatchesTheBaker) {
  ScratchDir dir("cli-bake");
  const Result r = Skycal("bake --out " + (dir / "default_clear.json"));
  ASSERT_EQ(r.rc, 0) << r.err;
  const render::Preset fresh = render::LoadPreset(dir / "default_clear.json");
  const render::Preset bundled = render::LoadPreset(std::string(SKYCAL_SOURCE_DIR) + "/datasets/presets/default_clear.json");
  ASSERT_EQ(fresh.luts.rayleigh.size(), bundled.luts.rayleigh.size());
  double worst = 0.0;
  for (auto [a, b] : {std::pair{&fresh.luts.rayleigh, &bundled.luts.rayleigh}, std::pair{&fresh.luts.mie, &bundled.luts.mie}}) {
    for (size_t i = 0; i < a->size(); ++i) {
      worst = std::max(worst, std::abs((*a)[i] - (*b)[i]) / std::max<double>((*b)[i], 1e-3));
    }
  }
  // 1e-5: the bake is deterministic (thread count does not change it); this only allows
  // for a different libm rounding on another machine.
  EXPECT_LT(worst, 1e-5) << "re-bake the bundled preset (see the comment above)";
  EXPECT_EQ(fresh.haziness_g, bundled.haziness_g);
}

}  // namespace
}  // namespace skycal

namespace skycal {
namespace {

// A small reference rendered from the bundled preset, for fit/export tests.
std::string SmallReference(const ScratchDir& dir, const std::string& name, double elevation) {
  const Result r = Skycal("render --sun-elevation " + std::to_string(elevation) +
                          " --sun-azimuth 30 --size 128x64 --backend cpu --out " + (dir / (name + ".exr")));
  EXPECT_EQ(r.rc, 0) << r.err;
  return dir / (name + ".exr");
}

TEST(Cli, FitWritesItsOutputsAndExportMakesGameTables) {
  ScratchDir dir("cli-fit");
  const std::string a = SmallReference(dir, "morning", 12.0), b = SmallReference(dir, "noon", 55.0);
  Result r = Skycal("fit --reference " + a + " --time 8 --quiet --backend cpu --out " + (dir / "fit_a") + " --json");
  ASSERT_EQ(r.rc, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_LT(j["references"][0]["rel_rmse"].get<double>(), 0.01);
  EXPECT_GT(j["references"][0]["pixels"]["sky_fitted"].get<long long>(), 1000);
  EXPECT_GT(j["references"][0]["pixels"]["below_horizon"].get<long long>(), 1000);
  EXPECT_FALSE(j["skipped"].empty());
  for (const char* f : {"preset.json", "preset.rayleigh.exr", "fit/morning.exr", "report.png", "fit.json"}) {
    EXPECT_TRUE(std::filesystem::exists(dir.path() / "fit_a" / f)) << f;
  }
  const auto preset = ReadJsonFile(dir / "fit_a/preset.json");
  EXPECT_EQ(preset["provenance"]["inputs"][0]["sha256"].get<std::string>().size(), 64u);
  EXPECT_EQ(preset["time_of_day_h"].get<double>(), 8.0);
  ASSERT_EQ(Skycal("fit --reference " + b + " --time 12 --quiet --backend cpu --out " + (dir / "fit_b")).rc, 0);

  r = Skycal("export --preset " + (dir / "fit_b/preset.json") + " --preset " + (dir / "fit_a/preset.json") + " --out " +
             (dir / "game") + " --json");
  ASSERT_EQ(r.rc, 0) << r.err;
  const auto m = nlohmann::json::parse(r.out);
  const double scale = m["pre_exposure"].get<double>();
  EXPECT_EQ(std::exp2(std::round(std::log2(scale))), scale);  // a power of two
  const ExrRGB mie = ReadExrRGB(dir / "game/fit_a/mie.exr");
  EXPECT_EQ(mie.attributes.floats.at("preExposure"), static_cast<float>(scale));
  const render::Preset pa = render::LoadPreset(dir / "fit_a/preset.json");
  float peak = 0.0f;
  for (size_t i = 0; i < mie.image.pixels.size(); ++i) {
    peak = std::max(peak, mie.image.pixels[i]);
    EXPECT_NEAR(mie.image.pixels[i], pa.luts.mie[i] * scale, 1e-3 * pa.luts.mie[i] * scale + 1e-7);  // half precision
  }
  EXPECT_LE(peak, 0.25f * 65504.0f);
  const std::string csv = Slurp(dir / "game/keyframes.csv");
  EXPECT_EQ(csv.find("time_of_day_h,preset,haziness_g"), 0u);
  EXPECT_LT(csv.find("\n8,fit_a"), csv.find("\n12,fit_b"));  // sorted by time
}

TEST(Cli, FitBadInputLeavesNothing) {
  ScratchDir dir("cli-fitbad");
  const std::string good = SmallReference(dir, "good", 20.0);
  const std::string out = " --quiet --out " + (dir / "out");
  // No valid pixel: every sky pixel NaN.
  {
    capture::LatLongFrame f = capture::ReadLatLongFrame(good);
    for (int y = 0; y < f.radiance.height / 2; ++y)
      for (int x = 0; x < f.radiance.width; ++x) f.radiance.at(x, y, 1) = std::nanf("");
    capture::WriteLatLongFrame(dir / "nan.exr", f);
  }
  ExpectFailure("fit --reference " + (dir / "nan.exr") + out, "no valid sky pixel", dir);
  // No sun attribute and nothing to detect: a uniform sky.
  {
    capture::LatLongFrame f;
    f.radiance = ImageRGB(128, 64);
    std::fill(f.radiance.pixels.begin(), f.radiance.pixels.end(), 100.0f);
    capture::WriteLatLongFrame(dir / "uniform.exr", f);
  }
  ExpectFailure("fit --reference " + (dir / "uniform.exr") + out, "no sun direction", dir);
  // Truncated EXR and wrong channels.
  {
    const std::string bytes = Slurp(good);
    std::ofstream(dir / "trunc.exr", std::ios::binary).write(bytes.data(), bytes.size() / 3);
  }
  ExpectFailure("fit --reference " + (dir / "trunc.exr") + out, "trunc.exr", dir);
  ExpectFailure("fit --reference " + (dir / "nope.exr") + out, "no such file", dir);
  // Absurd options.
  ExpectFailure("fit --reference " + good + " --sun-cone 90" + out, "--sun-cone", dir);
  ExpectFailure("fit --reference " + good + " --loss-scale 0" + out, "--loss-scale", dir);
  ExpectFailure("fit --reference " + good + " --pyramid 64,32" + out, "--pyramid", dir);
  ExpectFailure("fit --reference " + good + " --model bruneton" + out, "unknown model variant", dir);
  ExpectFailure("fit --reference " + good + " --time 25" + out, "--time", dir);
  ExpectFailure("fit --reference " + good + " --out " + (dir / "missing/out"), "does not exist", dir);
  // An output directory holding somebody else's files is never overwritten.
  std::filesystem::create_directory(dir.path() / "mine");
  testing::WriteText(dir / "mine/notes.txt", "keep me");
  const Result r = Skycal("fit --reference " + good + " --quiet --out " + (dir / "mine"));
  EXPECT_EQ(r.rc, 1);
  EXPECT_EQ(Slurp(dir / "mine/notes.txt"), "keep me");
  ExpectFailure("export --preset " + (dir / "nope.json") + " --out " + (dir / "game"), "nope.json", dir);
}

}  // namespace
}  // namespace skycal

#include "skycal/core/latlong.h"

namespace skycal {
namespace {

std::string Vec17(const nlohmann::json& v) {
  std::ostringstream ss;
  ss.precision(17);
  ss << v[0].get<double>() << "," << v[1].get<double>() << "," << v[2].get<double>();
  return ss.str();
}

TEST(Cli, ExportWritesSunColumnsSh9AndFogAtTheFittedSun) {
  ScratchDir dir("cli-export-sun");
  const std::string ref = SmallReference(dir, "morning", 12.0);
  ASSERT_EQ(Skycal("fit --reference " + ref + " --time 8 --quiet --backend cpu --out " + (dir / "fit_a")).rc, 0);
  const Result r = Skycal("export --preset " + (dir / "fit_a/preset.json") + " --backend cpu --out " + (dir / "game") + " --json");
  ASSERT_EQ(r.rc, 0) << r.err;
  const auto m = nlohmann::json::parse(r.out);
  const double scale = m["pre_exposure"].get<double>();
  const auto& p = m["presets"][0];
  for (const auto& s : m["skipped"]) EXPECT_EQ(s["block"].get<std::string>().find("sun"), std::string::npos) << s;

  // Keyframe columns.
  const std::string csv = Slurp(dir / "game/keyframes.csv");
  EXPECT_NE(csv.find(",pre_exposure,sun_elevation_deg,sun_illuminance_r,sun_illuminance_g,sun_illuminance_b,"
                     "sun_illuminance_lux\n"),
            std::string::npos)
      << csv;
  const auto keys = ReadJsonFile(dir / "game/keyframes.json")["keys"];
  ASSERT_EQ(keys.size(), 1u);
  const auto& k = keys[0];
  EXPECT_NEAR(k["sun_elevation_deg"].get<double>(), 12.0, 1e-3);
  const double er = k["sun_illuminance_r"].get<double>(), eg = k["sun_illuminance_g"].get<double>(),
               eb = k["sun_illuminance_b"].get<double>();
  EXPECT_GT(eg, 1000.0);
  EXPECT_LT(eg, 128000.0);  // attenuated at 12 degrees
  EXPECT_NEAR(k["sun_illuminance_lux"].get<double>(), 0.2126 * er + 0.7152 * eg + 0.0722 * eb, 1e-6 * eg);
  const render::Preset pa = render::LoadPreset(dir / "fit_a/preset.json");
  const std::array<double, 3> sun = {p["sun"]["direction"][0].get<double>(), p["sun"]["direction"][1].get<double>(),
                            p["sun"]["direction"][2].get<double>()};
  const double zenith = std::acos(sun[1]);
  const auto t = render::SunTransmittance(pa.luts, zenith);
  EXPECT_NEAR(er, pa.sun_illuminance_lux * pa.sun_tint_rgb[0] * t[0], 1e-6 * er);

  // SH-9: 27 numbers, DC term = mean radiance over the sphere / Y00.
  const auto sh = ReadJsonFile(dir / "game/fit_a/sh9.json");
  ASSERT_EQ(sh["coefficients"].size(), 9u);
  int numbers = 0;
  for (const auto& c : sh["coefficients"])
    for (const auto& v : c) numbers += v.is_number() ? 1 : 0;
  EXPECT_EQ(numbers, 27);
  EXPECT_EQ(p["sh9"]["coefficients"], sh["coefficients"]);
  ASSERT_EQ(Skycal("render --preset " + (dir / "fit_a/preset.json") + " --sun-dir " + Vec17(p["sun"]["direction"]) +
                   " --size 256x128 --backend cpu --no-sun-disc --out " + (dir / "sky.exr"))
                .rc,
            0);
  const ImageRGB sky = ReadExrRGB(dir / "sky.exr").image;
  double sum[3] = {0, 0, 0}, upper[3] = {0, 0, 0}, omega = 0.0, upper_omega = 0.0;
  for (int y = 0; y < sky.height; ++y)
    for (int x = 0; x < sky.width; ++x) {
      const double w = latlong::PixelSolidAngle(x, y, sky.width, sky.height);
      omega += w;
      const bool up = latlong::Latitude(y, sky.height) > 0.0;
      upper_omega += up ? w : 0.0;
      for (int c = 0; c < 3; ++c) {
        sum[c] += w * sky.at(x, y, c);
        if (up) upper[c] += w * sky.at(x, y, c);
      }
    }
  EXPECT_NEAR(omega, 4.0 * M_PI, 1e-9);
  const double y00 = 0.5 / std::sqrt(M_PI);
  for (int c = 0; c < 3; ++c) {
    const double mean = sum[c] / (4.0 * M_PI);
    EXPECT_NEAR(sh["coefficients"][0][c].get<double>() * y00, mean, 1e-3 * mean) << c;
    EXPECT_NEAR(p["fog"]["color_rgb"][c].get<double>(), upper[c] / upper_omega, 1e-4 * upper[c] / upper_omega) << c;
  }

  // Fog lat-long: 64x32 half float, pre-exposed, smooth and near the fog colour above the horizon.
  const ExrRGB fog = ReadExrRGB(dir / "game/fit_a/fog.exr");
  EXPECT_EQ(fog.attributes.floats.at("preExposure"), static_cast<float>(scale));
  ASSERT_EQ(fog.image.width, 64);
  ASSERT_EQ(fog.image.height, 32);
  double fog_upper = 0.0, fog_w = 0.0;
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 64; ++x) {
      for (int c = 0; c < 3; ++c) EXPECT_TRUE(std::isfinite(fog.image.at(x, y, c)) && fog.image.at(x, y, c) > 0.0f);
      const double w = latlong::PixelSolidAngle(x, y, 64, 32);
      fog_upper += w * fog.image.at(x, y, 1) / scale;
      fog_w += w;
    }
  const double fog_g = p["fog"]["color_rgb"][1].get<double>();
  EXPECT_NEAR(fog_upper / fog_w, fog_g, 0.3 * fog_g);
  for (int y = 0; y < 32; ++y)  // the seam columns hold the same direction
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(fog.image.at(0, y, c), fog.image.at(63, y, c), 2e-3 * fog.image.at(0, y, c));
}

TEST(Cli, ExportOfAPresetWithoutProvenanceSkipsTheSunColumns) {
  ScratchDir dir("cli-export-nosun");
  const std::string ref = SmallReference(dir, "noon", 50.0);
  ASSERT_EQ(Skycal("fit --reference " + ref + " --time 12 --quiet --backend cpu --out " + (dir / "fit")).rc, 0);
  auto j = ReadJsonFile(dir / "fit/preset.json");
  j.erase("provenance");
  j["name"] = "bare";
  WriteJsonFileAtomically(dir / "fit/bare.json", j);  // next to the LUT EXRs it names
  const Result r = Skycal("export --preset " + (dir / "fit/bare.json") + " --backend cpu --out " + (dir / "game") + " --json");
  ASSERT_EQ(r.rc, 0) << r.err;
  const auto m = nlohmann::json::parse(r.out);
  bool sun_reason = false, columns_reason = false;
  for (const auto& s : m["skipped"]) {
    const std::string block = s["block"], reason = s["reason"];
    if (block.find("sun, SH-9 and fog of preset 'bare'") != std::string::npos && reason.find("no provenance") != std::string::npos)
      sun_reason = true;
    if (block == "keyframe sun columns" && reason.find("'bare'") != std::string::npos) columns_reason = true;
  }
  EXPECT_TRUE(sun_reason) << m["skipped"];
  EXPECT_TRUE(columns_reason) << m["skipped"];
  const std::string csv = Slurp(dir / "game/keyframes.csv");
  EXPECT_EQ(csv.find("sun_illuminance_r"), std::string::npos);
  EXPECT_NE(csv.find("\n12,bare"), std::string::npos);
  EXPECT_TRUE(std::filesystem::exists(dir.path() / "game/bare/mie.exr"));
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "game/bare/sh9.json"));
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "game/bare/fog.exr"));
  EXPECT_TRUE(m["presets"][0]["sh9"].is_null());
}

}  // namespace
}  // namespace skycal
