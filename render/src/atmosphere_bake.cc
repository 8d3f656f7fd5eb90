// Single-scattering baker for the sky model's LUTs; see atmosphere_bake.h for the maths
// and the sources of the constants.
//
// Quadrature (all in double precision):
//   - Optical depth along a segment uses the segment's end altitudes: an exponential
//     density is integrated exactly under the assumption that altitude is linear in the
//     path length over the segment, rho0 * H * (1 - exp(-dh / H)) / dh per metre of path,
//     and the ozone tent likewise through its piecewise-quadratic antiderivative. Vertical
//     rays are therefore exact; on slanted rays the error comes only from the curvature
//     of altitude along the path, ds^2 / (8 r) per segment (~15 m for a 28 km grazing
//     segment, ~1% of the Mie density there, far less for Rayleigh).
//   - Nodes crowd toward the low (dense) end of each ray: t_i = L (i / n)^2. A ray toward
//     the sun that first descends is split at its tangent point (its lowest altitude).
//   - The in-scattering integrand along the view ray is integrated per segment with the
//     logarithmic mean of its end values, exact for an exponentially varying integrand
//     (transmittance times density), and bounded by the trapezoid otherwise.
//   - The planet's shadow on the view ray (the points whose ray toward the sun meets the
//     planet) is a single interval, found analytically (a line against the half cylinder
//     behind the planet); its ends become extra nodes and segments inside it scatter
//     nothing, so twilight rows are not at the mercy of the node spacing.
#include "skycal/render/atmosphere_bake.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <thread>
#include <vector>

#include "skycal/core/error.h"
#include "skycal/core/format_number.h"
#include "skycal/core/math_constants.h"

namespace skycal::render {
namespace {

// Numbers in messages: %g (core/format_number.h).
std::string Num(double v) { return FormatNumber(v); }

// Density-weighted path lengths (m) of the three constituents: multiplied by the
// coefficients at density 1 they give optical depths.
struct Column {
  double rayleigh = 0.0, mie = 0.0, ozone = 0.0;
  Column& operator+=(const Column& o) {
    rayleigh += o.rayleigh;
    mie += o.mie;
    ozone += o.ozone;
    return *this;
  }
};

// Densities at one point of a ray.
struct Sample {
  double h;       // altitude, m (clamped at 0)
  double rho_r;   // Rayleigh density, 1
  double rho_m;   // Mie density, 1
  double ozone_F; // antiderivative of the ozone tent at h, m
};

class Atmosphere {
 public:
  explicit Atmosphere(const AtmosphereOptions& o)
      : bottom_(o.planet_radius_m),
        top_(o.atmosphere_top_m),
        h_r_(o.rayleigh_scale_height_m),
        h_m_(o.mie_scale_height_m),
        oz_c_(o.ozone_center_altitude_m),
        oz_a_(0.5 * o.ozone_width_m) {
    for (int c = 0; c < 3; ++c) {
      ext_r_[c] = o.rayleigh_scattering_per_m[c];
      ext_o_[c] = o.ozone_absorption_per_m[c];
    }
    ext_m_ = o.mie_extinction_per_m;
  }

  double bottom() const { return bottom_; }
  double top() const { return top_; }

  Sample At(double radius) const {
    Sample s;
    s.h = std::max(radius - bottom_, 0.0);
    s.rho_r = std::exp(-s.h / h_r_);
    s.rho_m = std::exp(-s.h / h_m_);
    s.ozone_F = OzoneAntiderivative(s.h);
    return s;
  }

  // Column of a segment of path length ds between two samples.
  Column Segment(const Sample& a, const Sample& b, double ds) const {
    Column c;
    const double dh = b.h - a.h;
    c.rayleigh = ds * ExpMean(a.rho_r, b.rho_r, dh, h_r_);
    c.mie = ds * ExpMean(a.rho_m, b.rho_m, dh, h_m_);
    if (std::abs(dh) > 1e-3) {
      c.ozone = ds * (b.ozone_F - a.ozone_F) / dh;
    } else {
      c.ozone = ds * OzoneDensity(0.5 * (a.h + b.h));
    }
    return c;
  }

