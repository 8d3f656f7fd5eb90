// The game's sky as the game draws it: a preset (with its `clouds` section and weather map)
// -> the sky model with HZD's clouds composited over it -> lat-long radiance. In memory
// (RenderGameImage: the image a calibration compares with the photo) or written as a
// lat-long EXR with an optional PNG preview through the OCIO view transform
// (WriteGameRender: `skycal render`).
#pragma once
#include <array>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "skycal/controllers/game_clouds.h"
#include "skycal/core/image.h"
#include "skycal/render/renderer.h"

namespace skycal::controllers {

std::string DefaultPresetPath();  // datasets/presets/default_clear.json in the data directory (core/data_dir.h)

// The EXR channel a game image with clouds carries their transmittance in (render --clouds,
// calibrate's render.exr); `skycal compare` reads it.
inline constexpr const char* kCloudTransmittancePlane = "cloudTransmittance";

struct GameRenderOptions {
  std::string preset_path;                          // preset JSON; empty: DefaultPresetPath()
  std::array<double, 3> sun_dir = {0.0, 1.0, 0.0};  // unit vector toward the sun, +Y up (core/latlong.h)
  int width = 1024, height = 512;                   // pixels, a 2:1 lat-long (width = 2 x height)
  render::Backend backend = render::Backend::kVulkan;  // Vulkan: the game's compute shaders; CPU: the double reference
  render::GroundMode ground = render::GroundMode::kLit;
  bool sun_disc = true;
  bool vulkan_validation = false;                   // VK_LAYER_KHRONOS_validation
  GameCloudOptions clouds;
  // A scale on the final radiance (sky and clouds), finite and > 0: a fit's exposure, so
  // that the image is in the photo's units. 1: cd/m^2.
  double exposure = 1.0;
  bool verbose = true;  // progress lines (the backend, the file written); warnings are always given
  // Where progress lines and warnings go, one line each without a prefix (a verb writes the
  // fields named in them as its flags). Empty: standard error, as "[render] LINE".
  std::function<void(const std::string&)> log;

  // False and the field, its value and the expectation in *why.
  bool IsValid(std::string* why) const;
};

struct GameImage {
  ImageRGB radiance;                       // lat-long, cd/m^2 x exposure per channel, scene-linear Rec.709
  std::vector<float> cloud_transmittance;  // per pixel in [0, 1], row-major; empty without clouds
  std::array<double, 3> sun_dir{};         // the unit vector rendered
  std::string preset_path;                 // the preset rendered (DefaultPresetPath() when none was given)
  bool clouds_drawn = false;
  std::string clouds_origin;               // the file the clouds section came from (clouds drawn)
  std::string weather_map_origin;          // the weather map EXR (clouds drawn)
  // `skycal render --json`'s pieces: backend, device, preset, model, sun_direction,
  // sun_elevation_deg, sun_azimuth_deg, size, clouds (null without), warnings and time_ms
  // (milliseconds: init, render = sky + clouds).
  nlohmann::json summary;
};

// Renders the sky (and the clouds) in memory. Throws skycal::Error naming the field or file
// at fault (an invalid option, a preset or cloud section that does not load, a backend
// failure).
GameImage RenderGameImage(const GameRenderOptions& options);

struct GameRenderFileOptions {
  GameRenderOptions render;
  std::string out_exr;  // required, *.exr: envmap=latlong, sunDirection and skycal* attributes
  std::string out_png;  // optional, *.png: the preview through the OCIO view transform ($OCIO or config/skycal.ocio)
  bool half = false;    // half floats instead of float
  // The preview's exposure in stops, within [-64, 64]; NaN: automatic (log-average -> 0.18).
  double png_exposure_ev = std::numeric_limits<double>::quiet_NaN();
  std::optional<double> time_of_day_h;  // hours in [0, 24): the skycalTimeOfDay attribute (fit records it, batch orders by it)

  bool IsValid(std::string* why) const;  // as GameRenderOptions::IsValid, the outputs as well
};

// RenderGameImage, then the EXR (and the PNG) committed together: a failed preview leaves
// every file as it was. Outputs never replace the preset, its LUTs or the weather map, and
// both are checked writable before any render. Returns `skycal render --json`'s summary.
// Throws skycal::Error.
nlohmann::json WriteGameRender(const GameRenderFileOptions& options);

}  // namespace skycal::controllers
