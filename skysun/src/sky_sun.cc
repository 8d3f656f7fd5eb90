// The sun's direction from the sky's luminance pattern: a grid search over candidate suns
// of the CIE general sky (CIE S 011/E:2003) fitted on ln luminance. Method: sky_sun.h.
#include "skycal/skysun/sky_sun.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <Eigen/Dense>

#include "skycal/core/error.h"
#include "skycal/core/format_number.h"
#include "skycal/core/latlong.h"
#include "skycal/core/luminance.h"
#include "skycal/refsky/cie_sky.h"

namespace skycal::skysun {
namespace {

using Vec3d = latlong::Vec3d;
constexpr double kDeg = std::numbers::pi / 180.0;

struct Cell {
  double ln_y = 0.0;  // solid-angle weighted mean of ln Y
  double weight = 0.0;  // steradians of sky in the cell
  Vec3d dir{};          // unit vector, solid-angle weighted mean direction
};

// ln f(chi) of one indicatrix group tabulated on chi in [0, pi] (the indicatrix depends on
// the angle to the sun only), linear interpolation: one acos per cell and candidate.
struct IndicatrixTable {
  static constexpr int kSize = 4096;
  std::vector<double> ln_f;
  double Lookup(double chi) const {
    const double t = std::clamp(chi / std::numbers::pi, 0.0, 1.0) * (kSize - 1);
    const int i = std::min(static_cast<int>(t), kSize - 2);
    const double u = t - i;
    return ln_f[i] * (1.0 - u) + ln_f[i + 1] * u;
  }
};

// The models fitted at every candidate sun: ln Y = basis . beta + ln f_g(chi) + residual, beta
// solved in closed form. kCie: one model per CIE type, z = ln Y - ln phi(Z), basis {1} (the
// free scale). kPolynomial: one model per CIE indicatrix group, z = ln Y, basis
// {1, u, .., u^degree} in u = sin(elevation) (a free smooth gradation).
struct SkyModel {
  std::vector<int> cie_type;              // per model: the CIE type reported
  std::vector<int> group_of_model;        // per model: index into tables
  std::vector<IndicatrixTable> tables;    // one per distinct (c, d, e)
  std::vector<std::vector<double>> z;     // per model, per cell
  int basis_size = 1;
  std::vector<double> basis;              // per cell, basis_size values
  std::vector<double> normal_inverse;     // (sum w b b^T)^-1, basis_size^2, row-major
};

struct Candidate {
  Vec3d dir{};
  double cost = std::numeric_limits<double>::infinity();  // log RMSE, ln units
  int type_index = -1;
  double log_scale = 0.0;
};

std::string CheckRange(const char* field, double v, double lo, double hi, bool closed_lo = false) {
  if (std::isfinite(v) && (v > lo || (closed_lo && v == lo)) && v <= hi) return "";
  return std::string("SkySunOptions::") + field + " = " + FormatNumber(v) + " must be in " + (closed_lo ? "[" : "(") +
         FormatNumber(lo) + ", " + FormatNumber(hi) + "]";
}

bool Usable(const ImageRGB& img, const std::vector<float>& mask, int x, int y, double clip) {
  const size_t k = static_cast<size_t>(y) * img.width + x;
  if (!mask.empty() && !(mask[k] >= 0.5f)) return false;
  const float* p = &img.pixels[img.index(x, y)];
  for (int c = 0; c < 3; ++c) {
    if (!std::isfinite(p[c])) return false;
    if (clip > 0.0 && p[c] >= clip) return false;
  }
  return Rec709Luminance<double>(p[0], p[1], p[2]) > 0.0;
}

// Bins the usable sky pixels above the horizon into cells of about cell_deg a side.
std::vector<Cell> BinSky(const ImageRGB& img, const std::vector<float>& mask, const SkySunOptions& o) {
  const int cols = std::max(4, static_cast<int>(std::lround(360.0 / o.cell_deg)));
  const int rows = std::max(1, static_cast<int>(std::lround(90.0 / o.cell_deg)));
  std::vector<Cell> acc(static_cast<size_t>(cols) * rows);
  for (int y = 0; y < img.height; ++y) {
    const double lat = latlong::Latitude(y, img.height);
    if (!(lat > 0.0)) continue;
    const int r = std::min(rows - 1, static_cast<int>((std::numbers::pi / 2 - lat) / (std::numbers::pi / 2) * rows));
    for (int x = 0; x < img.width; ++x) {
      if (!Usable(img, mask, x, y, o.clip_value)) continue;
      const double lon = latlong::Longitude(x, img.width);
      const int c = std::min(cols - 1, static_cast<int>((std::numbers::pi - lon) / (2 * std::numbers::pi) * cols));
      const float* p = &img.pixels[img.index(x, y)];
      const double w = latlong::PixelSolidAngle(x, y, img.width, img.height);
      const Vec3d v = latlong::PixelDirection(x, y, img.width, img.height);
      Cell& cell = acc[static_cast<size_t>(r) * cols + c];
      cell.ln_y += w * std::log(Rec709Luminance<double>(p[0], p[1], p[2]));
      cell.weight += w;
      for (int k = 0; k < 3; ++k) cell.dir[k] += w * v[k];
    }
  }
  std::vector<Cell> cells;
  const double band = (std::numbers::pi / 2) / rows, sector = 2 * std::numbers::pi / cols;
  for (size_t i = 0; i < acc.size(); ++i) {
    Cell c = acc[i];
    const int r = static_cast<int>(i) / cols;
    // Solid angle of the full cell: sector x (sin of its upper latitude - sin of its lower).
    const double full = sector * (std::cos(r * band) - std::cos((r + 1) * band));
    if (!(c.weight >= o.min_cell_fill * full)) continue;
    c.ln_y /= c.weight;
    c.dir = latlong::Normalized(c.dir, "sky cell direction");
    cells.push_back(c);
  }
  return cells;
}

IndicatrixTable Tabulate(const refsky::CieSkyType& t) {
  IndicatrixTable table;
  table.ln_f.resize(IndicatrixTable::kSize);
  for (int i = 0; i < IndicatrixTable::kSize; ++i) {
    const double chi = std::numbers::pi * i / (IndicatrixTable::kSize - 1);
    // f > 0 for every standard type; the floor only guards a user table.
    table.ln_f[i] = std::log(std::max(1e-6, refsky::CieIndicatrix(t, chi)));
  }
  return table;
}

// The basis per cell and the inverse of its weighted normal matrix (fixed: the basis depends
// on the cell's elevation only, not on the sun).
void SetBasis(const std::vector<Cell>& cells, int degree, SkyModel* m) {
  const int k = degree + 1;
  m->basis_size = k;
  m->basis.resize(cells.size() * k);
  Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(k, k);
  for (size_t i = 0; i < cells.size(); ++i) {
    Eigen::VectorXd b(k);
    for (int j = 0; j < k; ++j) b[j] = std::pow(cells[i].dir[1], j);
    normal += cells[i].weight * b * b.transpose();
    for (int j = 0; j < k; ++j) m->basis[i * k + j] = b[j];
  }
  // Pseudo-inverse: a mask leaving a narrow elevation band makes the powers of u nearly
  // collinear; the minimum-norm fit keeps the cost right there.
  const Eigen::MatrixXd inv = normal.completeOrthogonalDecomposition().pseudoInverse();
  m->normal_inverse.assign(inv.data(), inv.data() + k * k);  // symmetric: layout does not matter
}

// The indicatrix tables (shared by types of one indicatrix group) and the models.
SkyModel BuildModel(const std::vector<Cell>& cells, const SkySunOptions& o) {
  SkyModel m;
  const auto types = refsky::LoadCieSkyTypes(o.cie_csv_path.empty() ? refsky::DefaultCieCsvPath() : o.cie_csv_path);
  std::vector<const refsky::CieSkyType*> group_rep;
  const bool cie = o.gradation == SkySunOptions::Gradation::kCie;
  for (const auto& t : types) {
    int g = -1;
    for (size_t k = 0; k < group_rep.size(); ++k)
      if (group_rep[k]->c == t.c && group_rep[k]->d == t.d && group_rep[k]->e == t.e) g = static_cast<int>(k);
    const bool new_group = g < 0;
    if (new_group) {
      g = static_cast<int>(group_rep.size());
      group_rep.push_back(&t);
      m.tables.push_back(Tabulate(t));
    }
    if (!cie && !new_group) continue;  // kPolynomial: one model per indicatrix group
    m.cie_type.push_back(t.type);
    m.group_of_model.push_back(g);
    std::vector<double> z(cells.size());
    for (size_t i = 0; i < cells.size(); ++i)
      z[i] = cells[i].ln_y - (cie ? std::log(refsky::CieGradation(t, cells[i].dir[1])) : 0.0);
    m.z.push_back(std::move(z));
  }
  SetBasis(cells, cie ? 0 : o.polynomial_degree, &m);
  return m;
}

// Every model fitted for one sun direction: beta = N^-1 sum w b r (r = z - ln f), the cost
// sqrt((sum w r^2 - c^T N^-1 c) / sum w), the weighted RMS of the residual after the fit.
Candidate Evaluate(const SkyModel& m, const std::vector<Cell>& cells, const Vec3d& sun,
                   std::vector<std::vector<double>>& ln_f) {
  const size_t n = cells.size();
  const int k = m.basis_size;
  ln_f.resize(m.tables.size());
  for (size_t g = 0; g < m.tables.size(); ++g) ln_f[g].resize(n);
  double sw = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const Vec3d& v = cells[i].dir;
    const double chi = std::acos(std::clamp(v[0] * sun[0] + v[1] * sun[1] + v[2] * sun[2], -1.0, 1.0));
    for (size_t g = 0; g < m.tables.size(); ++g) ln_f[g][i] = m.tables[g].Lookup(chi);
    sw += cells[i].weight;
  }
  Candidate best;
  best.dir = sun;
  std::vector<double> c(k), beta(k);
  for (size_t t = 0; t < m.z.size(); ++t) {
    const std::vector<double>& z = m.z[t];
    const std::vector<double>& f = ln_f[m.group_of_model[t]];
    double swr2 = 0.0;
    std::fill(c.begin(), c.end(), 0.0);
    for (size_t i = 0; i < n; ++i) {
      const double r = z[i] - f[i], w = cells[i].weight;
      swr2 += w * r * r;
      for (int j = 0; j < k; ++j) c[j] += w * r * m.basis[i * k + j];
    }
    double explained = 0.0;
    for (int a = 0; a < k; ++a) {
      beta[a] = 0.0;
      for (int b = 0; b < k; ++b) beta[a] += m.normal_inverse[a * k + b] * c[b];
      explained += c[a] * beta[a];
    }
    const double cost = std::sqrt(std::max(0.0, (swr2 - explained) / sw));
    if (cost < best.cost) {
      best = Candidate{sun, cost, static_cast<int>(t), beta[0]};
    }
  }
  return best;
}

// Candidates on an elevation/azimuth grid of `step` within +-`radius` of (el0, az0) (deg),
// elevations clamped to [min_elevation, 90]; radius >= 180 covers the sphere.
void SearchGrid(const SkyModel& m, const std::vector<Cell>& cells, double el0, double az0, double radius, double step,
                const SkySunOptions& o, std::vector<Candidate>* out) {
  std::vector<std::vector<double>> ln_f;
  const double el_lo = std::max(o.min_elevation_deg, el0 - radius), el_hi = std::min(90.0, el0 + radius);
  const bool full_circle = radius >= 180.0;
  const int n_el = static_cast<int>(std::floor((el_hi - el_lo) / step + 1e-9)) + 1;
  const int n_az = full_circle ? static_cast<int>(std::lround(360.0 / step))
                               : static_cast<int>(std::floor(2 * radius / step + 1e-9)) + 1;
  for (int i = 0; i < n_el; ++i) {
    const double el = el_lo + i * step;
    // At the zenith every azimuth is one direction.
    const int n = el >= 90.0 - 1e-9 ? 1 : n_az;
    for (int j = 0; j < n; ++j) {
      const double az = full_circle ? -180.0 + j * step : az0 - radius + j * step;
      out->push_back(Evaluate(m, cells, latlong::DirectionFromElevationAzimuthDeg(el, az), ln_f));
    }
  }
}

double AngleDeg(const Vec3d& a, const Vec3d& b) {
  const double cx = a[1] * b[2] - a[2] * b[1], cy = a[2] * b[0] - a[0] * b[2], cz = a[0] * b[1] - a[1] * b[0];
  return std::atan2(std::sqrt(cx * cx + cy * cy + cz * cz), a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / kDeg;
}

const Candidate& Best(const std::vector<Candidate>& all) {
  return *std::min_element(all.begin(), all.end(),
                           [](const Candidate& a, const Candidate& b) { return a.cost < b.cost; });
}

std::vector<Cell> CheckedCells(const ImageRGB& img, const std::vector<float>& sky_mask, const SkySunOptions& o);

}  // namespace

std::string SkySunOptions::Invalid() const {
  for (const std::string& s : {CheckRange("cell_deg", cell_deg, 0.0, 30.0),
                               CheckRange("min_cell_fill", min_cell_fill, 0.0, 1.0),
                               CheckRange("coarse_step_deg", coarse_step_deg, 0.0, 30.0),
                               CheckRange("refine_step_deg", refine_step_deg, 0.0, coarse_step_deg),
                               CheckRange("final_step_deg", final_step_deg, 0.0, refine_step_deg),
                               CheckRange("relative_tolerance", relative_tolerance, 0.0, 10.0, true),
                               CheckRange("absolute_tolerance", absolute_tolerance, 0.0, 10.0, true),
                               CheckRange("max_uncertainty_deg", max_uncertainty_deg, 0.0, 180.0)})
    if (!s.empty()) return s;
  if (!(min_elevation_deg >= -90.0 && min_elevation_deg < 90.0))
    return "SkySunOptions::min_elevation_deg = " + FormatNumber(min_elevation_deg) + " must be in [-90, 90)";
  if (polynomial_degree < 0 || polynomial_degree > 6)
    return "SkySunOptions::polynomial_degree = " + std::to_string(polynomial_degree) + " must be in [0, 6]";
  if (min_cells < 3) return "SkySunOptions::min_cells = " + std::to_string(min_cells) + " must be at least 3";
  if (!(clip_value >= 0.0)) return "SkySunOptions::clip_value = " + FormatNumber(clip_value) + " must be >= 0";
  return "";
}

bool SkySunOptions::IsValid(std::string* why) const {
  *why = Invalid();
  return why->empty();
}

namespace {

std::vector<Cell> CheckedCells(const ImageRGB& img, const std::vector<float>& sky_mask, const SkySunOptions& o) {
  if (const std::string why = o.Invalid(); !why.empty()) throw Error(why);
  if (!sky_mask.empty() && sky_mask.size() != static_cast<size_t>(img.width) * img.height)
    throw Error("sky sun: the sky mask has " + std::to_string(sky_mask.size()) + " values, the image " +
                std::to_string(img.width) + " x " + std::to_string(img.height) + " pixels");
  std::vector<Cell> cells = BinSky(img, sky_mask, o);
  if (static_cast<int>(cells.size()) < o.min_cells)
    throw Error("sky sun: " + std::to_string(cells.size()) + " sky cells above the horizon, SkySunOptions::min_cells = " +
                std::to_string(o.min_cells));
  return cells;
}

}  // namespace

SkySunEstimate FitSunFromSky(const ImageRGB& img, const std::vector<float>& sky_mask, const SkySunOptions& o) {
  const std::vector<Cell> cells = CheckedCells(img, sky_mask, o);
  const SkyModel model = BuildModel(cells, o);
  std::vector<Candidate> all;
  SearchGrid(model, cells, 0.0, 0.0, 180.0, o.coarse_step_deg, o, &all);
  const Candidate coarse = Best(all);
  SearchGrid(model, cells, latlong::ElevationDeg(coarse.dir), latlong::AzimuthDeg(coarse.dir), o.coarse_step_deg,
             o.refine_step_deg, o, &all);
  const Candidate fine = Best(all);
  SearchGrid(model, cells, latlong::ElevationDeg(fine.dir), latlong::AzimuthDeg(fine.dir), o.refine_step_deg,
             o.final_step_deg, o, &all);
  const Candidate best = Best(all);
  SkySunEstimate e;
  e.direction = best.dir;
  e.elevation_deg = latlong::ElevationDeg(best.dir);
  e.azimuth_deg = latlong::AzimuthDeg(best.dir);
  e.sky_type = model.cie_type[best.type_index];
  e.log_rmse = best.cost;
  e.log_scale = best.log_scale;
  e.cells = static_cast<int>(cells.size());
  e.candidates = static_cast<int>(all.size());
  e.elevation_at_bound = e.elevation_deg <= o.min_elevation_deg + 0.5 * o.final_step_deg;
  e.uncertainty_deg = e.elevation_uncertainty_deg = e.azimuth_uncertainty_deg = o.final_step_deg;
  const double limit = best.cost * (1.0 + o.relative_tolerance) + o.absolute_tolerance;
  for (const Candidate& c : all) {
    if (c.cost > limit) continue;
    ++e.candidates_within_tolerance;
    e.uncertainty_deg = std::max(e.uncertainty_deg, AngleDeg(c.dir, best.dir));
    e.elevation_uncertainty_deg =
        std::max(e.elevation_uncertainty_deg, std::abs(latlong::ElevationDeg(c.dir) - e.elevation_deg));
    const double daz = std::remainder(latlong::AzimuthDeg(c.dir) - e.azimuth_deg, 360.0);
    e.azimuth_uncertainty_deg = std::max(e.azimuth_uncertainty_deg, std::abs(daz));
  }
  return e;
}

double SkyFitCostAt(const ImageRGB& img, const std::vector<float>& sky_mask, const SkySunOptions& o,
                    const std::array<double, 3>& sun, int* sky_type) {
  const std::vector<Cell> cells = CheckedCells(img, sky_mask, o);
  const SkyModel model = BuildModel(cells, o);
  std::vector<std::vector<double>> ln_f;
  const Candidate c = Evaluate(model, cells, latlong::Normalized(sun, "sky sun: the sun direction"), ln_f);
  if (sky_type) *sky_type = model.cie_type[c.type_index];
  return c.cost;
}

std::optional<SkySunEstimate> EstimateSunFromSky(const ImageRGB& img, const std::vector<float>& sky_mask,
                                                 const SkySunOptions& o, std::string* why) {
  SkySunEstimate e = FitSunFromSky(img, sky_mask, o);
  if (e.uncertainty_deg > o.max_uncertainty_deg) {
    *why = "the sky does not place the sun: candidates within tolerance of the best fit (log RMSE " +
           FormatNumber(e.log_rmse) + ") lie up to " + FormatNumber(e.uncertainty_deg) +
           " deg apart, SkySunOptions::max_uncertainty_deg = " + FormatNumber(o.max_uncertainty_deg);
    return std::nullopt;
  }
  if (e.elevation_at_bound) {
    *why = "the best fit's sun lies at the lowest elevation searched, SkySunOptions::min_elevation_deg = " +
           FormatNumber(o.min_elevation_deg) + ": the sky places no minimum in elevation";
    return std::nullopt;
  }
  return e;
}

}  // namespace skycal::skysun
