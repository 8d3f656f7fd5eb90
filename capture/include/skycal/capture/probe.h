// The gray diffuse probe (Wood, Forza Horizon 3 skies, GDC): a matte gray ball photographed in every frame.
// Its radiance, binned by surface normal, is what the sky + sun must reproduce ("diffuse
// probe + key light = this value"); its maximum luminance (the Forza statistic) dips to the
// ambient level when the sun is behind cloud; and, as in Debevec et al. 2003 ("Capturing
// light probes in the sun"), it lets a clipped sun's illuminance be recovered by linear
// least squares from the ball's unclipped pixels once the sky's irradiance is known.
//
// Camera model: ORTHOGRAPHIC. A distant ball (distance D >> radius r) is seen along
// parallel rays, so the pixel at normalised offset (u, v) = ((x - cx) / r, (y - cy) / r)
// from the ball's centre shows the surface point whose normal, in the camera frame of
// capture/lens.h (+X image right, +Y image down, +Z the viewing direction), is
//   n_cam = (u, v, -sqrt(1 - u^2 - v^2))        (it faces the camera: n_cam.z <= 0),
// and n_world = R * n_cam with R the camera-to-world rotation (as RigCamera::rotation in
// capture/rig.h; world = the project's lat-long frame, +Y up). For a pinhole camera at
// distance D the true normals differ by up to about asin(r / D) / 2 at the rim (under 1.5
// degrees for D > 10 r) and the rim normals are not seen at all; the outer edge_fraction
// of the radius (grazing normals, also where the ball's silhouette blurs) is rejected.
//
// Pixel centres sit at integer coordinates, (0, 0) the centre of the top-left pixel
// (core/latlong.h, capture/lens.h); the circle's centre uses the same coordinates.
//
// Binning: the visible normals (angle theta from the direction toward the camera, theta
// up to asin(1 - edge_fraction)) are split into `rings` rings of equal theta width, each
// cut into azimuth sectors of about the same angular width (so bins of roughly equal
// solid angle). A bin's sample is the mean radiance of its accepted pixels and the
// normalised mean of their normals.
#pragma once
#include <array>
#include <limits>
#include <optional>
#include <vector>

#include "skycal/core/image.h"

