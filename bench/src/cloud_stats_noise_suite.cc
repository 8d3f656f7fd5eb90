// Suite `cloud-stats-noise`: the shape noise of the cloud statistics (docs/cloud-fitting.md, regime 2),
// measured at the truth — what `bench_cloud_stats noise` wrote (bench/results/cloud_stats_noise.md),
// now a suite of `skycal bench`. Σ, the covariance of the statistics over D single shape draws
// (independent weather maps of the same weather statistics), and J, the Jacobian of the
// model's pooled statistics with respect to the lighting (central differences through the
// renderer). A linearised fit of R references (each one draw) against the model's mean of M
// draws moves the parameters by A (e_model - e_ref), A = (J' W J)^-1 J' W, so their
// covariance is A Σ (1/R + 1/M) A' for the objective's weights W (the sandwich: Σ need not
// be invertible). That predicts each parameter's spread under shape noise, and the singular
// values of Σ^-1/2 J say which directions the statistics separate at all.
//
// One case (no setting swept: no Pareto front). Full: 48 draws, 64x32, M = 4 (the program's
// defaults); --quick: 8 draws, M = 2. Error: the predicted sd of ln extinction for the default
// fitted set (extinction + ambient), bin-share weights, R = 1, M = the model maps. The
// program's `scan` mode (the cost along extinction of one pair, a debugging aid) is dropped.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include "skycal/cloudfit/cloud_stats_objective.h"
#include "skycal/bench/cloud_stats_scene.h"
#include "skycal/bench/cloud_stats_suite_grids.h"
#include "skycal/core/error.h"
#include "suite_util.h"
#include "suites_internal.h"

