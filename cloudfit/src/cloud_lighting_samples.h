// The cloud pixels of one reference that the lighting fit compares, and the model's value
// there: the composite exposure x (L_sky T + L_cloud) per channel (composite.h), with the
// clouds' shapes known (noise, weather map, wind time) and their lighting the parameters.
//
// Values come from a cloud render of the whole frame (the Vulkan renderer: what the game
// computes) or from the double CPU model at the samples alone (for GradientChecker, whose
// central differences need double values); derivatives always come from the same model
// source instantiated on ceres::Jet (forward mode through the whole march, one dual part
// per free parameter: SetFreeParameters) on the CPU, at the samples only: a Jet march of 15
// dual parts costs ~15 double marches, so the fit's Jacobian rows are a sample of the cloud
// pixels (CloudLightingOptions::samples).
#pragma once
#include <array>
#include <vector>

#include "resolved_clouds.h"
#include "skycal/cloudfit/cloud_lighting_params.h"
#include "skycal/clouds/cloud_renderer.h"

namespace skycal::cloudfit {

enum class CloudValueSource { kRenderer, kCpuDouble };

struct CloudSample {
  int x = 0, y = 0;                     // pixel of the reference (lat-long)
  double weight = 0.0;                  // share of the samples' solid angle (sums to 1)
  std::array<double, 3> reference{};    // the reference's radiance, cd/m^2 (image units)
  std::array<double, 3> sky{};          // the sky model behind the cloud, model units
};

// What a cloud render of the reference needs besides the lighting: the sky preset (the
// light: sun, SH-9 ambient, ground), the cloud parameters (shapes; their lighting fields
// are replaced at every evaluation), textures, and the request (sun, frame size, wind
// time, march options).
struct CloudSampleScene {
  render::Preset sky_preset;
  clouds::CloudParams params;
  const clouds::CloudNoise* noise = nullptr;
  const clouds::WeatherMap* weather = nullptr;
  clouds::CloudRenderRequest request;
};

class CloudSampleModel {
 public:
  // `renderer` (not owned) gives the values when `source` is kRenderer.
  CloudSampleModel(CloudSampleScene scene, std::vector<CloudSample> samples, CloudValueSource source,
                   clouds::CloudRenderer* renderer, int threads);

  // A new sky (the light and the radiance behind the clouds) and exposure: re-resolves
  // the light and fills every sample's `sky` from `sky_image` (model units, frame size).
  void SetSky(const render::Preset& sky_preset, const ImageRGB& sky_image, double exposure);

  // log of the composite per sample and channel (3 per sample) at `theta`
  // (kCloudLightingParameters values, CloudLightingNames order) and, when `jacobian` is
  // not null, d log(composite) / d theta (row-major, 3N x 14). False when a composite is
  // not positive and finite (the trial point leaves the model's domain).
  bool Evaluate(const double* theta, double* log_model, double* jacobian);

  // The parameters the Jacobian is wanted for (CloudLightingNames() indices); the other
  // columns are 0 (or, at the point of an earlier Jacobian with more columns, its values:
  // that one is reused). Default: all (the conditioning needs every column; the solve only its
  // free ones, and a Jet of 4 dual parts marches several times faster than one of 15). The
  // Jet's width is the smallest of 2, 4, 8, 12, 15 that holds them.
  void SetFreeParameters(const std::vector<int>& free);

  // The full-frame cloud render at `theta` when one of the renders since SetSky was made
  // there (the first, at the solve's start, and the last kKeptImages - 1): the report's
  // composites reuse them instead of rendering again. Null otherwise (or with kCpuDouble
  // values). Each kept image is ~2 MB at 512x256.
  static constexpr size_t kKeptImages = 4;
  const clouds::CloudImage* RenderedAt(const double* theta) const;
  // A render at `theta` made elsewhere (the report's, with values from the CPU model), kept
  // as RenderValues keeps its own, for RenderedAt.
  void KeepRendered(const double* theta, clouds::CloudImage image);

  const std::vector<CloudSample>& samples() const { return samples_; }
  CloudValueSource source() const { return source_; }
  size_t residuals() const { return 3 * samples_.size(); }
  double exposure() const { return exposure_; }
  const CloudSampleScene& scene() const { return scene_; }

  // Work done so far (for fit.json and the benchmark).
  int renders = 0, jacobians = 0;
  double render_time_s = 0.0, jacobian_time_s = 0.0;

 private:
  bool RenderValues(const double* theta, double* log_model);
  bool DoubleValues(const double* theta, double* log_model) const;
  bool JetValues(const double* theta, double* log_model, double* jacobian) const;
  template <int N>
  bool JetValuesOf(const double* theta, double* log_model, double* jacobian) const;

  CloudSampleScene scene_;
  std::vector<CloudSample> samples_;
  CloudValueSource source_;
  clouds::CloudRenderer* renderer_;
  int threads_;
  double exposure_ = 1.0;
  clouds::CloudShadeD shade_{};
  // The sun's part of the shade per unit CloudParams::sun_scale (the direct sun and the
  // sunlit ground's radiance) and the ground's sky-lit part: the scale is a fitted parameter.
  glsl::Vec3<double> sun_per_scale_, ground_sun_per_scale_, ground_sky_;
  void ResolveShade();
  clouds::CpuCloudTextures textures_;
  std::vector<std::array<double, 3>> views_;  // per sample, the renderer's view direction
  // The last rendered point and its composite (Ceres asks for the residuals and then the
  // Jacobian at the same point: one render serves both).
  std::vector<double> cached_theta_, cached_log_;
  // The last Jet march (the conditioning's Jacobian at the start is the solve's first).
  std::vector<double> jet_theta_, jet_log_, jet_jacobian_;
  std::vector<int> free_;  // SetFreeParameters; the Jet's dual parts, in order
  // Full-frame renders since SetSky, each with its point: the first, then the latest.
  std::vector<std::pair<std::vector<double>, clouds::CloudImage>> images_;
};

}  // namespace skycal::cloudfit
