// `skycal render`: the sky of a preset for one sun direction, as a lat-long EXR (and an
// optional PNG preview through the OCIO view transform). The verb parses and prints; the
// render is the controllers library's (controllers/game_render.h).
#pragma once
#include <array>
#include <limits>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "render_clouds.h"
#include "skycal/controllers/game_render.h"
#include "skycal/render/renderer.h"

namespace skycal::cli {

struct RenderOptions {
  std::string preset_path;                       // preset JSON (default: the bundled preset)
  std::optional<double> sun_elevation_deg;       // degrees above the horizon, [-90, 90]
  std::optional<double> sun_azimuth_deg;         // lat-long longitude, degrees, [-360, 360]
  std::optional<std::array<double, 3>> sun_dir;  // alternative: unit vector toward the sun
  int width = 1024, height = 512;                // pixels
  render::Backend backend = render::Backend::kVulkan;
  render::GroundMode ground = render::GroundMode::kLit;
  bool sun_disc = true;
  bool half = false;                             // write half floats instead of float
  std::string out_exr;                           // required, *.exr
  std::string out_png;                           // optional, *.png
  double png_exposure_ev = std::numeric_limits<double>::quiet_NaN();  // NaN: automatic
  bool vulkan_validation = false;
  CloudOptions clouds;                           // --clouds and its options
  std::optional<double> time_of_day_h;           // hours in [0, 24): the skycalTimeOfDay attribute (fit, batch)
  bool verbose = true;                           // progress lines on stderr ([render] ...; warnings always); skycal bench turns them off

  bool IsValid(std::string* why) const;
  std::array<double, 3> SunDirection() const;  // unit vector (valid options only)
};

// Renders and writes the outputs (controllers::WriteGameRender); returns the JSON summary.
// Throws skycal::Error naming the flags.
nlohmann::json RunRenderImpl(const RenderOptions& options);
// Parses the arguments after the verb (no I/O). Throws HelpRequested (command_line.h) for
// --help, skycal::Error naming the option on a bad command line.
RenderOptions ParseRenderArgs(int argc, char** argv);
int RunRender(int argc, char** argv);

// "lit" or "zero" (--ground of render and probe-predict); throws naming `option`.
render::GroundMode ParseGroundMode(const std::string& text, const std::string& option);

using controllers::DefaultPresetPath;  // datasets/presets/default_clear.json in the data directory

}  // namespace skycal::cli
