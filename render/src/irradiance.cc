#include "skycal/render/irradiance.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <thread>

#include "skycal/core/error.h"
#include "skycal/core/latlong.h"
#include "skycal/core/math_constants.h"

namespace skycal::render {
namespace {

// The image as a list of weighted samples (structure of arrays so the inner loop over
// pixels vectorises): direction and L(w) dw per channel. Zero pixels are dropped.
struct WeightedSamples {
  std::vector<double> x, y, z, r, g, b;
};

void CheckLatLong(const ImageRGB& img) {
  if (img.width < 2 || img.height < 2 || img.pixels.size() != static_cast<size_t>(img.width) * img.height * 3) {
    throw Error("irradiance: expected a lat-long image of at least 2x2 pixels, got " + std::to_string(img.width) + "x" +
                std::to_string(img.height));
  }
}

WeightedSamples Samples(const ImageRGB& img) {
  CheckLatLong(img);
  WeightedSamples s;
  const size_t n = static_cast<size_t>(img.width) * img.height;
  for (auto* v : {&s.x, &s.y, &s.z, &s.r, &s.g, &s.b}) v->reserve(n);
  for (int y = 0; y < img.height; ++y) {
    for (int x = 0; x < img.width; ++x) {
      double l[3];
      bool any = false;
      for (int c = 0; c < 3; ++c) {
        const double v = img.at(x, y, c);
        l[c] = std::isfinite(v) && v > 0.0 ? v : 0.0;
        any = any || l[c] > 0.0;
      }
      if (!any) continue;
      const double w = latlong::PixelSolidAngle(x, y, img.width, img.height);
      const auto d = latlong::PixelDirection(x, y, img.width, img.height);
      s.x.push_back(d[0]);
      s.y.push_back(d[1]);
      s.z.push_back(d[2]);
      s.r.push_back(l[0] * w);
      s.g.push_back(l[1] * w);
      s.b.push_back(l[2] * w);
    }
  }
  return s;
}

Rgb Integrate(const WeightedSamples& s, const Dir3& n) {
  double er = 0.0, eg = 0.0, eb = 0.0;
  const size_t count = s.x.size();
  const double nx = n[0], ny = n[1], nz = n[2];
  const double *px = s.x.data(), *py = s.y.data(), *pz = s.z.data();
  const double *pr = s.r.data(), *pg = s.g.data(), *pb = s.b.data();
  for (size_t i = 0; i < count; ++i) {
    const double c = std::max(0.0, nx * px[i] + ny * py[i] + nz * pz[i]);
    er += c * pr[i];
    eg += c * pg[i];
    eb += c * pb[i];
  }
  return {er, eg, eb};
}

Dir3 UnitNormal(const Dir3& n) { return latlong::Normalized(n, "irradiance normal"); }

}  // namespace

Rgb IrradianceQuadrature(const ImageRGB& latlong, const Dir3& normal) {
  return Integrate(Samples(latlong), UnitNormal(normal));
}

std::vector<Rgb> IrradianceQuadrature(const ImageRGB& latlong, const std::vector<Dir3>& normals, int threads) {
  std::vector<Dir3> unit(normals.size());
  for (size_t i = 0; i < normals.size(); ++i) unit[i] = UnitNormal(normals[i]);
  const WeightedSamples s = Samples(latlong);
  std::vector<Rgb> out(normals.size());
  const int workers = std::max(1, std::min<int>(threads, static_cast<int>(normals.size())));
  auto work = [&](int t) {
    for (size_t i = t; i < unit.size(); i += workers) out[i] = Integrate(s, unit[i]);
  };
  if (workers == 1) {
    work(0);
    return out;
  }
  std::vector<std::thread> pool;
  for (int t = 0; t < workers; ++t) pool.emplace_back(work, t);
  for (auto& th : pool) th.join();
  return out;
}

Rgb SunIrradiance(const Rgb& e_sun_rgb, const Dir3& sun_dir, const Dir3& normal, bool visible) {
  if (!visible) return {0.0, 0.0, 0.0};
  const double c = std::max(0.0, sun_dir[0] * normal[0] + sun_dir[1] * normal[1] + sun_dir[2] * normal[2]);
  return {e_sun_rgb[0] * c, e_sun_rgb[1] * c, e_sun_rgb[2] * c};
}

Rgb SunIlluminanceAtGround(const Preset& preset, const Dir3& sun_dir) {
  const auto s = latlong::Normalized(sun_dir, "sun direction");
  const double sun_zenith = std::atan2(std::hypot(s[0], s[2]), s[1]);
  const auto t = SunTransmittance(preset.luts, sun_zenith);
  Rgb e{};
  for (int c = 0; c < 3; ++c) e[c] = preset.sun_illuminance_lux * preset.sun_tint_rgb[c] * t[c];
  return e;
}

Rgb BallRadiance(const Rgb& irradiance, double albedo) {
  const double k = albedo / kPi;
  return {k * irradiance[0], k * irradiance[1], k * irradiance[2]};
}

std::array<double, 9> ShBasis(const Dir3& d) {
  const double x = d[0], y = d[1], z = d[2];
  const double c0 = 0.5 * std::sqrt(1.0 / kPi);
  const double c1 = std::sqrt(3.0 / (4.0 * kPi));
  const double c2 = 0.5 * std::sqrt(15.0 / kPi);
  const double c20 = 0.25 * std::sqrt(5.0 / kPi);
  const double c22 = 0.25 * std::sqrt(15.0 / kPi);
  return {c0, c1 * y, c1 * z, c1 * x, c2 * x * y, c2 * y * z, c20 * (3.0 * z * z - 1.0), c2 * x * z, c22 * (x * x - y * y)};
}

ShCoefficients ProjectSh9(const ImageRGB& latlong) {
  CheckLatLong(latlong);
  ShCoefficients sh{};
  const int w = latlong.width, h = latlong.height;
  for (int y = 0; y < h; ++y) {
    ShCoefficients row{};  // per-row partial sums keep the summation error small
    for (int x = 0; x < w; ++x) {
      double l[3];
      bool any = false;
      for (int c = 0; c < 3; ++c) {
        const double v = latlong.at(x, y, c);
        l[c] = std::isfinite(v) && v > 0.0 ? v : 0.0;
        any = any || l[c] > 0.0;
      }
      if (!any) continue;
      const double dw = latlong::PixelSolidAngle(x, y, w, h);
      const auto basis = ShBasis(latlong::PixelDirection(x, y, w, h));
      for (int k = 0; k < 9; ++k) {
        const double bw = basis[k] * dw;
        for (int c = 0; c < 3; ++c) row[k][c] += l[c] * bw;
      }
    }
    for (int k = 0; k < 9; ++k)
      for (int c = 0; c < 3; ++c) sh[k][c] += row[k][c];
  }
  return sh;
}

Rgb ShIrradiance(const ShCoefficients& sh, const Dir3& normal) {
  const auto basis = ShBasis(UnitNormal(normal));
  static constexpr int kBand[9] = {0, 1, 1, 1, 2, 2, 2, 2, 2};
  Rgb e{};
  for (int k = 0; k < 9; ++k) {
    const double a = kShClampedCosineBand[kBand[k]] * basis[k];
    for (int c = 0; c < 3; ++c) e[c] += a * sh[k][c];
  }
  return e;
}

std::vector<Dir3> FibonacciSphere(int n) {
  if (n < 1) throw Error("Fibonacci sphere: expected at least 1 point, got " + std::to_string(n));
  std::vector<Dir3> out(n);
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double y = 1.0 - (2.0 * i + 1.0) / n;
    const double r = std::sqrt(std::max(0.0, 1.0 - y * y));
    const double phi = golden * i;
    out[i] = {r * std::sin(phi), y, r * std::cos(phi)};
  }
  return out;
}

