// Partly cloudy photos: the clouds of the calibrated preset put where the photo has them
// (cloudfit/weather_inversion.h), by inverting its weather map through the game's march.
#pragma once
#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "calibrate_plan.h"
#include "skycal/cloudfit/cloud_lighting_fit.h"
#include "skycal/cloudfit/weather_inversion.h"
#include "skycal/clouds/cloud_renderer.h"
#include "skycal/core/image.h"
#include "skycal/core/staged_directory.h"
#include "skycal/fit/fit_report.h"

namespace skycal::controllers {

// Written beside the preset by the inversion: 1 where the photo constrained the map.
inline constexpr const char* kConstrainedTexelsFile = "weather_constrained.exr";

struct WeatherInversionRecord {
  bool done = false;
  std::string why_not;          // !done: why the statistical map stayed
  int texels = 0, constrained = 0;
  int render_width = 0;         // the refinement renders' lat-long width (pixels)
  std::vector<double> rms;      // per refinement render: RMS of rendered - photo opacity
  // The photo's opacity (capture/cloud_opacity.h): the clouds' colour (chromaticity), the sure
  // cloud pixels it is the median of (0: grey), and the share of the sky pixels whose colour
  // could not be unmixed (the cloud probability stood in).
  std::array<double, 3> cloud_colour{};
  long long colour_pixels = 0;
  double opacity_from_probability = 0.0;
  bool horizon_rule_off = false;  // the preset's horizon rule turned off (the map draws the horizon)
  double seconds = 0.0;
  fit::FitDecision Decision() const;
};

// The inversion's refinement renders' width (pixels) for a width x height photo; 0: the photo
// is smaller than 256x128, and its map is not inverted.
int InversionRenderWidth(int width, int height);

// The free lighting parameters a fit's `clouds` record (fit.json) left at an end of their range,
// as "phase_g1 0.99 (its maximum), ms_a 0 (its minimum)"; empty when none. On a photo's recovered
// shapes a lobe or factor runs there to make up for what the shapes get wrong (docs/calibrate.md),
// and an artist reading the preset should know it.
std::string ParametersAtBounds(const nlohmann::json& clouds);
// What the refit's record says of its restarts from the far side of a bound
// (CloudLightingOptions::restart_at_bounds), as a clause to append to its decision; "" when none ran.
std::string BoundRestartsText(const nlohmann::json& clouds);
// What the refit's record says of the holds it released after the solve
// (CloudLightingOptions::release_inseparable), as a clause to append to its decision; "" when none.
std::string ReleasedHoldsText(const nlohmann::json& clouds);

// The march the inversion and the day's predictions render: the game's (its noise, steps and
// optimisations) on `backend` (Vulkan, else the float CPU twin), its transmittance only (no
// light toward the sun, which the opacity does not read).
std::unique_ptr<clouds::CloudRenderer> OpacityRenderer(render::Backend backend);
clouds::CloudRenderRequest OpacityRequest(int width, int height);

// The clouds' IoU: the game's (transmittance < 0.5) against the photo's (cloud probability
// >= 0.5) over the compared pixels (weight >= 0.5); unset when neither has cloud there.
std::optional<double> CloudIou(const std::vector<float>& transmittance, const std::vector<float>& probability,
                               const std::vector<float>& compared);

// What the inversion read of the photo at its renders' width, kept for the light's step.
struct PhotoWeatherView {
  int width = 0, height = 0;
  std::vector<float> sky;      // the sky mask there
  std::vector<float> opacity;  // the photo's cloud opacity (PhotoOpacity)
  ImageRGB photo;              // the photo averaged down to it
  cloudfit::WeatherTexelView texels;
};

// `preset`'s clear sky at the photo's sun, width x height, without the disc, times `exposure`
// (the fit's): the photo's units (the sky the clouds are composited over).
ImageRGB ClearSkyInPhotoUnits(const PhotoAnalysis& a, const render::Preset& preset, double exposure, int width,
                              int height);

// Rewrites `out`/preset.weather.exr (the cloud statistics fit's map) so that the preset's
// clouds, marched as the game marches them at the photo's sun, cover what the photo's cloud
// probability covers. `backend` marches the renders (their transmittance only). `view`
// (optional) receives what it read of the photo.
WeatherInversionRecord InvertPhotoWeather(const PhotoAnalysis& a, const StagedDirectory& out, render::Backend backend,
                                          PhotoWeatherView* view = nullptr);

// The light inside the recovered clouds (cloudfit::RefineByLight), as the lighting refit's
// shape refinement (cloudfit::ShapeRefinement): with the lighting the refit's solve found, the
// map gains precipitation where the photo's clouds are darker than the game draws them, and
// the refit solves on from there. One step, from two lit renders at the view's width; then the
// coverage read from the light texel by texel (cloudfit::RefineCoverageByLight, 8 iterations
// of two renders; what it gains: bench/results/weather_inversion.md).
struct PrecipitationRecord {
  cloudfit::LightRefineStep step;
  int raised_texels = 0;                       // texels whose precipitation rose (by 0.01 or more)
  double mean_raised = 0.0, max_raised = 0.0;  // their precipitation
  cloudfit::CoverageLightResult coverage;     // then the coverage read from the light
  int width = 0;                               // the renders' lat-long width (pixels)
  double seconds = 0.0;
};
class RainFromTheLight : public cloudfit::ShapeRefinement {
 public:
  // `a` and `view` (the inversion's) outlive it.
  RainFromTheLight(const PhotoAnalysis& a, const PhotoWeatherView& view, render::Backend backend)
      : a_(a), view_(view), backend_(backend) {}
  // A failed lit render keeps the map (nullopt; Decision() says why): the refit ends as it was.
  std::optional<clouds::WeatherMap> Refine(const render::Preset& sky, const clouds::CloudParams& lit, double exposure,
                                           const clouds::WeatherMap& map) override;
  bool refined() const { return record_.has_value(); }
  // What it did, or why nothing ("precipitation: none read from the light").
  fit::FitDecision Decision() const;

