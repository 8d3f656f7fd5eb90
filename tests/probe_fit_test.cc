// The sun from the gray diffuse probe in `skycal fit` (fit/src/sun_from_probe.cc) and
// `skycal probe-extract`: synthetic probe scenes with a known sun, a day with clouds over
// the sun in some frames, and bad input.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <sstream>

#include <nlohmann/json.hpp>

#include "skycal/capture/latlong_frame.h"
#include "skycal/capture/probe.h"
#include "skycal/capture/rig.h"
#include "skycal/controllers/probe_extract.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/json_file.h"
#include "skycal/core/latlong.h"
#include "skycal/render/irradiance.h"
#include "skycal/render/renderer.h"
#include "skycal/testing/synthetic_probe.h"
#include "skycal/testing/synthetic_sky.h"
#include "run_binary.h"
#include "test_util.h"

namespace skycal {
namespace {

using Result = testing::ProcessResult;
using testing::Slurp;

Result Skycal(const std::string& args) { return testing::RunSkycal(SKYCAL_BINARY, args); }

const std::string kPreset = std::string(SKYCAL_SOURCE_DIR) + "/datasets/presets/default_clear.json";

// Writes synthetic::ProbeSamplesFor as a "skycal-probe-samples" file.
void WriteSyntheticProbe(const std::string& path, const render::Preset& preset, const std::array<double, 3>& sun,
                         const render::Rgb& e_sun, double albedo, double noise, unsigned seed,
                         double ground_albedo = 0.1) {
  const auto samples = synthetic::ProbeSamplesFor(preset, sun, e_sun, albedo, noise, seed, ground_albedo);
  nlohmann::json list = nlohmann::json::array();
  for (const auto& smp : samples) list.push_back({{"normal", smp.normal}, {"radiance", smp.radiance}, {"pixels", smp.pixels}});
  WriteJsonFileAtomically(path, {{"format", "skycal-probe-samples"},
                                 {"format_version", 1},
                                 {"image", "synthetic"},
                                 {"albedo", albedo},
                                 {"max_luminance", 0.0},
                                 {"max_luminance_clipped", true},
                                 {"samples", list}});
}

const char* kFitArgs = " --backend cpu --model ffxv --pyramid 64,128 --max-iterations 8 --quiet --json";

// The synthetic probe scene: a sky with a known sun (tinted away from the preset's),
// photographed with 2% noise and clipped like a single exposure (every channel above the
// 99.5th percentile of the sky's luminance clips: the disc and ~8 degrees of aureole), a
// gray ball (albedo 0.18) with 1% noise and its sun side clipped, on a ground of albedo
// 0.25 where the fit starts at the preset's 0.1. One joint fit: sun within 1%, ground
// albedo within 0.01, the sky within the noisy round trip's tolerance (0.5%,
// tests/fit_roundtrip_test.cc) of the clean truth.
TEST(ProbeFit, RecoversTheSunWithinOnePercent) {
  testing::ScratchDir dir("probe-fit-sun");
  const render::Preset truth = render::LoadPreset(kPreset);  // the fit starts at the bundled preset
  const double el = 35.0, az = 50.0;
  const auto sun = latlong::DirectionFromElevationAzimuthDeg(el, az);
  synthetic::WriteSyntheticReference(dir / "noon.exr", truth, el, az, 128, 0.02, 0.0, 11);
  capture::LatLongFrame frame = capture::ReadLatLongFrame(dir / "noon.exr");
  std::vector<float> lum;
  for (size_t i = 0; i < frame.radiance.pixels.size(); i += 3) lum.push_back(frame.radiance.pixels[i + 1]);
  std::nth_element(lum.begin(), lum.begin() + lum.size() * 995 / 1000, lum.end());
  const float clip = lum[lum.size() * 995 / 1000];
  int clipped = 0;
  for (float& v : frame.radiance.pixels) {
    if (v > clip) {
      v = clip;
      ++clipped;
    }
  }
  capture::WriteLatLongFrame(dir / "noon.exr", frame);
  const render::Rgb at_ground = render::SunIlluminanceAtGround(truth, sun);
  const std::array<double, 3> tint_scale = {0.85, 1.0, 1.12};
  render::Rgb e_sun{};
  for (int c = 0; c < 3; ++c) e_sun[c] = at_ground[c] * tint_scale[c];
  WriteSyntheticProbe(dir / "noon_ball.json", truth, sun, e_sun, 0.18, 0.01, 7, 0.25);

  const Result r = Skycal("fit --reference " + dir / "noon.exr" + " --probe noon=" + dir / "noon_ball.json" +
                          " --require-probe --absolute --out " + dir / "out" + kFitArgs);
  ASSERT_EQ(r.rc, 0) << r.err;
  const auto fit = ReadJsonFile(dir / "out/fit.json");
  const auto& s = fit["references"][0]["sun"];
  ASSERT_TRUE(s.is_object()) << fit.dump(1);
  std::cout << "[probe fit] " << clipped << " channel values clipped at " << clip << "; joint fit "
            << fit["time_s"].get<double>() << " s, of which probe residual evaluations "
            << fit["probe"]["evaluation_time_s"].get<double>() << " s\n";
  EXPECT_GT(fit["references"][0]["pixels"]["clipped"].get<int>(), 0);
  EXPECT_TRUE(s["visible"].get<bool>());
  double worst = 0.0;
  for (int c = 0; c < 3; ++c) {
    const double rel = s["illuminance_rgb"][c].get<double>() / e_sun[c] - 1.0;
    worst = std::max(worst, std::abs(rel));
  }
  const double lux_true = 0.2126 * e_sun[0] + 0.7152 * e_sun[1] + 0.0722 * e_sun[2];
  const double lux_rel = s["illuminance_lux"].get<double>() / lux_true - 1.0;
  const double ground = fit["probe"]["ground_albedo"]["value"].get<double>();
  // The fitted sky against the clean truth (above the horizon, outside 3 degrees of the sun).
  auto cpu = render::CreateRenderer(render::Backend::kCpu);
  render::RenderRequest req;
  req.sun_dir = sun;
  req.width = 128;
  req.height = 64;
  const ImageRGB clean = cpu->Render(truth, req);
  auto sky_error = [&](const std::string& out_dir) {
    const ImageRGB fitted = capture::ReadLatLongFrame(out_dir + "/fit/noon.exr").radiance;
    double se = 0.0, sw = 0.0;
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 128; ++x) {
        const auto v = latlong::PixelDirection(x, y, 128, 64);
        if (v[0] * sun[0] + v[1] * sun[1] + v[2] * sun[2] > std::cos(3.0 * M_PI / 180.0)) continue;
        const double w = latlong::PixelSolidAngle(x, y, 128, 64);
        for (int c = 0; c < 3; ++c) {
          const double d = fitted.at(x, y, c) / clean.at(x, y, c) - 1.0;
          se += w * d * d;
          sw += w;
        }
      }
    return std::sqrt(se / sw);
  };
  const double sky_vs_truth = sky_error(dir / "out");
  std::cout << "[probe-fit] E_sun true " << e_sun[0] << ", " << e_sun[1] << ", " << e_sun[2] << " recovered "
            << s["illuminance_rgb"].dump() << " worst rel " << worst << " lux rel " << lux_rel << " fraction "
            << s["fraction"] << " probe log RMSE " << s["log_rmse"] << "; ground albedo " << ground
            << " (truth 0.25); sky vs clean truth " << sky_vs_truth << "\n";
  EXPECT_LT(worst, 0.01);
  EXPECT_LT(std::abs(lux_rel), 0.01);
  EXPECT_NEAR(ground, 0.25, 0.01);
  EXPECT_LT(sky_vs_truth, 0.005);
  EXPECT_TRUE(fit["probe"]["ground_albedo"]["fitted"].get<bool>());
  // The preset carries it: sun_illuminance * tint * T(sun zenith) = the recovered illuminance.
  const render::Preset out = render::LoadPreset(dir / "out/preset.json");
  EXPECT_NEAR(out.ground_albedo, ground, 1e-12);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(out.sun_tint_rgb[c] / (truth.sun_tint_rgb[c] * tint_scale[c]), 1.0, 0.01) << c;
  }
  const render::Rgb again = render::SunIlluminanceAtGround(out, sun);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(again[c] / e_sun[c], 1.0, 0.01) << c;

