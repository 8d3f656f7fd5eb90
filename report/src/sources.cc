#include "sources.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include <nlohmann/json.hpp>

#include "json_fields.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "skycal/core/json_schema.h"
#include "skycal/fit/fit_result_file.h"
#include "skycal/report/html.h"

namespace skycal::report {
namespace fs = std::filesystem;
namespace {

std::string Label(const fs::path& root, const fs::path& dir);

}  // namespace

namespace {

std::string Label(const fs::path& root, const fs::path& dir) {
  const fs::path rel = dir.lexically_relative(root);
  return rel.empty() || rel == "." ? DisplayName(root) : rel.string();
}

// An image the fit listed (or that lies where the fit writes it): absolute path, or "" when
// it was not listed and is absent. A listed image that is missing is an error.
// A file name is any bytes, fit.json's strings are UTF-8: the writer replaced bytes that are
// not UTF-8 by U+FFFD (nlohmann's error_handler_t::replace). The file in p's directory whose
// name, replaced the same way, reads as p's name; p itself when there is none.
fs::path MatchReplacedName(const fs::path& p) {
  auto replaced = [](const std::string& n) {
    return nlohmann::json(n).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  };
  const std::string want = replaced(p.filename().string());
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(p.parent_path(), ec))
    if (replaced(e.path().filename().string()) == want) return e.path();
  return p;
}

// Only the run's own files are embedded: a fit.json naming an absolute path or "../.."
// would carry files from outside its directory into a page that is mailed alone.
void RequireInside(const fs::path& dir, const fs::path& p, const std::string& where) {
  std::error_code ec;
  const fs::path d = fs::weakly_canonical(dir, ec), f = fs::weakly_canonical(p, ec);
  if (std::mismatch(d.begin(), d.end(), f.begin(), f.end()).first != d.end()) {
    throw Error(where + ": the image '" + p.string() + "' lies outside the fit's directory '" + d.string() +
                "': a report embeds only the run's own files");
  }
}

// A listed image: `where` names its field.
std::string ListedImagePath(const fs::path& dir, const std::string& listed, const std::string& where) {
  fs::path p = dir / listed;
  if (!fs::is_regular_file(p)) p = MatchReplacedName(p);
  if (!fs::is_regular_file(p)) throw Error(where + ": the image '" + p.string() + "' does not exist");
  RequireInside(dir, p, where);
  return p.string();
}

std::string UnlistedImagePath(const fs::path& dir, const std::string& kind, const std::string& name) {
  const fs::path p = dir / "fit" / (name + "." + kind + ".png");
  return fs::is_regular_file(p) ? p.string() : std::string();
}

std::string ImagePath(const fs::path& dir, const std::optional<JsonAt>& images, const std::string& kind,
                      const std::string& name) {
  if (!images) return UnlistedImagePath(dir, kind, name);
  const JsonAt f = images->Child(kind);
  return ListedImagePath(dir, f.String(), f.Where());
}

// The `parameters` object of fit.json's `clouds` or `cloud_stats`: per cloud-lighting
// field value, initial, unit, held and why.
void ReadCloudParameters(const JsonAt& parent, std::vector<FitRecord::CloudParameter>* out) {
  const auto params = parent.Optional("parameters");
  if (!params) return;
  params->RequireObject();
  for (const auto& item : params->value.items()) {
    const JsonAt q = params->Child(item.key());
    FitRecord::CloudParameter cp;
    cp.name = item.key();
    cp.unit = q.OptionalString("unit").value_or("");
    cp.value = q.Number("value");
    cp.initial = q.OptionalNumber("initial").value_or(NAN);
    if (const auto b = q.Optional("held")) cp.held = b->Boolean();
    cp.why = q.OptionalString("why").value_or("");
    out->push_back(std::move(cp));
  }
}

// A number the report shows as a value: NaN (written as null) is refused, named.
double Finite(double v, const std::string& file, const std::string& field) {
  if (!std::isfinite(v)) throw Error(JsonField(file, field) + ": expected a finite number");
  return v;
}

ReferenceRecord ReadReference(const fs::path& dir, const std::string& file, size_t i, const fit::FitReferenceEntry& r) {
  const std::string at = "references[" + std::to_string(i) + "]";
  ReferenceRecord rec;
  rec.name = r.name;
  rec.rel_rmse = Finite(r.rel_rmse, file, at + ".rel_rmse");
  rec.log_rmse = Finite(r.log_rmse, file, at + ".log_rmse");
  rec.exposure = r.exposure;
  rec.sun_elevation_deg = r.sun_elevation_deg;
  rec.sun_lux_model = r.sun_illuminance_at_ground_lux;
  if (r.sun) {
    rec.probe_sun_visible = r.sun->visible;
    rec.probe_sun_fraction = r.sun->fraction;
    rec.probe_sun_lux = r.sun->illuminance_lux;
  }
  if (r.cloud_mask) rec.cloudy_fraction = Finite(r.cloud_mask->fraction, file, at + ".cloud_mask.fraction");
  if (r.pixels) {
    const nlohmann::json counts = fit::MaskCountsToJson(*r.pixels);  // by class name, as fit.json lists them
    for (const auto& [k, v] : counts.items()) rec.pixels.emplace_back(k, v.get<long long>());
  }
  for (const auto& [kind, image] : {std::pair{"reference", &rec.image_reference}, std::pair{"fit", &rec.image_fit},
                                    std::pair{"error", &rec.image_error}}) {
    if (!r.images) {
      *image = UnlistedImagePath(dir, kind, rec.name);
      continue;
    }
    const std::string listed = std::string(kind) == "reference" ? r.images->reference
                               : std::string(kind) == "fit"     ? r.images->fit
                                                                : r.images->error;
    *image = ListedImagePath(dir, listed, JsonField(file, at + ".images." + kind));
  }
  return rec;
}

// The convergence curves: the linear start's Gauss-Newton steps (grouped by level width),
// a day's joint steps, and each Ceres level's iterations.
std::vector<CostCurve> ReadConvergence(const fit::FitResultFile& doc) {
  std::vector<CostCurve> curves;
  if (doc.linear_start.single) {
    for (const fit::CostStep& s : doc.linear_start.single->cost_per_step) {
      const std::string label = "linear start, " + FormatNumber(s.width) + " wide (Gauss-Newton steps)";
      if (curves.empty() || curves.back().label != label) curves.push_back({label, {}});
      curves.back().cost.push_back(s.cost);
    }
  }
  if (doc.linear_start.day && !doc.linear_start.day->joint_robust_cost_per_step.empty()) {
    curves.push_back({"linear start, the day's joint steps", doc.linear_start.day->joint_robust_cost_per_step});
  }
  for (size_t i = 0; i < doc.levels.size(); ++i) {
    const fit::LevelReport& l = doc.levels[i];
    const std::string size = l.width > 0 && l.height > 0 ? FormatNumber(l.width) + "x" + FormatNumber(l.height)
                                                          : "level " + std::to_string(i);
    CostCurve c{"Ceres " + size + " (iterations)", l.cost_per_iteration};
    if (c.cost.empty()) {  // fit.json from before cost_per_iteration: the two ends
      c.cost = {l.initial_cost, l.final_cost};
      c.label += ", start and end only";
    }
    curves.push_back(std::move(c));
  }
  return curves;
}

std::vector<ParameterRow> ReadParameters(const std::string& preset_path) {
  std::vector<ParameterRow> rows;
  const nlohmann::json doc = ReadJsonObject(preset_path);
  const JsonAt root{doc, preset_path, ""};
  const JsonAt params = root.Child("parameters");
  params.RequireObject();
  for (const auto& [name, v] : params.value.items()) {
    const JsonAt p = params.Child(name);
    ParameterRow row;
    row.name = name;
    row.unit = p.OptionalString("unit").value_or("");
    row.description = p.OptionalString("description").value_or("");
    const JsonAt value = p.Child("value");
    if (value.value.is_array()) {
      for (size_t i = 0; i < value.Size(); ++i) row.value += (i ? ", " : "") + FormatNumber(value.Index(i).Number());
    } else {
      row.value = FormatNumber(value.Number());
    }
    const auto lo = p.OptionalNumber("min"), hi = p.OptionalNumber("max");
    if (lo && hi) row.range = FormatNumber(*lo) + " \xE2\x80\x93 " + FormatNumber(*hi);
    rows.push_back(std::move(row));
  }
  return rows;
}

std::vector<std::pair<std::string, std::string>> ReadSkipped(const JsonAt& doc) {
  std::vector<std::pair<std::string, std::string>> out;
  if (const auto s = doc.Optional("skipped")) {
    for (size_t i = 0; i < s->Size(); ++i) out.emplace_back(s->Index(i).String("block"), s->Index(i).String("reason"));
  }
  return out;
}

// fit.json's `clouds` and `cloud_stats` (JSON objects inside the typed file).
void ReadCloudSections(const fit::FitResultFile& doc, const fs::path& dir, const std::string& file, FitRecord* f) {
  nlohmann::json sections = nlohmann::json::object();
  if (!doc.clouds.is_null()) sections["clouds"] = doc.clouds;
  if (!doc.cloud_stats.is_null()) sections["cloud_stats"] = doc.cloud_stats;
  const JsonAt clouds{sections, file, ""};
  if (const auto c = clouds.Optional("clouds")) {
    if (const auto b = c->Optional("fitted")) f->clouds_fitted = b->Boolean();
    f->clouds_decision = c->OptionalString("decision").value_or("");
    if (const auto px = c->Optional("cloud_pixels")) {
      if (const auto i = px->Optional("initial")) f->cloud_pixels_log_rmse_initial = i->OptionalNumber("log_rmse");
      if (const auto e = px->Optional("final")) f->cloud_pixels_log_rmse_final = e->OptionalNumber("log_rmse");
    }
    ReadCloudParameters(*c, &f->cloud_parameters);
  }
  if (const auto cs = clouds.Optional("cloud_stats")) {
    f->clouds_fitted = true;
    ReadCloudParameters(*cs, &f->cloud_parameters);
    if (const auto refs = cs->Optional("references")) {
      for (size_t i = 0; i < refs->Size(); ++i) {
        const JsonAt r = refs->Index(i);
        FitRecord::CloudStatsPanel p;
        p.name = r.String("name");
        const auto images = r.Optional("images");
        p.image_reference = ImagePath(dir, images, "reference", p.name + ".clouds");
        p.image_fit = ImagePath(dir, images, "fit", p.name + ".clouds");
        p.image_error = ImagePath(dir, images, "error", p.name + ".clouds");
        const JsonAt e = r.Child("errors");
        p.atmosphere_rel_rmse = e.Child("atmosphere_only").Child("whole_sky").Number("rel_rmse");
        p.atmosphere_log_rmse = e.Child("atmosphere_only").Child("whole_sky").Number("log_rmse");
        p.clouds_rel_rmse = e.Child("with_cloud_statistics").Child("whole_sky").Number("rel_rmse");
        p.clouds_log_rmse = e.Child("with_cloud_statistics").Child("whole_sky").Number("log_rmse");
        f->cloud_stats_panels.push_back(std::move(p));
      }
    }
  }
}

// fit.json through its typed reader (skycal/fit/fit_result_file.h: the schema version, the
// required fields and their types); `clouds` and `cloud_stats` are read here, their fields named.
FitRecord ReadFit(const fs::path& root, const fs::path& dir) {
  FitRecord f;
  f.dir = dir.string();
  f.label = Label(root, dir);
  f.json_path = (dir / "fit.json").string();
  const fit::FitResultFile doc = fit::ReadFitResultFile(f.json_path);
  for (size_t i = 0; i < doc.references.size(); ++i) {
    f.references.push_back(ReadReference(dir, f.json_path, i, doc.references[i]));
  }
  f.haziness_g = Finite(doc.haziness_g, f.json_path, "haziness_g");
  f.time_s = doc.time_s;
  f.iterations = doc.iterations;
  f.termination = doc.termination;
  f.time_of_day_h = doc.time_of_day_h;
  if (!doc.options.is_null()) {
    const JsonAt o{doc.options, f.json_path, "options"};
    f.model = o.OptionalString("model").value_or("");
    f.backend = o.OptionalString("backend").value_or("");
    f.loss = o.OptionalString("loss").value_or("");
  }
  for (const fit::FitDecision& d : doc.decisions) {
    f.decisions.push_back({d.what, d.why, d.saved_ms_basis, d.rel_rmse_change_basis, d.saved_ms, d.rel_rmse_change});
  }
  for (const fit::SkipNote& n : doc.skipped) f.skipped.emplace_back(n.block, n.reason);
  f.warnings = doc.warnings;
  f.convergence = ReadConvergence(doc);
  ReadCloudSections(doc, dir, f.json_path, &f);
  if (fs::is_regular_file(dir / "preset.json")) f.parameters = ReadParameters((dir / "preset.json").string());
  if (fs::is_regular_file(dir / "report.png")) f.sheet_png = (dir / "report.png").string();
  f.calibration = doc.calibration;
  if (f.calibration && fs::is_regular_file(dir / "compare.png")) f.compare_png = (dir / "compare.png").string();
  return f;
}


ExportRecord ReadExport(const fs::path& root, const fs::path& dir) {
  ExportRecord e;
  e.dir = dir.string();
  e.label = Label(root, dir);
  e.json_path = (dir / "manifest.json").string();
  const nlohmann::json doc = ReadJsonObject(e.json_path);
  const JsonAt j{doc, e.json_path, ""};
  e.pre_exposure = j.Number("pre_exposure");
  const JsonAt presets = j.Child("presets");
  for (size_t i = 0; i < presets.Size(); ++i) e.presets.push_back(presets.Index(i).String("name"));
  e.skipped = ReadSkipped(j);
  const fs::path kf = dir / "keyframes.json";
  if (fs::is_regular_file(kf)) {
    const nlohmann::json kdoc = ReadJsonObject(kf.string());
    const JsonAt k{kdoc, kf.string(), ""};
    const JsonAt cols = k.Child("columns");
    for (size_t i = 0; i < cols.Size(); ++i) e.columns.push_back(cols.Index(i).String());
    if (const auto u = k.Optional("units")) {
      u->RequireObject();
      e.units = u->value;
    }
    const JsonAt keys = k.Child("keys");
    for (size_t i = 0; i < keys.Size(); ++i) {
      const JsonAt row = keys.Index(i);
      row.RequireObject();
      row.Number("time_of_day_h");
      e.keys.push_back(row.value);
    }
  }
  return e;
}

BenchRecord ReadBench(const fs::path& root, const fs::path& dir) {
  BenchRecord b;
  b.dir = dir.string();
  b.label = Label(root, dir);
  b.json_path = (dir / "results.json").string();
  const nlohmann::json doc = ReadJsonObject(b.json_path);
  const JsonAt j{doc, b.json_path, ""};
  if (const auto m = j.Optional("machine")) {
    b.machine = m->OptionalString("cpu_model").value_or("") + ", " + FormatNumber(m->OptionalNumber("cores").value_or(NAN)) +
                " cores, " + m->OptionalString("vulkan_device").value_or("");
    b.commit = m->OptionalString("commit").value_or("");
    b.date = m->OptionalString("date_utc").value_or("");
  }
  const JsonAt suites = j.Child("suites");
  for (size_t i = 0; i < suites.Size(); ++i) {
    const JsonAt s = suites.Index(i);
    BenchSuiteRecord r;
    r.name = s.String("name");
    r.summary = s.OptionalString("summary").value_or("");
    r.cases = static_cast<int>(s.Number("cases"));
    if (const auto f = s.Optional("pareto_front")) r.front = static_cast<int>(f->Size());
    r.default_case = s.OptionalString("default_case").value_or("");
    if (const auto d = s.Optional("default_on_front")) r.default_on_front = d->Boolean();
    r.wall_s = s.OptionalNumber("wall_s").value_or(NAN);
    if (const auto plots = s.Optional("plots")) {
      // The PNG (a third of the SVG's size: the page stays small enough to mail).
      for (size_t k = 0; k < plots->Size(); ++k) {
        const std::string name = plots->Index(k).String();
        if (name.size() > 4 && name.substr(name.size() - 4) == ".png") {
          const fs::path p = dir / name;
          if (!fs::is_regular_file(p)) throw Error(plots->Index(k).Where() + ": the plot '" + p.string() + "' does not exist");
          r.plot_path = p.string();
        }
      }
    }
    b.suites.push_back(std::move(r));
  }
  if (fs::is_regular_file(dir / "stress.md")) b.stress_md = ReadFile((dir / "stress.md").string());
  return b;
}

WindRecord ReadWind(const fs::path& path) {
  WindRecord w;
  w.json_path = path.string();
  const nlohmann::json j = ReadJsonObject(w.json_path);
  const JsonAt root{j, w.json_path, ""};
  w.speed_m_s = root.Child("wind").Number("speed_m_s");
  w.direction_deg = root.Child("wind").Number("direction_deg");
  const JsonAt pairs = root.Child("pairs");
  for (size_t k = 0; k < pairs.Size(); ++k) {
    const JsonAt p = pairs.Index(k);
    w.pairs.push_back({p.String("from"), p.String("to"), p.Number("dt_s"),
                       p.Child("predicted_by_the_moved_map").Number("cloud_iou"), p.Child("unmoved_map").Number("cloud_iou"),
                       p.Child("own_inverted_map").Number("cloud_iou")});
  }
  return w;
}

void Walk(const fs::path& root, const fs::path& dir, int depth, int max_depth, Sources* s) {
  if (fs::is_regular_file(dir / "fit.json")) s->fits.push_back(ReadFit(root, dir));
  if (fs::is_regular_file(dir / "manifest.json")) s->exports.push_back(ReadExport(root, dir));
  if (fs::is_regular_file(dir / "results.json")) s->benches.push_back(ReadBench(root, dir));
  if (depth >= max_depth) return;
  std::vector<fs::path> children;
  std::error_code ec;
  for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    if (name.empty() || name[0] == '.') continue;  // staging directories, temporaries
    if (e.is_directory(ec) && !e.is_symlink(ec)) children.push_back(e.path());
  }
  std::sort(children.begin(), children.end());
  for (const fs::path& c : children) Walk(root, c, depth + 1, max_depth, s);
}

}  // namespace

