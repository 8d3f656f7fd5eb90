// `skycal probe-predict`: the gray diffuse probe (Wood, Forza Horizon 3 skies, GDC) predicted from a preset:
// irradiance on the up normal and on Fibonacci-sphere normals (sky by quadrature over a
// disc-less render + the analytic sun term), ball radiance, SH-9 and its error.
#pragma once
#include <array>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "skycal/render/renderer.h"

namespace skycal::cli {

struct ProbePredictOptions {
  std::string preset_path;                       // preset JSON (default: the bundled preset)
  std::optional<double> sun_elevation_deg;       // degrees above the horizon, [-90, 90]
  std::optional<double> sun_azimuth_deg;         // lat-long longitude, degrees, [-360, 360]
  std::optional<std::array<double, 3>> sun_dir;  // alternative: vector toward the sun
  double albedo = 0.18;                          // the ball's Lambertian albedo, [0, 1]
  int normals = 64;                              // Fibonacci-sphere normals besides up, [0, 100000]
  int width = 512;                               // sky render width (height = width / 2)
  render::Backend backend = render::Backend::kVulkan;
  render::GroundMode ground = render::GroundMode::kLit;
  bool vulkan_validation = false;

  bool IsValid(std::string* why) const;
  std::array<double, 3> SunDirection() const;  // unit vector (valid options only)
};

// Renders, integrates and returns the JSON summary. Throws skycal::Error.
nlohmann::json RunProbePredictImpl(const ProbePredictOptions& options);
// Parses the arguments after the verb (no I/O). Throws HelpRequested (command_line.h) for
// --help, skycal::Error naming the option on a bad command line.
ProbePredictOptions ParseProbePredictArgs(int argc, char** argv);
int RunProbePredict(int argc, char** argv);

}  // namespace skycal::cli
