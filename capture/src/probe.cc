#include "skycal/capture/probe.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <string>

#include "skycal/capture/rig.h"
#include "skycal/capture/sun_detect.h"
#include "skycal/core/error.h"
#include "skycal/core/luminance.h"
#include "skycal/core/math_constants.h"

namespace skycal::capture {
namespace {

std::string CircleText(const BallCircle& c) {
  std::ostringstream s;
  s << "(cx " << c.cx << ", cy " << c.cy << ", radius " << c.radius_px << " px)";
  return s.str();
}

bool Finite3(const float* p) { return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]); }

// Algebraic (Kasa) circle fit: minimises sum (x^2 + y^2 + D x + E y + F)^2.
std::optional<BallCircle> FitCircle(const std::vector<cv::Point2d>& pts) {
  if (pts.size() < 8) return std::nullopt;
  // Centre the points for conditioning.
  double mx = 0, my = 0;
  for (const auto& p : pts) mx += p.x, my += p.y;
  mx /= pts.size();
  my /= pts.size();
  cv::Mat A(static_cast<int>(pts.size()), 3, CV_64F), b(static_cast<int>(pts.size()), 1, CV_64F);
  for (int i = 0; i < static_cast<int>(pts.size()); ++i) {
    const double x = pts[i].x - mx, y = pts[i].y - my;
    A.at<double>(i, 0) = x;
    A.at<double>(i, 1) = y;
    A.at<double>(i, 2) = 1.0;
    b.at<double>(i, 0) = -(x * x + y * y);
  }
  cv::Mat sol;
  if (!cv::solve(A, b, sol, cv::DECOMP_SVD)) return std::nullopt;
  const double D = sol.at<double>(0), E = sol.at<double>(1), F = sol.at<double>(2);
  const double r2 = (D * D + E * E) / 4.0 - F;
  if (!(r2 > 0.0)) return std::nullopt;
  return BallCircle{mx - D / 2.0, my - E / 2.0, std::sqrt(r2)};
}

}  // namespace

BallCircle DetectBall(const ImageRGB& image, const BallDetectOptions& options) {
  if (image.empty()) throw Error("probe: ball detection: the image is empty");
  const int w = image.width, h = image.height;
  const double max_r = options.max_radius_px > 0.0 ? options.max_radius_px : 0.5 * std::min(w, h);
  if (!(options.min_radius_px > 0.0) || !(max_r > options.min_radius_px))
    throw Error("probe: ball detection: need 0 < min_radius_px < max_radius_px");
  // Tone map: luminance / mean luminance, x / (1 + x), to 8 bits.
  cv::Mat lum(h, w, CV_32F);
  double sum = 0.0;
  long n = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float* p = &image.pixels[image.index(x, y)];
      double l = Finite3(p) ? Luminance(p) : 0.0;
      if (!(l > 0.0)) l = 0.0;
      lum.at<float>(y, x) = static_cast<float>(l);
      sum += l;
      ++n;
    }
  const double mean = n > 0 ? sum / n : 0.0;
  if (!(mean > 0.0)) throw Error("probe: ball detection: the image has no positive finite pixel");
  cv::Mat g8(h, w, CV_8U);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double v = lum.at<float>(y, x) / mean;
      g8.at<uint8_t>(y, x) = static_cast<uint8_t>(std::lround(255.0 * v / (1.0 + v)));
    }
  cv::Mat blurred;
  cv::GaussianBlur(g8, blurred, cv::Size(0, 0), 2.0);
  std::vector<cv::Vec3f> circles;
  const int min_r = static_cast<int>(std::floor(options.min_radius_px));
  const int max_r_i = static_cast<int>(std::ceil(max_r));
  cv::HoughCircles(blurred, circles, cv::HOUGH_GRADIENT, 1.0, /*minDist=*/std::max(1.0, 0.5 * std::min(w, h)),
                   /*canny high=*/80.0, /*accumulator=*/30.0, min_r, max_r_i);
  if (circles.empty())
    throw Error("probe: ball detection: no circle found (radius " + std::to_string(min_r) + ".." +
                std::to_string(max_r_i) + " px) in the " + std::to_string(w) + "x" + std::to_string(h) +
                " image; give the circle explicitly");
  BallCircle c{circles[0][0], circles[0][1], circles[0][2]};
  if (options.refine) {
    cv::Mat edges;
    cv::Canny(blurred, edges, 40.0, 80.0);
    std::vector<cv::Point2d> pts;
    const double band = 0.06 * c.radius_px + 2.0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        if (!edges.at<uint8_t>(y, x)) continue;
        const double d = std::hypot(x - c.cx, y - c.cy);
        if (std::abs(d - c.radius_px) <= band) pts.emplace_back(x, y);
      }
    // Only trust the refit when the edge covers a good share of the circumference.
    if (pts.size() > 2.0 * kPi * c.radius_px * 0.5) {
      if (auto f = FitCircle(pts); f && std::hypot(f->cx - c.cx, f->cy - c.cy) < band &&
                                   std::abs(f->radius_px - c.radius_px) < band)
        c = *f;
    }
  }
  return c;
}

