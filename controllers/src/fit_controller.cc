#include "fit_verb.h"

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <iostream>
#include <sstream>

#include "command_line.h"
#include "fit_option_args.h"
#include "option_values.h"
#include "fit_cloud_mask.h"
#include "finite_output.h"
#include "fit_report.h"
#include "report_verb.h"
#include "skycal/core/staged_directory.h"
#include "render_verb.h"
#include "skycal/capture/latlong_frame.h"
#include "skycal/core/error.h"
#include "skycal/core/json_file.h"
#include "skycal/core/latlong.h"
#include "skycal/core/luminance.h"
#include "skycal/core/sha256.h"
#include "skycal/core/version.h"
#include "skycal/fit/fit_result_file.h"
#include "skycal/fit/reference.h"
#include "skycal/fit/sky_fit.h"
#include "skycal/render/irradiance.h"
#include "verb_common.h"

namespace skycal::cli {
namespace fs = std::filesystem;
namespace {

// Probe samples per reference name: --probe STEM=FILE, else <reference stem>.probe.json beside it.
std::vector<std::optional<fit::ProbeSamples>> ProbesFor(const FitProbeOptions& o, const std::vector<fit::Reference>& refs) {
  std::map<std::string, std::string> given;
  for (const std::string& spec : o.probes) {
    const auto eq = spec.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == spec.size()) {
      throw Error("--probe " + spec + ": expected REF_STEM=SAMPLES.json");
    }
    if (!given.emplace(spec.substr(0, eq), spec.substr(eq + 1)).second) {
      throw Error("--probe: two sample files for '" + spec.substr(0, eq) + "'");
    }
  }
  for (const auto& [stem, file] : given) {
    bool found = false;
    for (const auto& r : refs) found = found || r.name == stem;
    if (!found) throw Error("--probe " + stem + "=" + file + ": no reference named '" + stem + "'");
  }
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
      if (o.require_probe) throw Error("--require-probe: no probe samples for reference " + r.path);
      out.emplace_back();
    } else {
      out.emplace_back(fit::LoadProbeSamples(file));
    }
  }
  return out;
}

}  // namespace

bool FitVerbOptions::IsValid(std::string* why) const {
  if (references.empty()) {
    *why = "at least one --reference is required";
    return false;
  }
  if (out_dir.empty()) {
    *why = "--out DIR is required";
    return false;
  }
  if (fit.IsValid(why)) return true;
  *why = WithFitFlags(*why);  // the library names FitOptions' fields; the user gave flags
  return false;
}

namespace {
nlohmann::json RunFitWithProbes(const FitVerbOptions& o, const FitProbeOptions& po, const FitCloudOptions& co,
                                const FitCloudStatsOptions& cs = {});
}  // namespace

nlohmann::json RunFitImpl(const FitVerbOptions& o) { return RunFitWithProbes(o, FitProbeOptions{}, FitCloudOptions{}); }

