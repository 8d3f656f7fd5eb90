// `skycal fit --clouds stats`: the cloud lighting of photographs, whose cloud shapes no noise
// reproduces (issue 11, regime 3). The clear pixels fit the atmosphere (--cloud-mask is
// implied: cloud probability >= 0.5 leaves the sky fit); then the cloud pixels fit the
// lighting by statistics (skycal/cloudfit/cloud_stats.h) against renders lit by the
// fitted atmosphere's own sun and ambient (shared: the cloud render takes both from the
// fitted preset). Before the lighting, the weather map's mean coverage is matched so the
// model's mean cloud opacity equals the photo's mean cloud probability over the sky.
// Writes fit.json's `cloud_stats` object and fit/<ref>.clouds.{reference,fit,error}.png.
#pragma once
#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "skycal/clouds/cloud_params.h"
#include "skycal/clouds/cloud_textures.h"
#include "skycal/fit/reference.h"
#include "skycal/fit/sky_fit.h"
#include "skycal/render/preset.h"

namespace skycal::cli {

struct FitCloudStatsOptions {
  bool enabled = false;      // --clouds stats
  int width = 128;           // --cloud-stats-width: pixels across the statistics' lat-long (height width / 2)
  int maps = 4;              // --cloud-stats-maps: weather maps (independent shape draws) the model pools
  int renders = 8;           // renders per evaluation (map m % maps, wind 1800 s apart)
  int max_iterations = 12;   // --cloud-stats-iterations
  uint64_t weather_seed = 1; // seeds of the model's weather maps: seed, seed + 1, ...
  // --cloud-stats-sun: the sun that lights the model's clouds. "photo": the photo's own disc
  // (skycal/cloudfit/photo_sun.h, in model units: divided by the sky fit's exposure) replaces the
  // fitted preset's sun illuminance and tint for the cloud renders; "model": the preset's.
  // Why: a sky fit without the disc does not pin the sun apart from the exposure (the gauge
  // keeps the initial preset's sun-to-sky ratio): on `sky` the photo's sun is 0.036 of the
  // model's, and with the model's the fit greyed the clouds (albedo 0.09, ambient at its bound).
  std::string sun = "photo";
  // --cloud-stats-probability: the clear-sky expectation of the cloud probability.
  // "fitted": recomputed against the sky fit's own render (which carries the glow around a
  // low sun the clear pixels near it pin: on `dawn` the bundled preset's expectation took
  // the glow over the ridge for cloud), a pixel cloud when both expectations say so (the
  // minimum) when the sky fit matches its clear pixels within 50% rel RMSE (not an overcast
  // frame's); "initial": --cloud-mask's probability (the bundled preset's clear sky) as is.
  std::string probability = "fitted";
  // --cloud-stats-sun-scale: "fit": the albedo held at water droplets' physical value
  // (kPhysicalCloudAlbedo) and a scale s on the sun above fitted with the ambient (in this
  // objective the albedo and a sun scale are one degree of freedom: L = C + a s D + a k A);
  // s >= 1 when the photo's disc is a lower bound (PhotoSun::saturated), else >= 0.1; s <= the
  // sky fit's own sun over the measured one (the clouds get no more than the sun a clear
  // atmosphere of that brightness has). "off": s = 1 and the albedo fitted (the behaviour
  // before; it sat at its bound 1 on `sky` and `city`).
  std::string sun_scale = "fit";
  // What a photograph's statistics can fit: the brightness of cloud against the clear sky
  // (scattering_albedo: the exposure is fixed by the clear pixels, so it is no longer traded
  // against it) and the ambient. Held at the bundled default_cloudy's values: the phase lobe
  // g1 and powder (with unknown shapes they land 86% / 100% off, median over 5 seed pairs,
  // even with the model pooled over 4 weather maps: bench/results/cloud_stats_seed_pairs_ensemble.md)
  // and extinction (the coverage match sets the opacity with it; fitted on dawn it ran to 0:
  // clouds that vanish leave their bins empty, and an empty bin adds no residual).
  // With sun_scale "fit" the albedo leaves this list (held physical).
  std::vector<std::string> fitted = {"scattering_albedo", "ambient_strength"};
  bool IsValid(std::string* why) const;
};

// Single-scattering albedo of cloud water droplets in the visible: absorption by liquid water
// at 0.4-0.7 um is so weak (imaginary refractive index ~1e-9) that droplets of ~10 um scatter
// all but ~1e-5 of what they extinguish (Hansen & Travis 1974, "Light scattering in planetary
// atmospheres"; Bohren & Huffman, "Absorption and Scattering of Light by Small Particles").
constexpr double kPhysicalCloudAlbedo = 0.9999;

// The sky-pixel classes of the automatic segmentation and cloud probability, per reference
// at its full size: probability as ApplyCloudMask used it.
struct CloudStatsPhoto {
  const fit::Reference* ref = nullptr;  // after --cloud-mask (cloud pixels user-masked)
  std::vector<float> cloud_probability;
  // Already refined against the first sky fit (RefineCloudMaskAndRefitSky): used as is. Not
  // refined again against a refitted sky: that fit took the released pixels, and against it
  // `dawn` lost 62% of its pink wisps at 45-90 deg from the sun (1814 -> 689 pixels).
  bool refined = false;
};

// What the statistics fit hands the fitted preset so that it renders what was fitted: the
// cloud lighting with a weather map at the matched coverage (the first of the model's
// ensemble: the photo's shapes are unknown, its cover and lighting are not), and the sun
// that lit the model's clouds (the photo's, with --cloud-stats-sun photo: the sky itself
// does not depend on the sun's illuminance, only the disc, the ground and the clouds do).
struct CloudStatsPresetUpdate {
  clouds::CloudParams params;
  clouds::WeatherMap weather;
  double sun_illuminance_lux = 0.0;
  std::array<double, 3> sun_tint_rgb{};
  // Whether the preset should take that sun: it was fitted (--cloud-stats-sun-scale fit),
  // or measured on a disc seen on every reference (its peak at least 100x the sky ring
  // around it; not on `dawn`, the sun behind the ridge: 8x, against 4,700x on `sky`).
  bool sun_measured = false;
  std::string sun_why;
};

// --cloud-stats-probability fitted, before the statistics: each reference whose sky fit
// matches its clear pixels within 50% gets the cloud probability against that fit's render
// too (the minimum of the two), and pixels the first mask took as cloud that are now clear
// return to the sky fit (pixel class kSky). When that releases more than
// kSkyRefitReleasedFraction of a reference's sky pixels, `refit()` runs the sky fit once more
// (the caller starts it from the first fit's preset). `probability` is updated in place.
// Returns fit.json's `cloud_stats.sky_refit`. Does nothing with a user --mask (`user_mask`):
// its pixels are user-masked too and cannot be told apart.
constexpr double kSkyRefitReleasedFraction = 0.01;
nlohmann::json RefineCloudMaskAndRefitSky(const FitCloudStatsOptions& o, bool user_mask, std::vector<fit::Reference>* refs,
                                          std::vector<std::vector<float>>* probability, const fit::FitResult& sky,
                                          const std::function<void()>& refit);

// Runs the statistics fit over `photos` (one lighting for all of them) with the sky fit's
// preset and exposures; writes the panels into `fit_dir`; returns fit.json's `cloud_stats`
// and, when `update` is given, what the fitted preset takes from it.
// Throws skycal::Error naming the reference when its size is not a multiple of the
// statistics' size or it has no cloud to fit.
nlohmann::json RunCloudStatsOnPhotos(const FitCloudStatsOptions& o, const std::vector<CloudStatsPhoto>& photos,
                                     const fit::FitResult& sky, const std::filesystem::path& fit_dir,
                                     CloudStatsPresetUpdate* update = nullptr);

// Writes the statistics fit into the fitted preset: its `clouds` section (the fitted lighting,
// weather_map naming <stem>.weather.exr written beside preset.json) and the sun that lit the
// clouds (illuminance and tint). Returns fit.json's `cloud_stats.preset` record: what changed,
// from what to what, and why.
nlohmann::json AttachCloudStats(const CloudStatsPresetUpdate& update, const std::filesystem::path& preset_json,
                                render::Preset* preset);

}  // namespace skycal::cli
