#include "skycal/fit/fit_result_file.h"

#include <cmath>
#include <limits>

#include "skycal/core/error.h"
#include "skycal/core/json_file.h"
#include "skycal/core/json_schema.h"
#include "skycal/fit/sky_fit.h"

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
                      {"partly_seen_columns", r.partly_seen_columns},
                      {"unseen_profile_terms", r.unseen_profile_terms},
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
          {"render_wall_ms", l.render_wall_ms},
          {"render_gpu_ms", l.render_gpu_ms ? nlohmann::json(*l.render_gpu_ms) : nlohmann::json(nullptr)},
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

nlohmann::json ToJson(const FitProbeSunEntry& s) {
  nlohmann::json j = {{"observable", s.observable},
                      {"visible", s.visible},
                      {"illuminance_rgb", s.illuminance_rgb},
                      {"illuminance_rgb_model", s.illuminance_rgb_model},
                      {"fitted_illuminance_rgb_model", s.fitted_illuminance_rgb_model},
                      {"fraction", s.fraction},
                      {"residual", s.residual},
                      {"log_rmse", s.log_rmse},
                      {"samples", s.samples},
                      {"sun_facing_samples", s.sun_facing_samples},
                      {"ground_facing_samples", s.ground_facing_samples},
                      {"probe", s.probe}};
  if (!s.note.empty()) j["note"] = s.note;
  if (s.illuminance_lux) j["illuminance_lux"] = *s.illuminance_lux;
  if (s.sun_tint_rgb) j["sun_tint_rgb"] = *s.sun_tint_rgb;
  return j;
}

}  // namespace

nlohmann::json FitReferenceEntryJson(const FitReferenceEntry& r) {
  nlohmann::json j = {{"name", r.name},
                      {"path", r.path},
                      {"rel_rmse", r.rel_rmse},
                      {"log_rmse", r.log_rmse},
                      {"exposure", r.exposure},
                      {"sun_direction", r.sun_direction},
                      {"sun_source", r.sun_source},
                      {"observed_lut_rows", r.observed_lut_rows},
                      {"clip_level", r.clip_level}};
  if (r.sun_elevation_deg) j["sun_elevation_deg"] = *r.sun_elevation_deg;
  if (r.pixels) j["pixels"] = MaskCountsToJson(*r.pixels);
  if (r.sun) j["sun"] = ToJson(*r.sun);
  if (r.images) j["images"] = {{"reference", r.images->reference}, {"fit", r.images->fit}, {"error", r.images->error}};
  if (r.sun_illuminance_at_ground_lux) j["sun_illuminance_at_ground_lux"] = *r.sun_illuminance_at_ground_lux;
  if (r.cloud_mask) {
    j["cloud_mask"] = {{"cloudy_pixels", r.cloud_mask->cloudy_pixels},
                       {"fraction", r.cloud_mask->fraction},
                       {"threshold", r.cloud_mask->threshold},
                       {"source", r.cloud_mask->source}};
  }
  return j;
}

FitResultFile FitResultFileFrom(const FitResult& result) {
  FitResultFile f;
  f.haziness_g = result.preset.haziness_g;
  f.time_s = result.time_s;
  f.iterations = result.iterations;
  f.termination = result.termination;
  f.backend_device = result.backend_description;
  f.probe = result.probe;
  f.linear_start = result.linear_start;
  f.levels = result.levels;
  f.skipped = result.skipped;
  f.decisions = result.decisions;
  f.unobserved_lut_rows = result.unobserved_rows;
  return f;
}

nlohmann::json ToJson(const FitCalibration& c) {
  nlohmann::json j = {{"photo", c.photo},
                      {"sky_kind", c.sky_kind},
                      {"sky_kind_reason", c.sky_kind_reason},
                      {"sky_share", c.sky_share},
                      {"zenith_sky_share", c.zenith_sky_share},
                      {"zenith_blue", c.zenith_blue},
                      {"texture", c.texture},
                      {"point_sources", c.point_sources},
                      {"sun_source", c.sun_source},
                      {"mask", c.mask},
                      {"render", c.render},
                      {"game_sky_pixels", c.game_sky_pixels},
                      {"game_per_pixel_log_rmse", c.game_per_pixel_log_rmse},
                      {"game_appearance_error", c.game_appearance_error},
                      {"game_sun_cone_deg", c.game_sun_cone_deg},
                      {"seconds", c.seconds}};
  if (c.cloud_share) j["cloud_share"] = *c.cloud_share;
  if (c.sun_uncertainty_deg) j["sun_uncertainty_deg"] = *c.sun_uncertainty_deg;
  if (c.game_cloud_iou) j["game_cloud_iou"] = *c.game_cloud_iou;
  return j;
}