  // A probe the model cannot match (the ground albedo held at 0.1 where it is 0.25) at ten
  // times the default weight: the probe's error goes into the sun (biased, reported), not
  // into the sky (the LUT is the sky pixels', fit/src/probe_terms.h).
  const Result held = Skycal("fit --reference " + dir / "noon.exr" + " --probe noon=" + dir / "noon_ball.json" +
                             " --no-ground-albedo --probe-weight 1 --absolute --out " + dir / "held" + kFitArgs);
  ASSERT_EQ(held.rc, 0) << held.err;
  const auto held_fit = ReadJsonFile(dir / "held/fit.json");
  const double held_sky = sky_error(dir / "held");
  std::cout << "[probe-fit] ground held at 0.1, probe weight 1: sky vs clean truth " << held_sky << ", probe log RMSE "
            << held_fit["references"][0]["sun"]["log_rmse"] << ", E_sun " << held_fit["references"][0]["sun"]["illuminance_rgb"]
            << "\n";
  EXPECT_LT(held_sky, 0.005);
  EXPECT_FALSE(held_fit["probe"]["ground_albedo"]["fitted"].get<bool>());
  EXPECT_GT(held_fit["references"][0]["sun"]["log_rmse"].get<double>(), 0.1);  // the mismatch is visible
}