std::optional<std::array<double, 3>> BallNormalAt(const BallCircle& circle, const std::array<double, 9>& R,
                                                  double x, double y) {
  const double u = (x - circle.cx) / circle.radius_px, v = (y - circle.cy) / circle.radius_px;
  const double rho2 = u * u + v * v;
  if (rho2 > 1.0) return std::nullopt;
  const double z = -std::sqrt(std::max(0.0, 1.0 - rho2));
  return std::array<double, 3>{R[0] * u + R[1] * v + R[2] * z, R[3] * u + R[4] * v + R[5] * z,
                               R[6] * u + R[7] * v + R[8] * z};
}

namespace {

// The options, the image and the rotation checked; the ball circle (given or detected)
// checked to be finite and inside the image.
BallCircle ProbeCircle(const ImageRGB& image, const std::array<double, 9>& R,
                       const std::optional<BallCircle>& circle_in, const ProbeOptions& options) {
  if (image.empty()) throw Error("probe: the image is empty");
  if (image.pixels.size() != static_cast<size_t>(image.width) * image.height * 3)
    throw Error("probe: the image's pixel buffer does not match its size");
  if (!(options.edge_fraction >= 0.0 && options.edge_fraction < 1.0))
    throw Error("probe: option edge_fraction must be in [0, 1)");
  if (options.rings < 1) throw Error("probe: option rings must be >= 1");
  if (options.min_pixels_per_sample < 1) throw Error("probe: option min_pixels_per_sample must be >= 1");
  if (std::isnan(options.clip_level) || !(options.clip_level > 0.0))
    throw Error("probe: option clip_level must be > 0");
  std::string why;
  if (!IsRotation(R, &why)) throw Error("probe: camera-to-world rotation: " + why);

  const BallCircle c = circle_in ? *circle_in : DetectBall(image, options.detect);
  if (!std::isfinite(c.cx) || !std::isfinite(c.cy) || !(c.radius_px > 0.0) || !std::isfinite(c.radius_px))
    throw Error("probe: ball circle " + CircleText(c) + " is invalid (need a finite centre and radius > 0)");
  const int w = image.width, h = image.height;
  constexpr double kTol = 0.5;  // the circle may reach the outer edge of the border pixels
  if (c.cx - c.radius_px < -kTol || c.cy - c.radius_px < -kTol || c.cx + c.radius_px > w - 1 + kTol ||
      c.cy + c.radius_px > h - 1 + kTol)
    throw Error("probe: ball circle " + CircleText(c) + " lies (partly) outside the " + std::to_string(w) + "x" +
                std::to_string(h) + " image");
  return c;
}

// Bins: rings of equal theta width up to theta_max, sectors of about the same width.
struct ProbeBins {
  double rho_max = 0.0, dtheta = 0.0;
  std::vector<int> ring_first, ring_sectors;
  int count() const { return ring_first.back(); }
};

ProbeBins MakeProbeBins(const ProbeOptions& options) {
  ProbeBins b;
  b.rho_max = 1.0 - options.edge_fraction;
  const double theta_max = std::asin(b.rho_max);
  b.dtheta = theta_max / options.rings;
  b.ring_first.assign(options.rings + 1, 0);
  b.ring_sectors.assign(options.rings, 1);
  for (int k = 0; k < options.rings; ++k) {
    const double mid = (k + 0.5) * b.dtheta;
    b.ring_sectors[k] = std::max(1, static_cast<int>(std::lround(2.0 * kPi * std::sin(mid) / b.dtheta)));
    b.ring_first[k + 1] = b.ring_first[k] + b.ring_sectors[k];
  }
  return b;
}

// Per bin: summed world normal (camera-to-world R), summed radiance, pixel count.
struct ProbeAcc {
  double n[3] = {0, 0, 0};
  double l[3] = {0, 0, 0};
  int count = 0;
};

// Walks the ball's pixels: counts (total, clipped, non-finite) and the brightest pixel
// into m; the usable ones (inside rho_max, finite, unclipped) into their bin's acc.
void AccumulateBall(const ImageRGB& image, const std::array<double, 9>& R, const BallCircle& c, const ProbeBins& bins,
                    const ProbeOptions& options, ProbeMeasurement& m, std::vector<ProbeAcc>& acc) {
  const int w = image.width, h = image.height;
  const double rho_max = bins.rho_max, dtheta = bins.dtheta;
  // Pixels are floats: compare in float so a clamp written as float(clip_level) counts.
  const float clip_f = static_cast<float>(options.clip_level);
  const int x0 = std::max(0, static_cast<int>(std::floor(c.cx - c.radius_px)));
  const int x1 = std::min(w - 1, static_cast<int>(std::ceil(c.cx + c.radius_px)));
  const int y0 = std::max(0, static_cast<int>(std::floor(c.cy - c.radius_px)));
  const int y1 = std::min(h - 1, static_cast<int>(std::ceil(c.cy + c.radius_px)));
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      const double u = (x - c.cx) / c.radius_px, v = (y - c.cy) / c.radius_px;
      const double rho = std::sqrt(u * u + v * v);
      if (rho > 1.0) continue;
      ++m.pixels_total;
      const float* p = &image.pixels[image.index(x, y)];
      const bool finite = Finite3(p);
      const bool clipped = finite && (p[0] >= clip_f || p[1] >= clip_f || p[2] >= clip_f);
      if (finite) {
        const double lum = Luminance(p);
        if (lum > m.max_luminance) {
          m.max_luminance = lum;
          m.max_luminance_clipped = clipped;
        } else if (lum == m.max_luminance && clipped) {
          m.max_luminance_clipped = true;
        }
      }
      if (rho > rho_max) continue;  // grazing edge ring
      if (!finite) {
        ++m.pixels_nonfinite;
        continue;
      }
      if (clipped) {
        ++m.pixels_clipped;
        continue;
      }
      const double theta = std::asin(std::min(1.0, rho));
      const int k = std::min(options.rings - 1, static_cast<int>(theta / dtheta));
      const double phi = std::atan2(v, u);  // (-pi, pi]
      const int s = std::min(bins.ring_sectors[k] - 1,
                             std::max(0, static_cast<int>((phi + kPi) / (2.0 * kPi) * bins.ring_sectors[k])));
      ProbeAcc& a = acc[bins.ring_first[k] + s];
      const double nz = -std::sqrt(std::max(0.0, 1.0 - rho * rho));
      const double nw[3] = {R[0] * u + R[1] * v + R[2] * nz, R[3] * u + R[4] * v + R[5] * nz,
                            R[6] * u + R[7] * v + R[8] * nz};
      for (int i = 0; i < 3; ++i) {
        a.n[i] += nw[i];
        a.l[i] += p[i];
      }
      ++a.count;
    }
  }
}

}  // namespace

