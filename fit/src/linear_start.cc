#include "linear_start.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cmath>
#include <numeric>

#include "robust_residual.h"

namespace skycal::fit {
namespace {

constexpr double kMadToSigma = 1.4826;      // MAD -> standard deviation for Gaussian errors
constexpr double kCauchyTuning = 2.385;     // 95% asymptotic efficiency (Holland & Welsch 1977)
constexpr double kGMax = 0.98;              // upper end of the g search (the preset allows 0.999)
// Scan nodes: denser toward 1, where the Mie lobe changes fastest with g.
constexpr double kScan[] = {0.0, 0.2, 0.4, 0.55, 0.65, 0.72, 0.78, 0.83, 0.87, 0.9, 0.93, 0.96, kGMax};
constexpr int kGoldenSteps = 14;            // bracket of ~0.1 -> ~1e-4 in g
constexpr double kRefineHalfWidth = 0.02;   // the robust refinement's bracket around the search's g
constexpr int kRefineSteps = 8;             // 0.04 -> ~1e-3 in g
constexpr int kRefineShifts = 6;            // moves of the bracket when the minimum is on its edge
constexpr int kMaxGaussNewton = 6;          // log-space steps at the final scale
constexpr int kMaxFinalSteps = 3;
constexpr int kLogLeastSquaresSteps = 2;    // before the scale estimate           // on the final level
constexpr double kSettledCost = 1e-5;       // relative cost change that ends them

// IRLS weight rho'(z), z = (e / s)^2 (the residual form of robust_residual.h).
std::vector<double> RobustWeights(RobustLoss loss, double scale, const std::vector<double>& e) {
  std::vector<double> w(e.size(), 1.0);
  if (loss == RobustLoss::kNone) return w;
  for (size_t i = 0; i < e.size(); ++i) {
    double rho = 0.0, drho = 1.0;
    RobustRho(loss, (e[i] / scale) * (e[i] / scale), &rho, &drho);
    w[i] = drho;
  }
  return w;
}

// Minimises f over [a, b] by golden sections, given f at the scan's best node inside.
template <typename F>
double GoldenSection(F&& f, double a, double b, int steps) {
  const double phi = 0.5 * (std::sqrt(5.0) - 1.0);
  double c = b - phi * (b - a), d = a + phi * (b - a);
  double fc = f(c), fd = f(d);
  for (int i = 0; i < steps; ++i) {
    if (fc < fd) {
      b = d; d = c; fd = fc; c = b - phi * (b - a); fc = f(c);
    } else {
      a = c; c = d; fc = fd; d = a + phi * (b - a); fd = f(d);
    }
  }
  return fc < fd ? c : d;
}

// Best g for the given weights and exposures: scan, then golden sections around the best.
double SearchHaziness(const LinearSky& sky, const std::vector<double>& exposures, const std::vector<double>& weights,
                      double g_hint, int* solves) {
  // The cost of g: the log error after one Gauss-Newton step from the relative-error
  // solution. The relative error alone is asymmetric: a dark outlier (a building at 0.15x
  // the sky) costs (1 / 0.15 - 1)^2 = 32 against ln(0.15)^2 = 3.6 in log units, and
  // would pick g.
  auto cost = [&](double g) {
    *solves += 2;
    const LinearSkySolution first = sky.Solve(g, exposures, weights);
    return sky.RobustLogCost(sky.Solve(g, exposures, weights, &first), exposures, RobustLoss::kNone, 1.0);
  };
  std::vector<double> nodes(std::begin(kScan), std::end(kScan));
  nodes.push_back(std::clamp(g_hint, 0.0, kGMax));
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  std::vector<double> costs;
  for (double g : nodes) costs.push_back(cost(g));
  if (std::getenv("SKYCAL_DEBUG_LINEAR")) {
    for (size_t i = 0; i < nodes.size(); ++i) {
      const auto sol = sky.Solve(nodes[i], exposures, weights);
      std::fprintf(stderr, "DEBUG scan g %.3f cost %.6g rel %.5f held %d\n", nodes[i], costs[i], sol.rel_rmse, sol.held_non_positive);
    }
  }
  const size_t best = static_cast<size_t>(std::min_element(costs.begin(), costs.end()) - costs.begin());
  const double lo = nodes[best > 0 ? best - 1 : 0], hi = nodes[std::min(best + 1, nodes.size() - 1)];
  const double g = GoldenSection(cost, lo, hi, kGoldenSteps);
  return cost(g) <= costs[best] ? g : nodes[best];
}

}  // namespace

double WeightedMedianAbs(const std::vector<double>& values, const std::vector<double>& weights) {
  std::vector<size_t> order(values.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return std::abs(values[a]) < std::abs(values[b]); });
  const double total = std::accumulate(weights.begin(), weights.end(), 0.0);
  double acc = 0.0;
  for (size_t i : order) {
    acc += weights[i];
    if (acc >= 0.5 * total) return std::abs(values[i]);
  }
  return 0.0;
}