namespace skycal::capture {

struct BallCircle {
  double cx = 0.0, cy = 0.0;  // centre, pixels (pixel centres at integer coordinates)
  double radius_px = 0.0;
};

struct ProbeSample {
  std::array<double, 3> normal{};    // unit surface normal, world frame (+Y up)
  std::array<double, 3> radiance{};  // mean linear RGB radiance of the bin's accepted pixels
  int pixels = 0;                    // accepted pixels averaged
};

struct BallDetectOptions {
  double min_radius_px = 8.0;
  double max_radius_px = 0.0;  // 0: half the image's shorter side
  bool refine = true;          // least-squares circle fit to the edge pixels near the Hough circle
};

struct ProbeOptions {
  // A pixel with any channel >= clip_level is saturated (sensor or merge clamp) and rejected.
  // Default: nothing is treated as clipped; set it to the merge's saturation level.
  double clip_level = std::numeric_limits<double>::infinity();
  double edge_fraction = 0.1;     // reject the outer edge_fraction of the radius (grazing normals)
  int rings = 12;                 // theta rings of the binning (>= 1)
  int min_pixels_per_sample = 4;  // bins with fewer accepted pixels give no sample
  BallDetectOptions detect;       // used when no circle is given
};

struct ProbeMeasurement {
  BallCircle circle;                 // the circle used (given or detected)
  std::vector<ProbeSample> samples;  // non-empty
  // The Forza statistic: the maximum Rec.709 luminance over the ball's finite pixels
  // (edge ring included, clipped pixels included: then it is a lower bound, and
  // max_luminance_clipped says so).
  double max_luminance = 0.0;
  bool max_luminance_clipped = false;
  int pixels_total = 0;      // pixel centres inside the circle
  int pixels_used = 0;       // accepted into samples
  int pixels_clipped = 0;    // rejected: some channel >= clip_level (inside the edge ring)
  int pixels_nonfinite = 0;  // rejected: NaN or infinite channel (inside the edge ring)
};

// Finds one ball: cv::HoughCircles (gradient method) on a tone-mapped, blurred 8-bit copy
// of the image's luminance, then (options.refine) an algebraic least-squares circle fit to
// the Canny edge pixels within 6% of the radius of the Hough circle. The strongest circle
// wins. Throws skycal::Error when the image is empty or no circle is found.
BallCircle DetectBall(const ImageRGB& image, const BallDetectOptions& options = {});

// Samples the ball. `circle` empty: DetectBall(image, options.detect). camera_to_world:
// row-major 3x3 (world = R * camera), must be a rotation. Throws skycal::Error naming what:
// empty image, bad options, a circle not wholly inside the image ("ball ... outside the
// image"), a non-rotation, no usable sample (ball fully clipped / non-finite).
ProbeMeasurement MeasureProbe(const ImageRGB& image, const std::array<double, 9>& camera_to_world,
                              const std::optional<BallCircle>& circle = std::nullopt,
                              const ProbeOptions& options = {});

// World normal seen at image position (x, y) on the ball (orthographic model above), or
// nothing outside the circle. Exposed for tests and renderers of synthetic probes.
std::optional<std::array<double, 3>> BallNormalAt(const BallCircle& circle, const std::array<double, 9>& camera_to_world,
                                                   double x, double y);

// ---- Sun recovery (Debevec et al. 2003) ----------------------------------------------
//
// Model per sample i and channel c:
//   R_i,c = albedo_c / pi * (E_sky,c(n_i) + E_sun,c * max(0, n_i . s))
// with E_sky(n_i) the irradiance of the sky WITHOUT the sun at normal n_i (computed
// elsewhere, e.g. from the fitted sky model or the frame) and s the unit sun direction.
// E_sun,c is the sun's illuminance on a surface facing it (same units as E_sky), solved per
// channel in closed form: E = sum c_i y_i / sum c_i^2 with c_i = max(0, n_i . s) and
// y_i = pi R_i / albedo - E_sky(n_i), clamped at 0.
//
// Visibility: sun_fraction = the fitted sun term's share of the measured luminance over the
// brightest samples (the top `bright_fraction` of sun-facing samples by luminance, at least
// one). Below visible_threshold the probe sits at the ambient level: the sun is occluded
// (cloud), visible = false and sun_illuminance = 0, the fit kept in fitted_sun_illuminance.
struct SunRecoveryOptions {
  double visible_threshold = 0.25;
  double bright_fraction = 0.1;
  int min_sun_facing_samples = 3;  // samples with n . s > 0.05 needed to solve
};

struct SunRecovery {
  std::array<double, 3> sun_illuminance{};         // = fitted_sun_illuminance when visible, else 0
  bool visible = false;
  double sun_fraction = 0.0;                       // see above, in [0, 1] for a sane fit
  double residual_rms_rel = 0.0;                   // RMS(R - model) / RMS(R), all samples and channels
  std::array<double, 3> fitted_sun_illuminance{};  // the least-squares fit, whatever the decision
  int samples_used = 0;
  int sun_facing_samples = 0;
};

// The sun's share of the probe: over the brightest sun-facing samples (sun_cos > 0.05; the
// top bright_fraction of them by measured Rec.709 luminance, at least one), the luminance
// of the sun term sun_radiance[i] over the measured luminance. Used for the visibility
// decision (here and in the joint fit, fit/src/sky_fit.cc). Throws on size mismatch.
double SunShareOfBrightest(const std::vector<ProbeSample>& samples, const std::vector<std::array<double, 3>>& sun_radiance,
                           const std::vector<double>& sun_cos, double bright_fraction);

// albedo: RGB reflectance of the ball (0 < albedo <= 1 typical; > 0 required).
// sky_irradiance[i]: E_sky at samples[i].normal (same size as samples). sun_direction: any
// non-zero vector (normalised here). Throws skycal::Error on size mismatch, non-positive
// albedo, non-finite input, a zero sun direction, or fewer than min_sun_facing_samples
// samples facing the sun (E_sun is then not observable from this view).
SunRecovery RecoverSun(const std::vector<ProbeSample>& samples, const std::array<double, 3>& albedo,
                       const std::vector<std::array<double, 3>>& sky_irradiance,
                       const std::array<double, 3>& sun_direction, const SunRecoveryOptions& options = {});

}  // namespace skycal::capture