ProbeMeasurement MeasureProbe(const ImageRGB& image, const std::array<double, 9>& R,
                              const std::optional<BallCircle>& circle_in, const ProbeOptions& options) {
  const BallCircle c = ProbeCircle(image, R, circle_in, options);
  const ProbeBins bins = MakeProbeBins(options);
  std::vector<ProbeAcc> acc(bins.count());

  ProbeMeasurement m;
  m.circle = c;
  m.max_luminance = -1.0;
  AccumulateBall(image, R, c, bins, options, m, acc);
  if (m.max_luminance < 0.0) m.max_luminance = 0.0;
  for (const ProbeAcc& a : acc) {
    if (a.count < options.min_pixels_per_sample) continue;
    const double len = std::sqrt(a.n[0] * a.n[0] + a.n[1] * a.n[1] + a.n[2] * a.n[2]);
    if (!(len > 0.0)) continue;
    ProbeSample s;
    for (int i = 0; i < 3; ++i) {
      s.normal[i] = a.n[i] / len;
      s.radiance[i] = a.l[i] / a.count;
    }
    s.pixels = a.count;
    m.pixels_used += a.count;
    m.samples.push_back(s);
  }
  if (m.samples.empty()) {
    std::ostringstream s;
    s << "probe: no usable sample on the ball " << CircleText(c) << ": of " << m.pixels_total << " ball pixels, "
      << m.pixels_clipped << " clipped (a channel >= clip_level " << options.clip_level << "), "
      << m.pixels_nonfinite << " non-finite, the rest in the grazing edge ring or in bins under "
      << options.min_pixels_per_sample << " pixels (ball fully clipped or too small?)";
    throw Error(s.str());
  }
  return m;
}