  // Per-channel optical depth of a column.
  std::array<double, 3> Tau(const Column& c) const {
    std::array<double, 3> t{};
    for (int i = 0; i < 3; ++i) t[i] = ext_r_[i] * c.rayleigh + ext_m_ * c.mie + ext_o_[i] * c.ozone;
    return t;
  }

  // Distance from radius r along a ray with cos(zenith) mu to the top boundary (r <= top).
  double DistanceToTop(double r, double mu) const {
    const double p2 = r * r * (1.0 - mu) * (1.0 + mu);  // squared distance of the line from the centre
    const double q = std::sqrt(std::max(top_ * top_ - p2, 0.0));
    // Upward: (top^2 - r^2) / (r mu + q) avoids cancelling r mu against q.
    if (mu > 0.0) return std::max((top_ - r) * (top_ + r), 0.0) / (r * mu + q);
    return q - r * mu;
  }

  // Column from radius r along a ray with cos(zenith) mu to the top boundary, ignoring
  // the ground (callers only ask for rays that do not meet it; altitudes are clamped at 0
  // for rays that graze it within rounding).
  Column ColumnToTop(double r, double mu, int steps) const {
    const double length = DistanceToTop(r, mu);
    const double p2 = r * r * (1.0 - mu) * (1.0 + mu);
    auto radius_at = [&](double t) {
      const double along = t + r * mu;  // signed distance from the point nearest the centre
      return std::sqrt(p2 + along * along);
    };
    Column total;
    if (!(length > 0.0)) return total;
    // Pieces [t0, t1] with the dense end at t0 (low_at_start) or t1.
    auto piece = [&](double t0, double t1, int n, bool low_at_start) {
      Sample prev = At(radius_at(low_at_start ? t0 : t1));
      double t_prev = low_at_start ? t0 : t1;
      for (int i = 1; i <= n; ++i) {
        const double u = static_cast<double>(i) / n;
        const double t = low_at_start ? t0 + (t1 - t0) * u * u : t1 - (t1 - t0) * u * u;
        const Sample cur = At(radius_at(t));
        total += Segment(prev, cur, std::abs(t - t_prev));
        prev = cur;
        t_prev = t;
      }
    };
    const double t_tangent = -r * mu;
    if (mu < 0.0 && t_tangent < length) {
      const int n_down = std::clamp(static_cast<int>(std::lround(steps * t_tangent / length)), 1, std::max(steps - 1, 1));
      const int n_up = std::max(steps - n_down, 1);
      piece(0.0, t_tangent, n_down, false);
      piece(t_tangent, length, n_up, true);
    } else {
      piece(0.0, length, steps, true);
    }
    return total;
  }

 private:
  // Mean over a segment of exp(-h / H) when h varies linearly from h0 to h0 + dh.
  static double ExpMean(double rho0, double rho1, double dh, double scale) {
    if (std::abs(dh) > 1e-4 * scale) return scale * (rho0 - rho1) / dh;
    return 0.5 * (rho0 + rho1);
  }

  double OzoneDensity(double h) const { return std::max(0.0, 1.0 - std::abs(h - oz_c_) / oz_a_); }

  // Antiderivative of the tent profile, 0 below the layer and a (half width) above it.
  double OzoneAntiderivative(double h) const {
    const double lo = oz_c_ - oz_a_, hi = oz_c_ + oz_a_;
    if (h <= lo) return 0.0;
    if (h <= oz_c_) return (h - lo) * (h - lo) / (2.0 * oz_a_);
    if (h < hi) return oz_a_ - (hi - h) * (hi - h) / (2.0 * oz_a_);
    return oz_a_;
  }

