#include "skycal/capture/lens.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "skycal/core/math_constants.h"

namespace skycal::capture {
namespace {

// Kannala-Brandt rays within this of 90 degrees (and beyond) skip OpenCV: its pinhole
// normalisation x = X / Z degenerates there.
constexpr double kOpenCvThetaLimit = kPi / 2 - 1e-6;

bool Fail(std::string* why, const std::string& message) {
  if (why) *why = message;
  return false;
}

std::string Num(double v) {
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

double HalfFovRad(const LensParams& lens) { return 0.5 * lens.fov_deg * kPi / 180.0; }

double KbPoly(const std::array<double, 4>& k, double t) {
  const double t2 = t * t;
  return t * (1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3]))));
}
double KbPolyDerivative(const std::array<double, 4>& k, double t) {
  const double t2 = t * t;
  return 1.0 + t2 * (3.0 * k[0] + t2 * (5.0 * k[1] + t2 * (7.0 * k[2] + t2 * 9.0 * k[3])));
}

// d rho / d theta divided by f.
double NormalisedRadiusDerivative(const LensParams& lens, double theta) {
  switch (lens.model) {
    case LensModel::kEquisolid: return std::cos(0.5 * theta);
    case LensModel::kStereographic: {
      const double c = std::cos(0.5 * theta);
      return 1.0 / (c * c);
    }
    case LensModel::kKannalaBrandt: return KbPolyDerivative(lens.kb_k, theta);
    case LensModel::kEquidistant:
    case LensModel::kLatLong: return 1.0;
  }
  return 1.0;
}

// Safeguarded Newton for the Kannala-Brandt polynomial on [0, hi] (increasing there).
double KbInverse(const std::array<double, 4>& k, double target, double hi) {
  double lo = 0.0, t = std::min(target, hi);
  for (int i = 0; i < 100; ++i) {
    const double g = KbPoly(k, t) - target;
    if (g > 0) hi = t; else lo = t;
    const double d = KbPolyDerivative(k, t);
    double next = t - g / d;
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const double step = std::abs(next - t);
    t = next;
    if (step <= 1e-16 * std::max(1.0, t)) break;
  }
  return t;
}

cv::Matx33d CameraMatrix(const LensParams& lens, double f) {
  return cv::Matx33d(f, 0, lens.center_x, 0, f, lens.center_y, 0, 0, 1);
}

// Fisheye image position from the angle off axis; also the jacobian when asked.
Vec2d FisheyePixel(const LensParams& lens, double f, const Vec3d& u, double s, double theta, std::array<double, 6>* jac) {
  const double rho = f * NormalisedRadius(lens, theta);
  Vec2d p{lens.center_x, lens.center_y};
  if (s > 0) {
    p[0] += rho * u[0] / s;
    p[1] += rho * u[1] / s;
  }
  if (jac) {
    if (s < 1e-12) {
      // On the axis every model has d rho / d theta = rho / sin(theta) = f.
      const double sign = u[2] >= 0 ? 1.0 : -1.0;
      *jac = {f * sign, 0, 0, 0, f * sign, 0};
    } else {
      const double cr = u[0] / s, sr = u[1] / s;                 // radial image direction
      const Vec3d e_theta{cr * u[2], sr * u[2], -s};             // d ray / d theta
      const Vec3d e_phi{-sr, cr, 0.0};                           // d ray / (sin theta d phi)
      const double radial = f * NormalisedRadiusDerivative(lens, theta);
      const double tangential = rho / s;
      for (int c = 0; c < 3; ++c) {
        (*jac)[c] = radial * cr * e_theta[c] - tangential * sr * e_phi[c];
        (*jac)[3 + c] = radial * sr * e_theta[c] + tangential * cr * e_phi[c];
      }
    }
  }
  return p;
}

