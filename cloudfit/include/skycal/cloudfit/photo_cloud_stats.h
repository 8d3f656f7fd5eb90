// The cloud lighting of photographs, whose cloud shapes no noise reproduces (docs/cloud-fitting.md,
// regime 3): the controller behind `skycal fit --clouds stats`. The clear pixels have fitted
// the atmosphere already (the caller's sky fit, cloud probability >= 0.5 left out); here the
// cloud pixels fit the lighting by statistics (cloud_stats.h) against renders lit by the
// fitted atmosphere's own sun and ambient (the cloud render takes both from the fitted
// preset). The stages, each with its own result below:
//   1. per photo: the sun's disc against the model's, the cloud probability (refined against
//      the sky fit's render), the pixel classes and the statistics' reference (PreparedPhoto);
//   2. the sun that lights the model's clouds (the photo's disc or the fitted preset's);
//   3. coverage: the weather maps' mean coverage matched by regula falsi until the model's
//      mean cloud opacity equals the photos' mean cloud probability (CoverageMatch);
//   4. the statistics fit, with the sun's scale profiled when the albedo is held at its
//      physical value (StatisticsFit, SunScaleProfile);
//   5. synthesis of the fit image: each cloud pixel by its bin's fitted median (FitImage);
//   6. what the fitted preset takes from it (CloudStatsPresetUpdate).
// Errors name the options field and its value (PhotoCloudStatsOptions::width = 48) and the
// reference's file; no file is written here.
#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "skycal/cloudfit/cloud_stats.h"
#include "skycal/clouds/cloud_params.h"
#include "skycal/clouds/cloud_textures.h"
#include "skycal/fit/reference.h"
#include "skycal/fit/sky_fit.h"
#include "skycal/render/preset.h"

