// Suite `fit-cie-study`: the fit's accuracy against the 15 CIE standard general skies (CIE
// S 011 / ISO 15469) at three sun elevations, one reference per fit, by model variant — what
// the bench_cie program measured (bench/results/cie.md), now a suite of `skycal bench`.
//
// For each sky type and sun elevation 10, 30, 60 deg (azimuth 0) a lat-long reference is
// written (grey RGB = luminance in cd/m^2, Lz = 5000 cd/m^2, 0 below the horizon,
// refsky::WriteCieReference) and fitted from the bundled preset with the CPU backend and the
// default fit options. Cases (the `model` axis): ffxv (the talk's two LUT terms), ffxv-iso
// (+ the isotropic LUT term, the default) and ffxv+overcast (ffxv with the preset's overcast
// weight set to 0.5, so the CIE overcast term — Moon-Spencer — joins the fit). Error: the
// median rel RMSE over the fits (fit::CompareToReference); `extra` has every fit's row with
// the error split by region (near the sun, near the horizon, the rest).
// 256x128 (--quick: 5 types at sun 30 deg, 128x64). Time: the whole sweep, one run.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>

#include "skycal/bench/study_suite_grids.h"
#include "skycal/core/latlong.h"
#include "skycal/core/math_constants.h"
#include "skycal/fit/reference.h"
#include "skycal/fit/sky_fit.h"
#include "skycal/refsky/reference_skies.h"
#include "suite_util.h"
#include "suites_internal.h"

namespace skycal::bench {

namespace {

constexpr double kDeg = kRadiansPerDegree;
constexpr double kZenithLuminance = 5000.0;  // Lz, cd/m^2 (absolute level of every reference)
constexpr double kCircumsolarDeg = 15.0;     // region boundaries of the error breakdown, degrees
constexpr double kHorizonBandDeg = 10.0;
constexpr double kTargetMedianRelRmse = 0.02;  // ffxv-iso median rel RMSE <= 2% (the fit issue's target)

// Relative error (solid-angle weighted RMS of (fit - ref)/ref over the fitted pixels, 3
// channels: fit::CompareToReference's weighting) in three regions: 3..15 deg from the sun
// (the sun cone is not fitted), elevation < 10 deg outside that, the rest.
nlohmann::json ErrorBreakdown(const fit::Reference& ref, const ImageRGB& fit) {
  const int w = ref.radiance.width, h = ref.radiance.height;
  double sw[3] = {0, 0, 0}, sq[3] = {0, 0, 0};
  const double cos_circ = std::cos(kCircumsolarDeg * kDeg), sin_band = std::sin(kHorizonBandDeg * kDeg);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      if (ref.pixel_class[i] != fit::PixelClass::kSky) continue;
      const auto v = latlong::PixelDirection(x, y, w, h);
      const double mu = v[0] * ref.sun_dir[0] + v[1] * ref.sun_dir[1] + v[2] * ref.sun_dir[2];
      const int region = mu >= cos_circ ? 0 : (v[1] < sin_band ? 1 : 2);
      const double omega = latlong::PixelSolidAngle(x, y, w, h);
      for (int c = 0; c < 3; ++c) {
        const double r = ref.radiance.pixels[3 * i + c], e = (fit.pixels[3 * i + c] - r) / r;
        sw[region] += omega;
        sq[region] += omega * e * e;
      }
    }
  auto rms = [&](int k) { return sw[k] > 0 ? std::sqrt(sq[k] / sw[k]) : 0.0; };
  return {{"circumsolar_3_15deg", rms(0)}, {"horizon_0_10deg", rms(1)}, {"rest", rms(2)}};
}

std::string Percent(double v) { return FormatFixed(100.0 * v, 2); }

std::string ElevKey(double e) { return FormatG(e, 6); }

// The fits of one case, from its extra["fits"].
std::vector<double> Column(const nlohmann::json& fits, const std::string& key, const std::string& sub = "") {
  std::vector<double> v;
  for (const auto& f : fits) v.push_back(sub.empty() ? f.at(key).get<double>() : f.at(key).at(sub).get<double>());
  return v;
}

}  // namespace

CieStudyPlan FitCieStudyPlan(bool quick) {
  CieStudyPlan p;
  p.grid.axes = {{"model", {"ffxv", "ffxv-iso", "ffxv+overcast"}, "ffxv-iso"}};
  p.width = quick ? 128 : 256;
  for (int t = 1; t <= 15; t += quick ? 3 : 1) p.types.push_back(t);
  p.elevations_deg = quick ? std::vector<double>{30.0} : std::vector<double>{10.0, 30.0, 60.0};
  return p;
}