// Lat-long model: camera ray -> world-aligned direction d = (-X, -Y, Z).
Vec2d LatLongPixel(const LensParams& lens, const Vec3d& u, std::array<double, 6>* jac) {
  const double dx = -u[0], dy = -u[1], dz = u[2];
  const double h = std::hypot(dx, dz);
  const double lon = std::atan2(dx, dz), lat = std::atan2(dy, h);
  const double sx = lens.center_x / kPi, sy = 2.0 * lens.center_y / kPi;
  if (jac) {
    const double hh = std::max(h, 1e-9);
    // d lon / d d = (dz, 0, -dx) / h^2; d lat / d d = (-dy dx / h, h, -dy dz / h).
    const Vec3d dlon{dz / (hh * hh), 0.0, -dx / (hh * hh)};
    const Vec3d dlat{-dy * dx / hh, h, -dy * dz / hh};
    const double m[3] = {-1.0, -1.0, 1.0};  // d d / d ray
    for (int c = 0; c < 3; ++c) {
      (*jac)[c] = -sx * dlon[c] * m[c];
      (*jac)[3 + c] = -sy * dlat[c] * m[c];
    }
  }
  return {lens.center_x - sx * lon, lens.center_y - sy * lat};
}

struct UnitRay {
  Vec3d u;
  double s, theta;
};
// The unit ray and its angle off the axis; nullopt for a zero or non-finite ray, or (when
// min_cos > -1) one clearly outside the field of view (cos(theta) < min_cos), found before
// the atan2.
std::optional<UnitRay> Normalise(const Vec3d& r, double min_cos = -2.0) {
  const double n = std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
  if (!std::isfinite(n) || n <= 0) return std::nullopt;
  UnitRay out;
  out.u = {r[0] / n, r[1] / n, r[2] / n};
  if (out.u[2] < min_cos) return std::nullopt;
  out.s = std::sqrt(out.u[0] * out.u[0] + out.u[1] * out.u[1]);
  out.theta = std::atan2(out.s, out.u[2]);
  return out;
}

bool Visible(const LensParams& lens, const UnitRay& r) {
  return lens.model == LensModel::kLatLong || r.theta <= HalfFovRad(lens) * (1 + 1e-12);
}

// cos(theta) below which a ray is certainly outside the fov (a margin keeps the exact
// test in Visible authoritative at the edge).
double RejectCos(const LensParams& lens) {
  if (lens.model == LensModel::kLatLong) return -2.0;
  return std::cos(HalfFovRad(lens)) - 1e-9;
}

bool UseOpenCvForward(const LensParams& lens, const UnitRay& r) {
  return lens.model == LensModel::kKannalaBrandt && r.theta < kOpenCvThetaLimit && r.s > 0;
}

// Largest theta_d OpenCV's undistortPoints handles here: its Newton solution must stay below
// kOpenCvThetaLimit, and OpenCV 4.6 clips theta_d at pi/2.
double OpenCvThetaDLimit(const LensParams& lens) {
  return std::min(kPi / 2, KbPoly(lens.kb_k, std::min(kOpenCvThetaLimit, HalfFovRad(lens))));
}

// OpenCV's undistortPoints for points with theta_d < OpenCvThetaDLimit; writes unit rays.
// A result whose theta does not reproduce theta_d (no convergence, OpenCV's failure marker)
// is recomputed with the in-house inverse.
void OpenCvUndistort(const LensParams& lens, double f, const std::vector<cv::Vec2d>& pts, std::vector<Vec3d>* rays) {
  std::vector<cv::Vec2d> und(pts.size());
  if (!pts.empty()) {
    cv::Mat src(1, static_cast<int>(pts.size()), CV_64FC2, const_cast<cv::Vec2d*>(pts.data()));
    cv::Mat dst(1, static_cast<int>(und.size()), CV_64FC2, und.data());
    cv::fisheye::undistortPoints(src, dst, CameraMatrix(lens, f), cv::Vec4d(lens.kb_k[0], lens.kb_k[1], lens.kb_k[2], lens.kb_k[3]),
                                 cv::noArray(), cv::noArray(),
                                 cv::TermCriteria(cv::TermCriteria::MAX_ITER + cv::TermCriteria::EPS, 50, 1e-15));
  }
  rays->resize(pts.size());
  for (size_t i = 0; i < pts.size(); ++i) {
    const double du = pts[i][0] - lens.center_x, dv = pts[i][1] - lens.center_y;
    const double rho = std::hypot(du, dv);
    const double theta_d = rho / f;
    const double r = std::hypot(und[i][0], und[i][1]);
    const double theta = std::atan(r);
    if (std::isfinite(r) && std::abs(KbPoly(lens.kb_k, theta) - theta_d) <= 1e-13 * std::max(1.0, theta_d) &&
        und[i][0] * du >= 0 && und[i][1] * dv >= 0) {
      const double n = std::sqrt(1.0 + r * r);
      (*rays)[i] = {und[i][0] / n, und[i][1] / n, 1.0 / n};
      continue;
    }
    const double t = KbInverse(lens.kb_k, theta_d, HalfFovRad(lens));
    const double st = std::sin(t);
    (*rays)[i] = {st * du / rho, st * dv / rho, std::cos(t)};
  }
}

}  // namespace