LinearStartReport RunLinearStart(const LinearSky& search, const LinearSky& robust, const LinearSky& final,
                                 FitState* state, const FitOptions& o, bool fit_g, bool fit_exposures) {
  LinearStartReport rep;
  std::vector<double> exposures;
  for (double le : state->log_exposure) exposures.push_back(std::exp(le));
  std::vector<double> weights;  // empty: least squares
  double g = std::clamp(state->g, 0.0, kGMax);
  auto update_exposures = [&](const LinearSky& level, const LinearSkySolution& s) {
    if (!fit_exposures) return;
    for (size_t r = 1; r < exposures.size(); ++r) exposures[r] *= level.BestExposure(s, r, weights);
  };
  auto alternate_exposures = [&](const LinearSky& level, int rounds) {
    for (int k = 0; k < rounds && fit_exposures; ++k) {
      update_exposures(level, level.Solve(g, exposures, weights));
      ++rep.solves;
    }
  };
  // 1. Least squares of the relative error: exposures at the start's g, then g, on the
  //    search level; then the final level.
  const auto t0 = std::chrono::steady_clock::now();
  alternate_exposures(search, 3);
  if (fit_g) g = SearchHaziness(search, exposures, weights, g, &rep.solves);
  alternate_exposures(search, 2);
  const auto t1 = std::chrono::steady_clock::now();
  rep.search_time_s = std::chrono::duration<double>(t1 - t0).count();
  const LinearSky* sky = &robust;
  LinearSkySolution sol = sky->Solve(g, exposures, weights);
  ++rep.solves;
  update_exposures(*sky, sol);
  // Least squares of the log error (Gauss-Newton steps, no robust weights): symmetric in
  // over- and under-estimation, so dark outliers do not dominate the scale estimate.
  for (int k = 0; k < kLogLeastSquaresSteps; ++k) {
    sol = sky->Solve(g, exposures, weights, &sol);
    ++rep.solves;
    update_exposures(*sky, sol);
  }
  rep.rel_rmse_least_squares = sol.rel_rmse;

  // 2. The loss scale from the least-squares residuals.
  std::vector<double> e = sky->LogErrors(sol, exposures);
  rep.residual_sigma = kMadToSigma * WeightedMedianAbs(e, sky->error_weights());
  rep.loss_scale = std::max(o.loss_scale, kCauchyTuning * rep.residual_sigma);
  double s = rep.loss_scale;

  // 3. Gauss-Newton steps of the robust log objective, the scale annealed from 8 s to s,
  //    then at s until the cost settles.
  auto gauss_newton_step = [&](double scale) {
    weights = RobustWeights(o.loss, scale, e);
    sol = sky->Solve(g, exposures, weights, &sol);
    ++rep.solves;
    ++rep.gauss_newton_steps;
    update_exposures(*sky, sol);
    e = sky->LogErrors(sol, exposures);
  };
  if (o.loss != RobustLoss::kNone) {
    for (double factor : {8.0, 4.0, 2.0, 1.0}) {
      gauss_newton_step(factor * s);
      gauss_newton_step(factor * s);
    }
    // The scale once more, from the robust solution's residuals: contamination pulls the
    // least-squares fit and inflates its MAD; the robust fit's residuals do not.
    const double sigma = kMadToSigma * WeightedMedianAbs(e, sky->error_weights());
    const double s2 = std::max(o.loss_scale, kCauchyTuning * sigma);
    if (s2 < s) {
      rep.residual_sigma = sigma;
      for (double factor : {0.5, 0.25}) gauss_newton_step(std::max(s2, factor * s));
      s = s2;
    }
    rep.loss_scale = s;
  }
  double cost = sky->RobustLogCost(sol, exposures, o.loss, s);
  auto settle = [&](int max_steps) {
    for (int k = 0; k < max_steps; ++k) {
      gauss_newton_step(s);
      const double next = sky->RobustLogCost(sol, exposures, o.loss, s);
      const bool settled = std::abs(cost - next) <= kSettledCost * cost;
      if (std::getenv("SKYCAL_DEBUG_LINEAR")) std::fprintf(stderr, "DEBUG GN cost %.8g -> %.8g rel %.5f held %d\n", cost, next, sol.rel_rmse, sol.held_non_positive);
      cost = next;
      if (settled) break;
    }
  };
  settle(kMaxGaussNewton);
  // 4. g once more under the robust log cost, in a narrow bracket around the search's g.
  if (fit_g) {
    const LinearSkySolution at = sol;
    auto robust_cost = [&](double gg) {
      ++rep.solves;
      return sky->RobustLogCost(sky->Solve(gg, exposures, weights, &at), exposures, o.loss, s);
    };
    // The bracket follows the minimum when it lands on an edge (the search level's
    // area averaging can bias g where g is weakly determined, e.g. a sun below the horizon).
    double g2 = g;
    for (int shift = 0; shift < kRefineShifts; ++shift) {
      const double lo = std::max(0.0, g2 - kRefineHalfWidth), hi = std::min(kGMax, g2 + kRefineHalfWidth);
      const double next = GoldenSection(robust_cost, lo, hi, kRefineSteps);
      const bool at_edge = (next - lo < 0.1 * kRefineHalfWidth && lo > 0.0) || (hi - next < 0.1 * kRefineHalfWidth && hi < kGMax);
      g2 = next;
      if (!at_edge) break;
    }
    if (std::abs(g2 - g) > 1e-6) {
      g = g2;
      settle(kMaxGaussNewton);
    }
  }
  const auto t2 = std::chrono::steady_clock::now();
  // 5. The final level: Gauss-Newton steps at the final g (the robust level's solution
  //    is its start: same unknowns, finer pixels).
  if (&final != &robust) {
    sky = &final;
    e = sky->LogErrors(sol, exposures);
    cost = sky->RobustLogCost(sol, exposures, o.loss, s);
    settle(kMaxFinalSteps);
  }
  const auto t3 = std::chrono::steady_clock::now();
  rep.robust_cost = cost;
  rep.robust_time_s = std::chrono::duration<double>(t2 - t1).count();
  rep.final_time_s = std::chrono::duration<double>(t3 - t2).count();
  rep.rel_rmse_robust = sol.rel_rmse;
  sky->Apply(sol, state);
  state->g = g;
  for (size_t r = 0; r < exposures.size(); ++r) state->log_exposure[r] = std::log(exposures[r]);
  rep.g = g;
  rep.held_non_positive = sol.held_non_positive;
  rep.exposures = exposures;
  rep.held = sky->HeldParameters(sol, state);
  rep.solution = sol;
  return rep;
}

CeilingReport MinimiseOverHaziness(const LinearSky& sky, const std::vector<double>& exposures, double g_hint) {
  int solves = 0;
  CeilingReport c;
  c.g = SearchHaziness(sky, exposures, {}, g_hint, &solves);
  const LinearSkySolution s = sky.Solve(c.g, exposures, {});
  c.rel_rmse = s.rel_rmse;
  c.held_non_positive = s.held_non_positive;
  return c;
}

}  // namespace skycal::fit
