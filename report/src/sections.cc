#include "sections.h"


#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "charts.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "skycal/core/png_io.h"
#include "skycal/report/html.h"
#include "skycal/report/plot_devices.h"

namespace skycal::report {
namespace {

std::string E(const std::string& s) { return EscapeHtml(s); }

std::string Percent(double fraction) { return FormatNumber(100.0 * fraction, 3) + "%"; }

std::string PlotImg(const Chart& chart, PageCounts* counts) {
  bool any = false;
  for (const ChartSeries& s : chart.series) {
    for (size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      any = any || (std::isfinite(s.x[i]) && std::isfinite(s.y[i]) && (!chart.log_y || s.y[i] > 0.0));
    }
  }
  if (!any) return "<p class=\"note\">" + E(chart.title) + ": no value to plot in these files.</p>\n";
  std::string why;
  if (!PlotDeviceAvailable("svgcairo", &why)) {
    ++counts->plots_skipped;
    counts->plots_skipped_why = why;
    return "<p class=\"note\">" + E(chart.title) + ": plot left out, " + E(why) + ".</p>\n";
  }
  ++counts->plots;
  return "<img class=\"plot\" alt=\"" + E(chart.title) + "\" src=\"" + DataUri("image/svg+xml", ChartSvg(chart)) + "\">\n";
}

std::string Row(const std::vector<std::string>& cells, bool header = false) {
  std::string r = "<tr>";
  for (const std::string& c : cells) r += (header ? "<th>" : "<td>") + c + (header ? "</th>" : "</td>");
  return r + "</tr>\n";
}

std::string SkippedList(const std::vector<std::pair<std::string, std::string>>& skipped, const std::string& what) {
  if (skipped.empty()) return "";
  std::string h = "<h4>" + E(what) + "</h4>\n<ul>\n";
  for (const auto& [block, reason] : skipped) h += "<li><b>" + E(block) + "</b>: " + E(reason) + "</li>\n";
  return h + "</ul>\n";
}

// One frame of the day: a reference of a fit.
struct Frame {
  const FitRecord* fit;
  const ReferenceRecord* ref;
  std::optional<double> time_h;
};

}  // namespace

std::string EmbedPng(const std::string& path, const std::string& alt, const std::string& cls, PageCounts* counts) {
  const std::string bytes = ReadFile(path);
  const Raster decoded = DecodePng(bytes, path);  // names the file when it is not a whole PNG
  ++counts->images;
  return "<img class=\"" + cls + "\" alt=\"" + E(alt) + "\" width=\"" + std::to_string(decoded.width) + "\" height=\"" +
         std::to_string(decoded.height) + "\" src=\"" + DataUri("image/png", bytes) + "\">";
}

namespace {

// The day's x axis: time of day when every frame has one, else the frame's number.
struct DayAxis {
  const std::vector<Frame>& frames;
  std::vector<double> x;
  bool timed = true;
  std::string x_label;
  double x_lo = 0.0, x_hi = 0.0;