const char* LensModelName(LensModel model) {
  switch (model) {
    case LensModel::kLatLong: return "latlong";
    case LensModel::kEquidistant: return "equidistant";
    case LensModel::kEquisolid: return "equisolid";
    case LensModel::kStereographic: return "stereographic";
    case LensModel::kKannalaBrandt: return "kannala-brandt";
  }
  return "?";
}

std::optional<LensModel> LensModelFromName(const std::string& name) {
  for (LensModel m : {LensModel::kLatLong, LensModel::kEquidistant, LensModel::kEquisolid, LensModel::kStereographic,
                      LensModel::kKannalaBrandt}) {
    if (name == LensModelName(m)) return m;
  }
  return std::nullopt;
}

bool LensParams::IsValid(std::string* why, int image_width, int image_height) const {
  const int w = image_width, h = image_height;
  if (w <= 0 || h <= 0) {
    return Fail(why, "image_size " + std::to_string(w) + "x" + std::to_string(h) + ": expected a positive width and height");
  }
  const std::string size = std::to_string(w) + "x" + std::to_string(h);
  const std::string name = LensModelName(model);
  if (!std::isfinite(fov_deg) || fov_deg <= 0.0 || fov_deg > 360.0) {
    return Fail(why, "fov_deg = " + Num(fov_deg) + ": expected a field of view in (0, 360] degrees");
  }
  if (model == LensModel::kStereographic && fov_deg >= 360.0) {
    return Fail(why, "fov_deg = " + Num(fov_deg) + ": a stereographic lens maps 360 degrees to an infinite radius; expected < 360");
  }
  if (!std::isfinite(center_x) || !std::isfinite(center_y)) return Fail(why, "center: expected finite pixel coordinates");
  if (!std::isfinite(radius_px) || radius_px <= 0.0) {
    return Fail(why, "radius_px = " + Num(radius_px) + ": expected a positive image circle radius in pixels");
  }
  for (double v : vignetting) {
    if (!std::isfinite(v)) return Fail(why, "vignetting: expected finite coefficients");
  }
  if (model == LensModel::kLatLong) {
    const LensParams ll = LatLongLens(w, h);
    if (w != 2 * h) return Fail(why, "image_size " + size + ": a latlong image must be 2:1 (width = 2 x height)");
    if (fov_deg != 360.0) return Fail(why, "fov_deg = " + Num(fov_deg) + ": a latlong image covers 360 degrees; expected 360");
    if (std::abs(center_x - ll.center_x) > 1e-9 || std::abs(center_y - ll.center_y) > 1e-9) {
      return Fail(why, "center = (" + Num(center_x) + ", " + Num(center_y) + "): a latlong " + size + " image has its centre at (" +
                           Num(ll.center_x) + ", " + Num(ll.center_y) + ")");
    }
    if (std::abs(radius_px - ll.radius_px) > 1e-9) {
      return Fail(why, "radius_px = " + Num(radius_px) + ": a latlong " + size + " image spans 180 degrees of longitude in " +
                           Num(ll.radius_px) + " pixels");
    }
    if (vignetting != std::array<double, 3>{}) return Fail(why, "vignetting: not supported for a latlong image; expected zeros");
    return true;
  }
  if (center_x < -0.5 || center_x > w - 0.5 || center_y < -0.5 || center_y > h - 0.5) {
    return Fail(why, "center = (" + Num(center_x) + ", " + Num(center_y) + "): expected a point inside the " + size +
                         " image (x in [-0.5, " + Num(w - 0.5) + "], y in [-0.5, " + Num(h - 0.5) + "])");
  }
  const double far_x = std::max(center_x + 0.5, w - 0.5 - center_x), far_y = std::max(center_y + 0.5, h - 0.5 - center_y);
  const double farthest = std::hypot(far_x, far_y);
  if (radius_px > farthest + 1e-9) {
    return Fail(why, "radius_px = " + Num(radius_px) + ": the image circle lies outside the " + size +
                         " image (the farthest image corner is " + Num(farthest) +
                         " pixels from the centre); expected the radius of the fov edge in this image's pixels");
  }
  if (model == LensModel::kKannalaBrandt) {
    for (double k : kb_k) {
      if (!std::isfinite(k)) return Fail(why, "kb_k: expected finite coefficients k1..k4");
    }
    const double tmax = HalfFovRad(*this);
    for (int i = 0; i <= 4096; ++i) {
      const double t = tmax * i / 4096.0;
      if (!(KbPolyDerivative(kb_k, t) > 0.0)) {
        return Fail(why, "kb_k: theta_d = theta (1 + k1 theta^2 + ...) stops increasing at theta = " + Num(t * 180.0 / kPi) +
                             " degrees, inside the fov; expected a monotonic distortion over fov_deg / 2");
      }
    }
  }
  for (int i = 0; i <= 1024; ++i) {
    const double r = i / 1024.0, r2 = r * r;
    const double g = 1.0 + r2 * (vignetting[0] + r2 * (vignetting[1] + r2 * vignetting[2]));
    if (!(g > 0.0)) {
      return Fail(why, "vignetting: gain 1 + a r^2 + b r^4 + c r^6 is " + Num(g) + " at r = " + Num(r) +
                           "; expected positive over the image circle (r in [0, 1])");
    }
  }
  return true;
}