namespace skycal::bench {

namespace {

// The lighting fields the Jacobian covers (the fit's default four first).
const std::vector<std::string> kFields = {"extinction",  "phase_g1",  "powder_strength",     "ambient_strength",
                                          "scattering_albedo", "phase_g2", "phase_blend", "ambient_height_bias",
                                          "ground_bounce"};

struct Subset {
  std::string label;
  std::vector<int> columns;  // into kFields
};

// Predicted sd of each parameter of `cols` (relative: J's columns are d stat / d ln p) for
// weights w (diagonal, squared weights) or a full weight matrix.
Eigen::VectorXd PredictedSd(const Eigen::MatrixXd& J, const Eigen::MatrixXd& W, const Eigen::MatrixXd& S, double scale) {
  const Eigen::MatrixXd JtW = J.transpose() * W;
  const Eigen::MatrixXd A = (JtW * J).ldlt().solve(JtW);
  const Eigen::MatrixXd C = A * S * A.transpose() * scale;
  return C.diagonal().cwiseMax(0.0).cwiseSqrt();
}

std::string Pct(double v) {
  char b[32];
  std::snprintf(b, sizeof b, v < 0.1 ? "%.1f%%" : "%.0f%%", 100.0 * v);
  return b;
}


// The analysis at `plan`'s sizes: the Markdown of cloud_stats_noise.md and its numbers.
struct NoiseAnalysis {
  std::string markdown;
  nlohmann::json numbers;
  long long renders = 0;
};

// The statistics of each of `draws` single shape draws at x.
std::vector<std::vector<double>> DrawAll(const cloudfit::CloudStatsObjective& obj, const std::vector<double>& x, int draws,
                                         const SuiteOptions& o, bool log_progress) {
  std::vector<std::vector<double>> v(draws, std::vector<double>(obj.num_residuals()));
  for (int d = 0; d < draws; ++d) {
    if (!obj.DrawStatistics(x.data(), d, v[d].data())) throw Error("shape draw failed");
    if (log_progress && d % 8 == 7)
      o.Log("[cloud-stats-noise]   " + std::to_string(d + 1) + "/" + std::to_string(draws) + " shape draws");
  }
  return v;
}

// Σ over the draws of the statistics every draw and the model fill (keep: their indices),
// and the bias of the other noise seed's draws: mean(seed 1) - mean(seed 101).
struct DrawCovariance {
  std::vector<int> keep;
  Eigen::MatrixXd S;
  Eigen::VectorXd bias;
};

DrawCovariance CovarianceOverDraws(const std::vector<std::vector<double>>& v,
                                   const std::vector<std::vector<double>>& v_other, const std::vector<double>& m0) {
  const int draws = static_cast<int>(v.size()), n = static_cast<int>(m0.size());
  DrawCovariance r;
  std::vector<int>& keep = r.keep;
  // Keep the statistics every draw and the model have (a bin a draw leaves empty has no quantile).
  for (int k = 0; k < n; ++k) {
    bool ok = std::isfinite(m0[k]);
    for (int d = 0; d < draws && ok; ++d) ok = std::isfinite(v[d][k]) && std::isfinite(v_other[d][k]);
    if (ok) keep.push_back(k);
  }
  const int nk = static_cast<int>(keep.size());
  Eigen::MatrixXd X(draws, nk);
  for (int d = 0; d < draws; ++d)
    for (int i = 0; i < nk; ++i) X(d, i) = v[d][keep[i]];
  const Eigen::RowVectorXd mean = X.colwise().mean();
  const Eigen::MatrixXd Xc = X.rowwise() - mean;
  r.S = Xc.transpose() * Xc / (draws - 1);
  r.bias.resize(nk);  // mean(noise seed 1) - mean(noise seed 101), per statistic
  for (int i = 0; i < nk; ++i) {
    double a = 0.0;
    for (int d = 0; d < draws; ++d) a += v_other[d][keep[i]];
    r.bias(i) = a / draws - mean(i);
  }
  return r;
}

// J by central differences of the pooled model, columns per ln(parameter).
Eigen::MatrixXd PooledJacobian(const cloudfit::CloudStatsObjective& obj, const std::vector<double>& x,
                               const std::vector<int>& keep, const SuiteOptions& o) {
  const int n = obj.num_residuals(), p = obj.num_parameters(), nk = static_cast<int>(keep.size());
  Eigen::MatrixXd J(nk, p);
  std::vector<double> xp = x, rp(n), rm(n);
  for (int j = 0; j < p; ++j) {
    const double h = obj.StepX(j, x[j]);
    const double hi = std::min(x[j] + h, obj.UpperX(j)), lo = std::max(x[j] - h, obj.LowerX(j));
    xp[j] = hi;
    if (!obj.ModelStatistics(xp.data(), rp.data())) throw Error("model render failed");
    xp[j] = lo;
    if (!obj.ModelStatistics(xp.data(), rm.data())) throw Error("model render failed");
    xp[j] = x[j];
    for (int i = 0; i < nk; ++i) {
      const double dv = rp[keep[i]] - rm[keep[i]];
      J(i, j) = (std::isfinite(dv) ? dv : 0.0) / (hi - lo) * x[j];  // d stat / d ln p
    }
    o.Log("[cloud-stats-noise]   Jacobian column " + obj.Name(j));
  }
  return J;
}

// Weights: the first design's (bin shares), the diagonal GLS (1 / var), the shrunk full GLS
// ((1 - lambda) Σ + lambda diag Σ)^-1; var: Σ's diagonal, floored at the noise sd floor.
struct NoiseWeights {
  Eigen::VectorXd var;
  Eigen::MatrixXd W_share, W_diag, W_full;
  double lambda = 0.5;
};

NoiseWeights MakeNoiseWeights(const cloudfit::CloudStatsObjective& obj, const Eigen::MatrixXd& S, const std::vector<int>& keep,
                              const cloudfit::CloudStatsOptions& options) {
  const int nk = static_cast<int>(keep.size());
  NoiseWeights nw;
  Eigen::VectorXd w_share(nk);
  nw.var = S.diagonal();
  for (int i = 0; i < nk; ++i) {
    w_share(i) = obj.Weight(keep[i]) * obj.Weight(keep[i]);
    nw.var(i) = std::max(nw.var(i), options.noise_sd_floor * options.noise_sd_floor);
  }
  nw.W_share = w_share.asDiagonal(), nw.W_diag = nw.var.cwiseInverse().asDiagonal();
  const double lambda = nw.lambda;
  Eigen::MatrixXd S_shrunk = (1.0 - lambda) * S;
  S_shrunk.diagonal() += lambda * nw.var;
  nw.W_full = S_shrunk.ldlt().solve(Eigen::MatrixXd::Identity(nk, nk));
  return nw;
}

// The 3D noise texture is a shape draw too: one weather map (draw 0), the noise seeds the
// seed pairs use (1-6 references, 101-106 models): the sd across them per statistic over
// the sd across weather maps, sorted.
std::vector<double> NoiseSeedSdRatios(const cloudfit::CloudStatsScene& model, const std::vector<cloudfit::CloudStatsReference>& refs,
                                      clouds::CloudRenderer& renderer, const cloudfit::CloudStatsOptions& options,
                                      const std::string& cache, const std::vector<double>& x, int n,
                                      const std::vector<int>& keep, const Eigen::VectorXd& var) {
  std::vector<std::vector<double>> vs;
  for (uint64_t seed : {1, 2, 3, 4, 5, 6, 101, 102, 103, 104, 105, 106}) {
    const clouds::CloudNoise nz = clouds::LoadOrGenerateCloudNoise(seed, cache);
    cloudfit::CloudStatsScene ms = model;
    ms.noise = &nz;
    const cloudfit::CloudStatsObjective o2(refs, ms, renderer, options);
    vs.emplace_back(n);
    if (!o2.DrawStatistics(x.data(), 0, vs.back().data())) throw Error("noise-seed draw failed");
  }
  std::vector<double> ratio;
  for (int i = 0; i < static_cast<int>(keep.size()); ++i) {
    double a = 0.0, a2 = 0.0;
    int c = 0;
    for (const auto& vv : vs)
      if (std::isfinite(vv[keep[i]])) {
        a += vv[keep[i]];
        a2 += vv[keep[i]] * vv[keep[i]];
        ++c;
      }
    if (c < 6) continue;
    const double m = a / c, sd = std::sqrt(std::max(0.0, (a2 - c * m * m) / (c - 1)));
    ratio.push_back(sd / std::sqrt(var(i)));
  }
  std::sort(ratio.begin(), ratio.end());
  return ratio;
}

// One subset of the fields: singular values of diag(Σ)^-1/2 J, the predicted sd per weight
// and (R, M), and the shift the noise seed's bias makes; Markdown into md, numbers returned.
nlohmann::json SubsetTables(const Subset& sub, const Eigen::MatrixXd& J, const Eigen::MatrixXd& S,
                            const Eigen::VectorXd& bias, const NoiseWeights& nw, int draws, int maps,
                            std::ostringstream& md) {
  const int nk = static_cast<int>(J.rows());
  const Eigen::VectorXd& var = nw.var;
  Eigen::MatrixXd Js(nk, sub.columns.size());
  for (size_t c = 0; c < sub.columns.size(); ++c) Js.col(c) = J.col(sub.columns[c]);
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(var.cwiseSqrt().cwiseInverse().asDiagonal() * Js);
  md << "### " << sub.label << "\n\nSingular values of diag(Σ)^-1/2 J:";
  nlohmann::json js = {{"singular_values", std::vector<double>(svd.singularValues().data(), svd.singularValues().data() + svd.singularValues().size())}};
  for (int i = 0; i < svd.singularValues().size(); ++i) {
    char b[32];
    std::snprintf(b, sizeof b, " %.3g", svd.singularValues()(i));
    md << b;
  }
  md << "\n\n| weights | R refs | M model draws |";
  for (int c : sub.columns) md << " " << kFields[c] << " |";
  md << "\n|---|---|---|";
  for (size_t c = 0; c < sub.columns.size(); ++c) md << "---|";
  md << "\n";
  const std::vector<std::pair<std::string, const Eigen::MatrixXd*>> ws = {
      {"bin shares", &nw.W_share}, {"diagonal GLS", &nw.W_diag}, {"shrunk GLS", &nw.W_full}};
  for (const auto& [wname, W] : ws)
    for (const auto& [R, M] : std::vector<std::pair<int, int>>{{1, maps}, {1, 1000000}, {3, maps}, {8, 16}}) {
      const Eigen::VectorXd sd = PredictedSd(Js, *W, S, 1.0 / R + 1.0 / M);
      md << "| " << wname << " | " << R << " | " << (M >= 1000000 ? std::string("inf") : std::to_string(M)) << " |";
      for (int c = 0; c < sd.size(); ++c) md << " " << Pct(sd(c)) << " |";
      md << "\n";
      js["predicted_sd_ln"][wname][std::to_string(R) + "x" + std::to_string(M)] =
          std::vector<double>(sd.data(), sd.data() + sd.size());
    }
  for (const auto& [wname, W] : ws) {
    const Eigen::MatrixXd JtW = Js.transpose() * *W;
    const Eigen::VectorXd shift = (JtW * Js).ldlt().solve(JtW * bias);
    md << "| " << wname << ": shift from the noise seed (1 vs 101, mean of " << draws << " draws) | | |";
    for (int c = 0; c < shift.size(); ++c) md << " " << (shift(c) >= 0 ? "+" : "-") << Pct(std::abs(shift(c))) << " |";
    md << "\n";
    js["noise_seed_shift_ln"][wname] = std::vector<double>(shift.data(), shift.data() + shift.size());
  }
  md << "\n";
  return js;
}

// The analysis's heading and method paragraph.
void WriteNoiseIntro(std::ostringstream& md, int draws, int maps, const cloudfit::CloudStatsOptions& options,
                     clouds::CloudRenderer& renderer, int nk, int n, double lambda) {
  md << "## Shape noise at the truth: predicted spread and what the statistics separate\n\n"
     << "(" << draws << " draws, M = " << maps << "; " << options.render_width << "x" << options.render_height << " renders through " << renderer.Describe()
     << "; the default bins and quantiles). Σ: covariance of the " << nk << " statistics (of " << n
     << "; those every draw and the model fill) over " << draws
     << " single shape draws (weather-map seeds 5000+, the model's noise seed 101) at default_cloudy's lighting, sun 25 deg up. "
     << "J: central differences of the model's statistics pooled over M = " << maps
     << " weather maps, per ln(parameter). Predicted sd of ln p for R references and M model draws: the sandwich "
     << "A Σ (1/R + 1/M) A', A = (J'WJ)^-1 J'W, for W = the first design's bin-share weights, the diagonal GLS "
     << "(W = diag Σ^-1) and a shrunk full GLS (W = ((1-λ)Σ + λ diag Σ)^-1, λ = " << lambda
     << ": " << draws << " draws cannot estimate a full " << nk << "x" << nk << " Σ). Singular values of "
     << "diag(Σ)^-1/2 J (per ln p; a direction with σ < 1 moves the statistics less than one draw's noise for "
     << "a 100% change).\n\n";
}

NoiseAnalysis AnalyseShapeNoise(const CloudStatsNoisePlan& plan, clouds::CloudRenderer& renderer, const SuiteOptions& o) {
  const int draws = plan.draws, maps = plan.model_maps;
  cloudfit::CloudStatsOptions options;
  options.render_width = plan.width;
  options.render_height = plan.width / 2;
  const std::string cache = CloudStatsCacheDir();
  options.fitted = kFields;
  options.model_renders = maps;
  // The reference only fixes the bins (its layout); the analysis draws its own shapes.
  auto scene = MakeCloudStatsScene(SKYCAL_SOURCE_DIR, {1, 11}, {101, 211}, 25.0, 30.0, options, renderer, cache);
  std::vector<clouds::WeatherMap> model_maps, draw_maps;
  model_maps.push_back(scene.weather);
  for (int e = 1; e < maps; ++e) model_maps.push_back(CloudStatsWeather(211 + 1000 * e, scene.truth.weather_extent_m));
  for (int d = 0; d < draws; ++d) draw_maps.push_back(CloudStatsWeather(5000 + d, scene.truth.weather_extent_m));
  cloudfit::CloudStatsScene model{&scene.preset, scene.truth, &scene.noise, &scene.weather};
  for (const auto& w : model_maps) model.weather_ensemble.push_back(&w);
  for (const auto& w : draw_maps) model.shape_draw_maps.push_back(&w);
  const std::vector<cloudfit::CloudStatsReference> refs = {scene.reference};  // the objective keeps a reference to it
  const cloudfit::CloudStatsObjective obj(refs, model, renderer, options);
  const int n = obj.num_residuals();
  const std::vector<double> x = obj.InitialX();
  // Σ over the draws.
  const std::vector<std::vector<double>> v = DrawAll(obj, x, draws, o, true);
  // The same draws with another noise seed (the seed pairs' references use seeds 1-6, the
  // model 101-106): a difference of the means is a bias no number of draws averages away.
  const clouds::CloudNoise other_noise = clouds::LoadOrGenerateCloudNoise(1, cache);
  cloudfit::CloudStatsScene model_other = model;
  model_other.noise = &other_noise;
  const cloudfit::CloudStatsObjective obj_other(refs, model_other, renderer, options);
  const std::vector<std::vector<double>> v_other = DrawAll(obj_other, x, draws, o, false);
  o.Log("[cloud-stats-noise]   " + std::to_string(draws) + " draws with noise seed 1");
  std::vector<double> m0(n);
  if (!obj.ModelStatistics(x.data(), m0.data())) throw Error("model render failed");
  const DrawCovariance cov = CovarianceOverDraws(v, v_other, m0);
  const Eigen::MatrixXd& S = cov.S;
  const int nk = static_cast<int>(cov.keep.size());
  const Eigen::MatrixXd J = PooledJacobian(obj, x, cov.keep, o);
  const NoiseWeights nw = MakeNoiseWeights(obj, S, cov.keep, options);
  const Eigen::VectorXd& var = nw.var;
  const std::vector<Subset> subsets = {{"default four (extinction, g1, powder, ambient)", {0, 1, 2, 3}},
                                       {"extinction + ambient", {0, 3}},
                                       {"extinction + g1 + ambient", {0, 1, 3}},
                                       {"extinction + powder + ambient", {0, 2, 3}},
                                       {"all nine", {0, 1, 2, 3, 4, 5, 6, 7, 8}}};
  std::ostringstream md;
  WriteNoiseIntro(md, draws, maps, options, renderer, nk, n, nw.lambda);
  nlohmann::json out = {{"draws", draws}, {"statistics", nk}, {"model_maps", maps},
                        {"render_width", options.render_width}};
  // Per-statistic noise and signal (median over statistics) for the reading.
  std::vector<double> sds(nk);
  for (int i = 0; i < nk; ++i) sds[i] = std::sqrt(S(i, i));
  std::sort(sds.begin(), sds.end());
  out["median_statistic_sd"] = sds[nk / 2];
  {
    const Eigen::VectorXd z = cov.bias.cwiseQuotient(var.cwiseSqrt()) * std::sqrt(static_cast<double>(draws) / 2.0);
    md << "Noise seed 1 vs 101 (same " << draws << " weather maps): the mean statistics differ by " << z.cwiseAbs().mean()
       << " standard errors (unpaired: conservative, the draws share their maps) on average (|z| > 3 for " << (z.array().abs() > 3.0).count() << " of " << nk
       << " statistics): a systematic difference the draws over weather maps do not contain.\n\n";
    out["noise_seed_mean_abs_z"] = z.cwiseAbs().mean();
  }
  {
    const std::vector<double> ratio = NoiseSeedSdRatios(model, refs, renderer, options, cache, x, n, cov.keep, var);
    const double med = ratio.empty() ? 0.0 : ratio[ratio.size() / 2];
    md << "Noise seeds as shape draws (12 seeds, one weather map): per statistic, sd across noise seeds / sd across "
       << "weather maps: median " << med << " (" << ratio.size() << " statistics; 10% / 90%: "
       << (ratio.empty() ? 0.0 : ratio[ratio.size() / 10]) << " / " << (ratio.empty() ? 0.0 : ratio[9 * ratio.size() / 10])
       << "). The model renders ONE noise texture, so this part of the reference's shape noise is a fixed offset "
       << "that its ensemble of weather maps does not average.\n\n";
    out["noise_seed_sd_ratio_median"] = med;
    o.Log("[cloud-stats-noise]   noise-seed draws: sd ratio median " + FormatG(med));
  }
  md << "Median shape-noise sd of a statistic: " << sds[nk / 2] << " (log radiance / share); 10% / 90%: " << sds[nk / 10]
     << " / " << sds[9 * nk / 10] << ".\n\n";
  for (const auto& sub : subsets) out["subsets"][sub.label] = SubsetTables(sub, J, S, cov.bias, nw, draws, maps, md);
  return {md.str(), out, obj.renders()};
}

}  // namespace

CloudStatsNoisePlan CloudStatsNoiseGridPlan(bool quick) {
  CloudStatsNoisePlan p;
  if (quick) p.draws = 8, p.model_maps = 2;
  return p;
}

Suite CloudStatsNoiseSuite() {
  Suite s;
  s.name = "cloud-stats-noise";
  s.summary = "the cloud statistics' shape noise at the truth: 48 shape draws, 4 model maps, 64x32 (--quick: 8 draws, "
              "2 maps)";
  s.error_metric = "predicted sd of ln extinction (extinction + ambient fitted, bin-share weights, 1 reference, M model maps)";
  s.error_axis = "predicted sd of ln extinction";
  s.pareto = false;  // one setting
  s.markdown = [](const std::vector<CaseResult>& cases) {
    std::string md = "`skycal bench --suite cloud-stats-noise` (bench/src/cloud_stats_noise_suite.cc; numbers in `results.json`).\n\n";
    for (const CaseResult& c : cases)
      md += c.extra.contains("markdown") ? c.extra["markdown"].get<std::string>() : "Case " + c.name + ": " + c.message + "\n";
    return md;
  };
  s.run = [](const SuiteOptions& o) {
    const CloudStatsNoisePlan plan = CloudStatsNoiseGridPlan(o.quick);
    Grid grid;
    grid.axes = {{"draws", {std::to_string(plan.draws)}, std::to_string(plan.draws)}};
    const std::unique_ptr<clouds::CloudRenderer> renderer = CreateCloudStatsRenderer();
    return RunGrid("cloud-stats-noise", grid, o, [&](CaseResult& c) {
      NoiseAnalysis a;
      c.time = Measure([&] { a = AnalyseShapeNoise(plan, *renderer, o); }, 0, 1);  // one run: the renders dominate
      const auto& sd = a.numbers["subsets"]["extinction + ambient"]["predicted_sd_ln"]["bin shares"]
                                 ["1x" + std::to_string(plan.model_maps)];
      c.error = sd.at(0).get<double>();
      if (!std::isfinite(c.error)) {
        c.outcome = Outcome::kNonFinite;
        c.message = "non-finite predicted sd";
      }
      c.extra = a.numbers;
      c.extra["markdown"] = a.markdown;
      c.extra["renders"] = a.renders;
      c.extra["width"] = plan.width;
    });
  };
  return s;
}

}  // namespace skycal::bench