namespace {
// Every file the fit reads, named by the option that gave it (StagedDirectory refuses an
// --out that is one of them).
std::vector<NamedPath> FitInputs(const FitVerbOptions& o, const FitProbeOptions& po, const FitCloudOptions& co,
                                 const std::string& init_path) {
  std::vector<NamedPath> read = PresetInputs("--init", init_path);
  for (const std::string& r : o.references) read.push_back({"--reference", r});
  if (!o.fit.mask_path.empty()) read.push_back({"--mask", o.fit.mask_path});
  for (const std::string& spec : po.probes) read.push_back({"--probe", spec.substr(spec.find('=') + 1)});
  for (const std::string& r : o.references) {  // the probe samples found beside a reference
    fs::path p(r);
    p.replace_extension(".probe.json");
    read.push_back({"--reference " + r + "'s probe samples", p.string()});
  }
  for (const NamedPath& p : FitCloudInputs(co)) read.push_back(p);
  return read;
}

// The references, each checked and (with --cloud-mask) its cloudy pixels left out.
struct LoadedReferences {
  std::vector<fit::Reference> refs;
  std::vector<fit::FitCloudMaskEntry> cloud_mask;
  std::vector<std::vector<float>> cloud_probability;  // per reference, for --clouds stats
};

LoadedReferences LoadFitReferences(const FitVerbOptions& o, bool cloud_shapes) {
  LoadedReferences l;
  std::set<std::string> names;
  for (const std::string& path : o.references) {
    l.refs.push_back(fit::LoadReference(path, o.fit));
    const fit::MaskCounts& n = l.refs.back().counts;  // the user's mask and the sun cone are choices, not damage
    RequireValidShare(path, n.sky, n.sky + n.invalid + n.clipped, "fittable sky pixels of those above the horizon "
                      "outside --mask and the sun cone");
    if (!names.insert(l.refs.back().name).second) {
      throw Error(path + ": two references share the name '" + l.refs.back().name + "' (fit/<name>.exr would collide)");
    }
    if (l.refs.back().row_mapping && (o.cloud_mask || cloud_shapes)) {
      throw Error(path + ": has horizon-biased rows (skycal resample): " +
                  std::string(o.cloud_mask ? "--cloud-mask" : "--cloud-preset (the cloud lighting fit)") +
                  " needs uniform 2:1 rows; fit the frame before resampling");
    }
    if (o.cloud_mask) {
      const CloudMaskApplied cm = ApplyCloudMask(&l.refs.back(), DefaultPresetPath());
      l.cloud_mask.push_back(cm.Entry());
      l.cloud_probability.push_back(cm.probability);
      Log("fit", path + ": --cloud-mask: " + std::to_string(cm.cloudy_pixels) + " cloudy sky pixels left out (" +
                     std::to_string(100.0 * cm.fraction) + "%, " + cm.source + ")");
    }
    const auto& r = l.refs.back();
    Log("fit", r.path + ": " + std::to_string(r.radiance.width) + "x" + std::to_string(r.radiance.height) + ", sun from " +
                   r.sun_source + " (elevation " + std::to_string(latlong::ElevationDeg(r.sun_dir)) + " deg), " +
                   std::to_string(r.counts.sky) + " sky pixels fitted");
    for (const auto& w : r.warnings) Log("fit", "warning: " + w);
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
// cannot observe the sun warns, or fails with --require-probe.
struct ProbeSuns {
  std::vector<std::optional<fit::ProbeSun>> suns;
  std::vector<std::optional<fit::FitProbeSunEntry>> entries;
};

ProbeSuns CollectProbeSuns(const std::vector<fit::Reference>& refs, const fit::FitResult& result,
                           const std::vector<std::optional<fit::ProbeSamples>>& probes, const FitProbeOptions& po,
                           bool absolute, std::vector<std::string>* warnings) {
  ProbeSuns ps{std::vector<std::optional<fit::ProbeSun>>(refs.size()),
               std::vector<std::optional<fit::FitProbeSunEntry>>(refs.size())};
  for (size_t r = 0; r < refs.size(); ++r) {
    if (!probes[r]) continue;
    const fit::ProbeSun& s = *result.references[r].sun;
    ps.suns[r] = s;
    ps.entries[r] = ProbeSunEntry(s, probes[r]->path, absolute);
    Log("fit", refs[r].name + ": probe sun " + (!s.observable ? "not observable (" + s.note + ")"
                                                              : s.visible ? std::string("visible") : std::string("occluded")) +
                   ", fraction " + std::to_string(s.fraction) + ", E_sun (model) " +
                   std::to_string(s.illuminance_model[0]) + ", " + std::to_string(s.illuminance_model[1]) + ", " +
                   std::to_string(s.illuminance_model[2]) + ", probe log RMSE " + std::to_string(s.log_rmse));
    if (!s.observable) {
      if (po.require_probe) throw Error(refs[r].name + ": --require-probe: the probe cannot observe the sun: " + s.note);
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
      Log("fit", "warning: " + w);
    }
  } else if (visible.size() > 1) {
    for (size_t r : visible) {
      ps->entries[r]->sun_tint_rgb = fit::SunTintFor(*preset, refs[r].sun_dir, ps->suns[r]->illuminance_model, nullptr);
    }
    const std::string w = std::to_string(visible.size()) +
                          " references see the sun on the probe: the preset's sun_tint_rgb is left as fitted "
                          "(per-reference tints in fit.json)";
    warnings->push_back(w);
    Log("fit", "warning: " + w);
  }
}

// fit/<name>.exr per reference, and its entries of fit.json (references, warnings) and of
// preset.json's provenance (inputs).
void WriteReferenceFits(const StagedDirectory& out, const std::vector<fit::Reference>& refs,
                        const fit::FitResult& result, const ProbeSuns& ps, fit::FitResultFile* file,
                        nlohmann::json* inputs) {
  for (size_t r = 0; r < refs.size(); ++r) {
    const auto& ref = refs[r];
    const auto& rf = result.references[r];
    capture::LatLongFrame frame;
    frame.radiance = rf.rendered;
    frame.sun_direction = ref.sun_dir;
    frame.row_mapping = ref.row_mapping;  // the fit image has the reference's rows
    frame.extra.strings["skycalReference"] = ref.path;
    frame.extra.floats["skycalExposure"] = static_cast<float>(rf.exposure);
    capture::WriteLatLongFrame(out / ("fit/" + ref.name + ".exr"), frame);
    fit::FitReferenceEntry e;
    e.name = ref.name;
    e.path = ref.path;
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
    inputs->push_back({{"path", ref.path}, {"sha256", ref.sha256}});
    for (const auto& w : ref.warnings) file->warnings.push_back(w);
  }
}

// --clouds stats: the cloud lighting by statistics of the cloud pixels, into fit.json's
// cloud_stats and the preset's clouds section.
void RunCloudStatsStage(const FitCloudStatsOptions& cs, const LoadedReferences& l, const nlohmann::json& sky_refit,
                        const StagedDirectory& out, fit::FitResult* result, fit::FitResultFile* file) {
  std::vector<cloudfit::CloudStatsPhoto> photos;
  for (size_t r = 0; r < l.refs.size(); ++r) {
    const nlohmann::json& rr = sky_refit.contains("references") ? sky_refit["references"][r] : nlohmann::json();
    photos.push_back({&l.refs[r], l.cloud_probability[r], rr.contains("cloud_pixels_by_sun_angle")});
  }
  file->clouds["mode"] = "stats";
  file->clouds["decision"] = "--clouds stats: the atmosphere on the clear pixels, the cloud lighting by "
                             "statistics of the cloud pixels (fit.json's cloud_stats)";
  cloudfit::CloudStatsPresetUpdate update;
  file->cloud_stats = RunCloudStatsOnPhotos(cs, photos, *result, out.staging() / "fit", &update);
  file->cloud_stats["preset"] = AttachCloudStats(update, out / "preset.json", &result->preset);
  file->cloud_stats["sky_refit"] = sky_refit;
}

// The previews are optional: an OCIO config that cannot be read ($OCIO naming a missing
// file) leaves them out, never the fit. Then what the report reads beside the errors: the
// images, the fitted sun at the ground (model units: lux with --absolute), the cloud mask.
void WritePreviewsAndReportFields(const StagedDirectory& out, const FitVerbOptions& o, const LoadedReferences& l,
                                  const fit::FitResult& result, fit::FitResultFile* file) {
  const std::vector<fit::Reference>& refs = l.refs;
  bool previews = true;
  try {
    WriteFitReport(out / "report.png", refs, result);
    WriteFitPanels(out / "fit", refs, result);
  } catch (const Error& e) {
    previews = false;
    Log("fit", std::string("previews skipped (report.png, fit/*.png): ") + e.what() + "; the fit is complete");
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

void CheckFitOptions(const FitVerbOptions& o, const FitCloudOptions& co, const FitCloudStatsOptions& cs) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  if (!co.IsValid(&why)) throw Error(why);
  if (cs.enabled && !cs.IsValid(&why)) throw Error(why);
  if (cs.enabled && !o.cloud_mask) throw Error("--clouds stats fits the atmosphere to the clear pixels: it needs --cloud-mask");
}

// The fit's stages: inputs read and checked, the sky (+ clouds) fit, the probe's sun, the
// fit images, the cloud statistics, preset.json, previews, fit.json, then the commit.
nlohmann::json RunFitWithProbes(const FitVerbOptions& o, const FitProbeOptions& po, const FitCloudOptions& co,
                                const FitCloudStatsOptions& cs) {
  CheckFitOptions(o, co, cs);
  const std::string init_path = o.init_preset.empty() ? DefaultPresetPath() : o.init_preset;
  StagedDirectory out(o.out_dir, "--out", "fit", FitInputs(o, po, co, init_path));  // fails early on an unusable --out
  std::filesystem::create_directories(out.staging() / "fit");
  render::Preset init = render::LoadPreset(init_path);
  const std::unique_ptr<LoadedCloudShapes> cloud_shapes = LoadFitCloudShapes(co);  // a bad section fails early
  LoadedReferences l = LoadFitReferences(o, cloud_shapes != nullptr);
  std::vector<fit::Reference>& refs = l.refs;
  const auto probes = ProbesFor(po, refs);  // before the fit: a missing or bad file fails early
  std::vector<const fit::ProbeSamples*> probe_ptrs;
  for (const auto& p : probes) probe_ptrs.push_back(p ? &*p : nullptr);
  fit::FitOptions fo = o.fit;
  if (!fo.time_of_day_h && refs.size() == 1 && refs[0].time_of_day_h) fo.time_of_day_h = refs[0].time_of_day_h;
  auto renderer = render::CreateRenderer(fo.backend);
  Log("fit", "objective backend: " + renderer->Describe());
  cloudfit::SkyCloudFit joint = RunSkyCloudFit(co, refs, init, fo, *renderer, probe_ptrs, cloud_shapes.get());
  nlohmann::json sky_refit;
  if (cs.enabled)  // the cloud mask against the sky fit's own render; the atmosphere refitted if it moved
    sky_refit = RefineCloudMaskAndRefitSky(cs, !o.fit.mask_path.empty(), &refs, &l.cloud_probability, joint.sky, [&] {
      const render::Preset first = joint.sky.preset;
      joint = RunSkyCloudFit(co, refs, first, fo, *renderer, probe_ptrs, cloud_shapes.get());
    });
  fit::FitResult& result = joint.sky;
  result.preset.name = fs::path(o.out_dir).filename().string();
  if (fo.time_of_day_h) result.preset.time_of_day_h = *fo.time_of_day_h;

  fit::FitResultFile file = fit::FitResultFileFrom(result);  // the fit's own part; the rest below
  nlohmann::json inputs = nlohmann::json::array();
  ProbeSuns ps = CollectProbeSuns(refs, result, probes, po, fo.absolute, &file.warnings);
  ApplyProbeSunTint(refs, &ps, &result.preset, &file.warnings);
  WriteReferenceFits(out, refs, result, ps, &file, &inputs);
  for (const auto& w : result.warnings) file.warnings.push_back(w);
  file.options = ResolvedFitOptionsJson(fo);
  file.clouds = CloudReportJson(co, joint);
  if (cs.enabled) RunCloudStatsStage(cs, l, sky_refit, out, &result, &file);
  if (cloud_shapes) AttachFittedClouds(joint, *cloud_shapes, out / "preset.json", &result.preset);
  nlohmann::json final_errors = nlohmann::json::array();  // the references' entries before the previews
  for (const fit::FitReferenceEntry& e : file.references) final_errors.push_back(fit::FitReferenceEntryJson(e));
  const nlohmann::json provenance = {{"provenance",
                                      {{"tool", std::string("skycal ") + kSkycalVersion},
                                       {"init_preset", {{"path", init_path}, {"sha256", Sha256OfFile(init_path)}}},
                                       {"inputs", inputs},
                                       {"options", file.options},
                                       {"final_errors", final_errors}}}};
  render::SavePreset(result.preset, out / "preset.json", &provenance);
  WritePreviewsAndReportFields(out, o, l, result, &file);
  file.time_of_day_h = fo.time_of_day_h;
  file.out = o.out_dir;
  fit::WriteFitResultFile(out / "fit.json", file);
  if (o.report) WriteVerbReport("fit", out.staging().string());
  out.Commit();
  for (const fit::FitReferenceEntry& e : file.references) {
    Log("fit", e.name + ": rel RMSE " + std::to_string(100.0 * e.rel_rmse) + "%, log RMSE " + std::to_string(e.log_rmse));
  }
  Log("fit", "wrote " + o.out_dir + " in " + std::to_string(result.time_s) + " s (" +
                 std::to_string(result.iterations) + " iterations)");
  return fit::FitResultFileJson(file);
}
}  // namespace

namespace {

// The --clouds family of fit's options (docs/cloud-fitting.md).
void RegisterFitCloudArgs(VerbCommandLine& cl, FitCommandLine* c) {
  cl.Text("--clouds", &c->clouds.mode, "MODE",
          "auto (default), on, off or stats: fit the cloud lighting too (on: per reference; a day\n"
          "of references adds a smoothness prior over time of day, --cloud-day-smoothness).\n"
          "auto: on when the reference's cloud mask finds >= 1% cloud pixels and\n"
          "--cloud-preset gives the shapes; a clear reference never marches clouds.\n"
          "stats: unknown shapes (a photograph): implies --cloud-mask; the atmosphere\n"
          "fits the clear pixels, then the cloud lighting fits statistics of the cloud\n"
          "pixels (fit.json's cloud_stats, fit/<ref>.clouds.*.png)");
  cl.Text("--cloud-preset", &c->clouds.preset, "PRESET.json",
          "the known cloud shapes: a preset whose clouds section (shape fields, start\n"
          "lighting) and weather map rendered the reference (e.g. default_cloudy.json)");
  cl.Number("--cloud-time", &c->clouds.time_s, "S",
            "wind time of the references' clouds, seconds (default: each reference's\n"
            "skycalCloudTimeS attribute, written by render --clouds, else 0)");
  cl.Number("--cloud-day-smoothness", &c->clouds.day_smoothness, "L",
            "a day of >= 3 references: weight of the second-difference prior on each cloud\n"
            "lighting parameter over time of day (relative change per h^2; default 0.02, 0: off)");
  cl.Integer("--cloud-samples", &c->clouds.samples, -1e9, 1e9, "expected an integer", "N",
             "cloud pixels in the Jet Jacobian (default 256; all when fewer)");
  cl.Repeatable("--cloud-hold", &c->clouds.hold, "NAME", "hold a cloud lighting parameter at the preset's value (repeatable)");
  cl.Integer("--cloud-stats-width", &c->cloud_stats.width, 16, 1024, "expected pixels in [16, 1024]", "PX",
             "--clouds stats: width of the statistics' lat-long renders (default 128; the\n"
             "frame's width must be a multiple)");
  cl.Integer("--cloud-stats-maps", &c->cloud_stats.maps, 1, 16, "expected an integer in [1, 16]", "N",
             "--clouds stats: weather maps (shape draws) the model pools (default 4; 2 renders each)");
  cl.Integer("--cloud-stats-iterations", &c->cloud_stats.max_iterations, 0, 200, "expected an integer in [0, 200]", "N",
             "--clouds stats: Ceres iterations at most (default 12)");
  cl.Text("--cloud-stats-sun", &c->cloud_stats.sun, "photo|model",
          "--clouds stats: the sun lighting the model's clouds: the photo's disc (lux in model\n"
          "units, fit.json's sun_check; default photo) or the fitted preset's (model)");
  cl.Text("--cloud-stats-probability", &c->cloud_stats.probability, "fitted|initial",
          "--clouds stats: the cloud probability's clear-sky expectation: also the sky fit's own\n"
          "render (cloud where both say so; default fitted) or --cloud-mask's alone (initial)");
  cl.Text("--cloud-stats-sun-scale", &c->cloud_stats.sun_scale, "fit|off",
          "--clouds stats: fit: albedo held at water's physical 0.9999, a scale on the sun (>= 1 where\n"
          "the disc is saturated) fitted with the ambient (default); off: the sun as measured, albedo fitted");
}

// --clouds MODE as the controllers take it: stats means unknown shapes, the statistics stage
// and --cloud-mask, with no known-shapes term.
void ApplyFitCloudMode(FitCommandLine* c) {
  c->cloud_stats.renders = 2 * c->cloud_stats.maps;
  if (c->clouds.mode != "auto" && c->clouds.mode != "on" && c->clouds.mode != "off" && c->clouds.mode != "stats") {
    throw Error("--clouds: unknown mode '" + c->clouds.mode + "' (expected auto, on, off or stats)");
  }
  if (c->clouds.mode == "stats") {
    if (!c->clouds.preset.empty()) throw Error("--clouds stats: the shapes are unknown: --cloud-preset does not apply");
    c->cloud_stats.enabled = true;
    c->clouds.mode = "off";  // no known-shapes term
    c->options.cloud_mask = true;
  }
}

}  // namespace

FitCommandLine ParseFitArgs(int argc, char** argv) {
  VerbCommandLine cl("fit", "skycal fit: fit the sky model to HDR reference skies",
                     "  skycal fit --reference REF.exr [--reference REF2.exr ...] [--model ffxv|ffxv-iso]\n"
                     "             [--backend vulkan|cpu] [--sun-dir X,Y,Z | --sun-elevation DEG --sun-azimuth DEG]\n"
                     "             [--mask MASK.exr] [--init PRESET.json] --out DIR [--json]\n"
                     "             [--clouds auto|on|off|stats] [--cloud-preset P.json] [--cloud-time S]\n"
                     "             [--cloud-stats-width PX] [--cloud-stats-maps N] [--cloud-stats-iterations N]\n"
                     "             [--cloud-stats-sun photo|model] [--cloud-stats-probability fitted|initial]\n"
                     "             [--cloud-stats-sun-scale fit|off]");
  FitCommandLine c;
  FitVerbOptions& o = c.options;
  fit::FitOptions& f = o.fit;
  std::optional<std::string> sun_dir;
  std::optional<double> el, az;
  FitOptionArgs fa;
  bool json = false;
  cl.Repeatable("--reference", &o.references, "F.exr", "lat-long EXR (project convention); repeat for a day of references");
  cl.Text("--sun-dir", &sun_dir, "X,Y,Z",
          "sun direction for every reference (else the EXR's sunDirection\n"
          "attribute, else detected in the image, with a warning)");
  cl.Number("--sun-elevation", &el, "DEG", "alternative to --sun-dir, with --sun-azimuth: degrees in [-90, 90]");
  cl.Number("--sun-azimuth", &az, "DEG", "lat-long longitude of the sun, degrees (0 -> +Z, 90 -> +X)");
  cl.Number("--time", &f.time_of_day_h, "HOURS", "time of day of the reference(s), recorded for `skycal export`");
  RegisterFitOptionArgs(cl, &fa, &f, &o.init_preset);
  cl.Repeatable("--probe", &c.probes.probes, "STEM=S.json",
                "probe samples (skycal probe-extract) for the reference named STEM\n"
                "(repeatable; default: <reference without .exr>.probe.json when present):\n"
                "the ball's samples join the fit as residuals; the sun's RGB illuminance\n"
                "(per reference) and the ground albedo become fitted parameters");
  cl.Flag("--require-probe", &c.probes.require_probe, "error unless every reference has probe samples");
  cl.Flag("--cloud-mask", &o.cloud_mask,
          "leave cloudy pixels out (cloud probability >= 0.5: the frame's mask.cloud channel,\n"
          "else estimated from colour against the bundled clear preset at the frame's sun)");
  cl.Text("--out", &o.out_dir, "DIR",
          "output directory (required): preset.json (+ LUT EXRs), fit/<ref>.exr and\n"
          "fit/<ref>.{reference,fit,error}.png, report.png, fit.json, report.html");
  bool no_report = false;
  cl.Flag("--no-report", &no_report, "do not write DIR/report.html (skycal report)");
  RegisterFitCloudArgs(cl, &c);
  cl.Flag("--json", &json, "print fit.json on stdout");
  cl.Parse(argc, argv);
  ApplyFitCloudMode(&c);
  ApplyFitOptionArgs(fa, &f);
  if (sun_dir && (el || az)) throw Error("give either --sun-dir or --sun-elevation/--sun-azimuth, not both");
  if (el.has_value() != az.has_value()) throw Error("--sun-elevation and --sun-azimuth go together");
  if (el && (*el < -90.0 || *el > 90.0)) throw Error("--sun-elevation: expected degrees in [-90, 90]");
  if (el) f.sun_dir = latlong::DirectionFromElevationAzimuthDeg(*el, *az);
  if (sun_dir) f.sun_dir = ParseVec3(*sun_dir, "--sun-dir");
  o.report = !no_report;
  // --cloud-mask takes the cloud pixels out of the fit; --clouds on fits them.
  if (o.cloud_mask && c.clouds.mode == "on")
    throw Error("--cloud-mask leaves the cloud pixels out and --clouds on fits their lighting: give one of them");
  return c;
}

int RunFit(int argc, char** argv) {
  return RunVerb("fit", WantsJson(argc, argv), [&]() {
    const FitCommandLine c = ParseFitArgs(argc, argv);
    return RunFitWithProbes(c.options, c.probes, c.clouds, c.cloud_stats);
  });
}

}  // namespace skycal::cli
