// Fitting the cloud lighting (docs/cloud-fitting.md, regime 1: known shapes). A reference rendered (or
// photographed) with clouds whose shapes are known -- noise seed, weather map, wind time --
// is compared with the sky + clouds composite exposure x (L_sky T + L_cloud); Ceres tunes
// the 15 lighting parameters of the clouds section (cloud_lighting_params.h): values
// through the cloud renderer (Vulkan: what the game computes), derivatives forward-mode
// through the same model source on ceres::Jet (CPU) at a sample of the cloud pixels.
// What the pixels cannot separate is held and said (cloud_lighting_conditioning.h).
//
// Three entry points: FitCloudLightingKnownSky (the sky given: the recovery tests),
// FitCloudDayKnownSky (a day of references with the sky given: per-reference lighting with
// a smoothness prior over time of day) and FitSkyAndClouds (`skycal fit --clouds`: the sky
// fitted on its clear pixels, then the cloud blocks on that sky).
#pragma once
#include <array>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "skycal/cloudfit/cloud_lighting_params.h"
#include "skycal/clouds/cloud_params.h"
#include "skycal/clouds/cloud_renderer.h"
#include "skycal/clouds/cloud_textures.h"
#include "skycal/fit/sky_fit.h"

namespace skycal::cloudfit {

// `skycal fit --clouds auto|on|off`.
enum class CloudMode { kAuto, kOn, kOff };
const char* ToString(CloudMode m);
// Throws skycal::Error naming `option` for anything but auto, on, off.
CloudMode ParseCloudMode(const std::string& text, const std::string& option);

// The known shapes (regime 1): the clouds section (shape fields; its lighting fields are
// the fit's start), the textures and the wind time; the march the renders use.
struct KnownCloudShapes {
  clouds::CloudParams params;
  const clouds::CloudNoise* noise = nullptr;
  const clouds::WeatherMap* weather = nullptr;
  double time_s = 0.0;  // s: wind offset = wind speed x time
  // s: per reference of a day, its own wind time (a time-lapse's clouds move); empty: time_s
  // for every reference.
  std::vector<double> time_s_per_reference;
  clouds::MarchOptions march;
  double TimeOf(size_t reference) const {
    return time_s_per_reference.empty() ? time_s : time_s_per_reference.at(reference);
  }
};

// Shapes refined once the lighting is known: FitSkyAndClouds (one reference) hands its map
// to Refine with the lighting its solve found; a refined map is solved on from there
// (CloudLightingOptions::iterations_after_refinement, no holds released, the sky and the
// cloud pixels kept) and is the fit's map (SkyCloudFit::refined_weather). Calibrate's reads
// precipitation from the photo's light (what the lighting cannot do, the map does, and the
// lighting then settles on it): in one fit, not a second one that fits the sky again.
class ShapeRefinement {
 public:
  virtual ~ShapeRefinement() = default;
  // `sky`: the fitted sky preset; `lit`: the clouds section with the fitted lighting;
  // `exposure`: the reference's. The refined map, or nullopt to keep `map` (nothing solved
  // again). May throw: the fit fails with it.
  virtual std::optional<clouds::WeatherMap> Refine(const render::Preset& sky, const clouds::CloudParams& lit,
                                                   double exposure, const clouds::WeatherMap& map) = 0;
};

struct CloudLightingOptions {
  // Cloud pixels whose Jacobian rows (Jet marches, ~15 double marches each) the fit uses;
  // all of them when there are fewer. One Jet march of the game's march costs ~2-4 ms at
  // 512x256 on this machine: 256 samples keep one Jacobian ~0.5-1 s on two cores
  // (docs/cloud-fitting.md, regime 1).
  int samples = 256;
  // Pixels whose transmittance through the known shapes (at the start) is below this are
  // cloud pixels: they leave the sky terms and join the cloud term (the composite models
  // them exactly, thin edges included).
  double cloud_transmittance = 0.999;
  // The separability rule: hold a parameter whose predicted error, with this per-pixel
  // relative noise and the samples used, exceeds max_predicted_error.
  double noise_level = 0.02;
  double max_predicted_error = 0.01;
  bool auto_hold = true;
  std::vector<std::string> hold;  // parameter names held whatever the conditioning says
  // Fit sun_scale (the clouds' sun relative to the preset's) as well: the cloud pixels then
  // set the sun-to-sky ratio a sky fit leaves to its exposure. Off: held at the start's.
  bool fit_sun_scale = false;
  int max_iterations = 100;
  // A day (three or more references): weight of the second-difference prior on each
  // lighting parameter over time of day (cloud_lighting_day_prior.h: relative curvature per
  // h^2). 0: every reference's lighting independent. Default: at references 2 h apart the
  // prior on a middle key weighs about as much as the cloud pixels' data on a parameter
  // they predict to 1% at 2% noise (256 samples), so it steers the weakly determined ones
  // and barely moves the well determined ones.
  double day_smoothness = 0.02;
  // FitSkyAndClouds: where the solve's values come from. True: a cloud render of the whole
  // frame per trial point (the renderer's numbers, the game's on Vulkan). False: the double
  // CPU model at the samples alone (the same model source as the shader, parity-tested
  // against it; ~1/10 of a Jet march a sample, not a frame's march): the refit of a
  // calibration, where the frame is rendered for the report and the game's image anyway.
  bool values_from_renderer = true;
  // One reference: a free parameter the solve leaves at an end of its range is solved again
  // from a quarter of the range in from the other end, and the lower cost kept (a refit on a
  // photo's recovered shapes has minima at opposite bounds; calibrate's uses
  // release_inseparable below, which gained more for one solve).
  bool restart_at_bounds = false;
  // One reference: after the solve, the parameters the separability rule held are freed and
  // the solve continues from its result; kept when the cost is lower (calibrate's refit: the
  // recovered shapes are not the photo's clouds, and a lobe or factor the image cannot pin
  // down alone still lowers the image's error; the values are then the image's best, not
  // determined ones, and the report says which).
  bool release_inseparable = false;
  // One reference: weight w of a pull of every parameter toward the solve's start,
  // sqrt(w) (theta - theta_start) / scale per parameter (scale: the conditioning's unit of
  // relative change), in each of its solves (the released holds' too; after a refinement,
  // toward the first solve's result). 0: none, as the regime-1 recovery needs (exact on
  // synthetic references). calibrate's refit on inverted shapes uses a weak one: there the
  // freed parameters are the image's best rather than determined ones, and without it a
  // small change of the start sends them to other basins (bench/results/weather_inversion.md).
  double start_prior = 0.0;
  // FitSkyAndClouds with one reference: the shapes refined after the solve (null: none), and
  // the iterations solved on the refined map from the lighting found before.
  ShapeRefinement* refine_shapes = nullptr;
  int iterations_after_refinement = 1;
  int threads = 2;
  bool verbose = false;
  bool IsValid(std::string* why) const;
};

struct CloudParamReport {
  std::string name, unit;
  double value = 0.0, initial = 0.0;
  bool held = false;
  std::string why;  // when held
  double sensitivity = 0.0;                 // RMS d log(composite) / d log(theta) at the start
  double predicted_relative_error = 0.0;    // at noise_level, with the free set
  double separability = 0.0;                // 1 / sqrt(VIF): 1 independent, 0 collinear
  std::string most_collinear_with;
  double collinear_cosine = 0.0;
};

struct PixelErrors {
  long long pixels = 0;
  double rel_rmse = std::numeric_limits<double>::quiet_NaN();  // solid-angle weighted, 3 channels
  double log_rmse = std::numeric_limits<double>::quiet_NaN();
};

struct CloudLightingReport {
  bool fitted = false;
  std::string reference;                     // the reference's name (a day: one report per reference)
  std::optional<double> time_of_day_h;       // its time of day, hours
  std::string decision;   // what auto/on/off decided and why
  std::vector<CloudParamReport> parameters;  // CloudLightingNames order
  std::vector<double> singular_values;       // column-normalised Jacobian, observed parameters, descending
  std::vector<double> singular_values_free;  // the parameters left free
  long long cloud_pixels = 0;                // fitted sky pixels with T < cloud_transmittance
  double cloud_fraction = 0.0;               // of the reference's fitted sky pixels
  int samples = 0;                           // of them in the Jacobian
  PixelErrors cloud_initial, cloud_final;    // every cloud pixel, from the value renderer
  PixelErrors clear;                         // the clear pixels (the sky terms), final
  int iterations = 0, renders = 0, jacobians = 0;
  // CloudLightingOptions::restart_at_bounds: the solves run again from the far side of a
  // bound, and the parameter whose restart was kept (empty: the first solve stood).
  int bound_restarts = 0;
  std::string bound_restart_kept;
  // CloudLightingOptions::release_inseparable: the holds released, whether the continued
  // solve was kept, and the cost before and after it (0.5 sum of squared weighted residuals).
  std::vector<std::string> released_holds;
  bool released_kept = false;
  double released_cost_before = 0.0, released_cost_after = 0.0;
  double render_time_s = 0.0, jacobian_time_s = 0.0, conditioning_time_s = 0.0, time_s = 0.0;
  // Stages of the whole fit (FitSkyAndClouds), s: the cloud renders that find the cloud
  // pixels, the sky fit on the clear pixels, the cloud solve (conditioning included), the
  // report's renders of the composites; sky_renders: the sky fit's backend renders.
  double cloud_pixels_time_s = 0.0, sky_fit_time_s = 0.0, solve_time_s = 0.0, report_time_s = 0.0;
  int sky_renders = 0;
  int prior_residuals = 0;  // the day's smoothness prior (0 for fewer than 3 references)
  std::string termination, value_source;
  clouds::CloudParams fitted_params;         // the section with the fitted lighting
};

// Regime 1 with the sky given: `reference` is a lat-long (cd/m^2, image units) whose
// pixels above the horizon, positive in every channel and with known-shape transmittance
// below o.cloud_transmittance are cloud pixels; the model is exposure x (sky T + clouds)
// with `sky` rendered from `sky_preset` (model units, the reference's size). `renderer`
// gives the values (null: the double CPU model at the samples). Throws skycal::Error when
// there is no cloud pixel.
CloudLightingReport FitCloudLightingKnownSky(const ImageRGB& reference, const std::array<double, 3>& sun_dir,
                                             const render::Preset& sky_preset, const ImageRGB& sky, double exposure,
                                             const KnownCloudShapes& shapes, const CloudLightingOptions& o,
                                             clouds::CloudRenderer* renderer);

// A day with the sky given: per reference its image, sun, sky and exposure, and its time
// of day (hours) for the prior; shapes.TimeOf(r) the wind time of reference r. One
// report per reference (input order); every reference holds the same parameters (those
// some reference cannot separate are held in all, so the day's keyframes share columns).
struct DayReference {
  const ImageRGB* reference = nullptr;
  std::array<double, 3> sun_dir{};
  const render::Preset* sky_preset = nullptr;
  const ImageRGB* sky = nullptr;
  double exposure = 1.0;
  double time_of_day_h = 0.0;
  std::string name;
};
std::vector<CloudLightingReport> FitCloudDayKnownSky(const std::vector<DayReference>& day, const KnownCloudShapes& shapes,
                                                     const CloudLightingOptions& o, clouds::CloudRenderer* renderer);

// The kinds of cloud term the fit can hold.
enum class CloudTermKind {
  kKnownShapes,  // regime 1: per-pixel residuals against the known shapes' composite
};

// The auto/on/off decision for one reference, from its cloud mask
// (skycal/capture/cloud_mask.h: colour against the clear sky rendered from `init`).
struct CloudDecision {
  bool march = false;
  std::string why;
  long long cloudy_pixels = 0, sky_pixels = 0;
  double cloud_fraction = 0.0;  // cloudy / sky pixels (mask probability >= 0.5)
  double time_s = 0.0;          // the mask's cost
};
// Messages name the mode ("CloudMode on: ...") and the shapes (KnownCloudShapes).
// Throws skycal::Error for CloudMode on without a cloud pixel (naming the reference) or
// without shapes. Several references (a day): the fraction is over all of them, and each
// needs a time of day (the prior's axis) when clouds are marched.
CloudDecision DecideClouds(CloudMode mode, const std::vector<fit::Reference>& refs, const render::Preset& init,
                           bool shapes_given, double min_cloud_fraction = 0.01);

struct SkyCloudFit {
  fit::FitResult sky;         // references[].rendered: the composite with clouds when they ran
  // The fit's cloud report: one reference's, or for a day the earliest reference's values
  // with the day's solve (iterations, renders, times summed over the references).
  CloudLightingReport clouds;
  std::vector<CloudLightingReport> references;  // per reference (input order) when fitted
  // The map CloudLightingOptions::refine_shapes returned (the fit's report is on it); none:
  // the known shapes' map.
  std::optional<clouds::WeatherMap> refined_weather;
};

// The fit with clouds, when decision.march: the cloud pixels (known-shape transmittance
// below the threshold at the start) leave the sky rows; the sky is fitted on the rest (its
// linear stage alone, as a clear sky: the cloud cost has no sky parameter, so a joint
// problem would only be block-diagonal, and the Ceres polish it forced cost ~50 sky
// renders); then the cloud blocks are solved on the fitted sky, after its gauge move (the
// sun's illuminance is not scaled with the LUT, so the clouds' sun-to-ambient balance is
// final only then), through the renderer with exact Jet Jacobians. Else the sky alone with
// every cloud parameter held. `cloud_renderer` gives the cloud values (Vulkan in the verb).
// `sky_pixel_class`, per reference: the sky stage's own classes (kSky: fitted) instead of
// the pixels clear through the shapes; null: those.
SkyCloudFit FitSkyAndClouds(const std::vector<fit::Reference>& refs, const render::Preset& init,
                            const fit::FitOptions& fit_options, render::SkyRenderer& renderer,
                            const std::vector<const fit::ProbeSamples*>& probes, const CloudDecision& decision,
                            CloudTermKind kind, const KnownCloudShapes* shapes, const CloudLightingOptions& o,
                            clouds::CloudRenderer* cloud_renderer,
                            const std::vector<std::vector<fit::PixelClass>>* sky_pixel_class = nullptr);

}  // namespace skycal::cloudfit