namespace {

// Relative errors of `approx` vs `ref` over normals and channels; see ProbePrediction.
void RelativeErrors(const std::vector<Rgb>& approx, const std::vector<Rgb>& ref, double* max_rel, double* rms_rel) {
  double peak = 0.0;
  for (const auto& e : ref)
    for (double v : e) peak = std::max(peak, std::abs(v));
  const double floor = std::max(1e-3 * peak, 1e-300);
  double mx = 0.0, sum2 = 0.0;
  size_t n = 0;
  for (size_t i = 0; i < ref.size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      const double rel = std::abs(approx[i][c] - ref[i][c]) / std::max(std::abs(ref[i][c]), floor);
      mx = std::max(mx, rel);
      sum2 += rel * rel;
      ++n;
    }
  }
  *max_rel = mx;
  *rms_rel = n ? std::sqrt(sum2 / n) : 0.0;
}

}  // namespace

ProbePrediction PredictProbe(const Preset& preset, const Dir3& sun_dir, const std::vector<Dir3>& normals, double albedo,
                             SkyRenderer& renderer, int width, GroundMode ground) {
  if (!(std::isfinite(albedo) && albedo >= 0.0 && albedo <= 1.0)) {
    throw Error("probe albedo: expected a value in [0, 1], got " + std::to_string(albedo));
  }
  if (width < 4 || width % 2 != 0) {
    throw Error("probe sky width: expected an even number of pixels >= 4, got " + std::to_string(width));
  }
  if (normals.empty()) throw Error("probe normals: expected at least one normal");
  ProbePrediction p;
  p.sun_dir = latlong::Normalized(sun_dir, "sun direction");
  p.albedo = albedo;
  p.width = width;
  p.height = width / 2;
  p.ground = ground;
  for (const auto& n : normals) p.normals.push_back(UnitNormal(n));

  RenderRequest req;
  req.sun_dir = p.sun_dir;
  req.width = p.width;
  req.height = p.height;
  req.sun_disc = false;  // the disc is the analytic term below (see the header)
  req.ground = ground;
  const ImageRGB sky = renderer.Render(preset, req);

  // The disc is hidden by the ground plane once its centre is below the horizon.
  p.sun_visible = p.sun_dir[1] > 0.0;
  p.sun_illuminance = SunIlluminanceAtGround(preset, p.sun_dir);
  p.sky_quadrature = IrradianceQuadrature(sky, p.normals, 2);
  p.sh = ProjectSh9(sky);
  const size_t n = p.normals.size();
  p.sky_sh.resize(n);
  p.irradiance.resize(n);
  p.irradiance_sh.resize(n);
  p.ball_radiance.resize(n);
  for (size_t i = 0; i < n; ++i) {
    p.sky_sh[i] = ShIrradiance(p.sh, p.normals[i]);
    const Rgb sun = SunIrradiance(p.sun_illuminance, p.sun_dir, p.normals[i], p.sun_visible);
    for (int c = 0; c < 3; ++c) {
      p.irradiance[i][c] = p.sky_quadrature[i][c] + sun[c];
      p.irradiance_sh[i][c] = p.sky_sh[i][c] + sun[c];
    }
    p.ball_radiance[i] = BallRadiance(p.irradiance[i], albedo);
  }
  RelativeErrors(p.sky_sh, p.sky_quadrature, &p.sh_max_rel_error, &p.sh_rms_rel_error);
  RelativeErrors(p.irradiance_sh, p.irradiance, &p.sh_total_max_rel_error, &p.sh_total_rms_rel_error);
  return p;
}

}  // namespace skycal::render
