// Lens models: the mapping between a camera's image positions and the rays it sees.
//
// Camera frame (OpenCV's, so Kannala-Brandt goes through cv::fisheye unchanged): the camera
// looks along +Z (the optical axis); +X points toward increasing image column (right in
// the image), +Y toward increasing image row (down in the image). Right-handed.
//
// Image coordinates follow the project convention (core/latlong.h): pixel centres at
// integer coordinates, (0, 0) the centre of the top-left pixel, x right, y down.
//
// Fisheye models put the ray at angle theta from the optical axis and azimuth phi =
// atan2(Y, X) at  pixel = (center_x, center_y) + rho(theta) * (cos phi, sin phi),  with
//   equidistant     rho = f theta
//   equisolid       rho = 2 f sin(theta / 2)
//   stereographic   rho = 2 f tan(theta / 2)
//   kannala-brandt  rho = f theta_d,  theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8)
//                   (OpenCV's fisheye model, fx = fy = f, no skew)
// and f chosen so that rho(fov / 2) = radius_px: the image circle is the edge of the field
// of view. Rays beyond fov / 2 are not seen; pixels beyond the circle see nothing.
//
// Kannala-Brandt goes through cv::fisheye::distortPoints / undistortPoints where OpenCV's
// model is defined: it normalises rays by Z (x = X/Z), so it covers theta < 90 degrees only
// (and OpenCV 4.6 clips theta_d at pi/2). Rays at or beyond 90 degrees (fisheyes wider than
// 180 degrees) use the same polynomial evaluated here, inverted by safeguarded Newton;
// tests/lens_unwrap_test.cc checks both paths agree.
//
// The lat-long model is a full panorama in the project convention (core/latlong.h) as
// seen from the camera frame: a camera with yaw = pitch = roll = 0 (rig.h) sees it exactly
// as the world lat-long. It needs fov_deg = 360, center = ((W-1)/2, (H-1)/2),
// radius_px = (W-1)/2 (the pixels spanning 180 degrees of longitude), W = 2 H; LatLongLens()
// fills them.
//
// Vignetting: the lens multiplies scene radiance by gain(r) = 1 + a r^2 + b r^4 + c r^6,
// r = distance from the centre / radius_px (Hugin's and Adobe's radial falloff model);
// correction divides by it. Fisheye models only (zero for lat-long).
#pragma once
#include <array>
#include <optional>
#include <span>
#include <string>

namespace skycal::capture {

enum class LensModel { kLatLong, kEquidistant, kEquisolid, kStereographic, kKannalaBrandt };

// "latlong", "equidistant", "equisolid", "stereographic", "kannala-brandt".
const char* LensModelName(LensModel model);
std::optional<LensModel> LensModelFromName(const std::string& name);

struct LensParams {
  LensModel model = LensModel::kEquisolid;
  double fov_deg = 180.0;                  // full field of view across the image circle
  double center_x = 0.0, center_y = 0.0;   // optical centre, pixels
  double radius_px = 0.0;                  // image circle radius (the fov edge), pixels
  std::array<double, 4> kb_k{};            // Kannala-Brandt k1..k4 (OpenCV fisheye D)
  std::array<double, 3> vignetting{};      // a, b, c of gain(r) = 1 + a r^2 + b r^4 + c r^6

  // False, with the field at fault and what was expected in *why (may be null), unless
  // the parameters describe a usable lens for a width x height image:
  //   fov_deg in (0, 360] (stereographic < 360; lat-long exactly 360); radius_px > 0;
  //   the centre inside the image; the image circle not wholly outside the image (radius
  //   at most the distance from the centre to the farthest corner: circles cropped by the
  //   frame, as with full-frame fisheyes, are fine); Kannala-Brandt theta_d increasing
  //   over the fov; vignetting gain > 0 over the circle; everything finite.
  bool IsValid(std::string* why, int image_width, int image_height) const;
};

// The lat-long "lens" of a width x height panorama in the project convention.
LensParams LatLongLens(int width, int height);

using Vec2d = std::array<double, 2>;
using Vec3d = std::array<double, 3>;

// Focal length f of the fisheye models (pixels per radian at the centre); for lat-long
// the pixels per radian of longitude. Assumes IsValid.
double FocalLengthPx(const LensParams& lens);
// rho(theta) / f of the model (theta in radians): the normalised image radius.
double NormalisedRadius(const LensParams& lens, double theta);
// Its inverse on [0, fov / 2]; nullopt where no angle in that range maps to rho_over_f.
std::optional<double> AngleFromNormalisedRadius(const LensParams& lens, double rho_over_f);

// Image position of a camera-frame ray (need not be unit length); nullopt when the ray is
// outside the field of view (or zero / non-finite). When `jacobian` is given it receives
// d(pixel)/d(ray) at the unit ray, row-major 2x3, valid for perturbations perpendicular to
// the ray (pixels per radian): the local footprint used to choose a filter.
std::optional<Vec2d> RayToPixel(const LensParams& lens, const Vec3d& ray, std::array<double, 6>* jacobian = nullptr);
// Unit camera-frame ray seen at an image position; nullopt outside the image circle.
std::optional<Vec3d> PixelToRay(const LensParams& lens, const Vec2d& pixel);

// Batched forms (one OpenCV call per batch for Kannala-Brandt). valid[i] = 0 where the
// single-point form returns nullopt (the output element is then left unspecified).
// `jacobians`, when not empty, receives RayToPixel's jacobian per ray.
void RaysToPixels(const LensParams& lens, std::span<const Vec3d> rays, std::span<Vec2d> pixels,
                  std::span<unsigned char> valid, std::span<std::array<double, 6>> jacobians = {});
void PixelsToRays(const LensParams& lens, std::span<const Vec2d> pixels, std::span<Vec3d> rays,
                  std::span<unsigned char> valid);

// gain(r) at an image position (1 for lat-long); divide observed values by it.
double VignettingGain(const LensParams& lens, const Vec2d& pixel);

}  // namespace skycal::capture