TEST(ProbeFit, DayWithCloudsOverTheSunDecidesVisibilityEveryFrame) {
  testing::ScratchDir dir("probe-fit-day");
  const render::Preset truth = render::LoadPreset(kPreset);
  const double els[] = {8.0, 20.0, 33.0, 45.0, 33.0, 20.0, 8.0};
  const double azs[] = {-100.0, -70.0, -40.0, 0.0, 40.0, 70.0, 100.0};
  const bool cloud_over_sun[] = {false, true, false, false, true, false, true};
  std::string args = "fit";
  for (int f = 0; f < 7; ++f) {
    const std::string stem = dir / ("frame" + std::to_string(f));
    const auto sun = latlong::DirectionFromElevationAzimuthDeg(els[f], azs[f]);
    synthetic::WriteSyntheticReference(stem + ".exr", truth, els[f], azs[f], 128);
    render::Rgb e_sun = render::SunIlluminanceAtGround(truth, sun);
    if (cloud_over_sun[f]) e_sun = {0.0, 0.0, 0.0};
    WriteSyntheticProbe(stem + ".probe.json", truth, sun, e_sun, 0.18, 0.01, 100 + f);  // auto-discovered
    args += " --reference " + stem + ".exr";
  }
  const Result r = Skycal(args + " --require-probe --out " + dir / "out" + kFitArgs);
  ASSERT_EQ(r.rc, 0) << r.err;
  const auto fit = ReadJsonFile(dir / "out/fit.json");
  for (int f = 0; f < 7; ++f) {
    const auto& s = fit["references"][f]["sun"];
    ASSERT_TRUE(s.is_object()) << f;
    std::cout << "[probe-day] frame " << f << " elevation " << els[f] << (cloud_over_sun[f] ? " cloud" : " clear")
              << ": visible " << s["visible"] << " fraction " << s["fraction"] << " E_sun(model) "
              << s["illuminance_rgb_model"].dump() << " exposure " << fit["references"][f]["exposure"] << "\n";
    EXPECT_EQ(s["visible"].get<bool>(), !cloud_over_sun[f]) << "frame " << f;
    if (!cloud_over_sun[f]) {
      const auto sun = latlong::DirectionFromElevationAzimuthDeg(els[f], azs[f]);
      const render::Rgb e_true = render::SunIlluminanceAtGround(truth, sun);
      for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(s["illuminance_rgb_model"][c].get<double>() / e_true[c], 1.0, 0.02) << "frame " << f << " ch " << c;
      }
    }
  }
  // Several frames see the sun: the preset's tint is left alone, with a warning.
  EXPECT_NE(fit["warnings"].dump().find("see the sun on the probe"), std::string::npos);
}