nlohmann::json FitResultFileJson(const FitResultFile& f) {
  nlohmann::json levels = nlohmann::json::array(), skipped = nlohmann::json::array(),
                 decisions = nlohmann::json::array(), unobserved = nlohmann::json::array(),
                 references = nlohmann::json::array();
  for (const LevelReport& l : f.levels) levels.push_back(ToJson(l));
  for (const SkipNote& s : f.skipped) skipped.push_back({{"block", s.block}, {"reason", s.reason}});
  for (const FitDecision& d : f.decisions) decisions.push_back(ToJson(d));
  for (const UnobservedRow& u : f.unobserved_lut_rows) {
    unobserved.push_back({{"row", u.row}, {"sun_zenith_deg", u.sun_zenith_deg}, {"reason", u.reason}});
  }
  for (const FitReferenceEntry& r : f.references) references.push_back(FitReferenceEntryJson(r));
  nlohmann::json j = {{"schema_version", f.schema_version},
                      {"haziness_g", f.haziness_g},
                      {"time_s", f.time_s},
                      {"probe", f.probe ? ToJson(*f.probe) : nlohmann::json()},
                      {"iterations", f.iterations},
                      {"termination", f.termination},
                      {"linear_start", ToJson(f.linear_start)},
                      {"levels", levels},
                      {"skipped", skipped},
                      {"decisions", decisions},
                      {"unobserved_lut_rows", unobserved},
                      {"backend_device", f.backend_device},
                      {"references", references},
                      {"warnings", f.warnings},
                      {"options", f.options},
                      {"clouds", f.clouds},
                      {"out", f.out}};
  if (!f.cloud_stats.is_null()) j["cloud_stats"] = f.cloud_stats;
  if (f.time_of_day_h) j["time_of_day_h"] = *f.time_of_day_h;
  if (f.calibration) j["calibration"] = ToJson(*f.calibration);
  return j;
}

void WriteFitResultFile(const std::string& path, const FitResultFile& file) {
  WriteJsonFileAtomically(path, FitResultFileJson(file));
}


