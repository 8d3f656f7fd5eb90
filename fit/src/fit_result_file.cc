#include "skycal/fit/fit_result_file.h"

namespace skycal::fit {
namespace {

nlohmann::json ToJson(const RenderCheckReport& r) {
  return {{"backend", r.backend},
          {"max_relative_difference", r.max_relative_difference},
          {"threshold", r.threshold},
          {"time_s", r.time_s}};
}

nlohmann::json ToJson(const LinearStartSingleReport& r) {
  nlohmann::json steps = nlohmann::json::array();
  for (const CostStep& s : r.cost_per_step) steps.push_back({{"width", s.width}, {"cost", s.cost}});
  nlohmann::json rings = nlohmann::json::array();
  for (const RingScaleReport& s : r.loss_scale_by_sun_distance) {
    rings.push_back({{"from_deg", s.from_deg}, {"to_deg", s.to_deg}, {"scale", s.scale}});
  }
  nlohmann::json j = {{"search_width", r.search_width},
                      {"robust_width", r.robust_width},
                      {"width", r.width},
                      {"unknowns", r.unknowns},
                      {"samples", r.samples},
                      {"solves", r.solves},
                      {"gauss_newton_steps", r.gauss_newton_steps},
                      {"search_time_s", r.search_time_s},
                      {"robust_time_s", r.robust_time_s},
                      {"final_time_s", r.final_time_s},
                      {"haziness_g", r.haziness_g},
                      {"rel_rmse_least_squares", r.rel_rmse_least_squares},
                      {"rel_rmse_robust", r.rel_rmse_robust},
                      {"residual_sigma_log", r.residual_sigma_log},
                      {"loss_scale", r.loss_scale},
                      {"loss_scale_floor", r.loss_scale_floor},
                      {"loss_scale_by_sun_distance", rings},
                      {"held_non_positive", r.held_non_positive},
                      {"cost_per_step", steps},
                      {"time_s", r.time_s}};
  if (r.render_check) j["render_check"] = ToJson(*r.render_check);
  return j;
}

nlohmann::json ToJson(const LinearStartDayReport& r) {
  nlohmann::json per_ref = nlohmann::json::array();
  for (const auto& [name, report] : r.references) per_ref.push_back({{"reference", name}, {"report", ToJson(report)}});
  return {{"mode", r.mode},
          {"haziness_g", r.haziness_g},
          {"loss_scale", r.loss_scale},
          {"per_reference_time_s", r.per_reference_time_s},
          {"joint_unknowns", r.joint_unknowns},
          {"joint_samples", r.joint_samples},
          {"joint_robust_cost_per_step", r.joint_robust_cost_per_step},
          {"joint_time_s", r.joint_time_s},
          {"render_check", ToJson(r.render_check)},
          {"references", per_ref},
          {"time_s", r.time_s}};
}

nlohmann::json ToJson(const LevelReport& l) {
  return {{"size", {l.width, l.height}},
          {"residuals", l.residuals},
          {"parameters", l.parameters},
          {"iterations", l.iterations},
          {"initial_cost", l.initial_cost},
          {"final_cost", l.final_cost},
          {"cost_per_iteration", l.cost_per_iteration},
          {"termination", l.termination},
          {"renders", l.renders},
          {"probe_final_solve_iterations", l.probe_final_solve_iterations},
          {"time_s", l.time_s}};
}

nlohmann::json ToJson(const ProbeReport& p) {
  nlohmann::json j = {{"references", p.references},
                      {"weight", p.weight},
                      {"quadrature_width", p.quadrature_width},
                      {"residuals", p.residuals},
                      {"dropped_samples", p.dropped_samples},
                      {"evaluation_time_s", p.evaluation_time_s},
                      {"ground_albedo", {{"fitted", p.ground_albedo_fitted},
                                         {"value", p.ground_albedo_value},
                                         {"initial", p.ground_albedo_initial}}}};
  if (!p.ground_albedo_fitted) j["ground_albedo"]["reason"] = p.ground_albedo_reason;
  return j;
}

}  // namespace

nlohmann::json ToJson(const LinearStartReportOut& r) {
  if (r.single) return ToJson(*r.single);
  if (r.day) return ToJson(*r.day);
  return nullptr;
}

nlohmann::json ToJson(const FitDecision& d) {
  nlohmann::json j = {{"what", d.what}, {"why", d.why}, {"saved_ms", d.saved_ms}, {"saved_ms_basis", d.saved_ms_basis}};
  if (d.rel_rmse_change) {
    j["rel_rmse_change"] = *d.rel_rmse_change;
    j["rel_rmse_change_basis"] = d.rel_rmse_change_basis;
  }
  return j;
}

nlohmann::json FitSummaryJson(const FitResult& result) {
  nlohmann::json levels = nlohmann::json::array(), skipped = nlohmann::json::array(),
                 decisions = nlohmann::json::array(), unobserved = nlohmann::json::array();
  for (const LevelReport& l : result.levels) levels.push_back(ToJson(l));
  for (const SkipNote& s : result.skipped) skipped.push_back({{"block", s.block}, {"reason", s.reason}});
  for (const FitDecision& d : result.decisions) decisions.push_back(ToJson(d));
  for (const UnobservedRow& u : result.unobserved_rows) {
    unobserved.push_back({{"row", u.row}, {"sun_zenith_deg", u.sun_zenith_deg}, {"reason", u.reason}});
  }
  return {{"haziness_g", result.preset.haziness_g},
          {"time_s", result.time_s},
          {"probe", result.probe ? ToJson(*result.probe) : nlohmann::json()},
          {"iterations", result.iterations},
          {"termination", result.termination},
          {"linear_start", ToJson(result.linear_start)},
          {"levels", levels},
          {"skipped", skipped},
          {"decisions", decisions},
          {"unobserved_lut_rows", unobserved},
          {"backend_device", result.backend_description}};
}

}  // namespace skycal::fit
