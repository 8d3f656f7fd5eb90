// `skycal fit --clouds stats` (controllers/fit_cloud_stats.h; flags: cli/fit_verb.h): the command
// line, bad input, and the wiring at a small size — a synthetic "photo" (the default cloudy
// preset's clouds over its sky, 64x32) through the coverage match, the statistics fit and the
// panels. The recovery itself is measured in bench/results/cloud_stats_seed_pairs_ensemble.md,
// the real skies in bench/results/cloud_photos.md.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "fit_verb.h"
#include "skycal/bench/cloud_stats_scene.h"
#include "skycal/cloudfit/cloud_sun_scale.h"
#include "skycal/cloudfit/lighting_basis_renderer.h"
#include "skycal/cloudfit/photo_sun.h"
#include "skycal/core/error.h"
#include "skycal/core/latlong.h"
#include "skycal/render/preset.h"

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
  EXPECT_EQ(c.cloud_stats.sun_scale, "fit");
  EXPECT_EQ(Parse({"--reference", "a.exr", "--clouds", "stats", "--cloud-stats-sun-scale", "off", "--out", "d"}).cloud_stats.sun_scale,
            "off");
  o = FitCloudStatsOptions{};
  o.sun_scale = "free";
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("--cloud-stats-sun-scale 'free'"), std::string::npos) << why;
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
    cloudfit::CloudStatsOptions so;
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
  cloudfit::CloudStatsPresetUpdate update;
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
  // The albedo held at water's physical value, the sun's scale fitted in its place with the
  // ambient: bounds [0.1 (the synthetic disc is no lower bound), the sky fit's sun / the
  // measured one].
  EXPECT_EQ(j["parameters"]["scattering_albedo"]["held"], true);
  EXPECT_DOUBLE_EQ(j["parameters"]["scattering_albedo"]["value"].get<double>(), cloudfit::kPhysicalCloudAlbedo);
  EXPECT_EQ(j["parameters"]["ambient_strength"]["held"], false);
  const auto& ss = j["sun_scale"];
  EXPECT_GE(ss["scale"].get<double>(), ss["lower_bound"].get<double>());
  EXPECT_LE(ss["scale"].get<double>(), ss["upper_bound"].get<double>());
  EXPECT_NEAR(ss["fitted_lux"].get<double>(), ss["measured_lux"].get<double>() * ss["scale"].get<double>(), 1e-6 * ss["fitted_lux"].get<double>());
  EXPECT_GE(ss["evaluations"].get<int>(), 5);  // the grid at least
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
  // A frame narrower than the statistics' width: named, nothing run (a wider one of any size
  // is averaged down to it).
  o.width = 128;
  try {
    RunCloudStatsOnPhotos(o, {{&p.ref, p.probability}}, p.sky, dir);
    ADD_FAILURE() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("synthetic.exr"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("--cloud-stats-width 128"), std::string::npos) << e.what();
  }
}

