#include "skycal/controllers/fit_controller.h"

#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <set>

#include "fit_cloud_mask.h"
#include "fit_internal.h"
#include "fit_report.h"
#include "skycal/capture/latlong_frame.h"
#include "skycal/core/error.h"
#include "skycal/core/latlong.h"
#include "skycal/core/luminance.h"
#include "skycal/core/sha256.h"
#include "skycal/core/version.h"
#include "skycal/fit/fit_result_file.h"
#include "skycal/fit/reference.h"
#include "skycal/fit/sky_fit.h"
#include "skycal/render/irradiance.h"
#include "skycal/report/report.h"

namespace skycal::controllers {
namespace fs = std::filesystem;
namespace {

// Probe samples per reference name: FitControllerOptions::probes' REF_STEM=FILE, else
// <reference stem>.probe.json beside the reference.
std::map<std::string, std::string> GivenProbes(const FitControllerOptions& o, const std::vector<fit::Reference>& refs) {
  std::map<std::string, std::string> given;
  for (const std::string& spec : o.probes) {
    const auto eq = spec.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == spec.size()) {
      throw Error("FitControllerOptions::probes = " + spec + ": expected REF_STEM=SAMPLES.json");
    }
    if (!given.emplace(spec.substr(0, eq), spec.substr(eq + 1)).second) {
      throw Error("FitControllerOptions::probes: two sample files for '" + spec.substr(0, eq) + "'");
    }
  }
  for (const auto& [stem, file] : given) {
    bool found = false;
    for (const auto& r : refs) found = found || r.name == stem;
    if (!found) throw Error("FitControllerOptions::probes = " + stem + "=" + file + ": no reference named '" + stem + "'");
  }
  return given;
}

std::vector<std::optional<fit::ProbeSamples>> ProbesFor(const FitControllerOptions& o, const std::vector<fit::Reference>& refs) {
  const std::map<std::string, std::string> given = GivenProbes(o, refs);
  std::vector<std::optional<fit::ProbeSamples>> out;
  for (const auto& r : refs) {
    std::string file;
    if (auto it = given.find(r.name); it != given.end()) {
      file = it->second;
    } else {
      fs::path p(r.path);
      if (p.extension() == ".exr" || p.extension() == ".EXR") p.replace_extension("");
      const std::string candidate = p.string() + ".probe.json";
      if (fs::exists(candidate)) file = candidate;
    }
    if (file.empty()) {
      if (o.require_probe) throw Error("FitControllerOptions::require_probe: no probe samples for reference " + r.path);
      out.emplace_back();
    } else {
      out.emplace_back(fit::LoadProbeSamples(file));
    }
  }
  return out;
}

const char* LossName(fit::RobustLoss l) {
  return l == fit::RobustLoss::kCauchy ? "cauchy" : (l == fit::RobustLoss::kHuber ? "huber" : "none");
}

std::string InitPresetPath(const FitControllerOptions& o) {
  return o.init_preset.empty() ? DefaultClearPresetPath() : o.init_preset;
}

void CheckOptions(const FitControllerOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
}

}  // namespace

bool FitControllerOptions::IsValid(std::string* why) const {
  auto fail = [why](const std::string& text) {
    if (why) *why = text;
    return false;
  };
  if (references.empty()) return fail("FitControllerOptions::references is empty (expected at least one lat-long EXR)");
  if (!fit.mask_paths.empty() && fit.mask_paths.size() != references.size())
    return fail("FitOptions::mask_paths holds " + std::to_string(fit.mask_paths.size()) + " masks for " +
                std::to_string(references.size()) + " references (expected one per reference, in order)");
  if (out_dir.empty()) return fail("FitControllerOptions::out_dir is empty (expected a directory)");
  std::string w;
  if (!fit.IsValid(&w) || !clouds.IsValid(&w) || (cloud_stats.enabled && !cloud_stats.IsValid(&w))) return fail(w);
  if (cloud_stats.enabled && !cloud_mask) {
    return fail("FitCloudStatsOptions::enabled = true fits the atmosphere to the clear pixels: it needs "
                "FitControllerOptions::cloud_mask = true");
  }
  return true;
}

