// The photo's clouds where the photo has them: a weather map whose coverage makes the
// game's own cloud march put cloud where the photograph sees cloud (Dobashi et al. recover
// cloud density from one photograph, CGF 2010; here the unknown is the game's weather map,
// and the forward model is the game's march).
//
// Texels and pixels are linked through the march's geometry (clouds/model/cloud_geometry.glsl.h:
// spheres of radius planet_radius + altitude around the planet's centre (0, -(R +
// camera_height), 0)): a pixel's ray crosses the layer between its base and top, and every
// texel under the crossing (sampled at kLayerSamples altitudes) is linked to it; each texel
// is also linked to the pixel that sees its centre at the layer's mid altitude (so that no
// texel between two far pixels is left out). A texel is constrained when it has a link to a
// sky pixel above the horizon within the draw distance; the others (below the horizon,
// behind buildings, beyond the draw distance) keep the statistical map's coverage.
//
// The march's coverage -> opacity relation is monotone (what the base noise keeps above
// 1 - coverage grows with coverage), so the map is refined with renders: each constrained
// texel's coverage moves by gain x (photo opacity - rendered opacity) at its pixel.
#pragma once
#include <vector>

#include "skycal/clouds/cloud_params.h"
#include "skycal/clouds/cloud_textures.h"

namespace skycal::cloudfit {

// The links between the texels of the map (row-major) and the pixels of a `width` x `height`
// lat-long (core/latlong.h): the sparse pattern of the Jacobian of pixel opacity by texel
// coverage.
struct WeatherTexelView {
  int map_width = 0, map_height = 0, width = 0, height = 0;
  std::vector<std::pair<int, int>> links;  // (texel, pixel)
  int constrained = 0;                     // texels with at least one link
};

// `sky`: width * height weights (>= 0.5 sky) or empty (every pixel above the horizon).
WeatherTexelView ProjectWeatherTexels(const clouds::CloudParams& p, int map_width, int map_height, int width, int height,
                                      const std::vector<float>& sky);

// The first guess: each constrained texel's coverage = clamp(gain x the mean opacity of its
// pixels); unconstrained texels unchanged. `opacity`: width * height values in [0, 1].
void SeedCoverage(const WeatherTexelView& view, const std::vector<float>& opacity, double gain, clouds::WeatherMap* map);

// One refinement step: coverage += gain x the mean (photo - rendered) opacity of each
// constrained texel's pixels, clamped to [0, 1]. Returns the RMS of (rendered - photo) over
// the linked pixels (each counted once) before the step.
double RefineCoverage(const WeatherTexelView& view, const std::vector<float>& photo_opacity,
                      const std::vector<float>& rendered_opacity, double gain, clouds::WeatherMap* map);

// A lat-long of width x height box-averaged to out_width x out_height (integer factors).
std::vector<float> DownsampleLatLong(const std::vector<float>& values, int width, int height, int out_width, int out_height);

}  // namespace skycal::cloudfit