// ---- The reader ----------------------------------------------------------------------------
namespace {

// A value of the document and where it is: errors read "FILE: field 'references[0].rel_rmse': ...".
struct At {
  const nlohmann::json& v;
  const std::string& file;
  std::string field;
  std::string Where() const { return field.empty() ? file : JsonField(file, field); }
  [[noreturn]] void Fail(const std::string& what) const {
    throw Error(Where() + ": " + what + ", found " + std::string(v.type_name()));
  }
  At Index(size_t i) const { return {v[i], file, field + "[" + std::to_string(i) + "]"}; }
  At Key(const std::string& k, const nlohmann::json& child) const {
    return {child, file, field.empty() ? k : field + "." + k};
  }
  void RequireObject() const {
    if (!v.is_object()) Fail("expected an object");
  }
};

// A number written from a double; null reads as NaN (nlohmann writes NaN and infinities as null).
void Read(const At& a, double* x) {
  if (a.v.is_null()) {
    *x = std::numeric_limits<double>::quiet_NaN();
    return;
  }
  if (!a.v.is_number()) a.Fail("expected a number");
  *x = a.v.get<double>();
}
void Read(const At& a, long long* x) {
  if (!a.v.is_number_integer()) a.Fail("expected an integer");
  *x = a.v.get<long long>();
}
void Read(const At& a, int* x) {
  long long v = 0;
  Read(a, &v);
  if (v < std::numeric_limits<int>::min() || v > std::numeric_limits<int>::max()) a.Fail("expected a 32-bit integer");
  *x = static_cast<int>(v);
}
void Read(const At& a, bool* x) {
  if (!a.v.is_boolean()) a.Fail("expected true or false");
  *x = a.v.get<bool>();
}
void Read(const At& a, std::string* x) {
  if (!a.v.is_string()) a.Fail("expected a string");
  *x = a.v.get<std::string>();
}
void Read(const At& a, nlohmann::json* x) { *x = a.v; }

template <class T>
void Read(const At& a, std::vector<T>* x) {
  if (!a.v.is_array()) a.Fail("expected an array");
  x->assign(a.v.size(), T{});
  for (size_t i = 0; i < a.v.size(); ++i) Read(a.Index(i), &(*x)[i]);
}
template <class T, size_t N>
void Read(const At& a, std::array<T, N>* x) {
  if (!a.v.is_array() || a.v.size() != N) a.Fail("expected an array of " + std::to_string(N) + " numbers");
  for (size_t i = 0; i < N; ++i) Read(a.Index(i), &(*x)[i]);
}
template <class T>
void Read(const At& a, std::optional<T>* x) {
  if (a.v.is_null()) {
    x->reset();
    return;
  }
  x->emplace();
  Read(a, &**x);
}

// Members: absent leaves the default (older files lack newer fields); Required throws.
template <class T>
void Optional(const At& obj, const std::string& key, T* x) {
  obj.RequireObject();
  const auto it = obj.v.find(key);
  if (it != obj.v.end()) Read(obj.Key(key, *it), x);
}
template <class T>
void Required(const At& obj, const std::string& key, T* x) {
  obj.RequireObject();
  const auto it = obj.v.find(key);
  if (it == obj.v.end()) throw Error(JsonField(obj.file, obj.Key(key, obj.v).field) + ": missing");
  Read(obj.Key(key, *it), x);
}

void Read(const At& a, SkipNote* x) {
  Required(a, "block", &x->block);
  Required(a, "reason", &x->reason);
}

void Read(const At& a, FitDecision* x) {
  Required(a, "what", &x->what);
  Required(a, "why", &x->why);
  Required(a, "saved_ms", &x->saved_ms);
  Optional(a, "saved_ms_basis", &x->saved_ms_basis);
  Optional(a, "rel_rmse_change", &x->rel_rmse_change);
  Optional(a, "rel_rmse_change_basis", &x->rel_rmse_change_basis);
}

void Read(const At& a, FitCalibration* x) {
  Required(a, "photo", &x->photo);
  Required(a, "sky_kind", &x->sky_kind);
  Optional(a, "sky_kind_reason", &x->sky_kind_reason);
  Optional(a, "sky_share", &x->sky_share);
  Optional(a, "zenith_sky_share", &x->zenith_sky_share);
  Optional(a, "zenith_blue", &x->zenith_blue);
  Optional(a, "texture", &x->texture);
  Optional(a, "point_sources", &x->point_sources);
  Optional(a, "cloud_share", &x->cloud_share);
  Required(a, "sun_source", &x->sun_source);
  Optional(a, "sun_uncertainty_deg", &x->sun_uncertainty_deg);
  Optional(a, "mask", &x->mask);
  Optional(a, "render", &x->render);
  Optional(a, "game_sky_pixels", &x->game_sky_pixels);
  Required(a, "game_per_pixel_log_rmse", &x->game_per_pixel_log_rmse);
  Required(a, "game_appearance_error", &x->game_appearance_error);
  Optional(a, "game_sun_cone_deg", &x->game_sun_cone_deg);
  Optional(a, "game_cloud_iou", &x->game_cloud_iou);
  Optional(a, "seconds", &x->seconds);
}

void Read(const At& a, UnobservedRow* x) {
  Optional(a, "row", &x->row);
  Optional(a, "sun_zenith_deg", &x->sun_zenith_deg);
  Optional(a, "reason", &x->reason);
}

void Read(const At& a, LevelReport* x) {
  std::array<int, 2> size{};
  Optional(a, "size", &size);
  x->width = size[0];
  x->height = size[1];
  Optional(a, "residuals", &x->residuals);
  Optional(a, "parameters", &x->parameters);
  Optional(a, "iterations", &x->iterations);
  Optional(a, "initial_cost", &x->initial_cost);
  Optional(a, "final_cost", &x->final_cost);
  Optional(a, "cost_per_iteration", &x->cost_per_iteration);
  Optional(a, "termination", &x->termination);
  Optional(a, "renders", &x->renders);
  Optional(a, "render_wall_ms", &x->render_wall_ms);
  Optional(a, "render_gpu_ms", &x->render_gpu_ms);
  Optional(a, "probe_final_solve_iterations", &x->probe_final_solve_iterations);
  Optional(a, "time_s", &x->time_s);
}

void Read(const At& a, RenderCheckReport* x) {
  Optional(a, "backend", &x->backend);
  Optional(a, "max_relative_difference", &x->max_relative_difference);
  Optional(a, "threshold", &x->threshold);
  Optional(a, "time_s", &x->time_s);
}

void Read(const At& a, CostStep* x) {
  Optional(a, "width", &x->width);
  Optional(a, "cost", &x->cost);
}

void Read(const At& a, RingScaleReport* x) {
  Optional(a, "from_deg", &x->from_deg);
  Optional(a, "to_deg", &x->to_deg);
  Optional(a, "scale", &x->scale);
}

void Read(const At& a, LinearStartSingleReport* x) {
  Optional(a, "search_width", &x->search_width);
  Optional(a, "robust_width", &x->robust_width);
  Optional(a, "width", &x->width);
  Optional(a, "unknowns", &x->unknowns);
  Optional(a, "samples", &x->samples);
  Optional(a, "solves", &x->solves);
  Optional(a, "gauss_newton_steps", &x->gauss_newton_steps);
  Optional(a, "search_time_s", &x->search_time_s);
  Optional(a, "robust_time_s", &x->robust_time_s);
  Optional(a, "final_time_s", &x->final_time_s);
  Optional(a, "haziness_g", &x->haziness_g);
  Optional(a, "rel_rmse_least_squares", &x->rel_rmse_least_squares);
  Optional(a, "rel_rmse_robust", &x->rel_rmse_robust);
  Optional(a, "residual_sigma_log", &x->residual_sigma_log);
  Optional(a, "loss_scale", &x->loss_scale);
  Optional(a, "loss_scale_floor", &x->loss_scale_floor);
  Optional(a, "loss_scale_by_sun_distance", &x->loss_scale_by_sun_distance);
  Optional(a, "held_non_positive", &x->held_non_positive);
  Optional(a, "partly_seen_columns", &x->partly_seen_columns);
  Optional(a, "unseen_profile_terms", &x->unseen_profile_terms);
  Optional(a, "cost_per_step", &x->cost_per_step);
  Optional(a, "time_s", &x->time_s);
  Optional(a, "render_check", &x->render_check);
}

void Read(const At& a, std::pair<std::string, LinearStartSingleReport>* x) {
  Required(a, "reference", &x->first);
  Required(a, "report", &x->second);
}

void Read(const At& a, LinearStartDayReport* x) {
  Optional(a, "mode", &x->mode);
  Optional(a, "haziness_g", &x->haziness_g);
  Optional(a, "loss_scale", &x->loss_scale);
  Optional(a, "per_reference_time_s", &x->per_reference_time_s);
  Optional(a, "joint_unknowns", &x->joint_unknowns);
  Optional(a, "joint_samples", &x->joint_samples);
  Optional(a, "joint_robust_cost_per_step", &x->joint_robust_cost_per_step);
  Optional(a, "joint_time_s", &x->joint_time_s);
  Optional(a, "render_check", &x->render_check);
  Optional(a, "references", &x->references);
  Optional(a, "time_s", &x->time_s);
}

// A day's linear start has a `mode`; one reference's does not.
void Read(const At& a, LinearStartReportOut* x) {
  *x = {};
  if (a.v.is_null()) return;
  a.RequireObject();
  if (a.v.contains("mode")) {
    Read(a, &x->day.emplace());
  } else {
    Read(a, &x->single.emplace());
  }
}

void Read(const At& a, ProbeReport* x) {
  Optional(a, "references", &x->references);
  Optional(a, "weight", &x->weight);
  Optional(a, "quadrature_width", &x->quadrature_width);
  Optional(a, "residuals", &x->residuals);
  Optional(a, "dropped_samples", &x->dropped_samples);
  Optional(a, "evaluation_time_s", &x->evaluation_time_s);
  const auto it = a.v.find("ground_albedo");
  if (it == a.v.end()) return;
  const At g = a.Key("ground_albedo", *it);
  Optional(g, "fitted", &x->ground_albedo_fitted);
  Optional(g, "value", &x->ground_albedo_value);
  Optional(g, "initial", &x->ground_albedo_initial);
  Optional(g, "reason", &x->ground_albedo_reason);
}

void Read(const At& a, FitProbeSunEntry* x) {
  Required(a, "visible", &x->visible);
  Optional(a, "observable", &x->observable);
  Optional(a, "illuminance_rgb", &x->illuminance_rgb);
  Optional(a, "illuminance_rgb_model", &x->illuminance_rgb_model);
  Optional(a, "fitted_illuminance_rgb_model", &x->fitted_illuminance_rgb_model);
  Optional(a, "fraction", &x->fraction);
  Optional(a, "residual", &x->residual);
  Optional(a, "log_rmse", &x->log_rmse);
  Optional(a, "samples", &x->samples);
  Optional(a, "sun_facing_samples", &x->sun_facing_samples);
  Optional(a, "ground_facing_samples", &x->ground_facing_samples);
  Optional(a, "probe", &x->probe);
  Optional(a, "note", &x->note);
  Optional(a, "illuminance_lux", &x->illuminance_lux);
  Optional(a, "sun_tint_rgb", &x->sun_tint_rgb);
}

void Read(const At& a, FitCloudMaskEntry* x) {
  Required(a, "fraction", &x->fraction);
  Optional(a, "cloudy_pixels", &x->cloudy_pixels);
  Optional(a, "threshold", &x->threshold);
  Optional(a, "source", &x->source);
}

void Read(const At& a, FitReferenceImages* x) {
  Required(a, "reference", &x->reference);
  Required(a, "fit", &x->fit);
  Required(a, "error", &x->error);
}

void Read(const At& a, MaskCounts* x) {
  Optional(a, "sky_fitted", &x->sky);
  Optional(a, "below_horizon", &x->below_horizon);
  Optional(a, "sun_cone", &x->sun_cone);
  Optional(a, "invalid", &x->invalid);
  Optional(a, "clipped", &x->clipped);
  Optional(a, "user_masked", &x->user_masked);
}

void Read(const At& a, FitReferenceEntry* x) {
  Required(a, "name", &x->name);
  Required(a, "rel_rmse", &x->rel_rmse);
  Required(a, "log_rmse", &x->log_rmse);
  Optional(a, "path", &x->path);
  Optional(a, "exposure", &x->exposure);
  Optional(a, "sun_direction", &x->sun_direction);
  Optional(a, "sun_elevation_deg", &x->sun_elevation_deg);
  Optional(a, "sun_source", &x->sun_source);
  Optional(a, "observed_lut_rows", &x->observed_lut_rows);
  Optional(a, "clip_level", &x->clip_level);
  Optional(a, "pixels", &x->pixels);
  Optional(a, "sun", &x->sun);
  Optional(a, "images", &x->images);
  Optional(a, "sun_illuminance_at_ground_lux", &x->sun_illuminance_at_ground_lux);
  Optional(a, "cloud_mask", &x->cloud_mask);
}

}  // namespace

