// The cloud lighting fit where the cloud SHAPES are unknown (docs/cloud-fitting.md, regime 2: what a
// photograph is). Noise cannot reproduce a photo's clouds pixel by pixel, so the objective
// compares statistics that do not need them: per bin of (angle from the sun, elevation,
// opacity class), weighted quantiles of the log radiance of cloud pixels, per channel, of
// the photo and of a render with the model's own shapes. The bins carry the lighting's
// signatures: the silver lining toward the sun (phase lobes), dark bases and bright tops
// (extinction, ambient), powder darkening away from the sun at thin edges (powder).
//
// The render is the composite L = L_sky T + L_cloud through a clouds::CloudRenderer (Vulkan
// by default; the CPU reference works too), each pixel weighted by its opacity class, the
// photo's pixels by its cloud opacity (capture's cloud probability for a photograph, 1 - T
// of the reference render for a synthetic test). Quantiles are interpolated along the
// weighted CDF, so they are continuous in the parameters (values and weights move, the
// interpolation never jumps); derivatives are central differences through the renderer
// (cloud_stats_term.h says why not Jets).
//
// This header keeps Ceres and Vulkan out: the cost and the FitTerm are in cloudfit/src.
#pragma once
#include <array>
#include <string>
#include <vector>

#include "skycal/clouds/cloud_params.h"
#include "skycal/clouds/cloud_renderer.h"
#include "skycal/core/image.h"
#include "skycal/render/preset.h"

