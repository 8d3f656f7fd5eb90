#include "cloud_lighting_solve.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <iostream>

#include "cloud_lighting_cost.h"
#include "cloud_lighting_day_prior.h"
#include "skycal/core/error.h"
#include "skycal/core/latlong.h"

namespace skycal::cloudfit {
namespace {

// Progress on stderr (stdout may carry --json).
class Progress final : public ceres::IterationCallback {
 public:
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    std::cerr << "[fit] clouds iteration " << s.iteration << "  cost " << s.cost << "  |step| " << s.step_norm << std::endl;
    return ceres::SOLVER_CONTINUE;
  }
};

// sqrt(w) (theta_k - start_k) / unit_k per parameter (CloudLightingOptions::start_prior).
struct StartPrior {
  double sqrt_w;
  CloudLighting start, unit;
  template <typename T>
  bool operator()(const T* theta, T* r) const {
    for (int k = 0; k < kCloudLightingParameters; ++k) r[k] = T(sqrt_w) * (theta[k] - T(start[k])) / T(unit[k]);
    return true;
  }
};

}  // namespace

clouds::CloudRenderRequest RequestFor(const std::array<double, 3>& sun_dir, int width, int height,
                                      const KnownCloudShapes& shapes) {
  clouds::CloudRenderRequest r;
  r.sun_dir = sun_dir;
  r.width = width;
  r.height = height;
  r.time_s = shapes.time_s;
  r.march = shapes.march;
  return r;
}

std::vector<size_t> CloudPixels(const std::vector<char>& usable, const std::vector<float>& transmittance,
                                double threshold) {
  if (usable.size() != transmittance.size()) throw Error("cloud lighting fit: mask and cloud render differ in size");
  std::vector<size_t> out;
  for (size_t i = 0; i < usable.size(); ++i) {
    if (usable[i] && transmittance[i] < threshold) out.push_back(i);
  }
  return out;
}

std::vector<CloudSample> ChooseSamples(const std::vector<size_t>& pixels, const ImageRGB& reference, int count) {
  std::vector<CloudSample> out;
  const size_t n = std::min(pixels.size(), static_cast<size_t>(std::max(count, 1)));
  double total = 0.0;
  for (size_t k = 0; k < n; ++k) {
    const size_t i = pixels[k * pixels.size() / n];
    CloudSample s;
    s.x = static_cast<int>(i % reference.width);
    s.y = static_cast<int>(i / reference.width);
    s.weight = latlong::PixelSolidAngle(s.x, s.y, reference.width, reference.height);
    total += s.weight;
    for (int c = 0; c < 3; ++c) s.reference[c] = reference.pixels[3 * i + c];
    out.push_back(s);
  }
  for (CloudSample& s : out) s.weight /= total;
  return out;
}

Conditioning ConditionAt(CloudSampleModel* model, const CloudLighting& theta, const CloudLightingOptions& o) {
  std::vector<int> every(kCloudLightingParameters);
  std::iota(every.begin(), every.end(), 0);
  model->SetFreeParameters(every);  // the conditioning looks at every column
  std::vector<double> values(model->residuals()), jac(model->residuals() * kCloudLightingParameters);
  if (!model->Evaluate(theta.data(), values.data(), jac.data())) {
    throw Error("cloud lighting fit: the composite is not positive and finite at the starting lighting");
  }
  ConditioningOptions co;
  co.noise = o.noise_level;
  co.max_relative_error = o.max_predicted_error;
  co.auto_hold = o.auto_hold;
  co.user_held.assign(kCloudLightingParameters, false);
  for (const std::string& h : o.hold) co.user_held[CloudLightingIndex(h)] = true;
  if (!o.fit_sun_scale) {
    const int k = CloudLightingIndex("sun_scale");
    co.user_held[k] = true;
    co.held_why.assign(kCloudLightingParameters, "");
    co.held_why[k] = "held: the sun's scale is fitted only when asked (CloudLightingOptions::fit_sun_scale; calibrate's "
                     "refit on a photo's recovered shapes)";
  }
  return AnalyseConditioning(jac, theta, co);
}