  double bottom_, top_, h_r_, h_m_, oz_c_, oz_a_;
  std::array<double, 3> ext_r_{}, ext_o_{};
  double ext_m_ = 0.0;
};

// Mean of a positive function over a segment from its end values, exact when the
// function is exponential in the path length; falls back to the trapezoid when an end is
// zero (underflowed transmittance).
double LogMean(double a, double b) {
  if (!(a > 0.0) || !(b > 0.0)) return 0.5 * (a + b);
  const double x = b / a - 1.0;
  if (std::abs(x) < 1e-4) return a * (1.0 + x * (0.5 - x / 12.0));
  return (b - a) / std::log1p(x);
}

// The part of the view ray t in [0, length] inside the planet's shadow: the set of points
// whose ray toward the sun meets the planet is the solid half cylinder of the planet's
// radius behind it, convex, so its intersection with the ray is one interval.
struct Interval {
  double lo = 0.0, hi = 0.0;
  bool empty() const { return !(hi > lo); }
  bool contains(double t) const { return t > lo && t < hi; }
};

Interval ShadowOnRay(double r0, double sin_e, double cos_ts, double sin_ts, double mu, double planet_radius,
                     double length) {
  // Observer o = (0, r0, 0), view v, sun s; x(t) = o + t v.
  // In the cylinder: |x|^2 - (x.s)^2 < R^2  <=>  A t^2 + 2 B t + C < 0.
  // Behind the planet: x.s = o.s + t mu < 0.
  const double os = r0 * cos_ts;
  const double a = (1.0 - mu) * (1.0 + mu);
  const double b = r0 * sin_e - os * mu;
  const double c = (r0 * sin_ts - planet_radius) * (r0 * sin_ts + planet_radius);
  constexpr double kInf = std::numeric_limits<double>::infinity();
  Interval none{0.0, 0.0};
  double lo = -kInf, hi = kInf;
  if (a > 1e-14) {
    const double disc = b * b - a * c;
    if (disc <= 0.0) return none;
    const double q = -(b + std::copysign(std::sqrt(disc), b));
    double t1 = q / a, t2 = q != 0.0 ? c / q : -t1;
    if (t1 > t2) std::swap(t1, t2);
    lo = t1;
    hi = t2;
  } else if (c >= 0.0) {
    return none;  // along the sun direction: inside the cylinder for all t or for none
  }
  if (mu > 0.0) {
    hi = std::min(hi, -os / mu);
  } else if (mu < 0.0) {
    lo = std::max(lo, -os / mu);
  } else if (os >= 0.0) {
    return none;
  }
  lo = std::max(lo, 0.0);
  hi = std::min(hi, length);
  if (!(hi > lo)) return none;
  return {lo, hi};
}

struct Integrals {
  std::array<double, 3> rayleigh{}, mie{};  // integral of rho * T(o->x) * T(x->sun) ds, m
};

// The view ray's integration nodes in [0, length], crowded toward the observer, with the
// shadow's ends as nodes; lit[i]: segment i is outside the shadow. Returns whether any is.
bool PlaceViewNodes(double length, const Interval& shadow, int n, std::vector<double>& nodes, std::vector<char>& lit) {
  nodes.clear();
  for (int i = 0; i <= n; ++i) {
    const double u = static_cast<double>(i) / n;
    nodes.push_back(length * u * u);
  }
  if (!shadow.empty()) {
    if (shadow.lo > 0.0) nodes.push_back(shadow.lo);
    if (shadow.hi < length) {
      // Twilight: the lit part beyond the shadow is where all the light comes from, but it
      // lies where the base nodes are sparsest; give it its own nodes, crowded toward the
      // shadow's edge (the lowest, densest lit air).
      const double span = length - shadow.hi;
      for (int i = 0; i < n; ++i) {
        const double u = static_cast<double>(i) / n;
        nodes.push_back(shadow.hi + span * u * u);
      }
    }
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  }
  const size_t segs = nodes.size() - 1;
  lit.assign(segs, 1);
  bool any_lit = false;
  for (size_t i = 0; i < segs; ++i) {
    lit[i] = !shadow.contains(0.5 * (nodes[i] + nodes[i + 1]));
    any_lit = any_lit || lit[i];
  }
  return any_lit;
}

// Single scattering integrals for one view ray and one sun direction.
Integrals IntegrateViewRay(const Atmosphere& atm, const AtmosphereOptions& opts, double r0, double sin_e,
                           double cos_e, double cos_ts, double sin_ts, double cos_phi, std::vector<double>& nodes,
                           std::vector<char>& lit) {
  Integrals out;
  const double length = atm.DistanceToTop(r0, sin_e);
  if (!(length > 0.0)) return out;
  const double mu = cos_e * sin_ts * cos_phi + sin_e * cos_ts;  // cos(view, sun)
  const Interval shadow = ShadowOnRay(r0, sin_e, cos_ts, sin_ts, mu, atm.bottom(), length);

  if (!PlaceViewNodes(length, shadow, opts.view_steps, nodes, lit)) return out;
  const size_t segs = nodes.size() - 1;

  const double p2 = r0 * r0 * cos_e * cos_e;
  const double os = r0 * cos_ts;
  auto radius_at = [&](double t) {
    const double along = t + r0 * sin_e;
    return std::sqrt(p2 + along * along);
  };

  Column to_observer;  // column from the observer to the current node
  Sample prev = atm.At(r0);
  std::array<double, 3> f_r_prev{}, f_m_prev{};
  auto integrand = [&](size_t node, const Sample& s, double radius, std::array<double, 3>& f_r,
                       std::array<double, 3>& f_m) {
    const bool needed = (node > 0 && lit[node - 1]) || (node < segs && lit[node]);
    if (!needed) return;
    const double t = nodes[node];
    const double mu_s = std::clamp((os + t * mu) / radius, -1.0, 1.0);
    Column total = atm.ColumnToTop(radius, mu_s, opts.sun_steps);
    total += to_observer;
    const auto tau = atm.Tau(total);
    for (int c = 0; c < 3; ++c) {
      const double tr = std::exp(-tau[c]);
      f_r[c] = s.rho_r * tr;
      f_m[c] = s.rho_m * tr;
    }
  };
  integrand(0, prev, r0, f_r_prev, f_m_prev);
  for (size_t i = 0; i < segs; ++i) {
    const double radius = radius_at(nodes[i + 1]);
    const Sample cur = atm.At(radius);
    const double ds = nodes[i + 1] - nodes[i];
    to_observer += atm.Segment(prev, cur, ds);
    std::array<double, 3> f_r{}, f_m{};
    integrand(i + 1, cur, radius, f_r, f_m);
    if (lit[i]) {
      for (int c = 0; c < 3; ++c) {
        out.rayleigh[c] += ds * LogMean(f_r_prev[c], f_r[c]);
        out.mie[c] += ds * LogMean(f_m_prev[c], f_m[c]);
      }
    }
    prev = cur;
    f_r_prev = f_r;
    f_m_prev = f_m;
  }
  return out;
}

}  // namespace

bool AtmosphereOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& field, double v, const std::string& expected) {
    *why = "atmosphere option " + field + " = " + Num(v) + " (expected " + expected + ")";
    return false;
  };
  auto finite_nonneg = [](double v) { return std::isfinite(v) && v >= 0.0; };
  // Physical bounds (atmosphere_bake.h): generous around Earth, tight enough that the
  // bake means something. Above an optical depth of 50 along the vertical, single
  // scattering leaves every LUT at zero (e^-50 ~ 2e-22): the preset would be black.
  if (!(planet_radius_m >= 1e3 && planet_radius_m <= 1e8)) {
    return fail("planet_radius_m", planet_radius_m, "[1e3, 1e8] m (Earth: 6.36e6)");
  }
  if (!std::isfinite(atmosphere_top_m) || !(atmosphere_top_m > planet_radius_m) ||
      !(atmosphere_top_m - planet_radius_m <= 1e6)) {
    return fail("atmosphere_top_m", atmosphere_top_m,
                "in (planet_radius_m, planet_radius_m + 1e6] = (" + Num(planet_radius_m) + ", " +
                    Num(planet_radius_m + 1e6) + "] m (Earth: radius + 6e4)");
  }
  if (!finite_nonneg(observer_altitude_m) || !(observer_altitude_m < atmosphere_top_m - planet_radius_m)) {
    return fail("observer_altitude_m", observer_altitude_m,
                "finite, >= 0 and below the atmosphere's top at " + Num(atmosphere_top_m - planet_radius_m) + " m");
  }
  for (int c = 0; c < 3; ++c) {
    if (!finite_nonneg(rayleigh_scattering_per_m[c])) {
      return fail("rayleigh_scattering_per_m[" + std::to_string(c) + "]", rayleigh_scattering_per_m[c],
                  "finite and >= 0, 1/m");
    }
  }
  if (!(rayleigh_scale_height_m >= 1.0 && rayleigh_scale_height_m <= 1e6)) {
    return fail("rayleigh_scale_height_m", rayleigh_scale_height_m, "[1, 1e6] m (Earth: 8000)");
  }
  if (!finite_nonneg(mie_scattering_per_m)) return fail("mie_scattering_per_m", mie_scattering_per_m, "finite and >= 0, 1/m");
  if (!std::isfinite(mie_extinction_per_m) || !(mie_extinction_per_m >= mie_scattering_per_m)) {
    return fail("mie_extinction_per_m", mie_extinction_per_m,
                "finite and >= mie_scattering_per_m = " + Num(mie_scattering_per_m) + " (absorption >= 0), 1/m");
  }
  if (!(mie_scale_height_m >= 1.0 && mie_scale_height_m <= 1e6)) {
    return fail("mie_scale_height_m", mie_scale_height_m, "[1, 1e6] m (Earth: 1200)");
  }
  for (int c = 0; c < 3; ++c) {
    if (!finite_nonneg(ozone_absorption_per_m[c])) {
      return fail("ozone_absorption_per_m[" + std::to_string(c) + "]", ozone_absorption_per_m[c], "finite and >= 0, 1/m");
    }
  }
  if (!(ozone_center_altitude_m >= 0.0 && ozone_center_altitude_m <= atmosphere_top_m - planet_radius_m)) {
    return fail("ozone_center_altitude_m", ozone_center_altitude_m,
                "[0, atmosphere thickness = " + Num(atmosphere_top_m - planet_radius_m) + "] m (Earth: 25000)");
  }
  if (!(ozone_width_m >= 1.0 && ozone_width_m <= 1e6)) return fail("ozone_width_m", ozone_width_m, "[1, 1e6] m (Earth: 15000)");
  if (!(sun_illuminance_lux > 0.0 && sun_illuminance_lux <= 2e5)) {
    return fail("sun_illuminance_lux", sun_illuminance_lux, "(0, 2e5] lux, the preset's bounds (Earth: 1.28e5)");
  }
  constexpr double kMaxVerticalDepth = 50.0;
  for (int c = 0; c < 3; ++c) {
    if (rayleigh_scattering_per_m[c] * rayleigh_scale_height_m > kMaxVerticalDepth) {
      return fail("rayleigh_scattering_per_m[" + std::to_string(c) + "]", rayleigh_scattering_per_m[c],
                  "a vertical optical depth (x rayleigh_scale_height_m) <= 50, i.e. <= " +
                      Num(kMaxVerticalDepth / rayleigh_scale_height_m) + " 1/m (Earth: ~1e-5)");
    }
    if (ozone_absorption_per_m[c] * ozone_width_m > kMaxVerticalDepth) {
      return fail("ozone_absorption_per_m[" + std::to_string(c) + "]", ozone_absorption_per_m[c],
                  "a vertical optical depth (x ozone_width_m) <= 50, i.e. <= " + Num(kMaxVerticalDepth / ozone_width_m) +
                      " 1/m (Earth: ~2e-6)");
    }
  }
  if (mie_extinction_per_m * mie_scale_height_m > kMaxVerticalDepth) {
    return fail(mie_scattering_per_m * mie_scale_height_m > kMaxVerticalDepth ? "mie_scattering_per_m" : "mie_extinction_per_m",
                mie_scattering_per_m * mie_scale_height_m > kMaxVerticalDepth ? mie_scattering_per_m : mie_extinction_per_m,
                "a vertical optical depth (x mie_scale_height_m) <= 50, i.e. <= " + Num(kMaxVerticalDepth / mie_scale_height_m) +
                    " 1/m (Earth: ~4e-6)");
  }
  constexpr int kMaxSteps = 100000;
  if (view_steps < 1 || view_steps > kMaxSteps) return fail("view_steps", view_steps, "1 .. 100000");
  if (sun_steps < 1 || sun_steps > kMaxSteps) return fail("sun_steps", sun_steps, "1 .. 100000");
  if (azimuth_samples < 1 || azimuth_samples > 10000) return fail("azimuth_samples", azimuth_samples, "1 .. 10000");
  return true;
}