TEST(ProbeFit, RequireProbeWithoutSamplesFailsAndWritesNothing) {
  testing::ScratchDir dir("probe-fit-require");
  const render::Preset truth = render::LoadPreset(kPreset);
  synthetic::WriteSyntheticReference(dir / "ref.exr", truth, 30.0, 0.0, 64);
  const Result r = Skycal("fit --reference " + dir / "ref.exr" + " --require-probe --out " + dir / "out" + kFitArgs);
  EXPECT_EQ(r.rc, 1);
  EXPECT_NE(r.err.find("require-probe"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out") && !std::filesystem::is_empty(dir / "out"));
  EXPECT_EQ(dir.CountEntries(), 1);  // ref.exr only: no staging directory left behind
  // A --probe for a reference that does not exist is refused as well.
  WriteSyntheticProbe(dir / "p.json", truth, latlong::DirectionFromElevationAzimuthDeg(30.0, 0.0), {1e5, 1e5, 1e5}, 0.18,
                      0.0, 1);
  const Result r2 = Skycal("fit --reference " + dir / "ref.exr" + " --probe other=" + dir / "p.json" + " --out " +
                           dir / "out" + kFitArgs);
  EXPECT_EQ(r2.rc, 1);
  EXPECT_FALSE(std::filesystem::exists(dir / "out"));
  // A probe whose every sample is black (a lens cap, a wrong exposure) names its file.
  WriteSyntheticProbe(dir / "black.json", truth, latlong::DirectionFromElevationAzimuthDeg(30.0, 0.0), {0.0, 0.0, 0.0},
                      1e-30, 0.0, 1, 0.0);
  auto doc = ReadJsonFile(dir / "black.json");
  for (auto& smp : doc["samples"]) smp["radiance"] = {0.0, 0.0, 0.0};
  WriteJsonFileAtomically(dir / "black.json", doc);
  const Result r3 = Skycal("fit --reference " + dir / "ref.exr" + " --probe ref=" + dir / "black.json" + " --out " +
                           dir / "out" + kFitArgs);
  EXPECT_EQ(r3.rc, 1);
  EXPECT_NE(r3.err.find("black.json: no usable probe sample"), std::string::npos) << r3.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out"));
  // An absurd weight is refused before any work.
  const Result r4 = Skycal("fit --reference " + dir / "ref.exr" + " --probe-weight -1 --out " + dir / "out" + kFitArgs);
  EXPECT_EQ(r4.rc, 1);
  EXPECT_NE(r4.err.find("--probe-weight"), std::string::npos) << r4.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out"));
}

// Probe sample files are read strictly and checked before the fit: a misspelt key, a
// missing format_version, a sample of 1e308 (which surfaced as a raw Ceres "invalid value")
// and a non-unit normal are refused naming the file and the field.
TEST(ProbeFit, SampleFilesAreCheckedBeforeTheFit) {
  testing::ScratchDir dir("probe-strict");
  const render::Preset truth = render::LoadPreset(kPreset);
  synthetic::WriteSyntheticReference(dir / "ref.exr", truth, 30.0, 0.0, 64);
  WriteSyntheticProbe(dir / "good.json", truth, latlong::DirectionFromElevationAzimuthDeg(30.0, 0.0), {1e5, 1e5, 1e5},
                      0.18, 0.0, 1);
  struct Case {
    std::function<void(nlohmann::json&)> edit;
    std::string needle;
  };
  const std::vector<Case> cases = {
      {[](auto& d) { d["sample"] = d["samples"]; d.erase("samples"); }, "field 'sample': unknown key (did you mean 'samples'?"},
      {[](auto& d) { d.erase("format_version"); }, "field 'format_version' is missing"},
      {[](auto& d) { d["samples"][3]["radiance"] = {1e308, 1.0, 1.0}; }, "field 'samples[3].radiance'"},
      {[](auto& d) { d["samples"][0]["radiance"] = {-1.0, 1.0, 1.0}; }, "field 'samples[0].radiance'"},
      {[](auto& d) { d["samples"][1]["normal"] = {0.0, 2.0, 0.0}; }, "field 'samples[1].normal': expected a unit vector"},
      {[](auto& d) { d["samples"][1]["radiance_rgb"] = {1.0, 1.0, 1.0}; }, "did you mean 'radiance'?"},
      {[](auto& d) { d["albedo"] = 1e300; }, "1e+300"},
      // Found by fuzz/probe_samples_fuzzer: a count as a huge float once overflowed the cast.
      {[](auto& d) { d["samples"][2]["pixels"] = 3.7e62; }, "field 'samples[2].pixels': expected a positive integer"},
      {[](auto& d) { d["samples"][2]["pixels"] = 4294967296LL; }, "field 'samples[2].pixels'"},
      {[](auto& d) { d["samples"][2]["pixels"] = 2.5; }, "field 'samples[2].pixels'"},
      {[](auto& d) { d["samples"][2]["pixels"] = 0; }, "field 'samples[2].pixels'"},
  };
  for (const Case& c : cases) {
    auto doc = ReadJsonFile(dir / "good.json");
    c.edit(doc);
    WriteJsonFileAtomically(dir / "bad.json", doc);
    const Result r = Skycal("fit --reference " + dir / "ref.exr" + " --probe ref=" + dir / "bad.json" + " --out " +
                            dir / "out" + kFitArgs);
    EXPECT_EQ(r.rc, 1) << c.needle;
    EXPECT_NE(r.err.find("bad.json"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(c.needle), std::string::npos) << "expected '" << c.needle << "' in: " << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "out"));
  }
}

// A photograph of a ball: background 0.5, ball radiance a + b max(0, n.s) per channel.
void WriteBallImage(const std::string& path, const capture::BallCircle& c, const std::array<double, 9>& rot,
                    const std::array<double, 3>& s) {
  ImageRGB img;
  img.width = 200;
  img.height = 150;
  img.pixels.assign(static_cast<size_t>(img.width) * img.height * 3, 0.5f);
  for (int y = 0; y < img.height; ++y) {
    for (int x = 0; x < img.width; ++x) {
      const auto n = capture::BallNormalAt(c, rot, x, y);
      if (!n) continue;
      const double cs = std::max(0.0, (*n)[0] * s[0] + (*n)[1] * s[1] + (*n)[2] * s[2]);
      for (int ch = 0; ch < 3; ++ch) {
        img.pixels[(static_cast<size_t>(y) * img.width + x) * 3 + ch] = static_cast<float>(1.0 + 0.1 * ch + 8.0 * cs);
      }
    }
  }
  WriteExrRGB(path, img, {});
}

// The controller's options name their fields (and the value where one is set); the verb
// writes them as the flags the user typed, as it always worded them.
TEST(ProbeExtract, OptionsNameTheirFieldsAndTheVerbItsFlags) {
  controllers::ProbeExtractOptions o;
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "ProbeExtractOptions::image is empty (expected a linear EXR)");
  o.image = "ball.exr";
  o.out = "s.json";
  EXPECT_TRUE(o.IsValid(&why)) << why;  // the control: the defaults are valid
  o.albedo = 1.5;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "ProbeExtractOptions::albedo = 1.5: expected a value in (0, 1]");
  o.albedo = 0.18;
  o.camera_ypr_deg = {400.0, 0.0, 0.0};
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "ProbeExtractOptions::camera_ypr_deg: expected degrees in [-360, 360]");

  testing::ScratchDir dir("probe-extract-flags");
  const Result albedo = Skycal("probe-extract --image " + dir / "ball.exr" + " --albedo 1.5 --out " + dir / "s.json");
  EXPECT_EQ(albedo.rc, 1);
  EXPECT_NE(albedo.err.find("--albedo 1.5: expected a value in (0, 1]"), std::string::npos) << albedo.err;
  const Result image = Skycal("probe-extract --out " + dir / "s.json");
  EXPECT_EQ(image.rc, 1);
  EXPECT_NE(image.err.find("--image IMG.exr is required"), std::string::npos) << image.err;
  EXPECT_EQ(dir.CountEntries(), 0);
}

