// Suites `capture-chart` and `capture-stars`: the colour-chart correction and the star
// removal of `skycal capture` — what the bench_chart_stars program measured
// (bench/results/capture_chart_stars.md), now suites of `skycal bench`. Both run the
// default options only (one setting each: the cases are inputs, not settings, so there is
// no time/error trade-off to plot).
//
// capture-chart: a ColorChecker (X-Rite's published sRGB values, linear Rec.709;
// tests/synthetic_chart.h) on the ground of a real sky frame at 40% of its median luminance,
// 5 px per chart unit per 512 px of width, 1% multiplicative noise, then a known 3x3 cast on
// the whole frame; found by OpenCV mcc (falling back to the known corners), fitted by OpenCV
// ccm. Error: the mean CIEDE2000 after the correction; `extra`: before/after mean and max,
// the cast's recovery max |(M C)/k - I| (k = trace / 3) and every patch.
// capture-stars: 300 synthetic stars (tests/synthetic_stars.h) over the bundled clear sky
// rendered at sun -6 deg (1024x512, CPU, 0.5% noise) per band of peak excess; error: the
// share of stars missed (1 - recall); `extra`: precision, pixels changed far from every
// star (must be 0), the restored pixels' p50/p95 relative error. `night`: the real night
// sky (datasets/real/night.exr): counts only, no truth (error not a number).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <numeric>
#include <optional>
#include <random>

#include "skycal/testing/synthetic_chart.h"  // the chart and stars the capture tests use too
#include "skycal/testing/synthetic_stars.h"
#include "skycal/bench/study_suite_grids.h"
#include "skycal/capture/color_chart.h"
#include "skycal/capture/star_removal.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/latlong.h"
#include "skycal/core/luminance.h"
#include "skycal/render/preset.h"
#include "suite_util.h"
#include "suites_internal.h"