void BakeSingleScattering(const AtmosphereOptions& opts, SkyLuts& luts) {
  std::string why;
  if (!opts.IsValid(&why)) throw Error("atmosphere bake: " + why);
  const LutGrid& g = luts.grid;
  if (g.n_theta < 2 || g.n_gamma < 2 || !std::isfinite(g.theta_max_deg) || !(g.theta_max_deg > 0.0) ||
      g.theta_max_deg > 180.0) {
    throw Error("atmosphere bake: LUT grid " + std::to_string(g.n_theta) + "x" + std::to_string(g.n_gamma) +
                ", theta_max_deg " + Num(g.theta_max_deg) + " (expected >= 2 rows and columns, theta_max in (0, 180] deg)");
  }
  const size_t n = luts.table_size();
  if (luts.rayleigh.size() != n || luts.mie.size() != n || luts.isotropic.size() != n ||
      luts.sun_transmittance.size() != static_cast<size_t>(g.n_theta) * 3) {
    throw Error("atmosphere bake: LUT tables are not sized for their " + std::to_string(g.n_theta) + "x" +
                std::to_string(g.n_gamma) + " grid (call SkyLuts::Resize first)");
  }

  const Atmosphere atm(opts);
  const double r0 = opts.planet_radius_m + opts.observer_altitude_m;
  const double e_sun = opts.sun_illuminance_lux;
  // Enough steps for the observer's own sun ray that its quadrature error is negligible
  // next to the LUT's interpolation (only n_theta rays).
  const int observer_sun_steps = std::max(opts.sun_steps, 2048);

  // One LUT row (sun zenith) at a time; rows are independent, so workers take them in
  // turn and the result does not depend on the number of threads.
  auto bake_row = [&](int row, std::vector<double>& nodes, std::vector<char>& lit) {
    // The model's row coordinate is linear in cos(sun zenith).
    const double cos_ts = LutRowSunHeight(g, row);
    const double sin_ts = std::sqrt((1.0 - cos_ts) * (1.0 + cos_ts));

    // Direct sun: blocked when the ray from the observer meets the planet.
    const bool blocked = cos_ts < 0.0 && r0 * sin_ts < opts.planet_radius_m;
    std::array<double, 3> tau_sun{};
    if (!blocked) tau_sun = atm.Tau(atm.ColumnToTop(r0, cos_ts, observer_sun_steps));
    for (int c = 0; c < 3; ++c) {
      luts.sun_transmittance[static_cast<size_t>(row) * 3 + c] = blocked ? 0.0f : static_cast<float>(std::exp(-tau_sun[c]));
    }

    for (int col = 0; col < g.n_gamma; ++col) {
      // The model's column coordinate is sqrt(sin(elevation)).
      const double sin_e = LutColumnViewHeight(g, col);
      const double cos_e = std::sqrt((1.0 - sin_e) * (1.0 + sin_e));
      // With the sun or the view at the zenith the relative azimuth does not matter.
      const int n_az = (sin_ts < 1e-12 || cos_e < 1e-12) ? 1 : opts.azimuth_samples;
      std::array<double, 3> sum_r{}, sum_m{};
      for (int k = 0; k < n_az; ++k) {
        // Midpoints over [0, pi]: the integral is symmetric in the relative azimuth.
        const double phi = (k + 0.5) * kPi / n_az;
        const Integrals in = IntegrateViewRay(atm, opts, r0, sin_e, cos_e, cos_ts, sin_ts, std::cos(phi), nodes, lit);
        for (int c = 0; c < 3; ++c) {
          sum_r[c] += in.rayleigh[c];
          sum_m[c] += in.mie[c];
        }
      }
      const size_t i = (static_cast<size_t>(row) * g.n_gamma + col) * 3;
      for (int c = 0; c < 3; ++c) {
        luts.rayleigh[i + c] = static_cast<float>(e_sun * opts.rayleigh_scattering_per_m[c] * sum_r[c] / n_az);
        luts.mie[i + c] = static_cast<float>(e_sun * opts.mie_scattering_per_m * sum_m[c] / n_az);
        luts.isotropic[i + c] = 0.0f;  // multiple scattering is not estimated
      }
    }
  };

  std::atomic<int> next_row{0};
  auto worker = [&] {
    std::vector<double> nodes;
    std::vector<char> lit;
    for (int row = next_row++; row < g.n_theta; row = next_row++) bake_row(row, nodes, lit);
  };
  const int n_workers = std::clamp(static_cast<int>(std::thread::hardware_concurrency()), 1, std::min(g.n_theta, 16));
  std::vector<std::thread> threads;
  for (int w = 1; w < n_workers; ++w) threads.emplace_back(worker);
  worker();
  for (std::thread& t : threads) t.join();
}

}  // namespace skycal::render
