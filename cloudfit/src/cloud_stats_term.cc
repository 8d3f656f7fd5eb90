#include "cloud_stats_term.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <Eigen/Dense>
#include <ceres/problem.h>
#include <ceres/solver.h>

#include "skycal/core/error.h"

namespace skycal::cloudfit {
namespace {

// Why each lighting field outside the fitted set is held (what the statistics cannot
// separate, measured in bench/results/cloud_stats_seed_pairs.md or argued from the model).
std::string WhyHeld(const std::string& name) {
  if (name == "scattering_albedo")
    return "an overall scale of the cloud radiance, traded against the sun's illuminance and the exposure";
  // Measured with unknown shapes (bench/results/cloud_stats_seed_pairs.md, "Shape noise"):
  // the statistics' shape noise predicts these spreads from one reference, and the seed
  // pairs land there.
  if (name == "phase_g1")
    return "not separable from one sky's statistics: shape noise alone predicts an sd of 84% (40% whitened); "
           "5 seed pairs land 38-105% off (median over three weightings; worst 89-221%)";
  if (name == "powder_strength")
    return "not separable from one sky's statistics: shape noise alone predicts an sd of 136% (75% whitened); "
           "5 seed pairs land 64-134% off (median over three weightings; at a bound in most pairs)";
  if (name == "extinction")
    return "not determined by one sky's statistics with unknown shapes: over 5 seed pairs the fit stays on its "
           "start's side of the truth (from 1.3x: +5..+39%, from 0.7x: -17..-44%, full GLS) and drags the ambient "
           "13-20% off with it (bench/results/cloud_stats_gls.md); a photo's coverage match sets the opacity with it";
  if (name == "powder_view_fade") return "only its product with powder_strength shows in the statistics";
  if (name == "rain_absorption") return "no precipitation in the weather map: no rain pixel constrains it";
  if (name == "ambient_height_bias" || name == "ground_bounce")
    return "traded against ambient_strength (the opacity bins do not resolve height in the layer)";
  if (name == "ms_octaves" || name == "ms_a" || name == "ms_b" || name == "ms_c")
    return "the multiple-scattering octaves trade against the overall brightness (a known degeneracy)";
  if (name == "atmosphere_blend") return "distance blend: needs per-pixel depth the statistics do not see";
  return "not in the fitted set (options.fitted)";
}

bool IsLightingField(const std::string& name) {
  static const char* kLighting[] = {"extinction",       "scattering_albedo", "phase_g1",          "phase_g2",
                                    "phase_blend",      "powder_strength",   "powder_view_fade",  "rain_absorption",
                                    "ambient_strength", "ambient_height_bias", "ground_bounce",   "ms_octaves",
                                    "ms_a",             "ms_b",              "ms_c",              "atmosphere_blend"};
  return std::find_if(std::begin(kLighting), std::end(kLighting), [&](const char* n) { return name == n; }) !=
         std::end(kLighting);
}

// Jacobian by central differences, one column per free parameter.
bool CentralDifferences(const CloudStatsObjective& obj, const double* x, double* jac) {
  const int n = obj.num_parameters(), m = obj.num_residuals();
  std::vector<double> xp(x, x + n), rp(m), rm(m);
  for (int j = 0; j < n; ++j) {
    const double h = obj.StepX(j, x[j]);
    // One-sided at a bound (the renderer refuses values outside the spec's range).
    const double hi = std::min(x[j] + h, obj.UpperX(j)), lo = std::max(x[j] - h, obj.LowerX(j));
    xp[j] = hi;
    if (!obj.Evaluate(xp.data(), rp.data())) return false;
    xp[j] = lo;
    if (!obj.Evaluate(xp.data(), rm.data())) return false;
    xp[j] = x[j];
    for (int i = 0; i < m; ++i) jac[static_cast<size_t>(i) * n + j] = (rp[i] - rm[i]) / (hi - lo);
  }
  return true;
}

}  // namespace

CloudStatsCost::CloudStatsCost(const CloudStatsObjective* objective) : objective_(objective) {
  set_num_residuals(objective->num_residuals());
  mutable_parameter_block_sizes()->push_back(objective->num_parameters());
}

bool CloudStatsCost::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  // Ceres asks again for the point it has just evaluated (the residuals at a candidate step,
  // then the Jacobian there once the step is accepted): each render is a Vulkan dispatch, so
  // the last point's residuals and Jacobian are kept.
  const int n = objective_->num_parameters(), m = objective_->num_residuals();
  const double* x = parameters[0];
  const bool same = !last_x_.empty() && std::equal(last_x_.begin(), last_x_.end(), x);
  const bool want_jac = jacobians && jacobians[0];
  if (!same || last_residuals_.empty()) {
    last_x_.assign(x, x + n);
    last_residuals_.assign(m, 0.0);
    last_jacobian_.clear();
    if (!objective_->Evaluate(x, last_residuals_.data())) {
      last_x_.clear();
      return false;
    }
  }
  std::copy(last_residuals_.begin(), last_residuals_.end(), residuals);
  if (!want_jac) return true;
  if (last_jacobian_.empty()) {
    last_jacobian_.assign(static_cast<size_t>(m) * n, 0.0);
    if (!CentralDifferences(*objective_, x, last_jacobian_.data())) {
      last_jacobian_.clear();
      return false;
    }
  }
  std::copy(last_jacobian_.begin(), last_jacobian_.end(), jacobians[0]);
  return true;
}