 private:
  const PhotoAnalysis& a_;
  const PhotoWeatherView& view_;
  render::Backend backend_;
  std::optional<PrecipitationRecord> record_;
  std::string failure_ = "the lighting refit did not reach it";
};

// The user's weather map (CalibrateOptions::weather_map) as the preset's, held: read over the
// preset's weather extent (its errors name the file) and written as `out`/preset.weather.exr.
fit::FitDecision HoldWeatherMap(const std::string& weather_map, const StagedDirectory& out);

// The known-shapes refit of the lighting: its cost flattens within about ten iterations on the
// inverted shapes (bench/results/calibrate.md); the default 100 costs seconds for nothing.
// After the precipitation it solves on from its result and moves by about a level (the
// clouds' sun and ambient): more iterations, or the held parameters released again, did not
// change the game's image (bench/results/weather_inversion.md).
inline constexpr int kRefitIterations = 10;
inline constexpr int kRefitAfterRainIterations = 1;

// The refit's weak pull toward the statistics fit's lighting on inverted shapes
// (CloudLightingOptions::start_prior, RefitPass::start_prior). There the freed parameters are
// the image's best, not determined ones: without the pull, a start that moves by 1e-4 sends
// them to another basin (phase_g1 0.99 or 0.53) and the game's image by up to 0.03 in
// per-pixel log RMSE. At this weight the worst landings go. It was chosen over `sky` and four
// synthetic skies, and checked on three others that had no say in it
// (bench/results/weather_inversion.md, "The refit's released holds, re-checked").
inline constexpr double kRefitStartPrior = 0.001;

// The refit's atmosphere is fitted on the photo's surely clear pixels: the colour ramp without
// its allowance for the haze round the sun (FitCloudOptions::sky_pixels_sun_boost). With the
// allowance a thin cloud by the sun passed for clear sky, and the fitted aureole came out too
// bright on the bundled partly cloudy photo; leaving the sun's surroundings out altogether lost
// the aureole's peak where the sky by the sun is clear (bench/results/weather_inversion.md,
// "The clear sky by the sun").
inline constexpr double kRefitSkySunBoost = 0.0;

// Near the sun the photo's colour reads glare, and the silver lining of a cloud in front of the
// sun, as clear sky (or, for its light, as the brightest cloud): within this angle of the sun
// (degrees) neither its opacity nor its light is trusted.
inline constexpr double kSunGlareDeg = 10.0;

// The cloud lighting refitted pixel by pixel on the recovered shapes: the known-shapes fit
// (regime 1, docs/cloud-fitting.md) with the inverted preset as its shapes and start, run in
// a staged subdirectory and moved over the statistics fit's files only when it succeeds
// (the statistics fit's fit.json kept as fit.statistics.json). `final_dir` names the preset.
// `pass.refine`: the map refined after the solve and solved on (kRefitAfterRainIterations).
struct RefitPass {
  int iterations = kRefitIterations;
  bool release_holds = true;                   // CloudLightingOptions::release_inseparable
  // CloudLightingOptions::start_prior: kRefitStartPrior on inverted shapes; 0 on the user's map
  // (the scene's own shapes: there the pull would only bias what the pixels determine).
  double start_prior = 0.0;
  cloudfit::ShapeRefinement* refine = nullptr;  // not owned; null: none
};
fit::FitDecision RefitCloudLighting(const FitPlan& plan, const StagedDirectory& out, const std::string& final_dir,
                                    const RefitPass& pass);

}  // namespace skycal::controllers