void AddCloudBlock(ceres::Problem* problem, CloudSampleModel* model, double* theta, const Conditioning& c) {
  problem->AddResidualBlock(new CloudLightingCost(model), nullptr, theta);
  std::vector<int> held, free;
  for (int k = 0; k < kCloudLightingParameters; ++k) {
    const clouds::CloudParamSpec& s = CloudLightingSpec(k);
    problem->SetParameterLowerBound(theta, k, s.min);
    problem->SetParameterUpperBound(theta, k, s.max);
    (c.parameters[k].held ? held : free).push_back(k);
  }
  model->SetFreeParameters(free);  // the held columns are the manifold's to drop: not marched
  if (held.size() == static_cast<size_t>(kCloudLightingParameters)) {
    problem->SetParameterBlockConstant(theta);
  } else if (!held.empty()) {
    problem->SetManifold(theta, new ceres::SubsetManifold(kCloudLightingParameters, held));
  }
}

BoundRestarts RestartAtBounds(const CloudLighting& start, const std::vector<char>& held,
                              const std::function<double(CloudLighting*)>& solve, CloudLighting* theta, double* cost) {
  BoundRestarts r;
  const CloudLighting first = *theta;
  for (int k = 0; k < kCloudLightingParameters; ++k) {
    const int end = CloudLightingRangeEnd(k, first[k]);
    if (held.at(static_cast<size_t>(k)) || end == 0) continue;
    const clouds::CloudParamSpec& spec = CloudLightingSpec(k);
    const double range = spec.max - spec.min;
    CloudLighting again = start;
    again[k] = end > 0 ? spec.min + 0.25 * range : spec.max - 0.25 * range;
    const double c = solve(&again);
    if (c < *cost) {
      *theta = again;
      *cost = c;
      r.kept = r.tried;
      r.parameter = CloudLightingNames()[k];
    }
    ++r.tried;
  }
  return r;
}

ReleasedHolds ReleaseInseparableHolds(const std::function<double(const Conditioning&, CloudLighting*)>& solve,
                                      Conditioning* c, CloudLighting* theta, double* cost) {
  ReleasedHolds r;
  Conditioning freed = *c;
  for (int k = 0; k < kCloudLightingParameters; ++k) {
    ParameterConditioning& pc = freed.parameters[k];
    if (!pc.held || !pc.inseparable) continue;
    pc.held = false;
    pc.why = "freed after the first solve, which held it (" + pc.why + "): the image's best value, not a determined one";
    r.names.push_back(CloudLightingNames()[k]);
  }
  if (r.names.empty()) return r;
  freed.singular_values_free.clear();  // of the conditioning's free set, which this is not
  CloudLighting again = *theta;
  r.cost_before = *cost;
  r.cost_after = solve(freed, &again);
  if (r.cost_after < *cost) {
    r.kept = true;
    *theta = again;
    *cost = r.cost_after;
    *c = freed;
  }
  return r;
}

ceres::Solver::Summary SolveCloudBlock(CloudSampleModel* model, double* theta, const Conditioning& c,
                                       const CloudLightingOptions& o, const CloudLighting& start) {
  return SolveCloudDay({model}, {theta}, c, {0.0}, {}, o, nullptr, &start);
}