namespace skycal::cloudfit {

// Single-scattering albedo of cloud water droplets in the visible: absorption by liquid water
// at 0.4-0.7 um is so weak (imaginary refractive index ~1e-9) that droplets of ~10 um scatter
// all but ~1e-5 of what they extinguish (Hansen & Travis 1974, "Light scattering in planetary
// atmospheres"; Bohren & Huffman, "Absorption and Scattering of Light by Small Particles").
constexpr double kPhysicalCloudAlbedo = 0.9999;

// The probability's `fitted` expectation applies when the sky fit's clear pixels are within
// this relative RMSE (`sky` 0.17 and `dawn` 0.38 are; the overcast `city`'s 5.4 is not, and
// against its sky fit the overcast lost 84% of its cloud pixels).
constexpr double kMaxSkyFitRelForProbability = 0.5;

// RefineCloudMaskAndRefitSky refits the sky when a reference loses more than this fraction
// of its sky pixels from the cloud mask.
constexpr double kSkyRefitReleasedFraction = 0.01;

struct PhotoCloudStatsOptions {
  int width = 128;            // pixels across the statistics' lat-long (height width / 2), even, [16, 1024]
  int maps = 4;               // weather maps (independent shape draws) the model pools, [1, 16]
  int renders = 8;            // renders per evaluation (map m % maps, wind 1800 s apart), [maps, 64]
  int max_iterations = 12;    // Ceres iterations of each statistics fit, [0, 200]
  uint64_t weather_seed = 1;  // seeds of the model's weather maps: seed, seed + 1, ...
  // The sun that lights the model's clouds. "photo": the photo's own disc (photo_sun.h, in
  // model units: divided by the sky fit's exposure) replaces the fitted preset's sun
  // illuminance and tint for the cloud renders; "model": the preset's. Why: a sky fit without
  // the disc does not pin the sun apart from the exposure (the gauge keeps the initial
  // preset's sun-to-sky ratio): on `sky` the photo's sun is 0.036 of the model's, and with the
  // model's the fit greyed the clouds (albedo 0.09, ambient at its bound).
  std::string sun = "photo";
  // The clear-sky expectation of the cloud probability. "fitted": recomputed against the sky
  // fit's own render (which carries the glow around a low sun the clear pixels near it pin:
  // on `dawn` the bundled preset's expectation took the glow over the ridge for cloud), a
  // pixel cloud when both expectations say so (the minimum) when the sky fit matches its
  // clear pixels within kMaxSkyFitRelForProbability (not an overcast frame's); "initial": the
  // caller's probability (the bundled preset's clear sky) as is.
  std::string probability = "fitted";
  // "fit": the albedo held at water droplets' physical value (kPhysicalCloudAlbedo) and a
  // scale s on the sun above fitted with the ambient (in this objective the albedo and a sun
  // scale are one degree of freedom: L = C + a s D + a k A); s >= 1 when the photo's disc is a
  // lower bound (PhotoSun::saturated), else >= 0.1; s <= the sky fit's own sun over the
  // measured one (the clouds get no more than the sun a clear atmosphere of that brightness
  // has). "off": s = 1 and the albedo fitted (it sat at its bound 1 on `sky` and `city`).
  std::string sun_scale = "fit";
  // What a photograph's statistics can fit: the brightness of cloud against the clear sky
  // (scattering_albedo: the exposure is fixed by the clear pixels, so it is no longer traded
  // against it) and the ambient. Held at the start's values: the phase lobe g1 and powder
  // (with unknown shapes they land 86% / 100% off, median over 5 seed pairs, even with the
  // model pooled over 4 weather maps: bench/results/cloud_stats_seed_pairs_ensemble.md) and
  // extinction (the coverage match sets the opacity with it; fitted on dawn it ran to 0:
  // clouds that vanish leave their bins empty, and an empty bin adds no residual). With
  // sun_scale "fit" the albedo leaves this list (held physical).
  std::vector<std::string> fitted = {"scattering_albedo", "ambient_strength"};
  // The start: the clouds section whose shape statistics and lighting the model starts from
  // (the bundled default_cloudy's), and the 3D noise texture's seed and cache (empty:
  // clouds::DefaultCloudNoiseCacheDir()).
  clouds::CloudParams initial;
  uint64_t noise_seed = 1;
  std::string noise_cache_dir;
  // Progress lines (null: silent).
  std::function<void(const std::string&)> log;
  // Names the field and its value on failure.
  bool IsValid(std::string* why) const;
};

// One photograph: after the sky fit's cloud mask (cloud pixels user-masked), with its cloud
// probability at its full size.
struct CloudStatsPhoto {
  const fit::Reference* ref = nullptr;
  std::vector<float> cloud_probability;
  // Already refined against the first sky fit (RefineCloudMaskAndRefitSky): used as is. Not
  // refined again against a refitted sky: that fit took the released pixels, and against it
  // `dawn` lost 62% of its pink wisps at 45-90 deg from the sun (1814 -> 689 pixels).
  bool refined = false;
};

// The photo's sun against the model's, in model units (the photo divided by the sky fit's
// exposure; photo_sun.h measures the disc): green channel [1] where one number is needed.
struct PhotoSunCheck {
  std::array<double, 3> photo_lux_model_units{}, model_lux{}, photo_over_model{};
  int disc_pixels = 0;
  double peak_over_background = 0.0;  // the disc's peak over its ring's median (green)
  bool clipped = false, clean_disc = false, saturated = false;
  double direct_to_diffuse = 0.0;
};

// Cloud pixels (probability >= 0.5, above the horizon) per bin of angle from the sun.
std::vector<long long> CloudPixelsBySunAngle(const std::vector<float>& probability, const fit::Reference& ref,
                                             const std::vector<double>& edges_deg);

// How the cloud probability the statistics use came about.
struct CloudProbabilityRecord {
  std::string expectation;  // PhotoCloudStatsOptions::probability
  std::vector<double> sun_angle_edges_deg;
  std::vector<long long> initial_cloud_pixels_by_sun_angle;
  double sky_fit_clear_rel_rmse = 0.0;
  bool refined = false;                // refined here or before (CloudStatsPhoto::refined)
  bool refined_before = false;         // against the first sky fit (RefineCloudMaskAndRefitSky)
  std::vector<long long> cloud_pixels_by_sun_angle;  // after refining here; empty otherwise
};

// Stage 1, per photo.
struct PreparedPhoto {
  CloudStatsReference stats_ref;  // at the statistics' size, model units
  fit::Reference whole;           // every sky pixel (clear and cloud) of the segmentation as kSky
  fit::Reference clear, cloud;    // the same restricted to probability < 0.5 / >= 0.5
  long long non_sky_segmented = 0;
  PhotoSunCheck sun_check;
  std::vector<float> probability;  // full size: the cloud probability the statistics use
  CloudProbabilityRecord probability_record;
  double mean_cloud_probability = 0.0;  // over stats_ref's sky above the lowest elevation bin
};

// Stage 3.
struct CoverageStep {
  double mean_coverage = 0.0, model_mean_opacity = 0.0;
};
struct CoverageMatch {
  double target = 0.0;    // the photos' mean cloud probability
  double coverage = 0.0;  // the weather maps' matched mean coverage
  double achieved = 0.0;  // the model's mean opacity at it
  double time_s = 0.0;
  std::vector<CoverageStep> steps;
  std::vector<clouds::WeatherMap> maps;  // the model's ensemble at that coverage
};

// Stage 4 with PhotoCloudStatsOptions::sun_scale "fit": the profile of the cost over s.
struct SunScaleProfile {
  double measured_lux = 0.0, scale = 1.0, fitted_lux = 0.0;
  std::vector<double> sky_fit_sun_lux_green;  // per reference: the sky fit's sun at the ground
  double lower = 0.0, upper = 0.0;
  bool at_lower = false, at_upper = false;
  bool saturated = false;  // every disc a lower bound: s >= 1
  std::vector<double> scales, costs;
  std::vector<double> iterations;  // of the statistics fit at each scale (fit.json has written them as numbers)
  double time_s = 0.0;
};

// Stage 4.
struct StatisticsFit {
  CloudStatsOptions options;  // the statistics' options as run (bins, quantiles)
  CloudStatsResult result;
  bool fit_sun = false;       // the sun's scale fitted (sun_scale below), the albedo held
  bool linear = false;        // only albedo and ambient: renders synthesized from cached marches
  long long marches = 0;      // renders of the cloud renderer itself
  std::string renderer;       // what rendered (Describe())
  SunScaleProfile sun_scale;  // with fit_sun
};

// Stage 5, per photo: the statistical fit image (each sky pixel the atmosphere's fit where
// clear and, by its cloud membership, the model's median radiance of its (sun angle,
// elevation, opacity) bin where cloud; the photo's own cloud map places the clouds) and the
// errors of the atmosphere alone and with it, over the whole sky, its clear and cloud pixels.
struct FitImage {
  ImageRGB image;
  fit::ImageErrors atmosphere_whole, atmosphere_clear, atmosphere_cloud;
  fit::ImageErrors stats_whole, stats_clear, stats_cloud;
};

// Stage 6: what the fitted preset takes so that it renders what was fitted: the cloud
// lighting with a weather map at the matched coverage (the first of the model's ensemble: the
// photo's shapes are unknown, its cover and lighting are not), and the sun that lit the
// model's clouds (the photo's with sun "photo": the sky itself does not depend on the sun's
// illuminance, only the disc, the ground and the clouds do).
struct CloudStatsPresetUpdate {
  clouds::CloudParams params;
  clouds::WeatherMap weather;
  double sun_illuminance_lux = 0.0;
  std::array<double, 3> sun_tint_rgb{};
  // Whether the preset should take that sun: it was fitted (sun_scale "fit"), or measured on
  // a disc seen on every reference (its peak at least kVisibleDiscPeakOverSky x the sky ring
  // around it; not on `dawn`, the sun behind the ridge: 8x, against 4,700x on `sky`).
  bool sun_measured = false;
  // Which sun lit the clouds: the photo's disc (sun "photo") or the model's, its scale fitted
  // (sun_scale "fit") or not; the disc seen on every reference, by the weakest peak over its ring.
  bool photo_sun = false, sun_fitted = false;
  bool disc_seen = false;
  double weakest_peak_over_background = 0.0;
};
// A visible disc peaks thousands of times above the sky around it (`sky` 4,700x, `city`
// 5,200x through overcast); a sun behind terrain leaves a glow (`dawn` 8x).
constexpr double kVisibleDiscPeakOverSky = 100.0;

struct PhotoCloudStatsResult {
  std::vector<PreparedPhoto> photos;
  render::Preset cloud_preset;  // the fitted preset with the sun that lit the clouds
  CoverageMatch coverage;
  StatisticsFit fit;
  std::vector<FitImage> images;  // per photo
  CloudStatsPresetUpdate update;
};

// Runs the stages over `photos` (one lighting for all of them) with the sky fit's preset and
// exposures (sky.references[r] belongs to photos[r]). Throws skycal::Error on invalid
// options, naming the reference when its width is not a multiple of the statistics' width or
// it has no cloud to fit.
PhotoCloudStatsResult FitPhotoCloudStats(const PhotoCloudStatsOptions& o, const std::vector<CloudStatsPhoto>& photos,
                                         const fit::FitResult& sky);

// Before the sky fit is final, with probability "fitted": each reference whose sky fit
// matches its clear pixels within kMaxSkyFitRelForProbability gets the cloud probability
// against that fit's render too (the minimum of the two), and pixels the first mask took as
// cloud that are now clear return to the sky fit (pixel class kSky). When that releases more
// than kSkyRefitReleasedFraction of a reference's sky pixels, `refit()` runs the sky fit once
// more. `probability` is updated in place. Nothing with a user mask (`user_mask`): its
// pixels are user-masked too and cannot be told apart.
struct ReleasedPixels {
  std::string name;
  double sky_fit_clear_rel_rmse = 0.0;
  bool refined = false;  // false: the sky fit missed its clear pixels by more than the bound
  std::vector<double> sun_angle_edges_deg;
  std::vector<long long> initial_cloud_pixels_by_sun_angle, cloud_pixels_by_sun_angle;
  long long released = 0;
  double released_fraction = 0.0;
};
struct SkyRefit {
  enum class Skipped { kNo, kInitialProbability, kUserMask, kBelowThreshold } skipped = Skipped::kNo;
  std::vector<ReleasedPixels> references;
  bool refitted = false;
  double time_s = 0.0;
};
SkyRefit RefineCloudMaskAndRefitSky(const PhotoCloudStatsOptions& o, bool user_mask, std::vector<fit::Reference>* refs,
                                    std::vector<std::vector<float>>* probability, const fit::FitResult& sky,
                                    const std::function<void()>& refit);

}  // namespace skycal::cloudfit
