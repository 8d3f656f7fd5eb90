#include "skycal/capture/color_difference.h"

#include <cmath>

#include "skycal/core/luminance.h"
#include "skycal/core/math_constants.h"

namespace skycal::capture {

Rgb LinearRec709ToXyz(const Rgb& c) {
  return {0.4124 * c[0] + 0.3576 * c[1] + 0.1805 * c[2],  //
          Rec709Luminance(c),  // the Y row: the Rec.709 luminance weights
          0.0193 * c[0] + 0.1192 * c[1] + 0.9505 * c[2]};
}

Rgb XyzToLab(const Rgb& xyz) {
  // The white of the matrix above: (1, 1, 1) in linear Rec.709.
  const double white[3] = {0.9505, 1.0, 1.089};
  auto f = [](double t) {
    constexpr double d = 6.0 / 29.0;
    return t > d * d * d ? std::cbrt(t) : t / (3.0 * d * d) + 4.0 / 29.0;
  };
  const double fx = f(xyz[0] / white[0]), fy = f(xyz[1] / white[1]), fz = f(xyz[2] / white[2]);
  return {116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)};
}

double DeltaE76(const Rgb& a, const Rgb& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

namespace {
double Deg(double rad) { return rad * 180.0 / kPi; }
double Rad(double deg) { return deg * kPi / 180.0; }
// Hue angle in degrees [0, 360); 0 for a neutral (a' = b = 0), as the formula specifies.
double HueDeg(double b, double a) {
  if (a == 0.0 && b == 0.0) return 0.0;
  const double h = Deg(std::atan2(b, a));
  return h < 0.0 ? h + 360.0 : h;
}
}  // namespace

double DeltaE2000(const Rgb& lab1, const Rgb& lab2) {
  const double L1 = lab1[0], a1 = lab1[1], b1 = lab1[2];
  const double L2 = lab2[0], a2 = lab2[1], b2 = lab2[2];
  // a' stretched by G (the chroma-dependent compensation of a* near the neutral axis).
  const double c_mean = 0.5 * (std::hypot(a1, b1) + std::hypot(a2, b2));
  const double c7 = std::pow(c_mean, 7.0);
  const double g = 0.5 * (1.0 - std::sqrt(c7 / (c7 + std::pow(25.0, 7.0))));
  const double a1p = (1.0 + g) * a1, a2p = (1.0 + g) * a2;
  const double c1p = std::hypot(a1p, b1), c2p = std::hypot(a2p, b2);
  const double h1p = HueDeg(b1, a1p), h2p = HueDeg(b2, a2p);
  // Differences.
  const double dLp = L2 - L1, dCp = c2p - c1p;
  double dhp = 0.0;
  if (c1p * c2p != 0.0) {
    dhp = h2p - h1p;
    if (dhp > 180.0) dhp -= 360.0;
    if (dhp < -180.0) dhp += 360.0;
  }
  const double dHp = 2.0 * std::sqrt(c1p * c2p) * std::sin(Rad(dhp / 2.0));
  // Means (hue: the shorter arc; a neutral takes the other's hue).
  const double Lp = 0.5 * (L1 + L2), Cp = 0.5 * (c1p + c2p);
  double hp = h1p + h2p;
  if (c1p * c2p != 0.0) {
    if (std::abs(h1p - h2p) <= 180.0) hp = 0.5 * (h1p + h2p);
    else hp = (h1p + h2p < 360.0) ? 0.5 * (h1p + h2p + 360.0) : 0.5 * (h1p + h2p - 360.0);
  }
  const double t = 1.0 - 0.17 * std::cos(Rad(hp - 30.0)) + 0.24 * std::cos(Rad(2.0 * hp)) +
                   0.32 * std::cos(Rad(3.0 * hp + 6.0)) - 0.20 * std::cos(Rad(4.0 * hp - 63.0));
  const double d_theta = 30.0 * std::exp(-((hp - 275.0) / 25.0) * ((hp - 275.0) / 25.0));
  const double cp7 = std::pow(Cp, 7.0);
  const double rc = 2.0 * std::sqrt(cp7 / (cp7 + std::pow(25.0, 7.0)));
  const double sl = 1.0 + 0.015 * (Lp - 50.0) * (Lp - 50.0) / std::sqrt(20.0 + (Lp - 50.0) * (Lp - 50.0));
  const double sc = 1.0 + 0.045 * Cp, sh = 1.0 + 0.015 * Cp * t;
  const double rt = -std::sin(Rad(2.0 * d_theta)) * rc;
  const double l = dLp / sl, c = dCp / sc, h = dHp / sh;
  return std::sqrt(l * l + c * c + h * h + rt * c * h);
}

double SrgbDecode(double v) { return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); }
double SrgbEncode(double v) { return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055; }

}  // namespace skycal::capture
