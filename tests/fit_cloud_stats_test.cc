// `skycal fit --clouds stats` (cli/fit_cloud_stats.h): the command line, bad input, and the
// wiring at a small size — a synthetic "photo" (the default cloudy preset's clouds over its
// sky, 64x32) through the coverage match, the statistics fit and the panels. The recovery
// itself is measured in bench/results/cloud_stats_seed_pairs_ensemble.md, the real skies in
// bench/results/cloud_photos.md.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "fit_cloud_stats.h"
#include "fit_verb.h"
#include "lighting_basis_renderer.h"
#include "photo_sun.h"
#include "skycal/bench/cloud_stats_scene.h"
#include "skycal/core/error.h"
#include "skycal/core/latlong.h"

namespace skycal::cli {
namespace {

namespace fs = std::filesystem;

FitCommandLine Parse(std::vector<std::string> words) {
  std::vector<char*> argv;
  for (auto& w : words) argv.push_back(w.data());
  return ParseFitArgs(static_cast<int>(argv.size()), argv.data());
}

std::string ErrorOf(std::vector<std::string> words) {
  try {
    Parse(std::move(words));
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(FitCloudStats, CommandLine) {
  const FitCommandLine c = Parse({"--reference", "a.exr", "--clouds", "stats", "--cloud-stats-maps", "3", "--out", "d"});
  EXPECT_TRUE(c.cloud_stats.enabled);
  EXPECT_TRUE(c.options.cloud_mask);   // the clear pixels fit the atmosphere
  EXPECT_EQ(c.clouds.mode, "off");     // no known-shapes term
  EXPECT_EQ(c.cloud_stats.maps, 3);
  EXPECT_EQ(c.cloud_stats.renders, 6);  // two wind times per map
  // Control: without --clouds stats nothing of it is on.
  EXPECT_FALSE(Parse({"--reference", "a.exr", "--out", "d"}).cloud_stats.enabled);
  EXPECT_NE(ErrorOf({"--reference", "a.exr", "--clouds", "stats", "--cloud-preset", "p.json", "--out", "d"}).find("--cloud-preset"),
            std::string::npos);
  EXPECT_NE(ErrorOf({"--reference", "a.exr", "--clouds", "stats", "--cloud-stats-width", "8", "--out", "d"})
                .find("--cloud-stats-width"),
            std::string::npos);
  std::string why;
  FitCloudStatsOptions o;
  EXPECT_TRUE(o.IsValid(&why)) << why;
  o.width = 65;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("--cloud-stats-width 65"), std::string::npos) << why;
  EXPECT_EQ(c.cloud_stats.sun, "photo");
  EXPECT_EQ(c.cloud_stats.probability, "fitted");
  const FitCommandLine c2 = Parse({"--reference", "a.exr", "--clouds", "stats", "--cloud-stats-sun", "model",
                                   "--cloud-stats-probability", "initial", "--out", "d"});
  EXPECT_EQ(c2.cloud_stats.sun, "model");
  EXPECT_EQ(c2.cloud_stats.probability, "initial");
  o = FitCloudStatsOptions{};
  o.sun = "disc";
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("--cloud-stats-sun 'disc'"), std::string::npos) << why;
  o = FitCloudStatsOptions{};
  o.probability = "preset";
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("--cloud-stats-probability 'preset'"), std::string::npos) << why;
}

struct SyntheticPhoto {
  std::unique_ptr<clouds::CloudRenderer> renderer;
  bench::CloudStatsSyntheticScene scene;
  fit::Reference ref;
  fit::FitResult sky;
  std::vector<float> probability;
  SyntheticPhoto() {
    try {
      renderer = clouds::CreateVulkanCloudRenderer(false);
    } catch (const Error&) {
      renderer = clouds::CreateCpuCloudRenderer(clouds::CloudPrecision::kFloat, 2);
    }
    fit::CloudStatsOptions so;
    so.render_width = 64;
    so.render_height = 32;
    const std::string cache = (fs::temp_directory_path() / "skycal-cloud-stats-cache").string();
    scene = bench::MakeCloudStatsScene(SKYCAL_SOURCE_DIR, {1, 11}, {101, 211}, 25.0, 30.0, so, *renderer, cache);
    const auto& r = scene.reference;
    ref.path = "synthetic.exr";
    ref.name = "synthetic";
    ref.radiance = r.radiance;
    ref.sun_dir = r.sun_dir;
    probability = r.opacity;
    ref.pixel_class.assign(r.opacity.size(), fit::PixelClass::kSky);
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 64; ++x) {
        const size_t i = static_cast<size_t>(y) * 64 + x;
        if (latlong::Latitude(y, 32) <= 0.0) ref.pixel_class[i] = fit::PixelClass::kBelowHorizon;
        else if (probability[i] >= 0.5f) ref.pixel_class[i] = fit::PixelClass::kUserMasked;  // as --cloud-mask
      }
    sky.preset = scene.preset;
    fit::ReferenceFit rf;
    rf.exposure = 1.0;
    rf.rendered = r.radiance;  // the "atmosphere's fit": the photo itself (a control of the error bookkeeping)
    sky.references.push_back(rf);
  }
};