// A file without schema_version was written by a skycal from before the field: its fields
// are version 1's (the field was added without changing any other), so it reads as 1.
void RequireFitResultSchemaVersion(const nlohmann::json& doc, const std::string& origin) {
  if (!doc.is_object()) throw Error(origin + ": expected a JSON object, found " + std::string(doc.type_name()));
  const auto it = doc.find("schema_version");
  if (it == doc.end()) return;
  const std::string expected = std::to_string(kFitResultSchemaVersion);
  if (!it->is_number_integer()) {
    throw Error(JsonField(origin, "schema_version") + ": found " + it->dump() + ", expected the integer " + expected);
  }
  const long long found = it->get<long long>();
  if (found != kFitResultSchemaVersion) {
    throw Error(JsonField(origin, "schema_version") + ": found " + std::to_string(found) + ", expected " + expected +
                (found > kFitResultSchemaVersion ? " (written by a newer skycal: read it with that version)"
                                                 : " (not a version skycal wrote)"));
  }
}

FitResultFile FitResultFileFromJson(const nlohmann::json& doc, const std::string& origin) {
  RequireFitResultSchemaVersion(doc, origin);
  FitResultFile f;
  const At a{doc, origin, ""};
  Optional(a, "schema_version", &f.schema_version);
  Required(a, "references", &f.references);
  if (f.references.empty()) throw Error(JsonField(origin, "references") + ": expected at least one reference");
  Required(a, "haziness_g", &f.haziness_g);
  Optional(a, "time_s", &f.time_s);
  Optional(a, "iterations", &f.iterations);
  Optional(a, "termination", &f.termination);
  Optional(a, "backend_device", &f.backend_device);
  Optional(a, "probe", &f.probe);
  Optional(a, "linear_start", &f.linear_start);
  Optional(a, "levels", &f.levels);
  Optional(a, "skipped", &f.skipped);
  Optional(a, "decisions", &f.decisions);
  Optional(a, "unobserved_lut_rows", &f.unobserved_lut_rows);
  Optional(a, "warnings", &f.warnings);
  Optional(a, "options", &f.options);
  Optional(a, "clouds", &f.clouds);
  Optional(a, "cloud_stats", &f.cloud_stats);
  Optional(a, "time_of_day_h", &f.time_of_day_h);
  Optional(a, "calibration", &f.calibration);
  Optional(a, "out", &f.out);
  return f;
}

FitResultFile ReadFitResultFile(const std::string& path) { return FitResultFileFromJson(ReadJsonFile(path), path); }

}  // namespace skycal::fit
