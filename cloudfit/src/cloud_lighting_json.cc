#include "skycal/cloudfit/cloud_lighting_json.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace skycal::cloudfit {

namespace {
nlohmann::json Errors(const PixelErrors& e) {
  return {{"pixels", e.pixels}, {"rel_rmse", e.rel_rmse}, {"log_rmse", e.log_rmse}};
}
nlohmann::json Finite(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }
}  // namespace

nlohmann::json CloudReportJson(const CloudReportSettings& o, const SkyCloudFit& f) {
  const CloudLightingReport& r = f.clouds;
  nlohmann::json params = nlohmann::json::object();
  for (const CloudParamReport& p : r.parameters) {
    nlohmann::json j = {{"value", p.value}, {"unit", p.unit}, {"initial", p.initial}, {"held", p.held}};
    if (!p.why.empty()) j["why"] = p.why;  // held, or a hold released
    if (r.fitted) {
      j["sensitivity"] = Finite(p.sensitivity);
      j["predicted_relative_error"] = Finite(p.predicted_relative_error);
      j["separability"] = Finite(p.separability);
      j["most_collinear_with"] = p.most_collinear_with;
      j["collinear_cosine"] = Finite(p.collinear_cosine);
    }
    params[p.name] = j;
  }
  nlohmann::json cloud_time = o.time_s ? nlohmann::json(*o.time_s) : nlohmann::json("per reference: skycalCloudTimeS");
  nlohmann::json j = {{"mode", o.mode},
                      {"fitted", r.fitted},
                      {"decision", r.decision},
                      {"term", "known shapes (per-pixel composite residuals)"},
                      {"cloud_preset", o.preset},
                      {"cloud_time_s", cloud_time},
                      {"cloud_fraction", r.cloud_fraction},
                      {"parameters", params}};
  if (!r.fitted) return j;
  j["notes"] = {
      {"sensitivity", "RMS over sampled pixel channels of d ln(composite) / d ln(parameter) (or per 1% of its range "
                      "when the parameter is near 0), at the start"},
      {"predicted_relative_error", "sigma sqrt(diag((J^T J)^-1)) with sigma = 2% pixel noise over the samples, free set"},
      {"separability", "1 / sqrt(variance inflation) among all observed parameters: 1 independent, 0 collinear"},
      {"singular_values", "of the column-normalised Jacobian (d ln composite / d ln parameter), descending; "
                          "singular_values_free: of the free parameters' columns, empty when the solve released "
                          "the separability rule's holds (solve.released_holds)"},
      {"solve", "seconds of the whole fit (time_s, the same as fit.json time_s) and of its stages: cloud_pixels_time_s "
                "(the start's cloud renders that find the cloud pixels), sky_fit_time_s (the sky on its clear pixels; "
                "sky_renders backend renders), conditioning_time_s and cloud_solve_time_s (the Ceres solve of the cloud "
                "blocks, conditioning included; renders and jacobians counted, render_time_s and jacobian_time_s of it), "
                "report_time_s (the composites' errors); with a shape refinement (calibrate's precipitation), the "
                "solves before and after it summed, the refinement itself in time_s alone"}};
  j["singular_values"] = r.singular_values;
  j["singular_values_free"] = r.singular_values_free;
  j["cloud_pixels"] = {{"count", r.cloud_pixels}, {"samples", r.samples},
                       {"initial", Errors(r.cloud_initial)}, {"final", Errors(r.cloud_final)}};
  j["clear_pixels"] = Errors(r.clear);
  j["solve"] = {{"iterations", r.iterations},        {"termination", r.termination},
                {"renders", r.renders},              {"jacobians", r.jacobians},
                {"sky_renders", r.sky_renders},      {"value_source", r.value_source},
                {"render_time_s", r.render_time_s},  {"jacobian_time_s", r.jacobian_time_s},
                {"conditioning_time_s", r.conditioning_time_s},
                {"cloud_pixels_time_s", r.cloud_pixels_time_s},
                {"sky_fit_time_s", r.sky_fit_time_s}, {"cloud_solve_time_s", r.solve_time_s},
                {"report_time_s", r.report_time_s},  {"time_s", r.time_s}};
  if (r.bound_restarts > 0)  // CloudLightingOptions::restart_at_bounds
    j["solve"]["bound_restarts"] = {{"tried", r.bound_restarts}, {"kept", r.bound_restart_kept}};
  if (!r.released_holds.empty())  // CloudLightingOptions::release_inseparable
    j["solve"]["released_holds"] = {{"freed", r.released_holds},
                                    {"kept", r.released_kept},
                                    {"cost_before", r.released_cost_before},
                                    {"cost_after", r.released_cost_after}};
  if (f.references.size() > 1) {
    j["day"] = {{"references", f.references.size()},
                {"smoothness", o.day_smoothness},
                {"prior_residuals", r.prior_residuals},
                {"note", "one lighting per reference, a second-difference prior over time of day on each parameter "
                         "(relative to the start, per h^2) weighted by smoothness; parameters holds: a parameter one "
                         "reference cannot separate is held in all; `parameters` above are the earliest reference's"}};
    j["keyframes"] = CloudDayKeyframesJson(f)["keys"];
  }
  return j;
}

nlohmann::json CloudDayKeyframesJson(const SkyCloudFit& f) {
  std::vector<const CloudLightingReport*> order;
  for (const auto& r : f.references) order.push_back(&r);
  std::stable_sort(order.begin(), order.end(), [](auto* a, auto* b) {
    return a->time_of_day_h.value_or(0.0) < b->time_of_day_h.value_or(0.0);
  });
  nlohmann::json keys = nlohmann::json::array(), units = nlohmann::json::object();
  for (const CloudLightingReport* r : order) {
    nlohmann::json lighting = nlohmann::json::object();
    for (const CloudParamReport& p : r->parameters) {
      lighting[p.name] = p.value;
      units[p.name] = p.unit;
    }
    keys.push_back({{"time_of_day_h", r->time_of_day_h ? nlohmann::json(*r->time_of_day_h) : nlohmann::json()},
                    {"reference", r->reference},
                    {"lighting", lighting},
                    {"cloud_pixels", {{"count", r->cloud_pixels}, {"samples", r->samples},
                                      {"initial", Errors(r->cloud_initial)}, {"final", Errors(r->cloud_final)}}}});
  }
  return {{"keys", keys}, {"units", units}};
}

}  // namespace skycal::cloudfit