TEST(FitCloudStats, WiringAtASmallSize) {
  SyntheticPhoto p;
  const fs::path dir = fs::temp_directory_path() / ("skycal-fit-cloud-stats-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  FitCloudStatsOptions o;
  o.width = 32;  // the 64x32 frame box-averaged by 2
  o.maps = 1;
  o.renders = 1;
  o.max_iterations = 0;  // the wiring, not the recovery (benchmarked)
  // The "sky fit's render" here is the photo itself: against it nothing would be cloud. Told
  // that fit missed its clear pixels by 60%, the default `fitted` expectation is not used.
  p.sky.references[0].errors.rel_rmse = 0.6;
  CloudStatsPresetUpdate update;
  const nlohmann::json j = RunCloudStatsOnPhotos(o, {{&p.ref, p.probability}}, p.sky, dir, &update);
  EXPECT_EQ(j["references"][0]["cloud_probability"]["refined"], false);
  // The fitted preset takes the fit: its clouds section carries the lighting fit.json reports
  // and names a weather map written beside it; its sun is the one that lit the clouds only
  // when the photo's disc was seen.
  render::Preset preset = p.sky.preset;
  const nlohmann::json rec = AttachCloudStats(update, dir / "fitted.json", &preset);
  const nlohmann::json section = nlohmann::json::parse(preset.clouds_json);
  EXPECT_DOUBLE_EQ(section["scattering_albedo"]["value"].get<double>(), j["parameters"]["scattering_albedo"]["value"].get<double>());
  EXPECT_DOUBLE_EQ(section["ambient_strength"]["value"].get<double>(), j["parameters"]["ambient_strength"]["value"].get<double>());
  EXPECT_EQ(rec["weather_map"], "fitted.weather.exr");
  EXPECT_TRUE(fs::exists(dir / "fitted.weather.exr"));
  EXPECT_EQ(update.weather.width, 256);
  EXPECT_EQ(rec["sun_written"], update.sun_measured ? "clouds_lit_by" : "sky_fit");
  EXPECT_DOUBLE_EQ(preset.sun_illuminance_lux, update.sun_measured ? update.sun_illuminance_lux : p.sky.preset.sun_illuminance_lux);
  // Control: a disc the fit saw is written.
  update.sun_measured = true;
  update.sun_illuminance_lux = 1234.0;
  AttachCloudStats(update, dir / "fitted.json", &preset);
  EXPECT_DOUBLE_EQ(preset.sun_illuminance_lux, 1234.0);
  // Coverage first: regula falsi ends with the model's mean opacity within 0.005 of the photo's or
  // after 8 steps (at 32x16 the opacity is a coarse function of the coverage: 0.05 allowed).
  const double target = j["coverage"]["photo_mean_cloud_probability"], got = j["coverage"]["model_mean_opacity"];
  EXPECT_GT(target, 0.05);
  EXPECT_NEAR(got, target, 0.05);
  EXPECT_EQ(j["parameters"]["phase_g1"]["held"], true);
  EXPECT_EQ(j["parameters"]["extinction"]["held"], true);
  EXPECT_EQ(j["parameters"]["scattering_albedo"]["held"], false);
  EXPECT_EQ(j["render_size"][0], 32);
  const auto& r = j["references"][0];
  // The "atmosphere-only" image is the photo itself: zero error everywhere; the statistics'
  // image replaces each cloud pixel by its bin's median, which no bin reproduces exactly (the
  // same bookkeeping, shown to see a difference).
  EXPECT_LT(r["errors"]["atmosphere_only"]["whole_sky"]["rel_rmse"].get<double>(), 1e-6);
  EXPECT_GT(r["errors"]["atmosphere_only"]["whole_sky"]["pixels"].get<long long>(), 100);
  EXPECT_GT(r["errors"]["with_cloud_statistics"]["cloud"]["rel_rmse"].get<double>(), 0.01);
  EXPECT_GT(r["bins"].size(), 0u);
  for (const char* k : {"reference", "fit", "error"}) EXPECT_TRUE(fs::exists(dir / ("synthetic.clouds." + std::string(k) + ".png"))) << k;
  fs::remove_all(dir);
  // Control: with the sky fit within 50% the photo-as-expectation leaves no cloud to fit.
  p.sky.references[0].errors.rel_rmse = 0.1;
  try {
    RunCloudStatsOnPhotos(o, {{&p.ref, p.probability}}, p.sky, dir);
    ADD_FAILURE() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("synthetic.exr: --clouds stats: no cloud pixels"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
  // A frame whose width is not a multiple of the statistics' width: named, nothing run.
  o.width = 48;
  try {
    RunCloudStatsOnPhotos(o, {{&p.ref, p.probability}}, p.sky, dir);
    ADD_FAILURE() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("synthetic.exr"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("--cloud-stats-width 48"), std::string::npos) << e.what();
  }
}

// The photo's sun (cli/photo_sun.h): a disc of known illuminance spread over a few pixels
// of a 512x256 lat-long on a sky gradient is recovered; its ring's median is subtracted.
TEST(FitCloudStats, PhotoSunRecoversADiscOnASky) {
  const int w = 512, h = 256;
  ImageRGB img(w, h);
  const std::array<double, 3> sun = {0.0, std::sin(40.0 * M_PI / 180.0), std::cos(40.0 * M_PI / 180.0)};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) img.at(x, y, c) = static_cast<float>(1000.0 + 5.0 * y);  // a smooth sky
  // The disc: 2x2 pixels at the sun (E = radiance x solid angle, lux in image units).
  const auto p = latlong::PixelPosition(sun, w, h);
  const double e_true[3] = {5000.0, 4000.0, 3000.0};
  const int x0 = static_cast<int>(std::floor(p[0])), y0 = static_cast<int>(std::floor(p[1]));
  const double share[2][2] = {{0.4, 0.25}, {0.2, 0.15}};  // a disc straddling 4 pixels unequally
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 2; ++i)
      for (int c = 0; c < 3; ++c)
        img.at(x0 + i, y0 + j, c) +=
            static_cast<float>(share[j][i] * e_true[c] / latlong::PixelSolidAngle(x0 + i, y0 + j, w, h));
  const PhotoSun s = MeasurePhotoSun(img, sun);
  // The ring's median is the sky at the ring's mean row; the gradient across the 3-deg disc
  // is symmetric to first order: 1% covers what is left.
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(s.illuminance[c], e_true[c], 0.01 * e_true[c]) << c;
  EXPECT_FALSE(s.clipped());
  // Control: the same disc measured 10 deg away finds no sun.
  const std::array<double, 3> off = {0.0, std::sin(50.0 * M_PI / 180.0), std::cos(50.0 * M_PI / 180.0)};
  EXPECT_LT(std::abs(MeasurePhotoSun(img, off).illuminance[1]), 0.01 * e_true[1]);
  // A clipped disc: a plateau of equal values.
  for (int j = -2; j <= 2; ++j)
    for (int i = -2; i <= 2; ++i)
      for (int c = 0; c < 3; ++c) img.at(x0 + i, y0 + j, c) = 65504.0f;
  EXPECT_TRUE(MeasurePhotoSun(img, sun).clipped());
}

// The lighting basis (cli/lighting_basis_renderer.h): albedo and ambient from three cached
// marches equal a march at those values; anything else marches anew.
TEST(FitCloudStats, LightingBasisEqualsAMarch) {
  SyntheticPhoto p;
  clouds::CloudRenderer& raw = *p.renderer;
  LightingBasisCloudRenderer basis(raw, 4);
  clouds::CloudParams c = p.scene.truth;
  clouds::CloudScene scene{&p.scene.preset, &c, &p.scene.noise, &p.scene.weather};
  clouds::CloudRenderRequest req;
  req.sun_dir = p.ref.sun_dir;
  req.width = 64;
  req.height = 32;
  auto max_rel = [](const clouds::CloudImage& a, const clouds::CloudImage& b) {
    double worst = 0.0, peak = 0.0;
    for (float v : b.radiance.pixels) peak = std::max(peak, static_cast<double>(std::abs(v)));
    for (size_t i = 0; i < a.radiance.pixels.size(); ++i)
      worst = std::max(worst, std::abs(static_cast<double>(a.radiance.pixels[i]) - b.radiance.pixels[i]) / peak);
    return worst;
  };
  basis.Render(scene, req);  // the basis: 3 marches
  EXPECT_EQ(basis.marches(), 3);
  c.scattering_albedo = 0.37;
  c.ambient_strength = 4.2;
  const clouds::CloudImage synth = basis.Render(scene, req), marched = raw.Render(scene, req);
  EXPECT_EQ(basis.marches(), 3);
  EXPECT_EQ(basis.synthesized(), 1);
  // Float renders: the sums C + a (D + k A) round differently from one march; 1e-4 of the
  // brightest pixel is ~100x the float rounding of the three images.
  EXPECT_LT(max_rel(synth, marched), 1e-4);
  EXPECT_EQ(synth.transmittance, marched.transmittance);
  // Control: a different lighting differs by far more than the tolerance.
  c.ambient_strength = 1.0;
  EXPECT_GT(max_rel(raw.Render(scene, req), marched), 1e-2);
  // A non-linear field (the extinction) marches a new basis.
  c.extinction_per_m *= 1.1;
  basis.Render(scene, req);
  EXPECT_EQ(basis.marches(), 6);
  // The coverage match marches without light samples: the transmittance does not use them.
  clouds::CloudRenderRequest dark = req;
  dark.march.light_samples = 0;
  EXPECT_EQ(raw.Render(scene, dark).transmittance, raw.Render(scene, req).transmittance);
}

}  // namespace
}  // namespace skycal::cli