  template <class Value>
  ChartSeries Series(const std::string& label, Value value, bool line = true) const {
    ChartSeries s{label, {}, {}, line && timed};
    for (size_t i = 0; i < frames.size(); ++i) {
      s.x.push_back(x[i]);
      s.y.push_back(value(frames[i]));
    }
    return s;
  }
  // The chart over the whole axis, as an image (PlotImg).
  std::string Plot(Chart c, PageCounts* counts) const {
    c.x_min = x_lo;
    c.x_max = x_hi;
    return PlotImg(c, counts);
  }
};

double OrNan(const std::optional<double>& v) { return v ? *v : NAN; }

// Sun at the ground, haziness, exposure and error over the day.
std::string DayFitCharts(const DayAxis& ax, PageCounts* counts) {
  const std::vector<Frame>& frames = ax.frames;
  const std::string& x_label = ax.x_label;
  const auto opt = OrNan;
  std::string h;
  {
    Chart c{"sun illuminance at the ground", x_label, "lux (model units unless --absolute)", {}, true, {}};
    c.series.push_back(ax.Series("the fitted preset's sun: sun_illuminance x tint x transmittance(sun zenith)",
                                 [&](const Frame& f) { return opt(f.ref->sun_lux_model); }));
    bool probe = false;
    for (const Frame& f : frames) probe = probe || f.ref->probe_sun_lux.has_value();
    if (probe) {
      c.series.push_back(ax.Series("the gray probe's sun (0 where occluded: drawn as a gap on this log axis)",
                                   [&](const Frame& f) { return opt(f.ref->probe_sun_lux); }));
    } else {
      c.notes.push_back("no frame has a gray-probe sun (fit --probe ... --absolute): the dips of a sun behind cloud show there");
    }
    h += ax.Plot(std::move(c), counts);
  }
  {
    Chart c{"haziness g (Cornette-Shanks asymmetry of the Mie term)", x_label, "g (1)", {}, false, {}};
    c.series.push_back(ax.Series("haziness_g of the frame's fit", [&](const Frame& f) { return f.fit->haziness_g; }));
    h += ax.Plot(std::move(c), counts);
  }
  {
    Chart c{"exposure: image units per model unit", x_label, "exposure (1)", {}, true, {}};
    c.series.push_back(ax.Series("fitted exposure (1 with --absolute)", [&](const Frame& f) { return f.ref->exposure; }));
    h += ax.Plot(std::move(c), counts);
  }
  {
    Chart c{"per-frame error against the reference (fitted sky pixels)", x_label, "rel RMSE (%)", {}, false, {}};
    c.series.push_back(ax.Series("rel RMSE (solid-angle weighted, 3 channels)", [&](const Frame& f) { return 100.0 * f.ref->rel_rmse; }));
    h += ax.Plot(std::move(c), counts);
  }
  return h;
}

// Cloud cover masked out and cloud lighting over the day; *fitted_cloud: the cloud
// parameters some frame fitted.
std::string DayCloudCharts(const DayAxis& ax, PageCounts* counts, std::vector<std::string>* fitted_cloud) {
  const std::vector<Frame>& frames = ax.frames;
  const std::string& x_label = ax.x_label;
  const auto opt = OrNan;
  std::string h;
  bool clouds = false;
  for (const Frame& f : frames) clouds = clouds || f.ref->cloudy_fraction.has_value();
  if (clouds) {
    Chart c{"cloud cover masked out of the fit", x_label, "cloudy sky pixels (%)", {}, false, {}};
    c.series.push_back(ax.Series("fit --cloud-mask: sky pixels with cloud probability >= 0.5",
                                 [&](const Frame& f) { return 100.0 * opt(f.ref->cloudy_fraction); }));
    h += ax.Plot(std::move(c), counts);
  }
  // Cloud lighting over the day: each parameter some frame fitted (fit --clouds), as its
  // value over the start's (one chart: the parameters' units differ); frames without it are gaps.
  for (const Frame& f : frames)
    for (const FitRecord::CloudParameter& p : f.fit->cloud_parameters)
      if (f.fit->clouds_fitted && !p.held && std::find(fitted_cloud->begin(), fitted_cloud->end(), p.name) == fitted_cloud->end())
        fitted_cloud->push_back(p.name);
  if (!fitted_cloud->empty()) {
    Chart c{"cloud lighting (fit --clouds): fitted value / start value", x_label, "ratio (1)", {}, false, {}};
    for (const std::string& name : *fitted_cloud) {
      c.series.push_back(ax.Series(name, [&](const Frame& f) {
        for (const FitRecord::CloudParameter& p : f.fit->cloud_parameters)
          if (p.name == name && f.fit->clouds_fitted && !p.held && p.initial != 0.0) return p.value / p.initial;
        return static_cast<double>(NAN);
      }));
    }
    h += ax.Plot(std::move(c), counts);
  }
  return h;
}

// One row per frame: its fit, time, sun, haziness, exposure and error.
std::string DayTable(const std::vector<Frame>& frames) {
  const auto opt = OrNan;
  std::string h = "<table>\n" +
                  Row({"frame", "fit", "time of day (h)", "sun elevation (deg)", "haziness g", "exposure",
                       "sun at ground (lux)", "rel RMSE", "log RMSE"},
                      true);
  for (size_t i = 0; i < frames.size(); ++i) {
    const Frame& f = frames[i];
    h += Row({std::to_string(i + 1) + ": " + E(f.ref->name), E(f.fit->label), f.time_h ? FormatNumber(*f.time_h) : "\xE2\x80\x93",
              FormatNumber(opt(f.ref->sun_elevation_deg)), FormatNumber(f.fit->haziness_g), FormatNumber(f.ref->exposure),
              FormatNumber(opt(f.ref->sun_lux_model)), Percent(f.ref->rel_rmse), FormatNumber(f.ref->log_rmse)});
  }
  return h + "</table>\n";
}

}  // namespace

std::string DaySection(const std::vector<FitRecord>& fits, PageCounts* counts) {
  std::vector<Frame> frames;
  for (const FitRecord& f : fits) {
    for (const ReferenceRecord& r : f.references) {
      frames.push_back({&f, &r, f.references.size() == 1 ? f.time_of_day_h : std::nullopt});
    }
  }
  if (frames.size() < 2) return "";
  DayAxis ax{frames};
  for (const Frame& fr : frames) ax.timed = ax.timed && fr.time_h.has_value();
  for (size_t i = 0; i < frames.size(); ++i) ax.x.push_back(ax.timed ? *frames[i].time_h : static_cast<double>(i + 1));
  ax.x_label = ax.timed ? "time of day (h)" : "frame (in the order below; no time of day in fit.json)";
  ax.x_lo = *std::min_element(ax.x.begin(), ax.x.end()), ax.x_hi = *std::max_element(ax.x.begin(), ax.x.end());
  std::string h = "<section id=\"day\">\n<h2>The day: " + std::to_string(frames.size()) + " frames</h2>\n";
  h += "<p>One frame per fitted reference" + std::string(ax.timed ? ", by time of day" : ", in directory order") + ".</p>\n";
  h += "<div class=\"plots\">\n";
  h += DayFitCharts(ax, counts);
  std::vector<std::string> fitted_cloud;
  h += DayCloudCharts(ax, counts, &fitted_cloud);
  h += "</div>\n<p class=\"note\">" +
       std::string(fitted_cloud.empty() ? "Cloud lighting over the day: no frame here was fitted with <code>fit --clouds</code>. "
                                        : "Each fit's cloud-lighting values, units and held parameters are in its own section. ") +
       "Frames fitted with <code>--cloud-mask</code> are fitted on their clear pixels.</p>\n";
  h += DayTable(frames);
  return h + "</section>\n";
}

std::string WindSection(const WindRecord& w) {
  std::string h = "<section id=\"wind\">\n<h2>The day's wind</h2>\n<p>" + FormatNumber(std::round(w.speed_m_s * 100.0) / 100.0) +
                  " m/s toward azimuth " + FormatNumber(std::round(w.direction_deg * 10.0) / 10.0) +
                  "&deg; (as <code>clouds.wind_direction</code>: 0 toward +z, 90 toward +x), fitted from the weather maps "
                  "inverted from consecutive frames and written into each frame's preset. Each row: the earlier frame's "
                  "map moved by the wind to the later frame's time, against the later photo's clouds (cloud IoU); the "
                  "unmoved map is the control, the later frame's own map the best a map does.</p>\n<table>\n" +
                  Row({"from", "to", "seconds apart", "IoU, moved by the wind", "IoU, unmoved", "IoU, its own map"}, true);
  for (const WindRecord::Pair& p : w.pairs)
    h += Row({E(std::filesystem::path(p.from).filename().string()), E(std::filesystem::path(p.to).filename().string()),
              FormatNumber(p.dt_s), FormatNumber(std::round(p.iou_moved * 1000.0) / 1000.0),
              FormatNumber(std::round(p.iou_unmoved * 1000.0) / 1000.0), FormatNumber(std::round(p.iou_own * 1000.0) / 1000.0)});
  return h + "</table>\n<p class=\"note\">" + E(w.json_path) + "</p>\n</section>\n";
}

namespace {

// One reference of a fit: its images and its numbers.
std::string ReferenceBlock(const ReferenceRecord& r, PageCounts* counts) {
  std::string h = "<h3>Reference " + E(r.name) + "</h3>\n";
  if (!r.image_reference.empty() && !r.image_fit.empty() && !r.image_error.empty()) {
    h += "<div class=\"triptych\">\n";
    h += "<figure>" + EmbedPng(r.image_reference, "reference " + r.name, "image", counts) +
         "<figcaption>reference (OCIO view, the sky pixels' automatic exposure)</figcaption></figure>\n";
    h += "<figure>" + EmbedPng(r.image_fit, "fit of " + r.name, "image", counts) +
         "<figcaption>fit (same view and exposure)</figcaption></figure>\n";
    h += "<figure>" + EmbedPng(r.image_error, "error of " + r.name, "image", counts) +
         "<figcaption>(fit &minus; reference) / reference, luminance <span class=\"bar\"></span> &minus;20% &hellip; "
         "+20%; grey: not fitted</figcaption></figure>\n</div>\n";
  } else {
    h += "<p class=\"note\">No per-reference images in this fit directory (fit/" + E(r.name) +
         ".reference.png ...); written by skycal fit from this version on.</p>\n";
  }
  h += "<table class=\"kv\">\n";
  h += Row({"rel RMSE", Percent(r.rel_rmse) + " (solid-angle weighted, fitted sky pixels, 3 channels)"});
  h += Row({"log RMSE", FormatNumber(r.log_rmse) + " (natural log)"});
  h += Row({"exposure", FormatNumber(r.exposure) + " (image units per model cd/m&sup2;)"});
  if (r.sun_elevation_deg) h += Row({"sun elevation", FormatNumber(*r.sun_elevation_deg) + " deg"});
  if (r.sun_lux_model) h += Row({"sun at the ground (fitted preset)", FormatNumber(*r.sun_lux_model) + " lux (model units)"});
  if (r.probe_sun_visible) {
    h += Row({"gray probe's sun", std::string(*r.probe_sun_visible ? "visible" : "occluded") +
                                      (r.probe_sun_fraction ? ", sun share " + FormatNumber(*r.probe_sun_fraction, 3) : "") +
                                      (r.probe_sun_lux ? ", " + FormatNumber(*r.probe_sun_lux) + " lux" : "")});
  }
  if (r.cloudy_fraction) h += Row({"masked as cloud", Percent(*r.cloudy_fraction) + " of the sky pixels"});
  std::string px;
  for (const auto& [k, v] : r.pixels) px += (px.empty() ? "" : ", ") + E(k) + " " + std::to_string(v);
  if (!px.empty()) h += Row({"pixels", px});
  h += "</table>\n";
  return h;
}

// The solver's cost per step, stage after stage (empty without a convergence record).
std::string ConvergenceBlock(const FitRecord& f, PageCounts* counts) {
  if (f.convergence.empty()) return "";
  Chart c{"convergence: cost per step / iteration, by stage", "step (stages one after another)",
          "cost (1/2 sum of robust log residuals)", {}, true, {}};
  double at = 0.0;
  for (const CostCurve& cc : f.convergence) {
    ChartSeries s{cc.label, {}, {}, true};
    for (double v : cc.cost) {
      s.x.push_back(at);
      s.y.push_back(v);
      at += 1.0;
    }
    c.series.push_back(std::move(s));
  }
  c.notes.push_back("costs of different stages use different levels and loss scales: compare within a stage");
  return "<h3>Convergence</h3>\n<div class=\"plots\">" + PlotImg(c, counts) + "</div>\n";
}

// The preset's parameters and the cloud lighting's (each empty when the fit has none).
std::string ParameterTables(const FitRecord& f) {
  std::string h;
  if (!f.parameters.empty()) {
    h += "<h3>Fitted preset parameters (preset.json)</h3>\n<table>\n" + Row({"parameter", "value", "unit", "range", "meaning"}, true);
    for (const ParameterRow& p : f.parameters) h += Row({E(p.name), E(p.value), E(p.unit), E(p.range), E(p.description)});
    h += "</table>\n<p class=\"note\">The LUTs (cd/m&sup2;&middot;sr) are the EXRs beside preset.json.</p>\n";
  }
  if (!f.cloud_parameters.empty()) {
    h += "<h3>Cloud lighting (fit --clouds)</h3>\n<p>" + E(f.clouds_decision.empty() ? std::string("-") : f.clouds_decision);
    if (f.cloud_pixels_log_rmse_initial && f.cloud_pixels_log_rmse_final)
      h += " Cloud pixels' log RMSE " + FormatNumber(*f.cloud_pixels_log_rmse_initial) + " at the start, " +
           FormatNumber(*f.cloud_pixels_log_rmse_final) + " fitted.";
    h += "</p>\n<table>\n" + Row({"parameter", "value", "initial", "unit", "held: why"}, true);
    for (const FitRecord::CloudParameter& p : f.cloud_parameters)
      h += Row({E(p.name), FormatNumber(p.value), FormatNumber(p.initial), E(p.unit),
                p.held ? E(p.why.empty() ? std::string("held") : p.why) : std::string(f.clouds_fitted ? "fitted" : "-")});
    h += "</table>\n";
  }
  return h;
}

// One cloud-statistics panel: reference, fit and error images, whole-sky errors.
std::string CloudStatsBlock(const FitRecord::CloudStatsPanel& p, PageCounts* counts) {
  std::string h = "<h3>Cloud statistics of " + E(p.name) + " (fit --clouds stats)</h3>\n<div class=\"triptych\">\n";
  h += "<figure>" + EmbedPng(p.image_reference, "cloud statistics reference " + p.name, "image", counts) +
       "<figcaption>reference (the sky pixels the statistics see)</figcaption></figure>\n";
  h += "<figure>" + EmbedPng(p.image_fit, "cloud statistics fit of " + p.name, "image", counts) +
       "<figcaption>the atmosphere where clear; where cloud, the fitted model's median radiance of the pixel's (sun "
       "angle, elevation, opacity) bin: the photo's cloud map places the clouds, the lighting is the model's"
       "</figcaption></figure>\n";
  h += "<figure>" + EmbedPng(p.image_error, "cloud statistics error of " + p.name, "image", counts) +
       "<figcaption>(fit &minus; reference) / reference, luminance <span class=\"bar\"></span> &minus;20% &hellip; "
       "+20%</figcaption></figure>\n</div>\n<table class=\"kv\">\n";
  h += Row({"whole sky, the atmosphere alone", Percent(p.atmosphere_rel_rmse) + " rel RMSE, " +
                                                   FormatNumber(p.atmosphere_log_rmse) + " log RMSE"});
  h += Row({"whole sky, with the cloud statistics", Percent(p.clouds_rel_rmse) + " rel RMSE, " +
                                                        FormatNumber(p.clouds_log_rmse) + " log RMSE"});
  h += "</table>\n";
  return h;
}

// The fit's decisions, skipped blocks and warnings.
std::string DecisionsAndWarnings(const FitRecord& f) {
  std::string h;
  if (!f.decisions.empty()) {
    h += "<h3>Decisions (what the fit did not evaluate, and what that saved)</h3>\n<table>\n" +
         Row({"what", "why", "saved (ms)", "basis", "rel RMSE change", "basis"}, true);
    for (const DecisionRecord& d : f.decisions) {
      h += Row({E(d.what), E(d.why), FormatNumber(d.saved_ms, 3), E(d.saved_ms_basis),
                d.rel_rmse_change ? Percent(*d.rel_rmse_change) : "\xE2\x80\x93", E(d.rel_rmse_change_basis)});
    }
    h += "</table>\n";
  }
  h += SkippedList(f.skipped, "Skipped");
  if (!f.warnings.empty()) {
    h += "<h4>Warnings</h4>\n<ul class=\"warn\">\n";
    for (const std::string& w : f.warnings) h += "<li>" + E(w) + "</li>\n";
    h += "</ul>\n";
  }
  return h;
}

}  // namespace

// skycal calibrate's record: what the photo was taken for, and the game's image beside it.
std::string CalibrationBlock(const FitRecord& f, PageCounts* counts) {
  if (!f.calibration) return "";
  const fit::FitCalibration& c = *f.calibration;
  std::string h = "<h3>The game's image against the photo</h3>\n<table class=\"kv\">\n";
  h += Row({"photo", E(c.photo)});
  h += Row({"kind of sky", E(c.sky_kind) + " (" + E(c.sky_kind_reason) + ")"});
  h += Row({"sun from", E(c.sun_source) + (c.sun_uncertainty_deg ? ", uncertainty " + FormatNumber(*c.sun_uncertainty_deg, 3) + " deg" : "")});
  h += Row({"per-pixel log RMSE", FormatNumber(c.game_per_pixel_log_rmse, 3) + " (natural log, " +
                                      std::to_string(c.game_sky_pixels) + " sky pixels above the horizon)"});
  h += Row({"appearance error", FormatNumber(c.game_appearance_error, 3) + " (per 10 deg band: luminance quantiles, chromaticity)"});
  if (c.game_cloud_iou)
    h += Row({"clouds where the photo has them", FormatNumber(*c.game_cloud_iou, 3) +
                                                   " (intersection over union: game transmittance < 0.5, photo cloud probability >= 0.5)"});
  h += Row({"calibration time", FormatNumber(c.seconds, 3) + " s"});
  h += "</table>\n";
  if (!f.compare_png.empty())
    h += "<figure>" + EmbedPng(f.compare_png, "photo, game and error of " + f.label, "wide", counts) +
         "<figcaption>photo | the calibrated preset as the game renders it (render.exr) | ln(game/photo)</figcaption></figure>\n";
  return h;
}

std::string FitSection(const FitRecord& f, const std::string& anchor, PageCounts* counts) {
  std::string h = "<section id=\"" + anchor + "\">\n<h2>Fit: " + E(f.label) + "</h2>\n";
  h += "<table class=\"kv\">\n";
  h += Row({"file", E(f.label + "/fit.json")});
  if (f.time_of_day_h) h += Row({"time of day", FormatNumber(*f.time_of_day_h) + " h"});
  h += Row({"model / backend / loss", E(f.model) + " / " + E(f.backend) + " / " + E(f.loss)});
  h += Row({"haziness g", FormatNumber(f.haziness_g) + " (1)"});
  h += Row({"fit time", FormatNumber(f.time_s, 3) + " s"});
  h += Row({"Ceres iterations / termination",
            f.termination.empty() ? std::string("not run (the linear start's result stands; see the decisions)")
                                  : std::to_string(f.iterations) + " / " + E(f.termination)});
  h += "</table>\n";
  h += CalibrationBlock(f, counts);
  for (const ReferenceRecord& r : f.references) h += ReferenceBlock(r, counts);
  if (f.references.front().image_reference.empty() && !f.sheet_png.empty()) {
    h += "<figure>" + EmbedPng(f.sheet_png, "report.png of " + f.label, "image", counts) +
         "<figcaption>report.png: reference | fit | error per reference</figcaption></figure>\n";
  }
  h += ConvergenceBlock(f, counts);
  h += ParameterTables(f);
  for (const FitRecord::CloudStatsPanel& p : f.cloud_stats_panels) h += CloudStatsBlock(p, counts);
  h += DecisionsAndWarnings(f);
  return h + "</section>\n";
}

std::string ExportSection(const ExportRecord& e, const std::string& anchor, PageCounts* counts) {
  std::string h = "<section id=\"" + anchor + "\">\n<h2>Game tables: " + E(e.label) + "</h2>\n<table class=\"kv\">\n";
  h += Row({"file", E(e.label + "/manifest.json")});
  std::string names;
  for (const std::string& p : e.presets) names += (names.empty() ? "" : ", ") + E(p);
  h += Row({"presets", names});
  h += Row({"pre-exposure", FormatNumber(e.pre_exposure) + " (LUT texels = model LUT (cd/m&sup2;&middot;sr) &times; this; FP16)"});
  h += "</table>\n";
  if (!e.keys.empty()) {
    const auto value = [](const nlohmann::json& row, const std::string& col) {
      const auto it = row.find(col);
      return it != row.end() && it->is_number() ? it->get<double>() : NAN;
    };
    if (e.keys.size() >= 2) {
      h += "<div class=\"plots\">\n";
      Chart c{"keyframes: sun illuminance at the ground", "time of day (h)", "sun_illuminance_lux (lux)", {}, true, {}};
      ChartSeries s{"sun_illuminance_lux", {}, {}, true};
      ChartSeries g{"haziness_g", {}, {}, true};
      for (const nlohmann::json& row : e.keys) {
        s.x.push_back(value(row, "time_of_day_h"));
        s.y.push_back(value(row, "sun_illuminance_lux"));
        g.x.push_back(value(row, "time_of_day_h"));
        g.y.push_back(value(row, "haziness_g"));
      }
      bool any_sun = false;
      for (double v : s.y) any_sun = any_sun || (std::isfinite(v) && v > 0.0);
      if (any_sun) {
        c.series.push_back(s);
        h += PlotImg(c, counts);
      }
      Chart cg{"keyframes: haziness g", "time of day (h)", "haziness_g (1)", {g}, false, {}};
      h += PlotImg(cg, counts);
      h += "</div>\n";
    }
    h += "<h3>Keyframes (keyframes.json)</h3>\n<div class=\"scroll\"><table>\n";
    std::vector<std::string> head;
    for (const std::string& c : e.columns) {
      const auto u = e.units.find(c);
      head.push_back(E(c) + (u != e.units.end() && u->is_string() ? "<br><small>" + E(u->get<std::string>()) + "</small>" : ""));
    }
    h += Row(head, true);
    for (const nlohmann::json& row : e.keys) {
      std::vector<std::string> cells;
      for (const std::string& c : e.columns) {
        const auto it = row.find(c);
        if (it == row.end() || it->is_null()) cells.push_back("");
        else if (it->is_number()) cells.push_back(FormatNumber(it->get<double>()));
        else if (it->is_string()) cells.push_back(E(it->get<std::string>()));
        else cells.push_back(E(it->dump()));
      }
      h += Row(cells);
    }
    h += "</table></div>\n";
  }
  h += SkippedList(e.skipped, "Skipped by the export");
  return h + "</section>\n";
}

std::string BenchSection(const BenchRecord& b, const std::string& anchor, PageCounts* counts) {
  std::string h = "<section id=\"" + anchor + "\">\n<h2>Benchmark: " + E(b.label) + "</h2>\n<table class=\"kv\">\n";
  h += Row({"file", E(b.label + "/results.json")});
  h += Row({"machine", E(b.machine)});
  h += Row({"commit / date", E(b.commit) + " / " + E(b.date)});
  h += "</table>\n<table>\n" + Row({"suite", "what", "cases", "on the Pareto front", "default", "wall time (s)"}, true);
  for (const BenchSuiteRecord& s : b.suites) {
    h += Row({E(s.name), E(s.summary), std::to_string(s.cases), std::to_string(s.front),
              s.default_case.empty() ? "\xE2\x80\x93" : E(s.default_case) + (s.default_on_front ? " (on the front)" : " (dominated)"),
              FormatNumber(s.wall_s, 3)});
  }
  h += "</table>\n<div class=\"plots\">\n";
  for (const BenchSuiteRecord& s : b.suites) {
    if (s.plot_path.empty()) continue;
    h += "<figure>" + EmbedPng(s.plot_path, s.name + " Pareto plot", "plot", counts) + "<figcaption>" + E(s.name) +
         ": run time against error (PLplot, written by skycal bench)</figcaption></figure>\n";
  }
  h += "</div>\n";
  if (!b.stress_md.empty()) h += "<h3>Stress (stress.md)</h3>\n<pre>" + E(b.stress_md) + "</pre>\n";
  return h + "</section>\n";
}

}  // namespace skycal::report
