#include "linear_start.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>

#include "robust_residual.h"

namespace skycal::fit {
namespace {

constexpr double kMadToSigma = 1.4826;      // MAD -> standard deviation for Gaussian errors
constexpr double kCauchyTuning = 2.385;     // 95% asymptotic efficiency (Holland & Welsch 1977)
constexpr double kGMax = 0.98;              // upper end of the g search (the preset allows 0.999)
// Scan nodes: denser toward 1, where the Mie lobe changes fastest with g.
constexpr double kScan[] = {0.0, 0.3, 0.5, 0.65, 0.75, 0.82, 0.88, 0.93, kGMax};
constexpr int kGoldenSteps = 8;             // scan bracket (~0.06-0.3) -> ~0.003-0.015 in g (refined on the robust level)
constexpr double kRefineHalfWidth = 0.02;   // the robust refinement's bracket around the search's g
constexpr int kRefineSteps = 6;             // 0.04 -> ~2e-3 in g
constexpr int kRefineShifts = 6;            // moves of the bracket when the minimum is on its edge
constexpr size_t kMaxOtherMinima = 2;       // scan minima re-ranked on the robust level
constexpr int kMaxGaussNewton = 4;          // log-space steps at the final scale
constexpr int kMaxFinalSteps = 2;           // on the final level
constexpr int kLogLeastSquaresSteps = 2;    // before the scale estimate
constexpr int kScaleRounds = 4;             // re-estimations of the scales
constexpr double kSettledCost = 1e-4;       // relative cost change that ends them

// rel RMSE from log errors (rel = e^e - 1), solid-angle weighted.
double RelativeRmse(const LinearSky& sky, const std::vector<double>& e) {
  double sq = 0.0, w = 0.0;
  for (size_t i = 0; i < e.size(); ++i) {
    const double rel = std::expm1(e[i]);
    sq += sky.error_weights()[i] * rel * rel;
    w += sky.error_weights()[i];
  }
  return w > 0.0 ? std::sqrt(sq / w) : 0.0;
}

// IRLS weight rho'(z), z = (e / s)^2 (the residual form of robust_residual.h); the scale
// per sample times `factor` (annealing).
std::vector<double> RobustWeights(RobustLoss loss, const std::vector<double>& scales, double factor,
                                  const std::vector<double>& e) {
  std::vector<double> w(e.size(), 1.0);
  if (loss == RobustLoss::kNone) return w;
  for (size_t i = 0; i < e.size(); ++i) {
    const double scale = factor * scales[i];
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
enum class SearchCost { kLogAfterStep, kRelative };

// `other_minima` (optional) receives the scan's other local minima, best first (at most
// kMaxOtherMinima): where g is weakly determined (a sun below the horizon) the coarse
// level's area averaging can rank them differently from the finer levels.
double SearchHaziness(const LinearSky& sky, const std::vector<double>& exposures, const std::vector<double>& weights,
                      double g_hint, int* solves, SearchCost measure = SearchCost::kLogAfterStep,
                      int golden_steps = kGoldenSteps, std::vector<double>* other_minima = nullptr) {
  // The cost of g: the log error after one Gauss-Newton step from the relative-error
  // solution. The relative error alone is asymmetric: a dark outlier (a building at 0.15x
  // the sky) costs (1 / 0.15 - 1)^2 = 32 against ln(0.15)^2 = 3.6 in log units, and
  // would pick g.
  auto cost = [&](double g) {
    if (measure == SearchCost::kRelative) {
      ++*solves;
      return sky.Solve(g, exposures, weights).cost;
    }
    *solves += 2;
    const LinearSkySolution first = sky.Solve(g, exposures, weights, nullptr, false);
    return sky.RobustLogCost(sky.Solve(g, exposures, weights, &first, false), exposures, RobustLoss::kNone,
                             std::vector<double>(sky.num_samples(), 1.0));
  };
  std::vector<double> nodes(std::begin(kScan), std::end(kScan));
  nodes.push_back(std::clamp(g_hint, 0.0, kGMax));
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  std::vector<double> costs;
  for (double g : nodes) costs.push_back(cost(g));
  const size_t best = static_cast<size_t>(std::min_element(costs.begin(), costs.end()) - costs.begin());
  if (other_minima) {
    std::vector<std::pair<double, double>> minima;  // (cost, g)
    for (size_t i = 0; i < nodes.size(); ++i) {
      const bool left = i == 0 || costs[i] < costs[i - 1], right = i + 1 == nodes.size() || costs[i] < costs[i + 1];
      if (left && right && i != best) minima.emplace_back(costs[i], nodes[i]);
    }
    std::sort(minima.begin(), minima.end());
    other_minima->clear();
    for (size_t i = 0; i < minima.size() && i < kMaxOtherMinima; ++i) other_minima->push_back(minima[i].second);
  }
  const double lo = nodes[best > 0 ? best - 1 : 0], hi = nodes[std::min(best + 1, nodes.size() - 1)];
  const double g = GoldenSection(cost, lo, hi, golden_steps);
  return cost(g) <= costs[best] ? g : nodes[best];
}

}  // namespace

RingLossScales EstimateRingScales(const LinearSky& sky, const std::vector<double>& e, double floor, double* sigma) {
  RingLossScales out;
  *sigma = kMadToSigma * WeightedMedianAbs(e, sky.error_weights());
  out.global = std::max(floor, kCauchyTuning * *sigma);
  std::vector<double> ring_e[RingLossScales::kRings], ring_w[RingLossScales::kRings];
  for (size_t i = 0; i < e.size(); ++i) {
    int k = 0;
    while (k + 1 < RingLossScales::kRings && sky.sun_angles_deg()[i] >= RingLossScales::kOuterEdgeDeg[k]) ++k;
    ring_e[k].push_back(e[i]);
    ring_w[k].push_back(sky.error_weights()[i]);
  }
  for (int k = 0; k < RingLossScales::kRings; ++k) {
    const double ring_sigma = ring_e[k].empty() ? 0.0 : kMadToSigma * WeightedMedianAbs(ring_e[k], ring_w[k]);
    out.ring[k] = std::max(out.global, kCauchyTuning * ring_sigma);
  }
  return out;
}

namespace {

std::vector<double> PerSample(const LinearSky& sky, const RingLossScales& rings) {
  std::vector<double> out(sky.num_samples());
  for (size_t i = 0; i < out.size(); ++i) out[i] = rings.At(sky.sun_angles_deg()[i]);
  return out;
}

}  // namespace

double RingLossScales::At(double sun_angle_deg) const {
  for (int k = 0; k < kRings; ++k) {
    if (sun_angle_deg < kOuterEdgeDeg[k]) return ring[k];
  }
  return ring[kRings - 1];
}

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

namespace {

// The running state of RunLinearStart's steps: the level being solved (`sky`), its
// solution, that solution's log errors and robust cost, and the exposures, robust
// weights, loss scales and g the next solve uses.
struct StartRun {
  const FitOptions& o;
  bool fit_exposures = false;
  LinearStartReport rep;
  std::vector<double> exposures;
  std::vector<double> weights;  // empty: least squares
  double g = 0.0;
  const LinearSky* sky = nullptr;
  LinearSkySolution sol;
  std::vector<double> e;        // the current solution's log errors
  RingLossScales rings;
  std::vector<double> scales;   // per sample, from `rings`
  double cost = 0.0;            // robust cost of `e`

  void UpdateExposures(const LinearSky& level, const LinearSkySolution& s) {
    if (!fit_exposures) return;
    const std::vector<double> best = level.BestExposures(s, weights);
    for (size_t r = 1; r < exposures.size(); ++r) exposures[r] *= best[r];
  }
  void AlternateExposures(const LinearSky& level, int rounds) {
    for (int k = 0; k < rounds && fit_exposures; ++k) {
      UpdateExposures(level, level.Solve(g, exposures, weights, nullptr, false));
      ++rep.solves;
    }
  }
  // One Gauss-Newton step of the robust log objective, the scales times `factor`.
  void GaussNewtonStep(double factor) {
    weights = RobustWeights(o.loss, scales, factor, e);
    sol = sky->Solve(g, exposures, weights, &sol, false);
    ++rep.solves;
    ++rep.gauss_newton_steps;
    UpdateExposures(*sky, sol);
    e = sky->LogErrors(sol, exposures);
    rep.cost_per_step.push_back({sky->width(), sky->RobustCostOf(e, o.loss, scales)});
  }
  // Steps at 1x until the cost changes by at most kSettledCost (relative).
  void Settle(int max_steps) {
    for (int k = 0; k < max_steps; ++k) {
      GaussNewtonStep(1.0);
      const double next = sky->RobustCostOf(e, o.loss, scales);
      const bool settled = std::abs(cost - next) <= kSettledCost * cost;
      cost = next;
      if (settled) break;
    }
  }
};

// Step 1's second half on the robust level: a relative least-squares solve, then least
// squares of the log error (Gauss-Newton steps, no robust weights): symmetric in over-
// and under-estimation, so dark outliers do not dominate the scale estimate.
void LeastSquaresOnRobust(const LinearSky& robust, StartRun* run) {
  run->sky = &robust;
  const LinearSky* sky = run->sky;
  run->sol = sky->Solve(run->g, run->exposures, run->weights, nullptr, false);
  ++run->rep.solves;
  run->UpdateExposures(*sky, run->sol);
  for (int k = 0; k < kLogLeastSquaresSteps; ++k) {
    run->sol = sky->Solve(run->g, run->exposures, run->weights, &run->sol, false);
    ++run->rep.solves;
    run->UpdateExposures(*sky, run->sol);
  }
  run->rep.rel_rmse_least_squares = RelativeRmse(*sky, sky->LogErrors(run->sol, run->exposures));
}

// Step 3: Gauss-Newton steps of the robust log objective, the scales annealed from 8x
// down, then the scales re-estimated while they shrink.
void RobustSteps(StartRun* run) {
  const LinearSky* sky = run->sky;
  RingLossScales& rings = run->rings;
  for (double factor : {8.0, 4.0, 2.0, 1.0, 1.0}) run->GaussNewtonStep(factor);
  // The scales again from the robust solution's residuals, until they stop shrinking:
  // contamination pulls the least-squares fit and inflates its MADs; each robust fit
  // sheds more of that pull.
  for (int round = 0; round < kScaleRounds; ++round) {
    double sigma = 0.0;
    const RingLossScales again = EstimateRingScales(*sky, run->e, run->o.loss_scale, &sigma);
    bool shrank = again.global < 0.95 * rings.global;
    for (int k = 0; k < RingLossScales::kRings; ++k) shrank = shrank || again.ring[k] < 0.95 * rings.ring[k];
    if (!shrank) break;
    run->rep.residual_sigma = sigma;
    // Ring-wise the smaller scale: a scale only ever narrows.
    rings.global = std::min(rings.global, again.global);
    for (int k = 0; k < RingLossScales::kRings; ++k) rings.ring[k] = std::min(rings.ring[k], again.ring[k]);
    run->scales = PerSample(*sky, rings);
    run->GaussNewtonStep(1.0);
    run->GaussNewtonStep(1.0);
  }
}

// Step 4: g once more under the robust log cost, in a narrow bracket around the search's
// g, and around the scan's other local minima re-ranked at this level.
void RefineHaziness(const std::vector<double>& other_minima, StartRun* run) {
  const LinearSky* sky = run->sky;
  const LinearSkySolution at = run->sol;
  auto robust_cost = [&](double gg) {
    ++run->rep.solves;
    return sky->RobustLogCost(sky->Solve(gg, run->exposures, run->weights, &at, false), run->exposures, run->o.loss,
                              run->scales);
  };
  // The bracket follows the minimum when it lands on an edge (the search level's
  // area averaging can bias g where g is weakly determined, e.g. a sun below the horizon).
  auto refine = [&](double from) {
    double gg = from;
    for (int shift = 0; shift < kRefineShifts; ++shift) {
      const double lo = std::max(0.0, gg - kRefineHalfWidth), hi = std::min(kGMax, gg + kRefineHalfWidth);
      const double next = GoldenSection(robust_cost, lo, hi, kRefineSteps);
      const bool at_edge =
          (next - lo < 0.1 * kRefineHalfWidth && lo > 0.0) || (hi - next < 0.1 * kRefineHalfWidth && hi < kGMax);
      gg = next;
      if (!at_edge) break;
    }
    return gg;
  };
  double g2 = refine(run->g);
  double best_cost = robust_cost(g2);
  for (double candidate : other_minima) {
    if (robust_cost(candidate) >= best_cost) continue;
    const double refined = refine(candidate);
    const double c = robust_cost(refined);
    if (c < best_cost) {
      best_cost = c;
      g2 = refined;
    }
  }
  if (std::abs(g2 - run->g) > 1e-6) {
    run->g = g2;
    run->Settle(kMaxGaussNewton);
  }
}

// Step 5 on a final level finer than the robust one.
void FinalLevelSteps(const LinearSky& final, StartRun* run) {
  // The final level sees LUT columns the coarser one did not (nearer the horizon):
  // a relative least-squares solve places them before the robust log steps.
  run->sky = &final;
  const LinearSky* sky = run->sky;
  run->scales = PerSample(*sky, run->rings);
  run->weights.clear();
  run->sol = sky->Solve(run->g, run->exposures, run->weights, nullptr, false);
  ++run->rep.solves;
  run->e = sky->LogErrors(run->sol, run->exposures);
  run->cost = sky->RobustCostOf(run->e, run->o.loss, run->scales);
  run->Settle(kMaxFinalSteps);
}

}  // namespace

LinearStartReport RunLinearStart(const LinearSky& search, const LinearSky& robust, const LinearSky& final,
                                 FitState* state, const FitOptions& o, bool fit_g, bool fit_exposures) {
  StartRun run{o, fit_exposures};
  for (double le : state->log_exposure) run.exposures.push_back(std::exp(le));
  run.g = std::clamp(state->g, 0.0, kGMax);
  // 1. Least squares of the relative error: exposures at the start's g, then g, on the
  //    search level; then the final level.
  const auto t0 = std::chrono::steady_clock::now();
  run.AlternateExposures(search, 3);
  std::vector<double> other_minima;
  if (fit_g) run.g = SearchHaziness(search, run.exposures, run.weights, run.g, &run.rep.solves,
                                    SearchCost::kLogAfterStep, kGoldenSteps, &other_minima);
  run.AlternateExposures(search, 2);
  const auto t1 = std::chrono::steady_clock::now();
  run.rep.search_time_s = std::chrono::duration<double>(t1 - t0).count();
  LeastSquaresOnRobust(robust, &run);

  // 2. The loss scales from the least-squares residuals.
  run.e = run.sky->LogErrors(run.sol, run.exposures);
  run.rings = EstimateRingScales(*run.sky, run.e, o.loss_scale, &run.rep.residual_sigma);
  run.scales = PerSample(*run.sky, run.rings);

  // 3. Gauss-Newton steps of the robust log objective, the scales annealed from 8x down,
  //    then at 1x until the cost settles.
  if (o.loss != RobustLoss::kNone) RobustSteps(&run);
  run.rep.loss_scale = run.rings.global;
  run.rep.ring_scales = run.rings;
  run.cost = run.sky->RobustCostOf(run.e, o.loss, run.scales);  // e: the current solution's log errors
  run.Settle(kMaxGaussNewton);
  // 4. g once more under the robust log cost, in a narrow bracket around the search's g.
  if (fit_g) RefineHaziness(other_minima, &run);
  const auto t2 = std::chrono::steady_clock::now();
  // 5. The final level: Gauss-Newton steps at the final g (the robust level's solution
  //    is its start: same unknowns, finer pixels).
  if (&final != &robust) FinalLevelSteps(final, &run);
  const auto t3 = std::chrono::steady_clock::now();
  LinearStartReport& rep = run.rep;
  const LinearSky* sky = run.sky;
  rep.robust_cost = run.cost;
  rep.robust_time_s = std::chrono::duration<double>(t2 - t1).count();
  rep.final_time_s = std::chrono::duration<double>(t3 - t2).count();
  rep.rel_rmse_robust = RelativeRmse(*sky, run.e);
  sky->Apply(run.sol, state);
  state->g = run.g;
  for (size_t r = 0; r < run.exposures.size(); ++r) state->log_exposure[r] = std::log(run.exposures[r]);
  rep.g = run.g;
  rep.held_non_positive = run.sol.held_non_positive;
  rep.exposures = run.exposures;
  rep.held = sky->HeldParameters(run.sol, state);
  rep.solution = run.sol;
  return std::move(run.rep);
}

CeilingReport MinimiseOverHaziness(const LinearSky& sky, const std::vector<double>& exposures, double g_hint) {
  int solves = 0;
  CeilingReport c;
  // The ceiling's own measure (rel_rmse): the relative least-squares cost, to ~1e-4 in g.
  c.g = SearchHaziness(sky, exposures, {}, g_hint, &solves, SearchCost::kRelative, 14);
  const LinearSkySolution s = sky.Solve(c.g, exposures, {});
  c.rel_rmse = s.rel_rmse;
  c.held_non_positive = s.held_non_positive;
  return c;
}

}  // namespace skycal::fit
