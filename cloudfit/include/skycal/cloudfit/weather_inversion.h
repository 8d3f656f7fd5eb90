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
// One viewpoint sees each column of the layer along one azimuth, over a range of elevations
// (a texel 10 km away spans about 10 to 18 degrees from the base to 70% of the layer): a
// 2D map cannot put cloud in part of a column, so the first guess carves (space carving,
// Kutulakos & Seitz, IJCV 2000, with one camera): a clear pixel empties every texel its ray
// crosses at that height, which caps the texel's cloud top (written as the cloud type: the
// march's height gradients end near 30% of the layer for stratus, 70% for cumulus) and bounds its coverage by the clearest pixel that crosses it. Precipitation
// is cleared where the photo constrains the map (it would push the texel to a cumulonimbus the
// photo did not show).
//
// The march's coverage -> opacity relation is monotone (what the base noise keeps above
// 1 - coverage grows with coverage), so the map is then refined with renders: a pixel
// rendered too opaque thins, and one rendered too clear thickens, every texel its ray crosses
// below the texel's cloud top; each texel moves by gain x the mean of what its pixels ask, so
// where the rays that cross a texel disagree the clear ones hold it down. (Thickening only the
// first texel a too-clear ray meets, the one the march would show, pulled cloud toward the
// camera: opacity RMS and IoU worse on every map of `skycal bench --suite weather-inversion`,
// bench/results/weather_inversion.md.)
#pragma once
#include <array>
#include <functional>
#include <string>
#include <vector>

#include "skycal/clouds/cloud_params.h"
#include "skycal/clouds/cloud_textures.h"