namespace {

// rel[case][type][elevation key]: each case's rel RMSE per CIE sky type and sun elevation.
using CieErrors = std::vector<std::map<int, std::map<std::string, double>>>;

// Per sky type a row: the rel RMSE (%) per case and sun elevation; then their medians.
std::string CieTypeTable(const std::vector<const CaseResult*>& ok, CieErrors& rel, const std::vector<std::string>& elevs,
                         const std::vector<int>& type_list, const std::vector<refsky::CieSkyType>& types) {
  std::string md = "| Type | Description |";
  std::string rule = "|---:|:---|";
  for (const CaseResult* c : ok)
    for (const std::string& e : elevs) md += " " + Get(c->settings, "model") + " " + e + "° |", rule += "---:|";
  md += "\n" + rule + "\n";
  for (int t : type_list) {
    md += "| " + std::to_string(t) + " | " + (t >= 1 && t <= static_cast<int>(types.size()) ? types[t - 1].description : "") + " |";
    for (size_t k = 0; k < ok.size(); ++k)
      for (const std::string& e : elevs) md += " " + Percent(rel[k][t][e]) + " |";
    md += "\n";
  }
  md += "| | **median** |";
  for (size_t k = 0; k < ok.size(); ++k)
    for (const std::string& e : elevs) {
      std::vector<double> v;
      for (int t : type_list) v.push_back(rel[k][t][e]);
      md += " **" + Percent(Median(v)) + "** |";
    }
  return md;
}

// Per case: median rel RMSE, by region, log RMSE, the three worst skies, time per fit; then
// the target's verdict.
std::string CieSummaryTable(const std::vector<const CaseResult*>& ok, size_t skies) {
  std::string md = "\n\nMedian over all " + std::to_string(skies) +
                   " skies per configuration:\n\n| Configuration | median rel RMSE (%) | by region: circumsolar 3-15° / horizon "
                   "0-10° / rest (%) | median log RMSE | worst (type, sun elevation: %) | median time per fit (s) |\n"
                   "|:---|---:|---:|---:|:---|---:|\n";
  for (const CaseResult* c : ok) {
    const auto& fits = c->extra["fits"];
    std::vector<const nlohmann::json*> worst;
    for (const auto& f : fits) worst.push_back(&f);
    std::stable_sort(worst.begin(), worst.end(), [](const nlohmann::json* a, const nlohmann::json* b) {
      return a->at("rel_rmse").get<double>() > b->at("rel_rmse").get<double>();
    });
    std::string w;
    for (size_t k = 0; k < std::min<size_t>(3, worst.size()); ++k)
      w += std::string(k ? "; " : "") + "type " + std::to_string(worst[k]->at("sky_type").get<int>()) + ", " +
           ElevKey(worst[k]->at("sun_elevation_deg").get<double>()) + "°: " + Percent(worst[k]->at("rel_rmse").get<double>());
    md += "| " + Get(c->settings, "model") + (c->is_default ? " (default)" : "") + " | " + Percent(c->error) + " | " +
          Percent(Median(Column(fits, "breakdown", "circumsolar_3_15deg"))) + " / " +
          Percent(Median(Column(fits, "breakdown", "horizon_0_10deg"))) + " / " +
          Percent(Median(Column(fits, "breakdown", "rest"))) + " | " + FormatFixed(Median(Column(fits, "log_rmse")), 4) +
          " | " + w + " | " + FormatFixed(Median(Column(fits, "time_s")), 2) + " |\n";
  }
  for (const CaseResult* c : ok)
    if (Get(c->settings, "model") == "ffxv-iso")
      md += "\nTarget (fit issue): ffxv-iso median rel RMSE <= " + Percent(kTargetMedianRelRmse) + "%: " +
            (c->error <= kTargetMedianRelRmse ? "met" : "**not met**") + " (" + Percent(c->error) + "%).\n";
  return md;
}

std::string CieStudyMarkdown(const std::vector<CaseResult>& cases) {
  const auto types = refsky::LoadCieSkyTypes(refsky::DefaultCieCsvPath());
  std::string md =
      "# Fit accuracy against the CIE standard general skies\n\n"
      "`skycal bench --suite fit-cie-study` (bench/src/fit_cie_study_suite.cc; numbers in `results.json`).\n"
      "Relative RMSE (%) of the fitted model against each CIE sky (CIE S 011 / ISO 15469), solid-angle weighted over "
      "the sky above the horizon, sun cone (3 deg) excluded. One reference per fit, Lz = 5000 cd/m^2, start = the "
      "bundled preset `default_clear`, CPU backend, default fit options. `ffxv+overcast`: `ffxv` with the preset's "
      "overcast weight set to 0.5 and the overcast zenith luminance fitted. Columns: configuration / sun elevation.\n\n";
  std::vector<const CaseResult*> ok;
  for (const CaseResult& c : cases)
    if (c.extra.contains("fits")) ok.push_back(&c);
  if (ok.empty()) return md + "No case finished.\n";
  CieErrors rel(ok.size());
  std::vector<std::string> elevs;
  std::vector<int> type_list;
  for (size_t k = 0; k < ok.size(); ++k)
    for (const auto& f : ok[k]->extra["fits"]) {
      const int t = f.at("sky_type").get<int>();
      const std::string e = ElevKey(f.at("sun_elevation_deg").get<double>());
      rel[k][t][e] = f.at("rel_rmse").get<double>();
      if (std::find(elevs.begin(), elevs.end(), e) == elevs.end()) elevs.push_back(e);
      if (std::find(type_list.begin(), type_list.end(), t) == type_list.end()) type_list.push_back(t);
    }
  md += CieTypeTable(ok, rel, elevs, type_list, types);
  md += CieSummaryTable(ok, type_list.size() * elevs.size());
  return md;
}

// One CIE reference: its sky type and sun elevation.
struct CieRef {
  int type;
  double elevation_deg;
  fit::Reference ref;
};

// One case (model variant): a fit per reference, one run of the whole sweep.
void RunCieCase(CaseResult& c, const std::vector<CieRef>& refs, const render::Preset& preset, const fit::FitOptions& base,
                render::SkyRenderer& cpu) {
  const std::string& model = Get(c.settings, "model");
  fit::FitOptions f = base;
  f.variant = model == "ffxv-iso" ? render::ModelVariant::kFfxvIso : render::ModelVariant::kFfxv;
  render::Preset init = preset;
  init.variant = f.variant;
  if (model == "ffxv+overcast") init.overcast_weight = 0.5;
  nlohmann::json fits = nlohmann::json::array();
  bool finite = true;
  c.time = Measure(
      [&] {
        fits = nlohmann::json::array();
        for (const CieRef& r : refs) {
          const auto t0 = std::chrono::steady_clock::now();
          const fit::FitResult res = fit::FitSky({r.ref}, init, f, cpu);
          const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
          const fit::ReferenceFit& rf = res.references.at(0);
          finite = finite && std::isfinite(rf.errors.rel_rmse);
          fits.push_back({{"sky_type", r.type},
                          {"sun_elevation_deg", r.elevation_deg},
                          {"rel_rmse", rf.errors.rel_rmse},
                          {"log_rmse", rf.errors.log_rmse},
                          {"haziness_g", res.preset.haziness_g},
                          {"time_s", seconds},
                          {"breakdown", ErrorBreakdown(r.ref, rf.rendered)}});
        }
      },
      0, 1);  // one run of the whole sweep: 45 fits already average the noise
  c.error = Median(Column(fits, "rel_rmse"));
  c.converged = finite;
  if (!finite) {
    c.outcome = Outcome::kNonFinite;
    c.message = "non-finite fit error";
  }
  c.extra = {{"fits", fits}, {"skies", fits.size()}, {"ms_per_fit_median", 1000.0 * Median(Column(fits, "time_s"))}};
}

std::vector<CaseResult> RunCieStudy(const SuiteOptions& o) {
  const CieStudyPlan plan = FitCieStudyPlan(o.quick);
  const auto types = refsky::LoadCieSkyTypes(refsky::DefaultCieCsvPath());
  fit::FitOptions base;
  base.backend = render::Backend::kCpu;
  base.verbose = false;
  std::vector<CieRef> refs;
  for (int t : plan.types)
    for (double e : plan.elevations_deg) {
      const std::string path = (o.scratch / ("cie" + std::to_string(t) + "_" + ElevKey(e) + ".exr")).string();
      refsky::WriteCieReference(path, types.at(static_cast<size_t>(t) - 1), latlong::DirectionFromElevationAzimuthDeg(e, 0.0),
                                plan.width, kZenithLuminance);
      refs.push_back({t, e, fit::LoadReference(path, base)});
    }
  o.Log("[fit-cie-study] " + std::to_string(refs.size()) + " CIE references at " + std::to_string(plan.width) + "x" +
        std::to_string(plan.width / 2));
  const render::Preset preset = render::LoadPreset(DefaultPresetPath());
  auto cpu = render::CreateRenderer(render::Backend::kCpu);
  return RunGrid("fit-cie-study", plan.grid, o, [&](CaseResult& c) { RunCieCase(c, refs, preset, base, *cpu); });
}

}  // namespace

Suite FitCieStudySuite() {
  Suite s;
  s.name = "fit-cie-study";
  s.summary = "the 15 CIE general skies x sun 10/30/60 deg, 256x128 (--quick: 5 skies, sun 30, 128x64), one fit each "
              "from the bundled preset, CPU: model variant (ffxv, ffxv-iso, ffxv+overcast)";
  s.error_metric = "median rel RMSE over the CIE skies and sun elevations (the fitted sky vs the CIE reference)";
  s.error_axis = "median rel RMSE over the CIE fits";
  s.markdown = CieStudyMarkdown;
  s.run = RunCieStudy;
  return s;
}

}  // namespace skycal::bench
