#include "cloud_lighting_term.h"

#include <chrono>
#include <cmath>

#include "skycal/core/error.h"
#include "skycal/render/renderer.h"

namespace skycal::cloudfit {

CloudLightingTerm::CloudLightingTerm(CloudSampleModel* model, const CloudLighting& initial,
                                     const CloudLightingOptions& options)
    : model_(model), initial_(initial), theta_(initial), options_(options) {}

void CloudLightingTerm::RefreshSky(const fit::FitState& state, const fit::Reference& ref) {
  const render::Preset preset = state.ToPreset();
  render::RenderRequest req;
  req.sun_dir = ref.sun_dir;
  req.width = ref.radiance.width;
  req.height = ref.radiance.height;
  req.sun_disc = false;  // the sun cone is masked; the clouds' sun light is the direct term
  const ImageRGB sky = render::CreateRenderer(render::Backend::kCpu)->Render(preset, req);
  model_->SetSky(preset, sky, std::exp(state.log_exposure.at(0)));
}

long long CloudLightingTerm::AddTo(ceres::Problem& problem, fit::FitState& state, const fit::LevelContext& level) {
  if (!level.finest) return 0;
  RefreshSky(state, level.refs->at(0));
  if (!conditioned_) {
    const auto t0 = std::chrono::steady_clock::now();
    conditioning_ = ConditionAt(model_, initial_, options_);
    conditioning_time_s_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    conditioned_ = true;
  }
  model_->FreezeJacobianAt(theta_.data());
  AddCloudBlock(&problem, model_, theta_.data(), conditioning_);
  return static_cast<long long>(model_->residuals());
}

int CloudLightingTerm::AfterSolve(fit::FitState& /*state*/, const fit::LevelContext& level) {
  if (level.finest) model_->Unfreeze();
  return 0;
}

void CloudLightingTerm::Finish(const ceres::Solver::Summary& s) {
  iterations_ += static_cast<int>(s.iterations.size()) - 1;
  termination_ = ceres::TerminationTypeToString(s.termination_type);
}

void CloudLightingTerm::ReportSkips(std::vector<fit::SkipNote>* skipped, std::vector<fit::FitDecision>* decisions) const {
  (void)decisions;
  skipped->push_back({"cloud lighting on coarse pyramid levels",
                      "the cloud term joins the finest level only: its pixels are fitted at the reference's own size"});
}

}  // namespace skycal::cloudfit