namespace skycal::cloudfit {

struct CloudStatsOptions {
  // Bin edges (deg). Angle from the sun: the silver lining lives in the first bins.
  std::vector<double> sun_angle_edges_deg = {0.0, 20.0, 45.0, 90.0, 180.0};
  std::vector<double> elevation_edges_deg = {2.0, 15.0, 35.0, 90.0};
  std::vector<double> quantiles = {0.25, 0.5, 0.75};
  // The model's statistics pool this many renders, the wind moved by model_time_step_s
  // between them (other shapes from the same weather statistics): a photograph is one draw
  // of a cloud population, the model's side need not be, and pooling halves its share of
  // the shape noise in the statistics.
  int model_renders = 2;  // [1, 64]
  double model_time_step_s = 1800.0;  // s (10 m/s of wind: 18 km, half the draw distance)
  // Weight of the residual per (sun angle, elevation) bin matching the thick share of cloud
  // weight, thick / (thin + thick): the opacity distribution, which extinction sets.
  double opacity_share_weight = 1.0;
  // Opacity classes, smooth in the opacity a (1 - T): thick = smoothstep(thick_lo, thick_hi, a),
  // thin = smoothstep(thin_lo, thin_hi, a) (1 - thick). Thin edges carry the powder term.
  double thin_lo = 0.1, thin_hi = 0.35, thick_lo = 0.55, thick_hi = 0.9;
  // A bin joins the objective when the reference's weight in it reaches this solid angle
  // (sr; 0.01 sr is ~16 pixels of a 256x128 lat-long at mid elevations); a bin the render
  // leaves below half of it adds zero residuals at that point.
  double min_bin_sr = 0.01;
  // Residual per quantile and channel (log units, before the bin's weight) of a bin the
  // reference fills and the render leaves empty; 0: none (an empty bin then costs nothing,
  // and a parameter that empties bins can escape: extinction ran to 0 on the photo `dawn`).
  double empty_bin_log_residual = 0.0;
  // The lighting parameters fitted (clouds.* names of CloudParameterSpecs()); every other
  // field is held at the initial value, and cloud_stats / fit.json say why. The default: the
  // one field one sky's statistics recover with unknown shapes, ambient_strength (5 seed
  // pairs at 64x32, the others held at the truth: median 7.4% / worst 28.7% with the
  // diagonal whitening; `skycal bench --suite fit-cloud-stats-gls`,
  // bench/results/cloud_stats_gls.md). extinction is held (as the photo path holds it, where
  // the coverage match sets the opacity with it): the fits stay on their start's side of the
  // truth — from 1.3x: +5..+39% (median 29%), from 0.7x: -17..-44% (median 23%), full GLS —
  // and drag ambient 13-20% (median) along. phase_g1 and powder_strength are held: from one
  // sky the shape noise alone predicts an sd of 84% and 136% for them, and 5 seed pairs land
  // 38-134% off (median over three weightings; bench/results/cloud_stats_seed_pairs.md,
  // "Shape noise"). scattering_albedo with ambient: a pair lands 24% / 62% off (the same
  // bench). With known shapes all are recovered (fit them then). The silver-lining lobe
  // (phase_g2, phase_blend: 164-1,076% predicted), powder_view_fade, rain_absorption (no rain
  // in a fair-weather photo), ambient_height_bias and ground_bounce (traded against
  // ambient_strength), the multiple-scattering octaves and atmosphere_blend are held too.
  std::vector<std::string> fitted = {"ambient_strength"};
  // Central-difference step per parameter, as a fraction of its (max - min) range.
  double relative_step = 2e-3;
  int max_iterations = 25;
  // Whitening by the shape noise (a generalised least-squares objective; docs/cloud-fitting.md regime 2,
  // bench/results/cloud_stats_seed_pairs.md measures it). With noise_draws D > 0 the
  // objective renders D single shape draws of the model at its start (the scene's
  // shape_draw_maps, else its weather maps at further wind times), takes each statistic's
  // standard deviation over them (log radiance for a quantile, a fraction for a thick share)
  // and divides its residual by sd sqrt(1 + 1/model_renders) (the reference is one draw, the
  // model the mean of model_renders): a statistic the shapes move much counts little, and the
  // cost at the right lighting is ~ half the number of residuals. 0: each bin weighted by
  // its share of the reference's cloud (the first design).
  int noise_draws = 0;        // [0, 256]; >= 4 when on
  double noise_sd_floor = 0.02;  // lower bound of a statistic's sd (log radiance or share)
  // The whitening's covariance (with noise_draws > 0). "diagonal": each residual divided by
  // its statistic's sd (above). "full": a generalised least squares with the statistics' full
  // covariance over the draws, shrunk toward its diagonal, Σ = (1 - λ) S + λ diag(S) (D draws
  // cannot estimate a full covariance of ~100 statistics), each variance floored as above:
  // Ceres sees the fixed linear map r' = L^-1 r, Σ (1 + 1/M) = L Lᵀ, so the cost is
  // rᵀ Σ^-1 r and statistics that move together with the shapes (a bin's quantiles and
  // channels, neighbouring bins) count once (cloudfit/src/shape_noise_covariance.h).
  std::string noise_covariance = "diagonal";
  // λ of the "full" covariance: in [0, 1] fixed, or -1: estimated from the draws (Schäfer &
  // Strimmer 2005, the Ledoit-Wolf optimum for a diagonal target; at least 1e-3 when the
  // draws are fewer than the statistics, so Σ stays positive definite).
  double noise_shrinkage = -1.0;
  int render_width = 256, render_height = 128;  // pixels of the model's render per reference
  clouds::MarchOptions march;
  bool IsValid(std::string* why) const;
};

// One reference: the photo (or a synthetic render) with what is known about it.
struct CloudStatsReference {
  std::string name;
  ImageRGB radiance;                  // lat-long, cd/m^2 (model units: divide by the exposure first)
  std::vector<float> opacity;         // per pixel in [0, 1]: cloud opacity (cloud probability of a photo)
  std::vector<float> sky;             // per pixel: < 0.5 excludes (not sky); empty: every pixel above the horizon
  std::array<double, 3> sun_dir{};    // toward the sun, unit
  ImageRGB clear_sky;                 // the model's clear sky at the render size (L_sky of the composite)
  double cloud_time_s = 0.0;          // the model render's wind time
};

// What the model renders with: the preset's light, the starting cloud parameters, noise and
// weather map (the render's own shapes: any seed).
struct CloudStatsScene {
  const render::Preset* preset = nullptr;
  clouds::CloudParams initial;
  const clouds::CloudNoise* noise = nullptr;
  const clouds::WeatherMap* weather = nullptr;
  // The model's ensemble of shapes: when non-empty, model render m uses weather map
  // weather_ensemble[m % size] at wind offset (m / size) * model_time_step_s (`weather` is
  // then unused by the statistics). Several independent draws of the same weather statistics
  // make the model's statistics an expectation over shapes, not one draw
  // (bench/results/cloud_stats_seed_pairs.md measures what that buys).
  std::vector<const clouds::WeatherMap*> weather_ensemble;
  // The shape draws that measure the statistics' shape noise (options.noise_draws): draw d
  // renders shape_draw_maps[d % size] at wind offset (d / size) * model_time_step_s. Empty:
  // the weather ensemble (or `weather`) continued past the model's own renders (wind moves a
  // 60 km map 18 km a step: after a few steps the draws repeat shapes, so give maps here).
  std::vector<const clouds::WeatherMap*> shape_draw_maps;
  // The 3D noise textures of the shape draws: draw d renders shape_draw_noises[d % size]
  // (empty: `noise`). The noise texture is a shape draw too (its statistics' sd across seeds
  // is 0.75x that across weather maps, bench/results/cloud_stats_noise.md): give several here
  // and the measured shape noise holds it.
  std::vector<const clouds::CloudNoise*> shape_draw_noises;
  // The model's ensemble of noise textures: when non-empty, model render m uses
  // noise_textures[m % size] (`noise` stays the texture of the shape draws). The 3D noise is a
  // shape draw too: its density distribution moves the opacity distribution the way
  // extinction does (bench/results/cloud_stats_noise.md), and one texture cannot average it.
  std::vector<const clouds::CloudNoise*> noise_textures;
};

// Statistics of one image: per bin (sun angle x elevation x opacity class) the weight
// (solid angle x class membership, sr) and the weighted quantiles of log radiance per channel.
struct CloudStatistics {
  int sun_bins = 0, elevation_bins = 0;
  static constexpr int kOpacityClasses = 2;  // 0 thin, 1 thick
  std::vector<double> weight;                // [bin]
  std::vector<double> log_quantile;          // [bin][channel][quantile]
  // thick / (thin + thick) weight per (sun angle, elevation) bin: [sun * elevation_bins + elevation]
  std::vector<double> thick_share;
  int Bin(int sun, int elevation, int opacity_class) const {
    return (sun * elevation_bins + elevation) * kOpacityClasses + opacity_class;
  }
};
// The (sun angle, elevation) bin of a direction, false outside the edges; and the opacity
// classes' memberships of an opacity a (thin + thick <= 1; the rest is clear).
bool FindCloudBin(const CloudStatsOptions& options, double sun_angle_deg, double elevation_deg, int* sun_bin,
                  int* elevation_bin);
void OpacityClassWeights(const CloudStatsOptions& options, double opacity, double* thin, double* thick);

// `opacity` and `sky` as in CloudStatsReference; pixels with a non-positive or non-finite
// channel are left out. Throws skycal::Error on size mismatches.
CloudStatistics ComputeCloudStatistics(const ImageRGB& radiance, const std::vector<float>& opacity,
                                       const std::vector<float>& sky, const std::array<double, 3>& sun_dir,
                                       const CloudStatsOptions& options);
// The same over the pooled pixels of several images of one size (the model's renders).
CloudStatistics ComputeCloudStatistics(const std::vector<const ImageRGB*>& radiance,
                                       const std::vector<const std::vector<float>*>& opacity,
                                       const std::vector<float>& sky, const std::array<double, 3>& sun_dir,
                                       const CloudStatsOptions& options);

struct CloudStatsParameter {
  std::string name, unit;
  double initial = 0.0, value = 0.0;
  bool held = false;
  std::string why_held;  // empty when fitted
};

struct CloudStatsResult {
  clouds::CloudParams params;                 // the fitted set
  std::vector<CloudStatsParameter> parameters;  // every lighting field, fitted or held
  std::vector<CloudStatistics> reference_stats, initial_stats, final_stats;  // per reference
  double initial_cost = 0.0, final_cost = 0.0;  // 1/2 sum of squared residuals
  int iterations = 0;
  long long renders = 0;
  long long residuals = 0;
  double time_s = 0.0;
  // Singular values of the residual Jacobian at the solution (columns scaled to the
  // parameters' ranges), largest first: a small ratio names what the bins cannot separate.
  std::vector<double> singular_values;
  std::string termination;
  // With options.noise_draws > 0: the draws used and the median of the statistics' shape
  // noise sd (log radiance / share); the residuals were divided by it (whitened).
  int noise_draws = 0;
  double median_noise_sd = 0.0;
  // The whitening: "none" (bin-share weights), "diagonal" or "full" (options.noise_covariance),
  // and the full covariance's shrinkage λ toward its diagonal (0 otherwise).
  std::string noise_covariance = "none";
  double noise_shrinkage = 0.0;
};

// Fits the lighting of `scene.initial` so the model's statistics match the references'.
// Throws skycal::Error on invalid options, sizes or parameters (naming the field).
CloudStatsResult FitCloudStats(const std::vector<CloudStatsReference>& refs, const CloudStatsScene& scene,
                               clouds::CloudRenderer& renderer, const CloudStatsOptions& options);

// The composite L = L_sky T + L_cloud the statistics see, rendered for one reference.
struct CloudStatsRender {
  ImageRGB composite;
  std::vector<float> opacity;  // 1 - T
};
// `time_offset_s` is added to the reference's cloud_time_s; `weather` overrides the scene's
// map when given.
CloudStatsRender RenderForCloudStats(const CloudStatsReference& ref, const CloudStatsScene& scene,
                                     const clouds::CloudParams& params, clouds::CloudRenderer& renderer,
                                     const CloudStatsOptions& options, double time_offset_s = 0.0,
                                     const clouds::WeatherMap* weather = nullptr);

}  // namespace skycal::cloudfit
