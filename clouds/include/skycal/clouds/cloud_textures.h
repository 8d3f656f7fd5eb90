// The textures the Horizon Zero Dawn cloudscape samples (Schneider, "The Real-time
// Volumetric Cloudscapes of Horizon Zero Dawn", SIGGRAPH 2015): three tileable noise
// volumes and a weather map. Plain float arrays: both backends read the same texels and
// filter them with exact trilinear/bilinear weights in the shared model source (no
// hardware filtering in anything the fit differentiates or the parity test compares).
//
// Layout contract (shared by the generator, the cache, the CPU reference and the Vulkan
// texel buffers): texel (x, y, z) of an N^3 volume with C channels sits at
// ((z * N + y) * N + x) * C + c; a 2D N^2 texture at (y * N + x) * C + c. Every texture
// tiles: texel N wraps to texel 0.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace skycal::clouds {

struct CloudNoise {
  static constexpr int kBaseSize = 128;    // base shape volume, 128^3 RGBA
  static constexpr int kDetailSize = 32;   // detail erosion volume, 32^3 RGB
  static constexpr int kCurlSize = 128;    // curl turbulence, 128^2 RGB
  uint64_t seed = 0;
  // R: Perlin-Worley, G/B/A: Worley at 3 increasing frequencies; each in [0, 1].
  std::vector<float> base;
  // R/G/B: Worley at 3 increasing frequencies, each in [0, 1].
  std::vector<float> detail;
  // Curl of a tileable vector noise: a divergence-free 2D distortion (x, z) in the
  // horizontal plane plus a third component; each in [-1, 1].
  std::vector<float> curl;
  // Of the three arrays' bytes in the order above (hex). Set only by the makers that
  // validate the values (GenerateCloudNoise, LoadOrGenerateCloudNoise): renders then check
  // the sizes only. Code that changes the arrays must clear it (or recompute it after
  // ValidateCloudNoise); noise without it is validated in full on every render.
  std::string sha256;
};

// A world-space weather map (HZD): R coverage, G precipitation, B cloud type (0 stratus,
// 0.5 cumulus, 1 cumulonimbus), each in [0, 1]. Texel (x, y) covers world
// x in [-extent/2, extent/2) left to right and z in [-extent/2, extent/2) top to bottom
// (row 0 at -z), centred on the camera; it tiles beyond its extent.
struct WeatherMap {
  int width = 0, height = 0;
  double extent_m = 0.0;    // metres covered by the map along x and z
  std::vector<float> rgb;   // width * height * 3, row 0 at the top
};

}  // namespace skycal::clouds