// The sky refit on the refined mask (RefineCloudMaskAndRefitSky): against a "sky fit" that is
// the photo itself no pixel is cloud, so every cloud pixel of the first mask is released to the
// sky fit and the atmosphere refitted once; controls: a sky fit missing its clear pixels by 60%,
// a user --mask and --cloud-stats-probability initial release nothing and do not refit.
TEST(FitCloudStats, RefinedMaskReleasesPixelsAndRefitsTheSky) {
  // A 64x32 blue sky gradient (no march needed), a band the first mask called cloud.
  struct {
    fit::Reference ref;
    fit::FitResult sky;
    std::vector<float> probability;
  } p;
  p.ref.path = p.ref.name = "gradient";
  p.ref.radiance = ImageRGB(64, 32);
  p.ref.sun_dir = {0.0, std::sin(30.0 * M_PI / 180.0), std::cos(30.0 * M_PI / 180.0)};
  p.ref.pixel_class.assign(64 * 32, fit::PixelClass::kSky);
  p.probability.assign(64 * 32, 0.0f);
  long long cloud = 0;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 64; ++x) {
      const size_t i = static_cast<size_t>(y) * 64 + x;
      const float b = static_cast<float>(0.05 + 0.01 * y);
      p.ref.radiance.at(x, y, 0) = 0.3f * b;
      p.ref.radiance.at(x, y, 1) = 0.6f * b;
      p.ref.radiance.at(x, y, 2) = b;
      if (latlong::Latitude(y, 32) <= 0.0) {
        p.ref.pixel_class[i] = fit::PixelClass::kBelowHorizon;
      } else if (y >= 8 && y < 12) {
        p.ref.pixel_class[i] = fit::PixelClass::kUserMasked;
        p.probability[i] = 0.8f;
        ++cloud;
      }
    }
  p.ref.counts.user_masked = cloud;
  fit::ReferenceFit rf;
  rf.rendered = p.ref.radiance;  // the sky fit matches the photo: against it nothing is cloud
  p.sky.references.push_back(rf);
  auto run = [&](FitCloudStatsOptions o, bool user_mask, double rel, int* refits, fit::Reference* ref,
                 std::vector<float>* prob) {
    *ref = p.ref;
    *prob = p.probability;
    std::vector<fit::Reference> refs = {*ref};
    std::vector<std::vector<float>> probs = {*prob};
    fit::FitResult sky = p.sky;
    sky.references[0].errors.rel_rmse = rel;
    const nlohmann::json j = RefineCloudMaskAndRefitSky(o, user_mask, &refs, &probs, sky, [&] { ++*refits; });
    *ref = refs[0];
    *prob = probs[0];
    return j;
  };
  int refits = 0;
  fit::Reference ref;
  std::vector<float> prob;
  nlohmann::json j = run({}, false, 0.1, &refits, &ref, &prob);
  EXPECT_EQ(refits, 1);
  EXPECT_EQ(j["refitted"], true);
  EXPECT_EQ(j["references"][0]["released_pixels"].get<long long>(), cloud);
  EXPECT_EQ(ref.counts.user_masked, 0);
  EXPECT_EQ(std::count(ref.pixel_class.begin(), ref.pixel_class.end(), fit::PixelClass::kUserMasked), 0);
  EXPECT_LT(*std::max_element(prob.begin(), prob.end()), 0.5f);
  // Controls.
  refits = 0;
  j = run({}, false, 0.6, &refits, &ref, &prob);
  EXPECT_EQ(refits, 0);
  EXPECT_EQ(j["references"][0]["released_pixels"].get<long long>(), 0);
  EXPECT_EQ(ref.counts.user_masked, cloud);
  j = run({}, true, 0.1, &refits, &ref, &prob);
  EXPECT_EQ(refits, 0);
  FitCloudStatsOptions initial;
  initial.probability = "initial";
  j = run(initial, false, 0.1, &refits, &ref, &prob);
  EXPECT_EQ(refits, 0);
  EXPECT_EQ(j["refitted"], false);
}

// The photo's sun (skycal/cloudfit/photo_sun.h): a disc of known illuminance spread over a few pixels
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
  const cloudfit::PhotoSun s = cloudfit::MeasurePhotoSun(img, sun);
  // The ring's median is the sky at the ring's mean row; the gradient across the 3-deg disc
  // is symmetric to first order: 1% covers what is left.
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(s.illuminance[c], e_true[c], 0.01 * e_true[c]) << c;
  EXPECT_FALSE(s.clipped());
  // Control: the same disc measured 10 deg away finds no sun.
  const std::array<double, 3> off = {0.0, std::sin(50.0 * M_PI / 180.0), std::cos(50.0 * M_PI / 180.0)};
  EXPECT_LT(std::abs(cloudfit::MeasurePhotoSun(img, off).illuminance[1]), 0.01 * e_true[1]);
  // A clipped disc: a plateau of equal values.
  for (int j = -2; j <= 2; ++j)
    for (int i = -2; i <= 2; ++i)
      for (int c = 0; c < 3; ++c) img.at(x0 + i, y0 + j, c) = 65504.0f;
  EXPECT_TRUE(cloudfit::MeasurePhotoSun(img, sun).clipped());
}

// Saturation by energy (PhotoSun::saturated): on a uniform sky of radiance L the diffuse
// horizontal light is pi L (less the 3-deg disc's cap, ~0.2%), the disc's direct light E sin(40 deg).
TEST(FitCloudStats, PhotoSunSaturatedWhenTooWeakForItsSky) {
  const int w = 512, h = 256;
  const std::array<double, 3> sun = {0.0, std::sin(40.0 * M_PI / 180.0), std::cos(40.0 * M_PI / 180.0)};
  const auto p = latlong::PixelPosition(sun, w, h);
  const int x0 = static_cast<int>(std::floor(p[0])), y0 = static_cast<int>(std::floor(p[1]));
  auto sky_with_disc = [&](double sky, double e) {
    ImageRGB img(w, h);
    for (float& v : img.pixels) v = static_cast<float>(sky);
    for (int c = 0; c < 3; ++c) img.at(x0, y0, c) += static_cast<float>(e / latlong::PixelSolidAngle(x0, y0, w, h));
    return cloudfit::MeasurePhotoSun(img, sun);
  };
  const double direct = 4000.0 * std::sin(40.0 * M_PI / 180.0);
  const cloudfit::PhotoSun bright = sky_with_disc(1000.0, 4000.0);
  EXPECT_NEAR(bright.direct_to_diffuse(), direct / (M_PI * 1000.0), 0.01 * direct / (M_PI * 1000.0));
  EXPECT_TRUE(bright.clean_disc());
  EXPECT_FALSE(bright.saturated());  // 0.82 >= 0.5
  EXPECT_FALSE(bright.clipped());    // one pixel: no plateau
  const cloudfit::PhotoSun weak = sky_with_disc(3000.0, 4000.0);  // 0.27 < 0.5: the disc cannot be the sun
  EXPECT_NEAR(weak.direct_to_diffuse(), direct / (M_PI * 3000.0), 0.01 * direct / (M_PI * 3000.0));
  EXPECT_TRUE(weak.clean_disc());
  EXPECT_TRUE(weak.saturated());
  // Control: a veiled sun (the disc under 100x its sky, seen through cloud) is weak for its
  // sky by nature: not called saturated.
  const cloudfit::PhotoSun veiled = sky_with_disc(3000.0, 10.0);
  EXPECT_FALSE(veiled.clean_disc());
  EXPECT_FALSE(veiled.saturated());
}

