#include "skycal/cloudfit/cloud_sun_scale.h"

#include <algorithm>
#include <cmath>

#include "skycal/core/error.h"

namespace skycal::cloudfit {

bool SunScaleSearchOptions::IsValid(std::string* why) const {
  if (!(lower > 0.0 && upper > lower && std::isfinite(upper))) {
    *why = "sun scale bounds [" + std::to_string(lower) + ", " + std::to_string(upper) + "] (expected 0 < lower < upper)";
    return false;
  }
  if (grid_points < 3 || !(tolerance_ln > 0.0) || max_evaluations < grid_points) {
    *why = "sun scale search: expected grid_points >= 3, tolerance_ln > 0, max_evaluations >= grid_points";
    return false;
  }
  return true;
}

SunScaleSearch MinimizeOverSunScale(const std::function<double(double)>& cost, const SunScaleSearchOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  SunScaleSearch r;
  auto eval = [&](double ln_s) {
    const double s = std::clamp(std::exp(ln_s), o.lower, o.upper), c = cost(s);
    r.scales.push_back(s);
    r.costs.push_back(c);
    if (r.scales.size() == 1 || c < r.cost) {
      r.cost = c;
      r.scale = s;
    }
    return c;
  };
  const double a = std::log(o.lower), b = std::log(o.upper), h = (b - a) / (o.grid_points - 1);
  // A grid first (the cost need not be unimodal over the whole range: the ambient's bound
  // bends it),
  std::vector<double> grid(o.grid_points);
  for (int i = 0; i < o.grid_points; ++i) grid[i] = eval(a + i * h);
  const int best = static_cast<int>(std::min_element(grid.begin(), grid.end()) - grid.begin());
  // Then successive parabolas in ln s through the best point and its two neighbours (in s)
  // among the points known in the best grid point's bracket: with the best in the middle the
  // vertex stays between them (the profile is smooth there); a few evaluations where golden
  // sections took ~12 on the real skies.
  std::vector<std::pair<double, double>> pts;  // (ln s, cost), sorted by ln s
  for (int i = std::max(best - 1, 0); i <= std::min(best + 1, o.grid_points - 1); ++i) pts.push_back({a + i * h, grid[i]});
  if (pts.size() == 2) {  // the best grid point is a bound: a midpoint makes three
    const double m = 0.5 * (pts[0].first + pts[1].first);
    pts.insert(pts.begin() + 1, {m, eval(m)});
  }
  bool improved = true;  // the last step lowered the best cost
  while (static_cast<int>(r.scales.size()) < o.max_evaluations) {
    const size_t ib = std::min_element(pts.begin(), pts.end(), [](const auto& p, const auto& q) { return p.second < q.second; }) -
                      pts.begin();
    const size_t im = std::clamp<size_t>(ib, 1, pts.size() - 2);  // the middle of the three
    const auto [x0, f0] = pts[im - 1];
    const auto [x1, f1] = pts[im];
    const auto [x2, f2] = pts[im + 1];
    // The vertex of the parabola through the three (Brent's formula); where it does not open
    // upward, the midpoint of the wider side of the best point.
    const double p1 = (x1 - x0) * (x1 - x0) * (f1 - f2) - (x1 - x2) * (x1 - x2) * (f1 - f0);
    const double q1 = (x1 - x0) * (f1 - f2) - (x1 - x2) * (f1 - f0);
    const double curvature = ((f2 - f1) / (x2 - x1) - (f1 - f0) / (x1 - x0)) / (x2 - x0);
    const double xb = pts[ib].first;
    double x = curvature > 0.0 && q1 != 0.0 ? x1 - 0.5 * p1 / q1 : INFINITY;
    if (!std::isfinite(x)) x = ib == im ? (x2 - x1 > x1 - x0 ? 0.5 * (x1 + x2) : 0.5 * (x0 + x1)) : xb;
    // Brent's safeguard: a vertex within a tenth of the triple's width of the best point
    // creeps (one-sided parabolas beside a kink, e.g. where the ambient reaches its bound):
    // a golden step into the wider side instead.
    // So does a parabola that misled the last step (no lower cost).
    if (ib == im && (!improved || std::abs(x - x1) < 0.1 * (x2 - x0)) && std::abs(x2 - x0) >= 2.0 * o.tolerance_ln)
      x = x2 - x1 > x1 - x0 ? x1 + 0.381966 * (x2 - x1) : x1 - 0.381966 * (x1 - x0);
    x = std::clamp(x, pts.front().first, pts.back().first);
    double nearest = INFINITY;
    for (const auto& p : pts) nearest = std::min(nearest, std::abs(p.first - x));
    if (nearest < o.tolerance_ln) break;  // the next vertex lands on a point already known
    const double best_before = r.cost, f = eval(x);
    improved = f < best_before;
    pts.insert(std::upper_bound(pts.begin(), pts.end(), std::make_pair(x, -HUGE_VAL)), std::make_pair(x, f));
  }
  // A minimum at a bound: the grid's end point is the best and the sections stayed beside it.
  r.at_lower = std::log(r.scale) - a < 2.0 * o.tolerance_ln;
  r.at_upper = b - std::log(r.scale) < 2.0 * o.tolerance_ln;
  return r;
}

}  // namespace skycal::cloudfit