nlohmann::json ResolvedFitOptionsJson(const fit::FitOptions& fo) {
  nlohmann::json j = {{"model", render::ToString(fo.variant)}, {"backend", render::ToString(fo.backend)},
          {"absolute", fo.absolute},               {"sun_cone_deg", fo.sun_cone_deg},
          {"clip_fraction", fo.clip_fraction},     {"mask", fo.mask_path},
          {"loss", LossName(fo.loss)},             {"loss_scale", fo.loss_scale},
          {"pyramid_widths", fo.pyramid_widths},   {"max_iterations_per_level", fo.max_iterations_per_level},
          {"smoothness", fo.smoothness},
          {"linear_start", fo.linear_start},       {"linear_width", fo.linear_width},
          {"polish", fo.polish},
          {"prior_weight", fo.prior_weight},       {"unseen_profile", fo.unseen_profile},
          {"fit_haziness", fo.fit_haziness},
          {"probe_weight", fo.probe_weight},       {"probe_quadrature_width", fo.probe_quadrature_width},
          {"fit_ground_albedo", fo.fit_ground_albedo},
          {"numeric_derivatives", fo.numeric_derivatives}};
  if (!fo.mask_paths.empty()) j["masks"] = fo.mask_paths;
  return j;
}

// Every file the fit reads, named by the field that gave it (StagedDirectory refuses an
// out_dir that is one of them or holds one).
std::vector<NamedPath> FitControllerInputs(const FitControllerOptions& o) {
  std::vector<NamedPath> read = PresetFileInputs("FitControllerOptions::init_preset", InitPresetPath(o));
  for (const std::string& r : o.references) read.push_back({"FitControllerOptions::references", r});
  if (!o.fit.mask_path.empty()) read.push_back({"FitOptions::mask_path", o.fit.mask_path});
  for (const std::string& m : o.fit.mask_paths) read.push_back({"FitOptions::mask_paths", m});
  for (const std::string& spec : o.probes) read.push_back({"FitControllerOptions::probes", spec.substr(spec.find('=') + 1)});
  for (const std::string& r : o.references) {  // the probe samples found beside a reference
    fs::path p(r);
    p.replace_extension(".probe.json");
    read.push_back({"FitControllerOptions::references " + r + "'s probe samples", p.string()});
  }
  for (const NamedPath& p : FitCloudInputs(o.clouds)) read.push_back(p);
  return read;
}