namespace skycal::bench {

namespace {

std::string RealSky(const std::string& name) {
  const std::string path = std::string(SKYCAL_SOURCE_DIR) + "/datasets/real/" + name + ".exr";
  if (!std::filesystem::exists(path)) throw Error(path + ": missing (the real skies: run datasets/fetch_real_skies.sh)");
  return path;
}

double MedianLuminance(const ImageRGB& img) {
  std::vector<float> y;
  for (size_t i = 0; i < img.pixels.size(); i += 3)
    y.push_back(Rec709Luminance(img.pixels[i], img.pixels[i + 1], img.pixels[i + 2]));
  std::nth_element(y.begin(), y.begin() + y.size() / 2, y.end());
  return y[y.size() / 2];
}

// The sky with a chart on its ground at 40% of its median luminance, 1% noise.
ImageRGB ChartScene(const std::string& frame, std::array<double, 8>* corners) {
  ImageRGB img = ReadExrRGB(RealSky(frame)).image;
  const double unit = 5.0 * img.width / 512.0;
  *corners = testing::RenderChart(&img, {img.width * 0.58, img.height * 0.66, unit, 0.4 * MedianLuminance(img) / 0.89});
  std::mt19937 rng(14);
  std::normal_distribution<float> noise(0.0f, 0.01f);
  for (float& v : img.pixels) v = std::max(0.0f, v * (1.0f + noise(rng)));
  return img;
}

double Mean24(const std::array<double, 24>& v) { return std::accumulate(v.begin(), v.end(), 0.0) / 24.0; }
double Max24(const std::array<double, 24>& v) { return *std::max_element(v.begin(), v.end()); }

const ChartCast& FindCast(const std::string& name) {
  for (const ChartCast& c : ChartCasts())
    if (c.name == name) return c;
  throw Error("capture-chart: unknown cast '" + name + "'");
}

std::string CastDescription(const std::string& name) {
  if (name == "crosstalk-warm-wb") return "cross-talk + warm WB";
  if (name == "tungsten") return "tungsten-like";
  if (name == "nd-red-leak") return "ND filter red leak";
  return "none (identity)";
}

std::string Num(const nlohmann::json& j, const std::string& key, int decimals) {
  return j.contains(key) && j[key].is_number() ? FormatFixed(j[key].get<double>(), decimals) : "-";
}

// Peak-excess band of a `capture-stars` scene "x<lo>-<hi>".
std::pair<double, double> Band(const std::string& scene) {
  const size_t dash = scene.find('-');
  return {std::stod(scene.substr(1, dash - 1)), std::stod(scene.substr(dash + 1))};
}

}  // namespace

const std::vector<ChartCast>& ChartCasts() {
  static const std::vector<ChartCast> casts = {
      {"crosstalk-warm-wb", {0.82, 0.16, 0.04, 0.06, 0.87, 0.09, 0.01, 0.14, 0.64}},
      {"tungsten", {1.35, 0.05, 0.0, 0.02, 1.0, 0.03, 0.0, 0.08, 0.45}},
      {"nd-red-leak", {1.12, 0.06, 0.02, 0.01, 0.97, 0.02, 0.0, 0.03, 0.93}},
      {"none", {1, 0, 0, 0, 1, 0, 0, 0, 1}}};
  return casts;
}

Grid CaptureChartGrid(bool quick) {
  Grid g;
  std::vector<std::string> casts;
  for (const ChartCast& c : ChartCasts()) casts.push_back(c.name);
  if (quick) casts = {"crosstalk-warm-wb", "none"};
  g.axes = {{"frame", quick ? std::vector<std::string>{"sky"} : std::vector<std::string>{"sky", "dawn", "sunset"}, "sky"},
            {"cast", casts, "crosstalk-warm-wb"}};
  return g;
}

Grid CaptureStarsGrid(bool quick) {
  Grid g;
  const std::vector<std::string> scenes =
      quick ? std::vector<std::string>{"x0.6-1.2", "x30-300"}
            : std::vector<std::string>{"x0.3-0.6", "x0.6-1.2", "x1.2-2.5", "x2.5-6", "x6-30", "x30-300", "night"};
  g.axes = {{"scene", scenes, "x0.6-1.2"}};
  return g;
}

namespace {

std::string CaptureChartMarkdown(const std::vector<CaseResult>& cases) {
  std::string md =
      "# Colour-chart correction: a ColorChecker in real sky frames under known casts\n\n"
      "`skycal bench --suite capture-chart` (bench/src/capture_chart_stars_suites.cc). Chart: X-Rite's published "
      "sRGB values (linear Rec.709), on the frame's ground at 40% of the sky's median luminance, 5 px per chart unit "
      "per 512 px of width (patches 12.5 px at 512x256), 1% multiplicative noise, then the cast on the whole frame. "
      "Found by OpenCV mcc (the EV is that of the 8-bit image it was found in), fitted by OpenCV ccm (3x3, CIEDE2000 "
      "loss). CIEDE2000 against the published values after dividing out the exposure (neutral patches). `cast "
      "error`: max |(M C)/k - I| over the 9 entries, k = trace/3. Default options only (no trade-off: one setting).\n\n"
      "| frame | cast | found by | EV | mean dE00 before | max before | mean dE00 after | max after | cast error | fit ms |\n"
      "|---|---|---|---|---|---|---|---|---|---|\n";
  const CaseResult* first = nullptr;
  for (const CaseResult& c : cases) {
    if (!c.extra.contains("mean_de00_after")) {
      md += "| " + Get(c.settings, "frame") + " | " + CastDescription(Get(c.settings, "cast")) + " | " +
            ToString(c.outcome) + ": " + c.message + " |||||||| \n";
      continue;
    }
    if (!first) first = &c;
    const double ev = c.extra.value("detection_ev", 0.0);
    md += "| " + Get(c.settings, "frame") + " | " + CastDescription(Get(c.settings, "cast")) + " | " +
          c.extra.value("found_by", std::string()) + " | " + (ev >= 0 ? "+" : "") + FormatFixed(ev, 0) + " | " +
          Num(c.extra, "mean_de00_before", 2) + " | " + Num(c.extra, "max_de00_before", 2) + " | " +
          Num(c.extra, "mean_de00_after", 3) + " | " + Num(c.extra, "max_de00_after", 3) + " | " +
          Num(c.extra, "cast_error", 4) + " | " + FormatFixed(c.time.median_ms, 0) + " |\n";
  }
  if (first) {
    md += "\nPer patch, " + Get(first->settings, "frame") + " frame, " + CastDescription(Get(first->settings, "cast")) +
          " (CIEDE2000):\n\n| patch | name | before | after |\n|---|---|---|---|\n";
    const auto& b = first->extra["patch_de00_before"];
    const auto& a = first->extra["patch_de00_after"];
    for (int i = 0; i < 24; ++i)
      md += "| " + std::to_string(i + 1) + " | " + capture::ColorCheckerPatchName(i) + " | " +
            FormatFixed(b[i].get<double>(), 2) + " | " + FormatFixed(a[i].get<double>(), 3) + " |\n";
  }
  return md;
}

// One frame under one cast: the chart found (mcc, else the known corners), the correction
// fitted, its CIEDE2000 and how far it undoes the cast.
void RunChartCase(CaseResult& c, const SuiteOptions& o) {
  const ChartCast& cast = FindCast(Get(c.settings, "cast"));
  std::array<double, 8> corners{};
  ImageRGB img = ChartScene(Get(c.settings, "frame"), &corners);
  capture::Matrix3 m;
  std::copy(std::begin(cast.m), std::end(cast.m), m.begin());
  capture::ApplyColorCorrection(m, &img);
  const capture::ChartImage ci{Get(c.settings, "frame"), img,
                               std::vector<uint8_t>(static_cast<size_t>(img.width) * img.height, 0)};
  std::string found_by = "mcc";
  double ev = 0.0;
  capture::ColorCorrection cc;
  // mcc takes seconds a frame: one run per case (the 12 cases are the repetition).
  c.time = Measure(
      [&] {
        try {
          const capture::ChartDetection d = capture::FindColorChecker(ci, {});
          ev = d.detection_ev;
          cc = capture::FitColorCorrection(d.patches);
        } catch (const std::exception& e) {  // mcc's own failures are cv::Exception
          o.Log("[capture-chart] " + c.name + ": " + e.what() + "; with the known corners");
          capture::ChartOptions co;
          co.corners = corners;
          cc = capture::FitColorCorrection(capture::FindColorChecker(ci, co).patches);
          found_by = "corners (mcc failed)";
        }
      },
      0, o.Repeats(1));
  const capture::Matrix3 mc = capture::MultiplyMatrices(cc.matrix, m);
  const double k = (mc[0] + mc[4] + mc[8]) / 3.0;
  double cast_err = 0.0;
  for (int i = 0; i < 9; ++i) cast_err = std::max(cast_err, std::abs(mc[i] / k - (i % 4 == 0 ? 1.0 : 0.0)));
  c.error = Mean24(cc.delta_e_after);
  if (!std::isfinite(c.error) || !std::isfinite(cast_err)) {
    c.outcome = Outcome::kNonFinite;
    c.message = "non-finite CIEDE2000 or matrix";
  }
  c.extra = {{"found_by", found_by},
             {"detection_ev", ev},
             {"mean_de00_before", Mean24(cc.delta_e_before)},
             {"max_de00_before", Max24(cc.delta_e_before)},
             {"mean_de00_after", c.error},
             {"max_de00_after", Max24(cc.delta_e_after)},
             {"cast_error", cast_err},
             {"patch_de00_before", cc.delta_e_before},
             {"patch_de00_after", cc.delta_e_after}};
}

}  // namespace

Suite CaptureChartSuite() {
  Suite s;
  s.name = "capture-chart";
  s.summary = "colour-chart correction: a ColorChecker in real sky frames (sky, dawn, sunset) under known 3x3 casts, "
              "found by mcc, fitted by ccm (--quick: sky, 2 casts); default options only";
  s.error_metric = "mean CIEDE2000 of the 24 patches after the correction (against the published values)";
  s.error_axis = "mean dE00 after";
  s.pareto = false;  // one setting: the cases are inputs
  s.markdown = CaptureChartMarkdown;
  s.run = [](const SuiteOptions& o) {
    return RunGrid("capture-chart", CaptureChartGrid(o.quick), o, [&](CaseResult& c) { RunChartCase(c, o); });
  };
  return s;
}

namespace {

std::string CaptureStarsMarkdown(const std::vector<CaseResult>& cases) {
  std::string md =
      "# Star removal (`skycal bench --suite capture-stars`)\n\n"
      "bench/src/capture_chart_stars_suites.cc. The bundled clear preset at sun elevation -6 deg (azimuth 40), "
      "1024x512 (CPU renderer), 0.5% noise; 300 stars (Gaussian spread sigma 0.5 px, >= 8 px apart, elevations "
      "~10-67 deg) per band of peak excess (the star adds this many times the sky at its centre pixel before the "
      "spread; log-uniform); default options (7 px window, 6 sigma, +50%, <= 12 px groups, isolated by 2 px). "
      "Recall: stars whose centre pixel was replaced; precision: those / groups removed. `far changed`: pixels more "
      "than 3 px from every star that changed (must be 0). Default options only (no trade-off: one setting).\n\n"
      "| peak excess band (x sky) | stars | removed | recall | precision | far changed | restored p50 / p95 rel. error | ms |\n"
      "|---|---|---|---|---|---|---|---|\n";
  const CaseResult* night = nullptr;
  for (const CaseResult& c : cases) {
    const std::string& scene = Get(c.settings, "scene");
    if (scene == "night") {
      night = &c;
      continue;
    }
    if (!c.extra.contains("recall")) {
      md += "| " + scene.substr(1) + " | " + ToString(c.outcome) + ": " + c.message + " |||||||\n";
      continue;
    }
    md += "| " + scene.substr(1) + " | " + FormatG(c.extra["stars"].get<double>(), 6) + " | " +
          FormatG(c.extra["removed"].get<double>(), 6) + " | " + Num(c.extra, "recall", 3) + " | " +
          Num(c.extra, "precision", 3) + " | " + FormatG(c.extra["far_changed"].get<double>(), 6) + " | " +
          Num(c.extra, "restored_rel_error_p50", 4) + " / " + Num(c.extra, "restored_rel_error_p95", 4) + " | " +
          FormatFixed(c.time.median_ms, 0) + " |\n";
  }
  if (night && night->extra.contains("removed"))
    md += "\n## The real night sky (`datasets/real/night.exr`)\n\n| stars removed | pixels replaced | groups too large | "
          "groups not isolated | noise sigma (luminance) | ms |\n|---|---|---|---|---|---|\n| " +
          FormatG(night->extra["removed"].get<double>(), 6) + " | " +
          FormatG(night->extra["pixels_replaced"].get<double>(), 9) + " | " +
          FormatG(night->extra["rejected_large"].get<double>(), 6) + " | " +
          FormatG(night->extra["rejected_clustered"].get<double>(), 6) + " | " +
          FormatG(night->extra["noise_sigma"].get<double>(), 3) + " | " + FormatFixed(night->time.median_ms, 0) + " |\n";
  return md;
}

// The real night sky: no truth, the removal's counts only.
void RunNightCase(CaseResult& c, const SuiteOptions& o) {
  capture::StarRemovalResult r;
  const ImageRGB night = ReadExrRGB(RealSky("night")).image;
  c.time = Measure([&] { r = capture::RemoveStars(night, {}); }, 0, o.Repeats(1));
  c.extra = {{"removed", r.stars},
             {"pixels_replaced", r.pixels_replaced},
             {"rejected_large", r.rejected_large},
             {"rejected_clustered", r.rejected_clustered},
             {"noise_sigma", r.noise_sigma},
             {"size", std::to_string(night.width) + "x" + std::to_string(night.height)}};
  if (!std::isfinite(r.noise_sigma)) c.outcome = Outcome::kNonFinite, c.message = "non-finite noise sigma";
  // no truth: the error stays not a number
}

// The bundled preset at sun -6 deg (azimuth 40), 1024x512, CPU, 0.5% multiplicative noise.
ImageRGB RenderTwilight() {
  render::RenderRequest req;
  req.sun_dir = latlong::DirectionFromElevationAzimuthDeg(-6.0, 40.0);
  req.width = 1024;
  req.height = 512;
  ImageRGB twilight = render::CreateRenderer(render::Backend::kCpu)->Render(render::LoadPreset(DefaultPresetPath()), req);
  std::mt19937 rng(6);
  std::normal_distribution<float> noise(0.0f, 0.005f);
  for (float& v : twilight.pixels) v *= 1.0f + noise(rng);
  return twilight;
}

// 300 stars of the scene's band added to the twilight, removed, scored against the truth.
void RunStarBandCase(CaseResult& c, const SuiteOptions& o, const std::string& scene, const ImageRGB& sky) {
  const ImageRGB* twilight = &sky;
  capture::StarRemovalResult r;
  const auto [lo, hi] = Band(scene);
  ImageRGB starry = *twilight;
  const auto stars = testing::AddStars(&starry, 300, 64, 224, lo, hi, 8, 11);
  c.time = Measure([&] { r = capture::RemoveStars(starry, {}); }, 0, o.Repeats(1));
  const int w = starry.width, h = starry.height;
  int found = 0;
  for (const auto& st : stars) found += r.mask[static_cast<size_t>(std::lround(st.y)) * w + std::lround(st.x)] == 1;
  long long far_changed = 0;
  std::vector<double> restored;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      bool near = false;
      for (const auto& st : stars) near = near || (std::abs(x - st.x) <= 3 && std::abs(y - st.y) <= 3);
      for (int ch = 0; ch < 3; ++ch) {
        if (!near && r.image.at(x, y, ch) != starry.at(x, y, ch)) ++far_changed;
        if (r.mask[static_cast<size_t>(y) * w + x]) restored.push_back(std::abs(r.image.at(x, y, ch) / twilight->at(x, y, ch) - 1.0));
      }
    }
  std::sort(restored.begin(), restored.end());
  const double recall = static_cast<double>(found) / stars.size();
  c.error = 1.0 - recall;
  c.extra = {{"stars", stars.size()},
             {"removed", r.stars},
             {"recall", recall},
             {"precision", r.stars ? static_cast<double>(found) / r.stars : 0.0},
             {"far_changed", far_changed},
             {"restored_rel_error_p50", restored.empty() ? 0.0 : restored[restored.size() / 2]},
             {"restored_rel_error_p95", restored.empty() ? 0.0 : restored[restored.size() * 95 / 100]}};
  if (!std::isfinite(c.error)) c.outcome = Outcome::kNonFinite, c.message = "non-finite recall";
}

}  // namespace

Suite CaptureStarsSuite() {
  Suite s;
  s.name = "capture-stars";
  s.summary = "star removal: 300 synthetic stars per band of peak excess over a rendered twilight (sun -6 deg, "
              "1024x512), and the real night sky (--quick: 2 bands); default options only";
  s.error_metric = "share of the synthetic stars not removed (1 - recall); the night sky has no truth";
  s.error_axis = "1 - recall";
  s.pareto = false;  // one setting: the cases are inputs
  s.markdown = CaptureStarsMarkdown;
  s.run = [](const SuiteOptions& o) {
    std::optional<ImageRGB> twilight;  // rendered by the first synthetic case
    return RunGrid("capture-stars", CaptureStarsGrid(o.quick), o, [&](CaseResult& c) {
      const std::string& scene = Get(c.settings, "scene");
      if (scene == "night") return RunNightCase(c, o);
      if (!twilight) twilight = RenderTwilight();
      RunStarBandCase(c, o, scene, *twilight);
    });
  };
  return s;
}

}  // namespace skycal::bench