std::vector<CloudStatsParameter> DescribeCloudStatsParameters(const clouds::CloudParams& initial,
                                                              const clouds::CloudParams& fitted,
                                                              const std::vector<std::string>& fitted_names) {
  std::vector<CloudStatsParameter> out;
  clouds::CloudParams a = initial, b = fitted;
  for (const auto& spec : clouds::CloudParameterSpecs()) {
    if (!IsLightingField(spec.name)) continue;
    CloudStatsParameter p;
    p.name = spec.name;
    p.unit = spec.unit;
    p.initial = *spec.field(a);
    p.value = *spec.field(b);
    p.held = std::find(fitted_names.begin(), fitted_names.end(), p.name) == fitted_names.end();
    if (p.held) p.why_held = WhyHeld(p.name);
    out.push_back(p);
  }
  return out;
}

CloudStatsResult FitCloudStats(const std::vector<CloudStatsReference>& refs, const CloudStatsScene& scene,
                               clouds::CloudRenderer& renderer, const CloudStatsOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  CloudStatsObjective obj(refs, scene, renderer, options);
  std::vector<double> x = obj.InitialX();
  CloudStatsResult res;
  res.reference_stats = obj.reference_stats();
  res.residuals = obj.num_residuals();
  std::vector<double> r(obj.num_residuals());
  if (!obj.Evaluate(x.data(), r.data(), &res.initial_stats))
    throw Error("cloud stats: the initial parameters cannot be rendered");
  ceres::Problem::Options po;
  po.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(po);
  problem.AddResidualBlock(new CloudStatsCost(&obj), nullptr, x.data());
  for (int i = 0; i < obj.num_parameters(); ++i) {
    problem.SetParameterLowerBound(x.data(), i, obj.LowerX(i));
    problem.SetParameterUpperBound(x.data(), i, obj.UpperX(i));
  }
  ceres::Solver::Options so;
  so.max_num_iterations = options.max_iterations;
  so.linear_solver_type = ceres::DENSE_QR;
  so.function_tolerance = 1e-5;
  so.parameter_tolerance = 1e-5;
  so.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  res.initial_cost = summary.initial_cost;
  res.final_cost = summary.final_cost;
  res.iterations = static_cast<int>(summary.iterations.size());
  res.termination = summary.BriefReport() + "; residual evaluations " + std::to_string(summary.num_residual_evaluations) +
                    ", Jacobian evaluations " + std::to_string(summary.num_jacobian_evaluations);
  res.params = obj.ParamsAt(x.data());
  res.parameters = DescribeCloudStatsParameters(scene.initial, res.params, options.fitted);
  // Conditioning at the solution: Jacobian columns in units of each parameter's range.
  const int m = obj.num_residuals(), n = obj.num_parameters();
  std::vector<double> jac(static_cast<size_t>(m) * n);
  if (obj.Evaluate(x.data(), r.data(), &res.final_stats) && CentralDifferences(obj, x.data(), jac.data())) {
    Eigen::MatrixXd J(m, n);
    for (int i = 0; i < m; ++i)
      for (int j = 0; j < n; ++j) J(i, j) = jac[static_cast<size_t>(i) * n + j] * (obj.UpperX(j) - obj.LowerX(j));
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(J);
    for (int i = 0; i < svd.singularValues().size(); ++i) res.singular_values.push_back(svd.singularValues()(i));
  }
  if (!obj.noise_sd().empty()) {
    std::vector<double> sd = obj.noise_sd();
    std::nth_element(sd.begin(), sd.begin() + sd.size() / 2, sd.end());
    res.noise_draws = options.noise_draws;
    res.median_noise_sd = sd[sd.size() / 2];
    res.noise_covariance = obj.full_whitening() ? "full" : "diagonal";
    res.noise_shrinkage = obj.noise_shrinkage();
  }
  res.renders = obj.renders();
  res.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return res;
}

CloudStatsTerm::CloudStatsTerm(const std::vector<CloudStatsReference>& refs, const CloudStatsScene& scene,
                               clouds::CloudRenderer& renderer, const CloudStatsOptions& options)
    : objective_(refs, scene, renderer, options), x_(objective_.InitialX()), options_(options), initial_(scene.initial) {}

long long CloudStatsTerm::AddTo(ceres::Problem& problem, fit::FitState& /*state*/, const fit::LevelContext& level) {
  // The statistics need the whole render: only the finest level carries them (the coarse
  // levels shape the sky; the clouds' residuals would cost a render per evaluation there too).
  if (!level.finest) return 0;
  problem.AddResidualBlock(new CloudStatsCost(&objective_), nullptr, x_.data());
  for (int i = 0; i < objective_.num_parameters(); ++i) {
    problem.SetParameterLowerBound(x_.data(), i, objective_.LowerX(i));
    problem.SetParameterUpperBound(x_.data(), i, objective_.UpperX(i));
  }
  return objective_.num_residuals();
}

void CloudStatsTerm::ReportSkips(std::vector<fit::SkipNote>* skipped, std::vector<fit::FitDecision>* /*decisions*/) const {
  for (const auto& p : DescribeCloudStatsParameters(initial_, initial_, options_.fitted))
    if (p.held) skipped->push_back({"clouds." + p.name, "held: " + p.why_held});
}

CloudStatsResult CloudStatsTerm::result() const {
  CloudStatsResult res;
  res.params = objective_.ParamsAt(x_.data());
  res.parameters = DescribeCloudStatsParameters(initial_, res.params, options_.fitted);
  res.reference_stats = objective_.reference_stats();
  res.residuals = objective_.num_residuals();
  res.renders = objective_.renders();
  return res;
}

std::unique_ptr<CloudStatsTerm> MakeCloudStatsTerm(const std::vector<CloudStatsReference>& refs,
                                                   const CloudStatsScene& scene, clouds::CloudRenderer& renderer,
                                                   const CloudStatsOptions& options) {
  return std::make_unique<CloudStatsTerm>(refs, scene, renderer, options);
}

}  // namespace skycal::cloudfit