namespace {
// The references, each checked and (with cloud_mask) its cloudy pixels left out.
struct LoadedReferences {
  std::vector<fit::Reference> refs;
  std::vector<fit::FitCloudMaskEntry> cloud_mask;
  std::vector<std::vector<float>> cloud_probability;  // per reference, for the cloud statistics
};

LoadedReferences LoadFitReferences(const FitControllerOptions& o, bool cloud_shapes) {
  LoadedReferences l;
  std::set<std::string> names;
  for (size_t i = 0; i < o.references.size(); ++i) {
    const std::string& path = o.references[i];
    fit::FitOptions fo = o.fit;  // the reference's own mask, as mask_path
    if (!o.fit.mask_paths.empty()) fo.mask_path = o.fit.mask_paths.at(i);
    fo.mask_paths.clear();
    l.refs.push_back(fit::LoadReference(path, fo));
    const fit::MaskCounts& n = l.refs.back().counts;  // the user's mask and the sun cone are choices, not damage
    RequireValidShare(path, n.sky, n.sky + n.invalid + n.clipped, "fittable sky pixels of those above the horizon "
                      "outside FitOptions::mask_path and the sun cone");
    if (!names.insert(l.refs.back().name).second) {
      throw Error(path + ": two references share the name '" + l.refs.back().name + "' (fit/<name>.exr would collide)");
    }
    if (l.refs.back().row_mapping && (o.cloud_mask || cloud_shapes)) {
      throw Error(path + ": has horizon-biased rows (skycal resample): " +
                  std::string(o.cloud_mask ? "FitControllerOptions::cloud_mask = true"
                                           : "FitCloudOptions::preset (the cloud lighting fit)") +
                  " needs uniform 2:1 rows; fit the frame before resampling");
    }
    if (o.cloud_mask) {
      const CloudMaskApplied cm = ApplyCloudMask(&l.refs.back(), DefaultClearPresetPath());
      l.cloud_mask.push_back(cm.Entry());
      l.cloud_probability.push_back(cm.probability);
      FitLog(path + ": --cloud-mask: " + std::to_string(cm.cloudy_pixels) + " cloudy sky pixels left out (" +
             std::to_string(100.0 * cm.fraction) + "%, " + cm.source + ")");
    }
    const auto& r = l.refs.back();
    FitLog(r.path + ": " + std::to_string(r.radiance.width) + "x" + std::to_string(r.radiance.height) + ", sun from " +
           r.sun_source + " (elevation " + std::to_string(latlong::ElevationDeg(r.sun_dir)) + " deg), " +
           std::to_string(r.counts.sky) + " sky pixels fitted");
    for (const auto& w : r.warnings) FitLog("warning: " + w);
  }
  return l;
}

fit::FitProbeSunEntry ProbeSunEntry(const fit::ProbeSun& s, const std::string& probe_path, bool absolute) {
  fit::FitProbeSunEntry e;
  e.observable = s.observable;
  e.visible = s.visible;
  e.illuminance_rgb = s.illuminance_ref;
  e.illuminance_rgb_model = s.illuminance_model;
  e.fitted_illuminance_rgb_model = s.fitted_model;
  e.fraction = s.fraction;
  e.residual = s.residual;
  e.log_rmse = s.log_rmse;
  e.samples = s.samples;
  e.sun_facing_samples = s.sun_facing_samples;
  e.ground_facing_samples = s.ground_facing_samples;
  e.probe = probe_path;
  e.note = s.note;
  if (absolute) e.illuminance_lux = s.lux;
  return e;
}

// The sun each reference's probe saw (fit.json's references[i].sun), logged; a probe that
// cannot observe the sun warns, or fails with require_probe.
struct ProbeSuns {
  std::vector<std::optional<fit::ProbeSun>> suns;
  std::vector<std::optional<fit::FitProbeSunEntry>> entries;
};

ProbeSuns CollectProbeSuns(const std::vector<fit::Reference>& refs, const fit::FitResult& result,
                           const std::vector<std::optional<fit::ProbeSamples>>& probes, bool require_probe,
                           bool absolute, std::vector<std::string>* warnings) {
  ProbeSuns ps{std::vector<std::optional<fit::ProbeSun>>(refs.size()),
               std::vector<std::optional<fit::FitProbeSunEntry>>(refs.size())};
  for (size_t r = 0; r < refs.size(); ++r) {
    if (!probes[r]) continue;
    const fit::ProbeSun& s = *result.references[r].sun;
    ps.suns[r] = s;
    ps.entries[r] = ProbeSunEntry(s, probes[r]->path, absolute);
    FitLog(refs[r].name + ": probe sun " + (!s.observable ? "not observable (" + s.note + ")"
                                            : s.visible   ? std::string("visible")
                                                          : std::string("occluded")) +
           ", fraction " + std::to_string(s.fraction) + ", E_sun (model) " + std::to_string(s.illuminance_model[0]) +
           ", " + std::to_string(s.illuminance_model[1]) + ", " + std::to_string(s.illuminance_model[2]) +
           ", probe log RMSE " + std::to_string(s.log_rmse));
    if (!s.observable) {
      if (require_probe) {
        throw Error(refs[r].name + ": FitControllerOptions::require_probe: the probe cannot observe the sun: " + s.note);
      }
      warnings->push_back(refs[r].name + ": sun from the probe: " + s.note);
    }
  }
  return ps;
}

// One reference seeing the sun on its probe sets the preset's sun_tint_rgb; several leave it
// as fitted and record each one's tint.
void ApplyProbeSunTint(const std::vector<fit::Reference>& refs, ProbeSuns* ps, render::Preset* preset,
                       std::vector<std::string>* warnings) {
  std::vector<size_t> visible;
  for (size_t r = 0; r < refs.size(); ++r) {
    if (ps->suns[r] && ps->suns[r]->visible) visible.push_back(r);
  }
  if (visible.size() == 1) {
    const size_t r = visible[0];
    bool clamped = false;
    preset->sun_tint_rgb = fit::SunTintFor(*preset, refs[r].sun_dir, ps->suns[r]->illuminance_model, &clamped);
    ps->entries[r]->sun_tint_rgb = preset->sun_tint_rgb;
    if (clamped) {
      const std::string w = refs[r].name + ": the probe's sun needs a sun_tint_rgb outside its bounds: clamped";
      warnings->push_back(w);
      FitLog("warning: " + w);
    }
  } else if (visible.size() > 1) {
    for (size_t r : visible) {
      ps->entries[r]->sun_tint_rgb = fit::SunTintFor(*preset, refs[r].sun_dir, ps->suns[r]->illuminance_model, nullptr);
    }
    const std::string w = std::to_string(visible.size()) +
                          " references see the sun on the probe: the preset's sun_tint_rgb is left as fitted "
                          "(per-reference tints in fit.json)";
    warnings->push_back(w);
    FitLog("warning: " + w);
  }
}

std::string RecordedPath(const FitControllerOptions& o, const std::string& path) {
  return o.record_path && !path.empty() ? o.record_path(path) : path;
}

// The options' mask paths as the records name them.
void RecordPathsOfOptions(const FitControllerOptions& o, nlohmann::json* options) {
  if (options->contains("mask") && (*options)["mask"].is_string())
    (*options)["mask"] = RecordedPath(o, (*options)["mask"].get<std::string>());
  if (options->contains("masks"))
    for (auto& m : (*options)["masks"]) m = RecordedPath(o, m.get<std::string>());
}

// fit/<name>.exr per reference, and its entries of fit.json (references, warnings) and of
// preset.json's provenance (inputs).
void WriteReferenceFits(const FitControllerOptions& o, const StagedDirectory& out, const std::vector<fit::Reference>& refs,
                        const fit::FitResult& result, const ProbeSuns& ps, fit::FitResultFile* file,
                        nlohmann::json* inputs) {
  for (size_t r = 0; r < refs.size(); ++r) {
    const auto& ref = refs[r];
    const auto& rf = result.references[r];
    capture::LatLongFrame frame;
    frame.radiance = rf.rendered;
    frame.sun_direction = ref.sun_dir;
    frame.row_mapping = ref.row_mapping;  // the fit image has the reference's rows
    const std::string path = RecordedPath(o, ref.path);
    frame.extra.strings["skycalReference"] = path;
    frame.extra.floats["skycalExposure"] = static_cast<float>(rf.exposure);
    capture::WriteLatLongFrame(out / ("fit/" + ref.name + ".exr"), frame);
    fit::FitReferenceEntry e;
    e.name = ref.name;
    e.path = path;
    e.rel_rmse = rf.errors.rel_rmse;
    e.log_rmse = rf.errors.log_rmse;
    e.exposure = rf.exposure;
    e.sun_direction = ref.sun_dir;
    e.sun_elevation_deg = latlong::ElevationDeg(ref.sun_dir);
    e.sun_source = ref.sun_source;
    e.observed_lut_rows = rf.observed_rows;
    e.clip_level = ref.clip_level;
    e.pixels = ref.counts;
    e.sun = ps.entries[r];
    file->references.push_back(std::move(e));
    inputs->push_back({{"path", path}, {"sha256", ref.sha256}});
    for (const auto& w : ref.warnings) file->warnings.push_back(w);
  }
}

// The cloud statistics stage: the cloud lighting by statistics of the cloud pixels, into fit.json's
// cloud_stats and the preset's clouds section.
void RunCloudStatsStage(const FitCloudStatsOptions& cs, bool panels, const LoadedReferences& l,
                        const nlohmann::json& sky_refit, const StagedDirectory& out, fit::FitResult* result,
                        fit::FitResultFile* file) {
  std::vector<cloudfit::CloudStatsPhoto> photos;
  for (size_t r = 0; r < l.refs.size(); ++r) {
    const nlohmann::json& rr = sky_refit.contains("references") ? sky_refit["references"][r] : nlohmann::json();
    photos.push_back({&l.refs[r], l.cloud_probability[r], rr.contains("cloud_pixels_by_sun_angle")});
  }
  file->clouds["mode"] = "stats";
  file->clouds["decision"] = "--clouds stats: the atmosphere on the clear pixels, the cloud lighting by "
                             "statistics of the cloud pixels (fit.json's cloud_stats)";
  cloudfit::CloudStatsPresetUpdate update;
  file->cloud_stats = RunCloudStatsOnPhotos(cs, photos, *result, panels ? out.staging() / "fit" : fs::path(), &update);
  file->cloud_stats["preset"] = AttachCloudStats(update, out / "preset.json", &result->preset);
  file->cloud_stats["sky_refit"] = sky_refit;
}

// The previews are optional (FitControllerOptions::previews): an OCIO config that cannot be
// read ($OCIO naming a missing file) leaves them out, never the fit. Then what the report
// reads beside the errors: the images, the fitted sun at the ground (model units: lux with
// FitOptions::absolute), the cloud mask.
void WritePreviewsAndReportFields(const StagedDirectory& out, const FitControllerOptions& o, const LoadedReferences& l,
                                  const fit::FitResult& result, fit::FitResultFile* file) {
  const std::vector<fit::Reference>& refs = l.refs;
  bool previews = o.previews;
  try {
    if (previews) {
      WriteFitReport(out / "report.png", refs, result);
      WriteFitPanels(out / "fit", refs, result);
    }
  } catch (const Error& e) {
    previews = false;
    FitLog(std::string("previews skipped (report.png, fit/*.png): ") + e.what() + "; the fit is complete");
  }
  for (size_t r = 0; r < refs.size(); ++r) {
    fit::FitReferenceEntry& e = file->references[r];
    if (previews) {
      e.images = fit::FitReferenceImages{"fit/" + refs[r].name + ".reference.png", "fit/" + refs[r].name + ".fit.png",
                                         "fit/" + refs[r].name + ".error.png"};
    }
    const render::Rgb sun = render::SunIlluminanceAtGround(result.preset, refs[r].sun_dir);
    e.sun_illuminance_at_ground_lux = skycal::Rec709Luminance(sun);
    if (o.cloud_mask) e.cloud_mask = l.cloud_mask[r];
  }
}

// The sky (+ known-shapes clouds) fit; with the cloud statistics, the cloud mask refined
// against the sky fit's own render and the atmosphere refitted if it moved.
struct SolvedFit {
  fit::FitOptions fo;  // FitControllerOptions::fit with the reference's time of day
  cloudfit::SkyCloudFit joint;
  nlohmann::json sky_refit;  // fit.json's cloud_stats.sky_refit
};

SolvedFit SolveSkyAndClouds(const FitControllerOptions& o, const render::Preset& init, LoadedReferences* l,
                            const std::vector<const fit::ProbeSamples*>& probes, const LoadedCloudShapes* shapes) {
  SolvedFit s;
  std::vector<fit::Reference>& refs = l->refs;
  s.fo = o.fit;
  if (!s.fo.time_of_day_h && refs.size() == 1 && refs[0].time_of_day_h) s.fo.time_of_day_h = refs[0].time_of_day_h;
  auto renderer = render::CreateRenderer(s.fo.backend);
  FitLog("objective backend: " + renderer->Describe());
  s.joint = RunSkyCloudFit(o.clouds, refs, init, s.fo, *renderer, probes, shapes);
  if (o.cloud_stats.enabled) {
    s.sky_refit = RefineCloudMaskAndRefitSky(o.cloud_stats, !o.fit.mask_path.empty(), &refs, &l->cloud_probability,
                                             s.joint.sky, [&] {
                                               const render::Preset first = s.joint.sky.preset;
                                               s.joint = RunSkyCloudFit(o.clouds, refs, first, s.fo, *renderer, probes, shapes);
                                             });
  }
  s.joint.sky.preset.name = fs::path(o.out_dir).filename().string();
  if (s.fo.time_of_day_h) s.joint.sky.preset.time_of_day_h = *s.fo.time_of_day_h;
  return s;
}

// preset.json with its provenance: the tool, the starting preset, the references, the
// options and each reference's errors before the previews.
void SavePresetWithProvenance(const StagedDirectory& out, const render::Preset& preset, const std::string& init_path,
                              const std::string& init_record, const nlohmann::json& inputs,
                              const fit::FitResultFile& file) {
  nlohmann::json final_errors = nlohmann::json::array();
  for (const fit::FitReferenceEntry& e : file.references) final_errors.push_back(fit::FitReferenceEntryJson(e));
  const nlohmann::json provenance = {{"provenance",
                                      {{"tool", std::string("skycal ") + kSkycalVersion},
                                       {"init_preset", {{"path", init_record}, {"sha256", Sha256OfFile(init_path)}}},
                                       {"inputs", inputs},
                                       {"options", file.options},
                                       {"final_errors", final_errors}}}};
  render::SavePreset(preset, out / "preset.json", &provenance);
}

// report.html (skycal_report) over everything staged so far.
void WriteReportHtml(const StagedDirectory& out) {
  report::ReportOptions ro;
  ro.max_depth = 0;  // the fit's own output, not a caller's subdirectories
  report::ReportSummary s;
  try {
    s = report::WriteReport(out.staging().string(), ro);
  } catch (const Error& e) {
    throw Error(std::string("report.html: ") + e.what() + " (FitControllerOptions::report = false leaves the report out)");
  }
  FitLog("report.html: " + std::to_string(s.images) + " images, " + std::to_string(s.plots) + " plots, " +
         std::to_string(s.bytes / 1024) + " KiB");
  if (s.plots_skipped > 0) {
    FitLog("plots skipped: " + std::to_string(s.plots_skipped) + " chart(s) left out of the report, " +
           s.plots_skipped_why + "; the results are complete");
  }
}

// Everything the fit writes, in order: the probe's sun, fit/<ref>.exr, the cloud stages'
// files, preset.json, the previews, fit.json, report.html. Returns fit.json's record.
fit::FitResultFile WriteFitOutputs(const FitControllerOptions& o, const StagedDirectory& out, const std::string& init_path,
                                   const LoadedReferences& l, const std::vector<std::optional<fit::ProbeSamples>>& probes,
                                   const LoadedCloudShapes* shapes, SolvedFit* s) {
  fit::FitResult& result = s->joint.sky;
  fit::FitResultFile file = fit::FitResultFileFrom(result);  // the fit's own part; the rest below
  nlohmann::json inputs = nlohmann::json::array();
  ProbeSuns ps = CollectProbeSuns(l.refs, result, probes, o.require_probe, s->fo.absolute, &file.warnings);
  ApplyProbeSunTint(l.refs, &ps, &result.preset, &file.warnings);
  WriteReferenceFits(o, out, l.refs, result, ps, &file, &inputs);
  for (const auto& w : result.warnings) file.warnings.push_back(w);
  file.options = ResolvedFitOptionsJson(s->fo);
  RecordPathsOfOptions(o, &file.options);
  file.clouds = CloudReportJson(o.clouds, s->joint);
  if (file.clouds.is_object() && file.clouds.contains("cloud_preset") && file.clouds["cloud_preset"].is_string())
    file.clouds["cloud_preset"] = RecordedPath(o, file.clouds["cloud_preset"].get<std::string>());
  if (o.cloud_stats.enabled) RunCloudStatsStage(o.cloud_stats, o.previews, l, s->sky_refit, out, &result, &file);
  if (shapes) AttachFittedClouds(s->joint, *shapes, out / "preset.json", &result.preset);
  SavePresetWithProvenance(out, result.preset, init_path, RecordedPath(o, init_path), inputs, file);
  WritePreviewsAndReportFields(out, o, l, result, &file);
  file.time_of_day_h = s->fo.time_of_day_h;
  file.out = o.out_dir;
  fit::WriteFitResultFile(out / "fit.json", file);
  if (o.report) WriteReportHtml(out);
  return file;
}

}  // namespace