namespace skycal::cloudfit {

// The links between the texels of the map (row-major) and the pixels of a `width` x `height`
// lat-long (core/latlong.h): the sparse pattern of the Jacobian of pixel opacity by texel
// coverage, as each pixel's samples (`rays`: a (pixel, texel) pair per sample).
struct WeatherTexelView {
  int map_width = 0, map_height = 0, width = 0, height = 0;
  std::vector<char> linked;  // per texel (row-major): 1 when some pixel's ray or centre link reaches it
  int constrained = 0;       // texels linked
  // Each sky pixel's ray through the layer, front to back: the texel under each sample and
  // the sample's height fraction in the layer (0 base, 1 top).
  struct RaySample {
    int pixel = 0, texel = 0;
    float fraction = 0.0f;
  };
  std::vector<RaySample> rays;  // grouped by pixel, each pixel's samples in order
  // Where the camera stands on the map, m from its centre (x, z), one per frame: at the
  // wind's offset (clouds::WindOffsetM), where the march samples camera-relative (0, 0).
  std::vector<std::array<double, 2>> cameras;
};

// The tallest cloud type whose column is clear from `top` (a fraction of the layer) up:
// cumulus (0.5) from 0.6 up, else stratus (0). A blend of the two keeps cumulus up to 0.7 of
// the layer, and the tops the photo never sees are taken as cumulus, not cumulonimbus.
double CloudTypeForTop(double top);

struct CarveOptions {
  double clear_opacity = 0.3;   // a pixel below this opacity is clear sky
  double cumulus_top = 0.7;     // a column no clear pixel caps is taken as cumulus (its top unseen)
  // Below this height fraction every cloud type has cloud: a clear pixel there empties the
  // texel. A texel no pixel crosses that low takes the lowest opacity of the pixels crossing
  // it below fallback_top, else keeps its coverage. 0.15 / 0.4 against 0.3 / none: opacity
  // RMS lower on every map of `skycal bench --suite weather-inversion` (painted blobs 0.089
  // -> 0.052 with a 128-texel map), and on `sky` 0.234 -> 0.217.
  double base_top = 0.15;
  double fallback_top = 0.4;
  // Coverage per unit opacity: 1 makes a texel that every crossing pixel sees opaque fully
  // covered (the refinement thins it where the render is denser than the photo).
  double gain = 1.0;
};

// The first guess: each constrained texel's coverage = gain x the lowest opacity of the
// pixels crossing it below base_top (else below fallback_top; a texel no pixel crosses that
// low keeps its coverage), its type = CloudTypeForTop(the lowest height at
// which a clear pixel crosses it, at most cumulus_top), its precipitation 0; unconstrained
// texels unchanged. `opacity`: width * height values in [0, 1].
void CarveCoverage(const WeatherTexelView& view, const std::vector<float>& opacity, const CarveOptions& options,
                   clouds::WeatherMap* map);

// `sky`: width * height weights (>= 0.5 sky) or empty (every pixel above the horizon).
// `time_s`: the frame's time in the march's wind (p.wind_speed_m_s, p.wind_direction_deg),
// as clouds::CloudRenderRequest::time_s.
WeatherTexelView ProjectWeatherTexels(const clouds::CloudParams& p, int map_width, int map_height, int width, int height,
                                      const std::vector<float>& sky, double time_s = 0.0);

// Several frames of one sky as one view: consecutive time-lapse frames see the same map moved
// by the wind, each from another place on it, so a texel that one frame sees along a ray's
// length another sees across its rays (with one camera, the opacity says how much cloud a ray
// met, not where along it). Frame k's pixels become pixels k x width x height + p of a view
// `height` x frames rows tall (the frames' opacities concatenated in order); a texel is linked
// when any frame links it. Carving and refinement then run unchanged over every frame's rays.
// Throws skycal::Error when the views differ in map or image size, or none is given.
WeatherTexelView StackWeatherViews(const std::vector<WeatherTexelView>& views);

// The first guess: each constrained texel's coverage = clamp(gain x the mean opacity of its
// pixels); unconstrained texels unchanged. `opacity`: width * height values in [0, 1].
void SeedCoverage(const WeatherTexelView& view, const std::vector<float>& opacity, double gain, clouds::WeatherMap* map);

// One refinement step (the rule above): coverage moves by gain x the mean of what the
// texel's pixels ask, clamped to [0, 1]. Returns the RMS of (rendered - photo) over the
// linked pixels (each counted once) before the step.
double RefineCoverage(const WeatherTexelView& view, const std::vector<float>& photo_opacity,
                      const std::vector<float>& rendered_opacity, double gain, clouds::WeatherMap* map);

// Resolution by distance: what the photo resolves. A pixel of the view's lat-long spans
// d x 2 pi / width metres across at horizontal distance d; each constrained texel's coverage
// becomes the mean of the constrained texels within half that footprint (a box; none near the
// zenith, where a texel is wider than a pixel), so that texels between two far pixels' rays
// follow their neighbours instead of keeping a seed the photo never saw.
void SmoothCoverageByFootprint(const WeatherTexelView& view, double weather_extent_m, clouds::WeatherMap* map);
// The same for another channel of the map (0 coverage, 1 precipitation, 2 type).
void SmoothChannelByFootprint(const WeatherTexelView& view, double weather_extent_m, int channel, clouds::WeatherMap* map);

// The light inside the clouds. The opacity says where cloud is, not how the light falls inside
// it: once a column is opaque its coverage hardly changes its pixels' light
// (bench/results/weather_inversion.md, "The light inside the clouds"), so the shapes' light
// is the noise's, not the photo's. The map's precipitation is the lever the game
// gives: its rain absorption darkens a column (HZD's weather map; cloud_march.glsl.h) with
// little change to where its cloud is. One Gauss-Newton step per pixel, its derivatives from
// two lit renders: at the map (`at`) and with the channel of every constrained texel raised by
// `delta` (`raised`). Each pixel asks the change that best fits its opacity (every linked pixel)
// and its log luminance (where both `photo` and `at` give one; NaN elsewhere), at most
// max_step; each texel below its cloud top moves by the mean of what its pixels ask, within
// [0, 1]. The sign of the response is read, not assumed.
struct LitPixels {
  std::vector<float> opacity;        // 1 - transmittance, per pixel of the view's lat-long
  std::vector<float> log_luminance;  // ln Y, NaN where the pixel does not count
};
struct LightRefineOptions {
  // The map's channel refined: 1, precipitation. (0, coverage: its light barely moves where
  // the photo is opaque, and the opacity it moves instead made the image worse,
  // bench/results/weather_inversion.md.)
  int channel = 1;
  double delta = 0.3;     // the raise of the second render (a difference, not a tangent: the
                          // march's response is flat for small changes of precipitation)
  double max_step = 0.5;  // per step, at most
  double damping = 1e-3;  // added to each pixel's Gauss-Newton denominator (per unit channel^2)
  // Each pixel's step the mean of those within this many pixels: without it the rain followed
  // each pixel's texture, and the game's clouds near the horizon alternated from column to
  // column more than the photo's (bench/results/weather_inversion.md).
  int pixel_radius = 1;
  bool IsValid(std::string* why) const;  // false: LightRefineOptions::<field>, value and expectation
};
struct LightRefineStep {
  double log_rms = 0.0;  // RMS of the ln Y residual (at - photo) over the pixels that have one
  int pixels = 0;        // pixels with a ln Y residual
  int texels_moved = 0;  // texels whose channel changed by more than 0.001
};
// The second render's map: the channel of every constrained texel raised by delta (at most 1).
clouds::WeatherMap RaisedMap(const WeatherTexelView& view, const clouds::WeatherMap& map, const LightRefineOptions& options);
// Throws skycal::Error naming the field when the options or the pixels' sizes are wrong.
LightRefineStep RefineByLight(const WeatherTexelView& view, const LitPixels& photo, const LitPixels& at,
                              const LitPixels& raised, const LightRefineOptions& options, clouds::WeatherMap* map);

// The light inside the clouds, texel by texel, in coverage. Once a column is opaque its
// coverage hardly moves its opacity, but it moves its light: its density, self-shadowing and
// the shadow it casts on its neighbours (bench/results/weather_inversion.md, "How much the
// light sees inside an opaque column"). Raising every texel at once, as RefineByLight does,
// sums a texel's effect on its own rays with its shadow on others' and cannot tell them
// apart. Here each iteration moves every constrained texel's coverage by +-delta, the sign
// drawn at random per texel (simultaneous perturbation, Spall 1992, IEEE TAC 37(3)): a
// pixel's change over delta, times a texel's sign, estimates that texel's derivative for the
// pixels whose rays cross it, the other texels' moves being noise of zero mean. Each texel
// then takes the Gauss-Newton step of its pixels (ln Y where both images give one, and the
// opacity, weighted by opacity_weight, wherever the view links a pixel), at most max_step;
// the step is kept when the whole cost falls. Two renders an iteration: the perturbed map,
// and the stepped one (the next iteration's start).
struct CoverageLightOptions {
  int iterations = 8;
  double delta = 0.1;           // the perturbation of coverage
  double max_step = 0.1;        // per texel and iteration, at most
  double opacity_weight = 4.0;  // of the opacity's squared residual against ln Y's (keeps the shapes where they are)
  unsigned seed = 1;            // the signs' generator (std::mt19937): the same map, the same result
  bool IsValid(std::string* why) const;  // false: CoverageLightOptions::<field>, value and expectation
};
struct CoverageLightResult {
  // At the start, then after each iteration (a rejected step repeats the previous values).
  std::vector<double> log_rms, opacity_rms;
  int kept = 0;  // iterations whose step was kept
};
// `render`: the game's lit image of a map at the view's size (LitPixels: ln Y NaN where a pixel
// does not count, the same pixels for every map). Throws skycal::Error naming the field when
// the options or the pixels' sizes are wrong.
CoverageLightResult RefineCoverageByLight(const WeatherTexelView& view, const LitPixels& photo,
                                          const std::function<LitPixels(const clouds::WeatherMap&)>& render,
                                          const CoverageLightOptions& options, clouds::WeatherMap* map);

// The inverted map's texels a side (calibrate resamples a coarser statistics map to it first):
// over HZD's 60 km extent a 256 map's texel is 234 m, about 5 degrees seen from under a
// 2.75 km mid-layer, so the photo's zenith, its finest detail on the layer, averages into
// partial coverage; 512 gives 117 m. Finer (1024) costs more than it gains on the bundled
// partly cloudy photo (bench/results/calibrate.md).
inline constexpr int kInvertedMapSize = 512;

// The whole inversion: carve, smooth, then `refinements` times render (the march's opacity,
// view.width x view.height, through `render_opacity` of the current map), refine by `step`
// and smooth. Returns the RMS of rendered - photo opacity of each render.
struct InversionOptions {
  CarveOptions carve;
  // The opacity RMS flattens by about the sixth render at 512 pixels wide
  // (bench/results/weather_inversion.md).
  int refinements = 6;
  // Coverage per unit opacity error: the march's opacity grows about twice as fast as the
  // mean coverage at partly cloudy coverages (the statistics fit's matched coverage steps).
  double step = 0.5;
};
std::vector<double> InvertWeatherMap(const WeatherTexelView& view, double weather_extent_m,
                                     const std::vector<float>& photo_opacity,
                                     const std::function<std::vector<float>(const clouds::WeatherMap&)>& render_opacity,
                                     const InversionOptions& options, clouds::WeatherMap* map);

}  // namespace skycal::cloudfit