ceres::Solver::Summary SolveCloudDay(const std::vector<CloudSampleModel*>& models, const std::vector<double*>& thetas,
                                     const Conditioning& c, const std::vector<double>& times_h,
                                     const CloudLighting& scale, const CloudLightingOptions& o, int* prior_residuals,
                                     const CloudLighting* start) {
  if (models.size() != thetas.size() || models.size() != times_h.size() || models.empty()) {
    throw Error("cloud lighting fit: one model, block and time per reference");
  }
  ceres::Problem problem;
  for (size_t r = 0; r < models.size(); ++r) AddCloudBlock(&problem, models[r], thetas[r], c);
  int priors = 0;
  if (models.size() >= 3 && o.day_smoothness > 0.0) {
    std::vector<size_t> order(models.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return times_h[a] < times_h[b]; });
    for (size_t k = 1; k + 1 < order.size(); ++k) {
      const size_t a = order[k - 1], m = order[k], b = order[k + 1];
      problem.AddResidualBlock(new DaySmoothnessPrior(o.day_smoothness, times_h[a], times_h[m], times_h[b], scale),
                               nullptr, thetas[a], thetas[m], thetas[b]);
      ++priors;
    }
  }
  if (prior_residuals) *prior_residuals = priors * kCloudLightingParameters;
  if (models.size() == 1 && o.start_prior > 0.0) {
    if (!start) throw Error("cloud lighting fit: CloudLightingOptions::start_prior needs the solve's start");
    CloudLighting unit{};
    for (int k = 0; k < kCloudLightingParameters; ++k) unit[k] = std::max(c.parameters[k].scale, 1e-12);
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<StartPrior, kCloudLightingParameters, kCloudLightingParameters>(
            new StartPrior{std::sqrt(o.start_prior), *start, unit}),
        nullptr, thetas[0]);
  }
  ceres::Solver::Options so;
  // 15 parameters per reference, ~800 rows each: dense normal equations are tiny.
  so.linear_solver_type = models.size() == 1 ? ceres::DENSE_QR : ceres::DENSE_NORMAL_CHOLESKY;
  so.max_num_iterations = o.max_iterations;
  // The recovery targets are 1% on parameters whose effect on the image can be ~1e-3 in
  // log units, so the cost's tail matters (function tolerance 1e-8); a step below 1e-6 of
  // the parameters is below what float values (the Vulkan render) resolve: stop there.
  so.function_tolerance = 1e-8;
  so.gradient_tolerance = 1e-12;
  so.parameter_tolerance = 1e-6;
  // With bounds Ceres follows every trust-region step by a projected Armijo line search
  // whose cubic interpolation asks for the gradient at the trial point: a Jet Jacobian
  // (~256 Jet marches) for a point the step may reject. The bounds are the spec table's
  // wide ranges, which the steps clamp to anyway (the parameter blocks' Plus projects).
  so.max_num_line_search_step_size_iterations = 0;
  so.logging_type = ceres::SILENT;
  Progress progress;
  if (o.verbose) so.callbacks.push_back(&progress);
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  if (summary.termination_type == ceres::FAILURE) throw Error("cloud lighting fit: Ceres failed: " + summary.message);
  return summary;
}

ImageRGB Composite(const ImageRGB& sky_exposed, const clouds::CloudImage& cloud, double exposure) {
  const ImageRGB& sky = sky_exposed;
  if (sky.width != cloud.radiance.width || sky.height != cloud.radiance.height) {
    throw Error("cloud lighting fit: sky and cloud images differ in size");
  }
  ImageRGB out(sky.width, sky.height);
  for (size_t i = 0; i < cloud.transmittance.size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      out.pixels[3 * i + c] = static_cast<float>(
          sky.pixels[3 * i + c] * static_cast<double>(cloud.transmittance[i]) + exposure * cloud.radiance.pixels[3 * i + c]);
    }
  }
  return out;
}

PixelErrors CompositeErrors(const std::vector<size_t>& pixels, const ImageRGB& reference, const ImageRGB& composite) {
  PixelErrors e;
  double rel = 0.0, lg = 0.0, w = 0.0;
  for (size_t i : pixels) {
    const int x = static_cast<int>(i % reference.width), y = static_cast<int>(i / reference.width);
    const double omega = latlong::PixelSolidAngle(x, y, reference.width, reference.height);
    for (int c = 0; c < 3; ++c) {
      const double r = reference.pixels[3 * i + c], f = composite.pixels[3 * i + c];
      rel += omega * ((f - r) / r) * ((f - r) / r);
      const double d = f > 0.0 ? std::log(f / r) : 50.0;
      lg += omega * d * d;
    }
    w += 3.0 * omega;
    ++e.pixels;
  }
  if (w > 0.0) {
    e.rel_rmse = std::sqrt(rel / w);
    e.log_rmse = std::sqrt(lg / w);
  }
  return e;
}

void ReportParameters(const CloudLighting& initial, const CloudLighting& final_theta, const Conditioning& c,
                      CloudLightingReport* report) {
  report->parameters.clear();
  for (int k = 0; k < kCloudLightingParameters; ++k) {
    const ParameterConditioning& pc = c.parameters[k];
    CloudParamReport p;
    p.name = CloudLightingNames()[k];
    p.unit = CloudLightingSpec(k).unit;
    p.value = final_theta[k];
    p.initial = initial[k];
    p.held = pc.held;
    p.why = pc.why;
    p.sensitivity = pc.sensitivity;
    p.predicted_relative_error = pc.predicted_relative_error;
    p.separability = pc.separability;
    p.most_collinear_with = pc.most_collinear >= 0 ? CloudLightingNames()[pc.most_collinear] : "";
    p.collinear_cosine = pc.collinear_cosine;
    report->parameters.push_back(p);
  }
  report->singular_values = c.singular_values;
  report->singular_values_free = c.singular_values_free;
}

}  // namespace skycal::cloudfit