// The sun scale's search (skycal/cloudfit/cloud_sun_scale.h): a smooth profile's minimum, one with a kink
// (as where the ambient reaches its bound), and a minimum at a bound.
TEST(FitCloudStats, SunScaleSearchFindsTheProfileMinimum) {
  cloudfit::SunScaleSearchOptions o;
  o.lower = 0.1;
  o.upper = 100.0;
  const double truth = std::log(3.7);
  auto smooth = [&](double s) { const double d = std::log(s) - truth; return 1.0 + d * d + 0.3 * d * d * d * d; };
  cloudfit::SunScaleSearch r = cloudfit::MinimizeOverSunScale(smooth, o);
  EXPECT_NEAR(std::log(r.scale), truth, 0.03);
  EXPECT_LE(r.scales.size(), 12u);
  EXPECT_FALSE(r.at_lower || r.at_upper);
  EXPECT_EQ(r.scales.size(), r.costs.size());
  // A kink: steeper on one side (ambient at its bound beyond the minimum).
  auto kink = [&](double s) { const double d = std::log(s) - truth; return d < 0.0 ? -0.5 * d : 3.0 * d; };
  r = cloudfit::MinimizeOverSunScale(kink, o);
  EXPECT_NEAR(std::log(r.scale), truth, 0.1);
  // Falling over the whole range: the lower bound is the answer, and said so.
  r = cloudfit::MinimizeOverSunScale([](double s) { return s; }, o);
  EXPECT_DOUBLE_EQ(r.scale, 0.1);
  EXPECT_TRUE(r.at_lower);
  // Control: the answer follows the cost's minimum when it moves (0.5 instead of 3.7).
  auto moved = [&](double s) { const double d = std::log(s) - std::log(0.5); return d * d; };
  EXPECT_NEAR(std::log(cloudfit::MinimizeOverSunScale(moved, o).scale), std::log(0.5), 0.03);
  o.lower = 2.0;
  o.upper = 1.0;
  EXPECT_THROW(cloudfit::MinimizeOverSunScale(smooth, o), Error);
}

// The lighting basis (skycal/cloudfit/lighting_basis_renderer.h): albedo and ambient from three cached
// marches equal a march at those values; anything else marches anew.
TEST(FitCloudStats, LightingBasisEqualsAMarch) {
  SyntheticPhoto p;
  clouds::CloudRenderer& raw = *p.renderer;
  cloudfit::LightingBasisCloudRenderer basis(raw, 4);
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
  // The sun's scale: one more march (half the sun) splits D; 1.5 x the sun equals a march
  // of the preset with 1.5 x its sun_illuminance_lux (192 klux: within the preset's bound).
  basis.set_sun_scale(0.4);
  const clouds::CloudImage sun_synth = basis.Render(scene, req);
  EXPECT_EQ(basis.marches(), 6);  // the same three at half the sun
  render::Preset brighter = p.scene.preset;
  brighter.sun_illuminance_lux *= 0.4;
  clouds::CloudScene bright_scene = scene;
  bright_scene.preset = &brighter;
  const clouds::CloudImage sun_marched = raw.Render(bright_scene, req);
  EXPECT_LT(max_rel(sun_synth, sun_marched), 1e-4);
  EXPECT_GT(max_rel(marched, sun_marched), 1e-2);  // control: the sun's scale shows
  EXPECT_THROW(basis.set_sun_scale(0.0), Error);
  basis.set_sun_scale(1.0);
  // A non-linear field (the extinction) marches a new basis.
  c.extinction_per_m *= 1.1;
  basis.Render(scene, req);
  EXPECT_EQ(basis.marches(), 9);
  // The coverage match marches without light samples: the transmittance does not use them.
  clouds::CloudRenderRequest dark = req;
  dark.march.light_samples = 0;
  EXPECT_EQ(raw.Render(scene, dark).transmittance, raw.Render(scene, req).transmittance);
}

}  // namespace
}  // namespace skycal::cli