// The fit's stages: inputs read and checked, the sky (+ clouds) fit, the probe's sun, the
// fit images, the cloud statistics, preset.json, previews, fit.json.
nlohmann::json RunFitInto(const FitControllerOptions& o, const StagedDirectory& out) {
  const ScopedFitLog log(o.log);
  CheckOptions(o);
  const std::string init_path = InitPresetPath(o);
  fs::create_directories(out.staging() / "fit");
  const render::Preset init = render::LoadPreset(init_path);
  const std::unique_ptr<LoadedCloudShapes> cloud_shapes = LoadFitCloudShapes(o.clouds);  // a bad section fails early
  LoadedReferences l = LoadFitReferences(o, cloud_shapes != nullptr);
  const auto probes = ProbesFor(o, l.refs);  // before the fit: a missing or bad file fails early
  std::vector<const fit::ProbeSamples*> probe_ptrs;
  for (const auto& p : probes) probe_ptrs.push_back(p ? &*p : nullptr);
  SolvedFit s = SolveSkyAndClouds(o, init, &l, probe_ptrs, cloud_shapes.get());
  const fit::FitResultFile file = WriteFitOutputs(o, out, init_path, l, probes, cloud_shapes.get(), &s);
  for (const fit::FitReferenceEntry& e : file.references) {
    FitLog(e.name + ": rel RMSE " + std::to_string(100.0 * e.rel_rmse) + "%, log RMSE " + std::to_string(e.log_rmse));
  }
  return fit::FitResultFileJson(file);
}

nlohmann::json RunFitController(const FitControllerOptions& o) {
  const ScopedFitLog log(o.log);
  CheckOptions(o);
  StagedDirectory out(o.out_dir, "FitControllerOptions::out_dir", "fit", FitControllerInputs(o));  // fails early
  const nlohmann::json j = RunFitInto(o, out);
  out.Commit();
  FitLog("wrote " + o.out_dir + " in " + std::to_string(j["time_s"].get<double>()) + " s (" +
         std::to_string(j["iterations"].get<long long>()) + " iterations)");
  return j;
}

}  // namespace skycal::controllers
