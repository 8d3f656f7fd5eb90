#include "skycal/core/row_mapping.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <nlohmann/json.hpp>

#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/format_number.h"
#include "skycal/core/latlong.h"
#include "skycal/core/math_constants.h"

namespace skycal {
namespace {

constexpr double kHalfPi = kPi / 2;
constexpr double kMaxShape = 30.0;  // sinh(30) ~ 5e12: density ratio horizon : pole up to ~5e12

// b / sinh(b), 1 in the limit b -> 0.
double ShapeSlope(double b) { return b == 0.0 ? 1.0 : b / std::sinh(b); }
// pi/2 sinh(b s) / sinh(b) and its inverse, the linear limit at b = 0.
double Bend(double b, double s) { return b == 0.0 ? kHalfPi * s : kHalfPi * std::sinh(b * s) / std::sinh(b); }
double Unbend(double b, double e) { return b == 0.0 ? e / kHalfPi : std::asinh(e / kHalfPi * std::sinh(b)) / b; }

}  // namespace

bool RowMapping::IsValid(std::string* why) const {
  auto fail = [why](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (rows < 3 || rows > kMaxExrSide) return fail("rows: expected an integer in [3, " + std::to_string(kMaxExrSide) + "]");
  if (!(b_up >= 0.0 && b_up <= kMaxShape)) return fail("b_up: expected a finite number in [0, 30], found " + FormatNumber(b_up));
  if (!(b_down >= 0.0 && b_down <= kMaxShape)) {
    return fail("b_down: expected a finite number in [0, 30], found " + FormatNumber(b_down));
  }
  return true;
}

double RowMapping::HorizonRow() const {
  const double cu = ShapeSlope(b_up), cd = ShapeSlope(b_down);
  return (rows - 1) * cu / (cu + cd);
}

double RowMapping::Elevation(double y) const {
  const double yh = HorizonRow(), last = rows - 1.0;
  y = std::clamp(y, 0.0, last);
  if (y <= yh) return Bend(b_up, (yh - y) / yh);
  return -Bend(b_down, (y - yh) / (last - yh));
}

double RowMapping::Row(double e) const {
  const double yh = HorizonRow(), last = rows - 1.0;
  e = std::clamp(e, -kHalfPi, kHalfPi);
  if (e >= 0.0) return yh * (1.0 - Unbend(b_up, e));
  return yh + (last - yh) * Unbend(b_down, -e);
}

double RowMapping::Density(double e) const {
  const double yh = HorizonRow(), last = rows - 1.0;
  const bool up = e >= 0.0;
  const double b = up ? b_up : b_down, span = up ? yh : last - yh;
  const double s = Unbend(b, std::abs(e));
  // de/ds = pi/2 b cosh(b s) / sinh(b) (pi/2 at b = 0); dy/ds = span.
  const double de_ds = kHalfPi * std::cosh(b * s) * ShapeSlope(b);
  return span / de_ds;
}

double RowMapping::PixelSolidAngle(int x, int y, int width) const {
  const double dlon = 2.0 * kPi / (width - 1);
  const double top = Elevation(y - 0.5), bottom = Elevation(y + 0.5);  // clamped at the poles
  const double column = (x == 0 || x == width - 1) ? 0.5 * dlon : dlon;
  return (std::sin(top) - std::sin(bottom)) * column;
}

std::array<double, 3> RowMapping::PixelDirection(int x, int y, int width) const {
  return latlong::Direction(Elevation(y), latlong::Longitude(x, width));
}

std::string RowMapping::ToAttribute() const {
  nlohmann::json j = {{"mapping", "horizon-sinh"}, {"version", 1}, {"rows", rows}, {"b_up", b_up}, {"b_down", b_down}};
  return j.dump();
}

RowMapping RowMapping::FromAttribute(const std::string& text, const std::string& where) {
  const std::string prefix = where + ": attribute '" + kRowMappingAttribute + "'";
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception&) {
    throw Error(prefix + " is not JSON: expected {\"mapping\": \"horizon-sinh\", \"version\": 1, \"rows\": N, "
                         "\"b_up\": B, \"b_down\": B}");
  }
  if (!j.is_object()) throw Error(prefix + ": expected a JSON object");
  auto field = [&](const char* name) -> const nlohmann::json& {
    if (!j.contains(name)) throw Error(prefix + ": field '" + name + "' is missing");
    return j.at(name);
  };
  if (!field("mapping").is_string() || field("mapping").get<std::string>() != "horizon-sinh") {
    throw Error(prefix + ": field 'mapping': expected \"horizon-sinh\", found " + field("mapping").dump());
  }
  if (!field("version").is_number_integer() || field("version").get<long long>() != 1) {
    throw Error(prefix + ": field 'version': expected 1, found " + field("version").dump());
  }
  RowMapping m;
  const nlohmann::json& rows = field("rows");
  if (!rows.is_number_integer()) throw Error(prefix + ": field 'rows': expected an integer, found " + rows.dump());
  const long long r = rows.get<long long>();
  m.rows = static_cast<int>(std::clamp<long long>(r, -1, kMaxExrSide + 1LL));
  for (const char* name : {"b_up", "b_down"}) {
    const nlohmann::json& b = field(name);
    if (!b.is_number()) throw Error(prefix + ": field '" + name + "': expected a number, found " + b.dump());
    (std::string(name) == "b_up" ? m.b_up : m.b_down) = b.get<double>();
  }
  std::string why;
  if (!m.IsValid(&why)) throw Error(prefix + ": field " + why);
  return m;
}

RowMapping RowMapping::ForDensities(int source_height, double horizon_density, double zenith_density,
                                    double nadir_density) {
  if (source_height < 3) throw Error("row mapping: the source frame needs at least 3 rows");
  for (double d : {horizon_density, zenith_density, nadir_density}) {
    if (!(d > 0.0 && std::isfinite(d))) throw Error("row mapping: densities must be finite and > 0");
  }
  if (zenith_density > horizon_density || nadir_density > horizon_density) {
    throw Error("row mapping: the horizon density (" + FormatNumber(horizon_density) +
                ") must be at least the zenith's (" + FormatNumber(zenith_density) + ") and the nadir's (" +
                FormatNumber(nadir_density) + ")");
  }
  RowMapping m;
  m.b_up = std::acosh(horizon_density / zenith_density);
  m.b_down = std::acosh(horizon_density / nadir_density);
  // Uniform density (H - 1) / pi rows per radian; above the horizon dy/de at 0 is
  // y_h / (pi/2 c_up), so y_h = d (H - 1) c_up / 2, likewise below.
  const double span = horizon_density * (source_height - 1) * (ShapeSlope(m.b_up) + ShapeSlope(m.b_down)) / 2.0;
  m.rows = static_cast<int>(std::lround(span)) + 1;
  std::string why;
  if (!m.IsValid(&why)) throw Error("row mapping: " + why);
  return m;
}

namespace {

// ResampleToRows for finite values: a non-finite value would poison the running integral
// of its whole column below it.
ImageRGB ResampleFiniteToRows(const ImageRGB& uniform, const RowMapping& m) {
  const int w = uniform.width, H = uniform.height;
  // cum[k]: integral of the linear interpolant from row 0 to row k, per column and channel.
  const size_t stride = static_cast<size_t>(w) * 3;
  std::vector<double> cum(static_cast<size_t>(H) * stride, 0.0);
  for (int k = 1; k < H; ++k)
    for (size_t i = 0; i < stride; ++i)
      cum[k * stride + i] = cum[(k - 1) * stride + i] +
                            0.5 * (static_cast<double>(uniform.pixels[(k - 1) * stride + i]) + uniform.pixels[k * stride + i]);
  auto value = [&](int k, size_t i) { return static_cast<double>(uniform.pixels[static_cast<size_t>(k) * stride + i]); };
  // The horizon is an edge (sky above, ground below): a row above it reads only the
  // source's rows above it (lat > 0), extrapolated linearly from the last two up to the
  // horizon; likewise below. No sky row mixes in ground.
  const double horizon = 0.5 * (H - 1);
  const int last_sky = static_cast<int>(std::ceil(horizon)) - 1, first_ground = static_cast<int>(std::floor(horizon)) + 1;
  // Integral from 0 to t of the linear interpolant through rows k, k + 1, k in [k_lo, k_hi]
  // (outside its segment: the segment's line extended).
  auto integral = [&](double t, size_t i, int k_lo, int k_hi) {
    const int k = std::clamp(static_cast<int>(std::floor(t)), k_lo, k_hi);
    const double u = t - k, f0 = value(k, i), f1 = value(k + 1, i);
    return cum[k * stride + i] + u * f0 + 0.5 * u * u * (f1 - f0);
  };
  ImageRGB out(w, m.rows);
  for (int y = 0; y < m.rows; ++y) {
    const double centre = m.Elevation(y);
    const bool sky = centre > 0.0 && last_sky >= 1, ground = centre < 0.0 && first_ground <= H - 2;
    const double lo = ground ? horizon : 0.0, hi = sky ? horizon : H - 1.0;
    const int k_lo = ground ? first_ground : 0, k_hi = sky ? last_sky - 1 : H - 2;
    auto source_row = [&](double e) { return std::clamp(latlong::RowOfLatitude(e, H), lo, hi); };
    const double a = source_row(m.Elevation(y - 0.5)), b = source_row(m.Elevation(y + 0.5));
    const double mid = source_row(centre);
    for (size_t i = 0; i < stride; ++i) {
      double v;
      if (b - a > 1e-9) {
        v = (integral(b, i, k_lo, k_hi) - integral(a, i, k_lo, k_hi)) / (b - a);
      } else {
        const int k = std::clamp(static_cast<int>(std::floor(mid)), k_lo, k_hi);
        v = value(k, i) + (mid - k) * (value(k + 1, i) - value(k, i));
      }
      out.pixels[static_cast<size_t>(y) * stride + i] = static_cast<float>(v);
    }
  }
  return out;
}

}  // namespace

ImageRGB ResampleToRows(const ImageRGB& uniform, const RowMapping& m, long long* unsourced) {
  const int w = uniform.width, H = uniform.height;
  if (H < 2 || w < 1) throw Error("ResampleToRows: the source needs at least 2 rows");
  if (unsourced) *unsourced = 0;
  const size_t stride = static_cast<size_t>(w) * 3;
  std::vector<uint8_t> bad_column(stride, 0);  // per column and channel: holds a non-finite value
  ImageRGB zeroed = uniform, valid(w, H);
  bool any_bad = false;
  for (size_t p = 0; p < uniform.pixels.size(); ++p) {
    const bool ok = std::isfinite(uniform.pixels[p]);
    valid.pixels[p] = ok ? 1.0f : 0.0f;
    if (!ok) zeroed.pixels[p] = 0.0f, bad_column[p % stride] = 1, any_bad = true;
  }
  ImageRGB out = ResampleFiniteToRows(zeroed, m);
  if (!any_bad) return out;  // bit-identical to the unmasked integral
  const ImageRGB weight = ResampleFiniteToRows(valid, m);
  for (size_t p = 0; p < out.pixels.size(); ++p) {
    if (!bad_column[p % stride]) continue;
    if (weight.pixels[p] >= 0.5f) {
      out.pixels[p] /= weight.pixels[p];
    } else {
      out.pixels[p] = 0.0f;
      if (unsourced) ++*unsourced;
    }
  }
  return out;
}

int UniformHeightCovering(const RowMapping& m) {
  // Uniform rows per radian: (H - 1) / pi; the mapping's largest is at the horizon.
  return static_cast<int>(std::ceil(kPi * m.Density(0.0))) + 1;
}

}  // namespace skycal