LensParams LatLongLens(int width, int height) {
  LensParams lens;
  lens.model = LensModel::kLatLong;
  lens.fov_deg = 360.0;
  lens.center_x = 0.5 * (width - 1);
  lens.center_y = 0.5 * (height - 1);
  lens.radius_px = lens.center_x;
  return lens;
}

double NormalisedRadius(const LensParams& lens, double theta) {
  switch (lens.model) {
    case LensModel::kEquisolid: return 2.0 * std::sin(0.5 * theta);
    case LensModel::kStereographic: return 2.0 * std::tan(0.5 * theta);
    case LensModel::kKannalaBrandt: return KbPoly(lens.kb_k, theta);
    case LensModel::kEquidistant:
    case LensModel::kLatLong: return theta;
  }
  return theta;
}

double FocalLengthPx(const LensParams& lens) {
  if (lens.model == LensModel::kLatLong) return lens.radius_px / kPi;
  return lens.radius_px / NormalisedRadius(lens, HalfFovRad(lens));
}

std::optional<double> AngleFromNormalisedRadius(const LensParams& lens, double t) {
  const double tmax = HalfFovRad(lens);
  if (!std::isfinite(t) || t < 0.0 || t > NormalisedRadius(lens, tmax) * (1 + 1e-12)) return std::nullopt;
  double theta = 0.0;
  switch (lens.model) {
    case LensModel::kEquisolid: theta = 2.0 * std::asin(std::min(1.0, 0.5 * t)); break;
    case LensModel::kStereographic: theta = 2.0 * std::atan(0.5 * t); break;
    case LensModel::kKannalaBrandt: theta = KbInverse(lens.kb_k, t, tmax); break;
    case LensModel::kEquidistant:
    case LensModel::kLatLong: theta = t; break;
  }
  return std::min(theta, tmax);
}

std::optional<Vec2d> RayToPixel(const LensParams& lens, const Vec3d& ray, std::array<double, 6>* jacobian) {
  Vec2d p;
  unsigned char ok = 0;
  std::array<double, 6> j;
  RaysToPixels(lens, std::span<const Vec3d>(&ray, 1), std::span<Vec2d>(&p, 1), std::span<unsigned char>(&ok, 1),
               jacobian ? std::span<std::array<double, 6>>(&j, 1) : std::span<std::array<double, 6>>());
  if (!ok) return std::nullopt;
  if (jacobian) *jacobian = j;
  return p;
}

std::optional<Vec3d> PixelToRay(const LensParams& lens, const Vec2d& pixel) {
  Vec3d r;
  unsigned char ok = 0;
  PixelsToRays(lens, std::span<const Vec2d>(&pixel, 1), std::span<Vec3d>(&r, 1), std::span<unsigned char>(&ok, 1));
  if (!ok) return std::nullopt;
  return r;
}