TEST(ProbeExtract, SamplesAGivenBallAndRefusesBadInput) {
  testing::ScratchDir dir("probe-extract");
  const capture::BallCircle c{100.0, 75.0, 40.0};
  const auto rot = capture::RotationFromYawPitchRollDeg(30.0, 10.0, 0.0);
  const std::array<double, 3> s = latlong::DirectionFromElevationAzimuthDeg(40.0, 200.0);
  WriteBallImage(dir / "ball.exr", c, rot, s);

  const Result ok = Skycal("probe-extract --image " + dir / "ball.exr" +
                           " --circle 100,75,40 --camera-rotation 30,10,0 --albedo 0.2 --out " + dir / "s.json");
  ASSERT_EQ(ok.rc, 0) << ok.err;
  const auto doc = ReadJsonFile(dir / "s.json");
  EXPECT_EQ(doc["format"], "skycal-probe-samples");
  EXPECT_EQ(doc["format_version"], 1);
  EXPECT_EQ(doc["sha256"].get<std::string>().size(), 64u);
  EXPECT_DOUBLE_EQ(doc["albedo"].get<double>(), 0.2);
  ASSERT_GT(doc["samples"].size(), 20u);
  double worst = 0.0;
  for (const auto& smp : doc["samples"]) {
    const auto n = smp["normal"].get<std::array<double, 3>>();
    const double cs = std::max(0.0, n[0] * s[0] + n[1] * s[1] + n[2] * s[2]);
    for (int ch = 0; ch < 3; ++ch) {
      const double expect = 1.0 + 0.1 * ch + 8.0 * cs;
      worst = std::max(worst, std::abs(smp["radiance"][ch].get<double>() / expect - 1.0));
    }
  }
  std::cout << "[probe-extract] " << doc["samples"].size() << " samples, worst rel vs the normal's radiance " << worst
            << "\n";
  EXPECT_LT(worst, 0.15);  // measured 0.097 (at the terminator kink of max(0, n.s)): a bin averages radiance over its normals, the normal is their mean

  // Ball outside the image.
  const Result out = Skycal("probe-extract --image " + dir / "ball.exr" + " --circle 190,75,40 --out " + dir / "o.json");
  EXPECT_EQ(out.rc, 1);
  EXPECT_FALSE(std::filesystem::exists(dir / "o.json"));
  // Fully clipped: every ball pixel >= 1.
  const Result clipped =
      Skycal("probe-extract --image " + dir / "ball.exr" + " --circle 100,75,40 --clip-level 0.9 --out " + dir / "c.json");
  EXPECT_EQ(clipped.rc, 1);
  EXPECT_FALSE(std::filesystem::exists(dir / "c.json"));
  // No ball to find in a flat image.
  ImageRGB flat;
  flat.width = 64;
  flat.height = 48;
  flat.pixels.assign(64 * 48 * 3, 1.0f);
  WriteExrRGB(dir / "flat.exr", flat, {});
  const Result none = Skycal("probe-extract --image " + dir / "flat.exr" + " --out " + dir / "n.json");
  EXPECT_EQ(none.rc, 1);
  EXPECT_FALSE(std::filesystem::exists(dir / "n.json"));
  // Only the inputs and the one good output are there.
  EXPECT_EQ(dir.CountEntries(), 3);
}

}  // namespace
}  // namespace skycal