double SunShareOfBrightest(const std::vector<ProbeSample>& samples, const std::vector<std::array<double, 3>>& sun_radiance,
                           const std::vector<double>& sun_cos, double bright_fraction) {
  if (sun_radiance.size() != samples.size() || sun_cos.size() != samples.size()) {
    throw Error("sun share: need one sun radiance and cosine per probe sample");
  }
  auto lum = [](const std::array<double, 3>& v) { return Rec709Luminance(v); };
  std::vector<std::pair<double, size_t>> bright;  // (measured luminance, index) of sun-facing samples
  for (size_t i = 0; i < samples.size(); ++i) {
    if (sun_cos[i] > 0.05) bright.emplace_back(lum(samples[i].radiance), i);
  }
  std::sort(bright.begin(), bright.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  const size_t nb = std::max<size_t>(1, static_cast<size_t>(std::ceil(bright_fraction * bright.size())));
  double sun_lum = 0.0, meas_lum = 0.0;
  for (size_t j = 0; j < nb && j < bright.size(); ++j) {
    sun_lum += lum(sun_radiance[bright[j].second]);
    meas_lum += bright[j].first;
  }
  return meas_lum > 0.0 ? sun_lum / meas_lum : 0.0;
}

SunRecovery RecoverSun(const std::vector<ProbeSample>& samples, const std::array<double, 3>& albedo,
                       const std::vector<std::array<double, 3>>& sky_irradiance,
                       const std::array<double, 3>& sun_direction, const SunRecoveryOptions& options) {
  if (samples.empty()) throw Error("sun recovery: no probe samples");
  if (sky_irradiance.size() != samples.size())
    throw Error("sun recovery: " + std::to_string(sky_irradiance.size()) + " sky irradiance values for " +
                std::to_string(samples.size()) + " probe samples (need one per sample)");
  for (int c = 0; c < 3; ++c)
    if (!(albedo[c] > 0.0) || !std::isfinite(albedo[c]))
      throw Error("sun recovery: ball albedo channel " + std::to_string(c) + " must be finite and > 0");
  if (!(options.visible_threshold >= 0.0) || !(options.bright_fraction > 0.0 && options.bright_fraction <= 1.0) ||
      options.min_sun_facing_samples < 1)
    throw Error("sun recovery: invalid options (visible_threshold >= 0, 0 < bright_fraction <= 1, "
                "min_sun_facing_samples >= 1)");
  const double slen = std::sqrt(sun_direction[0] * sun_direction[0] + sun_direction[1] * sun_direction[1] +
                                sun_direction[2] * sun_direction[2]);
  if (!(slen > 0.0) || !std::isfinite(slen)) throw Error("sun recovery: the sun direction has no length");
  const std::array<double, 3> s{sun_direction[0] / slen, sun_direction[1] / slen, sun_direction[2] / slen};

  const size_t n = samples.size();
  std::vector<double> cosv(n);
  int facing = 0;
  for (size_t i = 0; i < n; ++i) {
    const auto& smp = samples[i];
    for (int c = 0; c < 3; ++c)
      if (!std::isfinite(smp.radiance[c]) || !std::isfinite(smp.normal[c]) || !std::isfinite(sky_irradiance[i][c]))
        throw Error("sun recovery: sample " + std::to_string(i) + " has a non-finite normal, radiance or sky irradiance");
    const double d = smp.normal[0] * s[0] + smp.normal[1] * s[1] + smp.normal[2] * s[2];
    cosv[i] = std::max(0.0, d);
    if (d > 0.05) ++facing;
  }
  if (facing < options.min_sun_facing_samples)
    throw Error("sun recovery: only " + std::to_string(facing) + " probe samples face the sun (need " +
                std::to_string(options.min_sun_facing_samples) +
                "): the sun lights the ball's far side, its illuminance is not observable from this view");

  SunRecovery r;
  r.samples_used = static_cast<int>(n);
  r.sun_facing_samples = facing;
  double cc = 0.0;
  for (size_t i = 0; i < n; ++i) cc += cosv[i] * cosv[i];
  for (int c = 0; c < 3; ++c) {
    double cy = 0.0;
    for (size_t i = 0; i < n; ++i) {
      const double y = kPi * samples[i].radiance[c] / albedo[c] - sky_irradiance[i][c];
      cy += cosv[i] * y;
    }
    r.fitted_sun_illuminance[c] = std::max(0.0, cy / cc);
  }
  // Residuals and the sun's share on the brightest sun-facing samples.
  double res2 = 0.0, meas2 = 0.0;
  for (size_t i = 0; i < n; ++i) {
    double model[3];
    for (int c = 0; c < 3; ++c) {
      model[c] = albedo[c] / kPi * (sky_irradiance[i][c] + r.fitted_sun_illuminance[c] * cosv[i]);
      const double d = samples[i].radiance[c] - model[c];
      res2 += d * d;
      meas2 += samples[i].radiance[c] * samples[i].radiance[c];
    }
  }
  r.residual_rms_rel = meas2 > 0.0 ? std::sqrt(res2 / meas2) : 0.0;
  std::vector<std::array<double, 3>> sun_radiance(n);
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) sun_radiance[i][c] = albedo[c] / kPi * r.fitted_sun_illuminance[c] * cosv[i];
  r.sun_fraction = SunShareOfBrightest(samples, sun_radiance, cosv, options.bright_fraction);
  r.visible = r.sun_fraction >= options.visible_threshold;
  if (r.visible) r.sun_illuminance = r.fitted_sun_illuminance;
  return r;
}

}  // namespace skycal::capture