void RaysToPixels(const LensParams& lens, std::span<const Vec3d> rays, std::span<Vec2d> pixels, std::span<unsigned char> valid,
                  std::span<std::array<double, 6>> jacobians) {
  const double f = FocalLengthPx(lens);
  const bool want_jac = !jacobians.empty();
  const double reject_cos = RejectCos(lens);
  std::vector<cv::Vec2d> cv_in;
  std::vector<size_t> cv_index;
  for (size_t i = 0; i < rays.size(); ++i) {
    const auto r = Normalise(rays[i], reject_cos);
    valid[i] = r && Visible(lens, *r);
    if (!valid[i]) continue;
    std::array<double, 6>* jac = want_jac ? &jacobians[i] : nullptr;
    if (lens.model == LensModel::kLatLong) {
      pixels[i] = LatLongPixel(lens, r->u, jac);
      continue;
    }
    pixels[i] = FisheyePixel(lens, f, r->u, r->s, r->theta, jac);  // also the jacobian for Kannala-Brandt
    if (UseOpenCvForward(lens, *r)) {
      cv_in.emplace_back(r->u[0] / r->u[2], r->u[1] / r->u[2]);
      cv_index.push_back(i);
    }
  }
  if (cv_in.empty()) return;
  std::vector<cv::Vec2d> cv_out(cv_in.size());
  cv::Mat src(1, static_cast<int>(cv_in.size()), CV_64FC2, cv_in.data());
  cv::Mat dst(1, static_cast<int>(cv_out.size()), CV_64FC2, cv_out.data());
  cv::fisheye::distortPoints(src, dst, CameraMatrix(lens, f), cv::Vec4d(lens.kb_k[0], lens.kb_k[1], lens.kb_k[2], lens.kb_k[3]));
  for (size_t j = 0; j < cv_index.size(); ++j) pixels[cv_index[j]] = {cv_out[j][0], cv_out[j][1]};
}

void PixelsToRays(const LensParams& lens, std::span<const Vec2d> pixels, std::span<Vec3d> rays, std::span<unsigned char> valid) {
  const double f = FocalLengthPx(lens);
  const double tmax = HalfFovRad(lens);
  const double cv_limit = lens.model == LensModel::kKannalaBrandt ? OpenCvThetaDLimit(lens) : 0.0;
  std::vector<cv::Vec2d> cv_in;
  std::vector<size_t> cv_index;
  for (size_t i = 0; i < pixels.size(); ++i) {
    const double px = pixels[i][0], py = pixels[i][1];
    valid[i] = 0;
    if (!std::isfinite(px) || !std::isfinite(py)) continue;
    if (lens.model == LensModel::kLatLong) {
      const double tol = 1e-9;
      if (px < -tol || px > 2 * lens.center_x + tol || py < -tol || py > 2 * lens.center_y + tol) continue;
      const double lon = kPi * (lens.center_x - px) / lens.center_x;
      const double lat = 0.5 * kPi * (lens.center_y - py) / lens.center_y;
      rays[i] = {-std::sin(lon) * std::cos(lat), -std::sin(lat), std::cos(lon) * std::cos(lat)};
      valid[i] = 1;
      continue;
    }
    const double du = px - lens.center_x, dv = py - lens.center_y;
    const double rho = std::hypot(du, dv);
    if (rho > lens.radius_px * (1 + 1e-12)) continue;
    valid[i] = 1;
    if (rho == 0.0) {
      rays[i] = {0.0, 0.0, 1.0};
      continue;
    }
    const double t = rho / f;
    if (lens.model == LensModel::kKannalaBrandt && t < cv_limit) {
      cv_in.emplace_back(px, py);
      cv_index.push_back(i);
      continue;
    }
    const double theta = AngleFromNormalisedRadius(lens, std::min(t, NormalisedRadius(lens, tmax))).value_or(tmax);
    const double st = std::sin(theta);
    rays[i] = {st * du / rho, st * dv / rho, std::cos(theta)};
  }
  if (cv_in.empty()) return;
  std::vector<Vec3d> cv_rays;
  OpenCvUndistort(lens, f, cv_in, &cv_rays);
  for (size_t j = 0; j < cv_index.size(); ++j) rays[cv_index[j]] = cv_rays[j];
}

double VignettingGain(const LensParams& lens, const Vec2d& pixel) {
  if (lens.model == LensModel::kLatLong) return 1.0;
  const double dx = pixel[0] - lens.center_x, dy = pixel[1] - lens.center_y;
  const double r2 = (dx * dx + dy * dy) / (lens.radius_px * lens.radius_px);
  const auto& v = lens.vignetting;
  return 1.0 + r2 * (v[0] + r2 * (v[1] + r2 * v[2]));
}

}  // namespace skycal::capture