std::string DisplayName(const fs::path& dir) {
  std::string name = dir.filename().string();
  const size_t tmp = name.find(".tmp-");
  if (name.size() > 1 && name[0] == '.' && tmp != std::string::npos) name = name.substr(1, tmp - 1);
  return name;
}

Sources FindSources(const std::string& root_dir, int max_depth) {
  const fs::path root = fs::absolute(root_dir).lexically_normal();
  std::error_code ec;
  if (!fs::is_directory(root, ec)) throw Error(root_dir + ": not a directory (expected a skycal fit, export or bench output)");
  Sources s;
  Walk(root, root, 0, max_depth, &s);
  if (fs::is_regular_file(root / "day.json")) s.wind = ReadWind(root / "day.json");
  if (s.empty()) {
    throw Error(root_dir + ": no fit.json (skycal fit), manifest.json (skycal export) or results.json (skycal bench) in it or " +
                std::to_string(max_depth) + " levels below");
  }
  const bool all_timed =
      std::all_of(s.fits.begin(), s.fits.end(), [](const FitRecord& f) { return f.time_of_day_h.has_value(); });
  if (all_timed) {
    std::stable_sort(s.fits.begin(), s.fits.end(),
                     [](const FitRecord& a, const FitRecord& b) { return *a.time_of_day_h < *b.time_of_day_h; });
  }
  return s;
}

}  // namespace skycal::report
