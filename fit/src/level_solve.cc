#include "level_solve.h"

#include <ceres/ceres.h>

#include <cmath>
#include <iostream>
#include <memory>

#include "pyramid.h"
#include "skycal/core/error.h"
#include "skycal/render/renderer_stats.h"

namespace skycal::fit {
namespace {

using Clock = std::chrono::steady_clock;
double Seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

// Renders the model at the current point for every reference, once per new evaluation
// point, before Ceres evaluates the residual blocks (the Vulkan backend's objective).
class RenderAtEvaluationPoint final : public ceres::EvaluationCallback {
 public:
  RenderAtEvaluationPoint(const FitState* state, const std::vector<Reference>* refs, render::SkyRenderer* renderer,
                          int width, int height, std::vector<ImageRGB>* images, bool* valid)
      : state_(state), refs_(refs), renderer_(renderer), width_(width), height_(height), images_(images), valid_(valid) {}
  void PrepareForEvaluation(bool /*evaluate_jacobians*/, bool new_evaluation_point) override {
    if (!new_evaluation_point && renders_ > 0) return;
    // A trial step far outside the model's domain (an overflowing LUT entry) is not
    // rendered: the residual blocks then report failure and Ceres shrinks the step.
    *valid_ = false;
    for (const auto* v : {&state_->log_lut, &state_->log_delta}) {
      for (double x : *v) {
        if (!(std::abs(x) < 80.0)) return;
      }
    }
    render::Preset preset;
    try {
      preset = state_->ToPreset();
      render::ValidatePreset(preset, "trial point");
    } catch (const Error&) {
      return;
    }
    for (size_t r = 0; r < refs_->size(); ++r) {
      render::RenderRequest req;
      req.sun_dir = (*refs_)[r].sun_dir;
      req.width = width_;
      req.height = height_;
      req.sun_disc = false;
      req.ground = render::GroundMode::kZero;
      const auto t0 = Clock::now();
      (*images_)[r] = renderer_->Render(preset, req);
      wall_ms_ += std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
      const std::optional<double> gpu = render::RendererDeviceStats(*renderer_).gpu_ms;
      if (gpu) gpu_ms_ = gpu_ms_.value_or(0.0) + *gpu;
    }
    ++renders_;
    *valid_ = true;
  }
  int renders() const { return renders_; }
  double wall_ms() const { return wall_ms_; }
  std::optional<double> gpu_ms() const { return gpu_ms_; }

 private:
  const FitState* state_;
  const std::vector<Reference>* refs_;
  render::SkyRenderer* renderer_;
  int width_, height_;
  std::vector<ImageRGB>* images_;
  bool* valid_;
  int renders_ = 0;
  double wall_ms_ = 0.0;
  std::optional<double> gpu_ms_;  // summed device time (none: the backend reports none)
};

class ProgressPrinter final : public ceres::IterationCallback {
 public:
  ProgressPrinter(std::string level, Clock::time_point start) : level_(std::move(level)), start_(start) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    std::cerr << "[fit] " << level_ << " iteration " << s.iteration << "  cost " << s.cost << "  |step| "
              << s.step_norm << "  elapsed " << Seconds(start_, Clock::now()) << " s" << std::endl;
    return ceres::SOLVER_CONTINUE;
  }

 private:
  std::string level_;
  Clock::time_point start_;
};

// The shared parameters' bounds and held blocks, after every term has added its blocks.
void BoundSharedParameters(const LevelSolveOptions& o, ceres::Problem* problem, FitState* state) {
  for (double* p : o.held) {
    if (problem->HasParameterBlock(p)) problem->SetParameterBlockConstant(p);
  }
  if (problem->HasParameterBlock(&state->g)) {
    if (o.fit_haziness) {
      problem->SetParameterLowerBound(&state->g, 0, 0.0);
      problem->SetParameterUpperBound(&state->g, 0, 0.999);
    } else {
      problem->SetParameterBlockConstant(&state->g);
    }
  }
  if (problem->HasParameterBlock(&state->log_overcast_zenith) && !o.fit_overcast) {
    problem->SetParameterBlockConstant(&state->log_overcast_zenith);
  }
  for (size_t r = 0; r < state->log_exposure.size(); ++r) {
    // Gauge: exposure x LUT scale is one degree of freedom. The first reference's
    // exposure is held during the solve and the scale is moved to it afterwards.
    if (problem->HasParameterBlock(&state->log_exposure[r]) && (o.absolute || r == 0)) {
      problem->SetParameterBlockConstant(&state->log_exposure[r]);
    }
  }
}

ceres::Solver::Options SolverOptions(const LevelSolveOptions& o, bool finest) {
  ceres::Solver::Options so;
  so.max_num_iterations = o.max_iterations;
  so.num_threads = 2;
  // The Jacobian has ~10^5 rows but each row block touches <= 15 parameters: a sparse
  // normal-equation Cholesky; dense solvers would materialise a ~0.5 GB dense Jacobian.
  so.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  so.sparse_linear_algebra_library_type =
      ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::SUITE_SPARSE) ? ceres::SUITE_SPARSE : ceres::EIGEN_SPARSE;
  // Coarse levels only need to bring the start close; the finest level converges fully.
  // After the linear start the polish only converts the relative-error optimum to the
  // robust log one: it stops once an iteration gains < 1e-4 of the cost (measured on
  // clean skies: the tail beyond that is ~40 iterations that gain 0.3% of the cost,
  // 0.15% of the rel RMSE, moving LUT entries the image barely sees).
  so.function_tolerance = !finest ? 1e-5 : o.after_linear_start ? 1e-4 : 1e-9;
  so.gradient_tolerance = finest ? 1e-12 : 1e-8;
  so.parameter_tolerance = finest ? 1e-7 : 1e-6;
  so.update_state_every_iteration = o.render_in_loop;  // the callback reads the parameter memory
  so.logging_type = ceres::SILENT;
  return so;
}

}  // namespace

