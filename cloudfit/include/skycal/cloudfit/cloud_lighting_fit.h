// Fitting the cloud lighting (issue 11, regime 1: known shapes). A reference rendered (or
// photographed) with clouds whose shapes are known -- noise seed, weather map, wind time --
// is compared with the sky + clouds composite exposure x (L_sky T + L_cloud); Ceres tunes
// the 14 lighting parameters of the clouds section (cloud_lighting_params.h): values
// through the cloud renderer (Vulkan: what the game computes), derivatives forward-mode
// through the same model source on ceres::Jet (CPU) at a sample of the cloud pixels.
// What the pixels cannot separate is held and said (cloud_lighting_conditioning.h).
//
// Two entry points: FitCloudLightingKnownSky (the sky given: the recovery tests and the
// benchmark's core) and FitSkyAndClouds (the joint fit of `skycal fit --clouds`: sky terms
// and the cloud term in one Ceres problem).
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
  clouds::MarchOptions march;
};

struct CloudLightingOptions {
  // Cloud pixels whose Jacobian rows (Jet marches, ~15 double marches each) the fit uses;
  // all of them when there are fewer. One Jet march of the game's march costs ~2-4 ms at
  // 512x256 on this machine: 256 samples keep one Jacobian ~0.5-1 s on two cores
  // (README "Fitting the cloud lighting").
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
  int max_iterations = 100;
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
  double render_time_s = 0.0, jacobian_time_s = 0.0, conditioning_time_s = 0.0, time_s = 0.0;
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

// The kinds of cloud term the joint fit can hold (MakeCloudTerm in cloud_lighting_fit.cc).
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
// Throws skycal::Error for --clouds on without a cloud pixel (naming the reference) or
// without shapes; several references with clouds on are refused (one at a time for now).
CloudDecision DecideClouds(CloudMode mode, const std::vector<fit::Reference>& refs, const render::Preset& init,
                           bool shapes_given, double min_cloud_fraction = 0.01);

struct SkyCloudFit {
  fit::FitResult sky;         // references[].rendered: the composite with clouds when they ran
  CloudLightingReport clouds;
};

// The joint fit: sky terms + the cloud term of `kind` in one Ceres problem (fit_term.h)
// when decision.march, else the sky alone with every cloud parameter held. `cloud_renderer`
// gives the cloud values (the Vulkan renderer in the verb).
SkyCloudFit FitSkyAndClouds(const std::vector<fit::Reference>& refs, const render::Preset& init,
                            const fit::FitOptions& fit_options, render::SkyRenderer& renderer,
                            const std::vector<const fit::ProbeSamples*>& probes, const CloudDecision& decision,
                            CloudTermKind kind, const KnownCloudShapes* shapes, const CloudLightingOptions& o,
                            clouds::CloudRenderer* cloud_renderer);

}  // namespace skycal::cloudfit