bool LevelSolveOptions::IsValid(std::string* why) const {
  if (width < 2 || width % 2 != 0) {
    *why = "level width must be even and >= 2, got " + std::to_string(width);
    return false;
  }
  if (count == 0 || index >= count) {
    *why = "level index " + std::to_string(index) + " outside 0.." + std::to_string(count);
    return false;
  }
  if (!(loss_scale > 0.0) || max_iterations < 1) {
    *why = "level loss scale must be > 0 and max iterations >= 1";
    return false;
  }
  return true;
}

LevelReport SolveLevel(const std::vector<FitTerm*>& terms, const std::vector<Reference>& refs,
                       const LevelSolveOptions& o, render::SkyRenderer& renderer, FitState* state) {
  std::string why;
  if (!o.IsValid(&why)) throw Error("fit: " + why);
  const auto t_level = Clock::now();
  std::vector<FitLevel> levels;
  double total_weight = 0.0;
  for (const Reference& ref : refs) {
    levels.push_back(BuildLevel(ref, o.width));
    total_weight += levels.back().total_weight;
  }
  const int lw = levels[0].width, lh = levels[0].height;
  std::vector<ImageRGB> rendered(refs.size());
  bool rendered_valid = false;

  ceres::Problem::Options popts;
  popts.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  std::unique_ptr<RenderAtEvaluationPoint> callback;
  if (o.render_in_loop) {
    callback = std::make_unique<RenderAtEvaluationPoint>(state, &refs, &renderer, lw, lh, &rendered, &rendered_valid);
    popts.evaluation_callback = callback.get();
  }
  ceres::Problem problem(popts);
  LevelContext ctx;
  ctx.refs = &refs;
  ctx.levels = &levels;
  ctx.total_weight = total_weight;
  ctx.index = o.index;
  ctx.first = o.index == 0;
  ctx.finest = o.index + 1 == o.count;
  ctx.loss_scale = o.loss_scale;
  ctx.rendered = o.render_in_loop ? &rendered : nullptr;
  ctx.rendered_valid = &rendered_valid;
  LevelReport report;
  for (FitTerm* term : terms) report.residuals += term->AddTo(problem, *state, ctx);
  BoundSharedParameters(o, &problem, state);

  ceres::Solver::Options so = SolverOptions(o, ctx.finest);
  const std::string level_name = std::to_string(lw) + "x" + std::to_string(lh);
  ProgressPrinter progress("level " + level_name, o.start);
  if (o.verbose) so.callbacks.push_back(&progress);
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  if (summary.termination_type == ceres::FAILURE) {
    throw Error("fit: Ceres failed at level " + level_name + ": " + summary.message);
  }
  for (FitTerm* term : terms) report.probe_final_solve_iterations += term->AfterSolve(*state, ctx);
  report.width = lw;
  report.height = lh;
  report.parameters = summary.num_effective_parameters;
  report.iterations = static_cast<int>(summary.iterations.size()) - 1;
  report.initial_cost = summary.initial_cost;
  report.final_cost = summary.final_cost;
  for (const ceres::IterationSummary& it : summary.iterations) report.cost_per_iteration.push_back(it.cost);
  report.termination = ceres::TerminationTypeToString(summary.termination_type);
  report.renders = callback ? callback->renders() : 0;
  report.render_wall_ms = callback ? callback->wall_ms() : 0.0;
  if (callback) report.render_gpu_ms = callback->gpu_ms();
  report.time_s = Seconds(t_level, Clock::now());
  return report;
}

}  // namespace skycal::fit
