// Suite `capture-response`: camera-response recovery against the known-response merge
// (docs/capture.md; what bench_response measured). Brackets of the real sunset sky
// (tests/synthetic_brackets.h; 1024x512, 512x256 with --quick) through tone curves the merge
// code has never seen (tests/response_shapes.h), 3..9 brackets 1..3 EV apart, photon + read
// noise and 0.6 DN of code noise, clipping. Each set is merged through the true curve (the
// floor) and through each recovery method. Time: the merge (response recovery included);
// error: the worse of median and p90 relative error over the well-measured pixels after one
// scale per channel (the white balance a colour chart fixes), as a multiple of the
// known-response merge's -- the target is 1.5. `extra` keeps the one-global-scale
// numbers too; the Markdown reproduces bench_response's two tables with `auto` added.
// A held-out family, reported apart: curves of Grossberg & Nayar's EMoR model drawn once
// (synthetic::EmorHeldOutShapes, fixed seed), 5 and 7 brackets 2 EV apart; the methods'
// defaults were set on the project's families, not these.
#include <algorithm>
#include <cstdio>
#include <map>
#include <memory>

#include "skycal/testing/response_shapes.h"
#include "skycal/capture/hdr_merge.h"
#include "suite_util.h"
#include "suites_internal.h"

namespace skycal::bench {
namespace {

constexpr int kEmorCurves = 12;  // held-out curves (--quick: the first 3)
constexpr unsigned kEmorSeed = 1;

// The held-out families: EMoR draws ("emor-N") and published camera curves ("cam-N").
bool IsHeldOut(const std::string& shape) { return shape.rfind("emor-", 0) == 0 || shape.rfind("cam-", 0) == 0; }
int HeldOutIndex(const std::string& shape) { return std::stoi(shape.substr(shape.find('-') + 1)); }

// The bench's shapes by short name (the grid's values), in table order: the project's
// families, then the held-out EMoR curves emor-1..emor-12.
std::vector<std::pair<std::string, synthetic::ResponseShape>> Shapes() {
  const std::vector<synthetic::ResponseShape> unseen = synthetic::UnseenResponseShapes();
  const synthetic::ToneCurve shoulder = synthetic::LogisticInStops(1.2, -3.0);
  std::vector<std::pair<std::string, synthetic::ResponseShape>> shapes = {
      {"log-s", unseen[0]},
      {"hable", unseen[1]},
      {"gamma-knee", unseen[2]},
      {"per-channel", unseen[3]},
      {"flat-shoulder", synthetic::FlatShoulderShape()},
      {"strong-shoulder", {"strong shoulder (logistic in stops, 1.2/stop, -3)", {shoulder, shoulder, shoulder}}}};
  const synthetic::EmorBasis basis = capture::ReadEmorBasis(std::string(SKYCAL_SOURCE_DIR) + "/datasets/response/emor_basis.csv");
  const auto emor = synthetic::EmorHeldOutShapes(basis, kEmorCurves, kEmorSeed);
  for (int i = 0; i < kEmorCurves; ++i) shapes.push_back({"emor-" + std::to_string(i + 1), emor[i]});
  const auto published = synthetic::PublishedCameraShapes();
  for (size_t i = 0; i < published.size(); ++i) shapes.push_back({"cam-" + std::to_string(i + 1), published[i]});
  return shapes;
}

std::vector<std::string> ShapeNames() {
  std::vector<std::string> names;
  for (const auto& [name, shape] : Shapes()) names.push_back(name);
  return names;
}

// auto-no-prior: auto with MergeOptions::emor_prior off (the Debevec solve's smoothness alone
// picks what the brackets leave undetermined), the control for the EMoR prior.
const char* kMethods[] = {"known", "auto", "auto-no-prior", "weighted", "debevec", "robertson"};

std::string Fixed2(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.2f", v);
  return b;
}
std::string Pct(double v) { return Fixed2(100.0 * v); }  // a fraction, in percent

// One bracket set's results by method, from the cases' extra.
struct SetRow {
  std::string shape, shape_name;
  int n = 0;
  double ev = 0.0;
  std::map<std::string, const CaseResult*> by_method;
  double Get(const std::string& method, const std::string& key) const {
    const auto it = by_method.find(method);
    if (it == by_method.end() || !it->second->extra.contains(key)) return NAN;
    return it->second->extra[key].get<double>();
  }
  bool Within(const std::string& method, bool balanced) const {
    const std::string m = balanced ? "median_balanced" : "median", p = balanced ? "p90_balanced" : "p90";
    return Get(method, m) <= 1.5 * Get("known", m) && Get(method, p) <= 1.5 * Get("known", p);
  }
};

std::vector<SetRow> Rows(const std::vector<CaseResult>& cases) {
  std::vector<SetRow> rows;
  for (const CaseResult& c : cases) {
    if (c.outcome != Outcome::kOk) continue;
    const std::string shape = bench::Get(c.settings, "shape");
    const int n = std::stoi(bench::Get(c.settings, "brackets"));
    const double ev = std::stod(bench::Get(c.settings, "ev"));
    if (rows.empty() || rows.back().shape != shape || rows.back().n != n || rows.back().ev != ev)
      rows.push_back({shape, c.extra.value("shape_name", shape), n, ev, {}});
    rows.back().by_method[bench::Get(c.settings, "method")] = &c;
  }
  return rows;
}

// A held-out family's section: per set, each method as a multiple of the known-response
// merge (one global scale; after the per-channel balance in brackets), whether auto's EMoR
// prior was used and how far it moved the curve, and the sets within 1.5x per method.
std::string HeldOutMarkdown(const std::vector<SetRow>& rows, const std::string& heading, const std::string& about) {
  std::string md = "\n## " + heading + "\n\n" + about +
                   " Ratios: method / known, median and p90, one global scale (after one scale per channel in brackets); "
                   "prior: whether auto's EMoR prior was used, and the range of ln f it moved over the well-exposed codes; "
                   "warnings: the auto merge's report.\n\n"
                   "| curve | brackets | known median / p90 | auto x median / x p90 | prior (moved ln f) | auto without the prior | "
                   "debevec | weighted | auto warnings |\n|---|---|---|---|---|---|---|---|---|\n";
  auto ratio = [](const SetRow& r, const std::string& m) {
    return Fixed2(r.Get(m, "median") / r.Get("known", "median")) + " / " + Fixed2(r.Get(m, "p90") / r.Get("known", "p90")) +
           " (" + Fixed2(r.Get(m, "median_balanced") / r.Get("known", "median_balanced")) + " / " +
           Fixed2(r.Get(m, "p90_balanced") / r.Get("known", "p90_balanced")) + ")";
  };
  auto prior = [](const SetRow& r) -> std::string {
    const auto a = r.by_method.find("auto");
    if (a == r.by_method.end() || !a->second->extra.value("emor_prior_used", false)) return "no";
    const auto& m = a->second->extra["emor_prior_moved_ln"];
    return "yes (" + Fixed2(m[0].get<double>()) + " .. " + Fixed2(m[1].get<double>()) + ")";
  };
  int total = 0, within[4] = {0, 0, 0, 0}, within_balanced[4] = {0, 0, 0, 0};
  const char* methods[4] = {"auto", "auto-no-prior", "debevec", "weighted"};
  for (const SetRow& r : rows) {
    md += "| " + r.shape_name + " | " + std::to_string(r.n) + " | " + Pct(r.Get("known", "median")) + " / " +
          Pct(r.Get("known", "p90")) + " | " + ratio(r, "auto") + " | " + prior(r) + " | " + ratio(r, "auto-no-prior") + " | " +
          ratio(r, "debevec") + " | " + ratio(r, "weighted") + " | " + FormatG(r.Get("auto", "warnings")) + " |\n";
    ++total;
    for (int m = 0; m < 4; ++m) within[m] += r.Within(methods[m], false), within_balanced[m] += r.Within(methods[m], true);
  }
  md += "\n| sets within 1.5x (median and p90) | auto | auto without the prior | debevec | weighted |\n|---|---|---|---|---|\n";
  const std::string t = " / " + std::to_string(total);
  auto counts = [&](const int* w) {
    std::string line;
    for (int m = 0; m < 4; ++m) line += " " + std::to_string(w[m]) + t + " |";
    return line;
  };
  md += "| one global scale |" + counts(within) + "\n";
  md += "| one scale per channel |" + counts(within_balanced) + "\n";
  return md;
}

std::string HeldOutSections(const std::vector<SetRow>& held_out) {
  std::vector<SetRow> emor, cameras;
  for (const SetRow& r : held_out) (r.shape.rfind("emor-", 0) == 0 ? emor : cameras).push_back(r);
  std::string md;
  if (!emor.empty())
    md += HeldOutMarkdown(
        emor, "Held-out family: EMoR curves (Grossberg & Nayar 2004)",
        "Curves f0 + sum c_i h_i of the Empirical Model of Response (datasets/response/emor_basis.csv, "
        "synthetic::EmorHeldOutShapes: c1 ~ U(-4, 5), c2..c6 ~ N(0, 1.0 / 0.4 / 0.25 / 0.12 / 0.08), strictly increasing "
        "draws only, seed 1), one curve in the three channels, 5 and 7 brackets 2 EV apart. The defaults were set on "
        "the project's families above. auto's prior is the EMoR itself, so for `auto` this family is no longer held "
        "out; `auto without the prior` is the method that was (its first run: 14 of 24 sets).");
  if (!cameras.empty())
    md += HeldOutMarkdown(
        cameras, "Held-out family: published camera curves",
        "The transfer curves camera makers and standards publish (synthetic::PublishedCameraShapes: sRGB, BT.709, "
        "HLG, S-Log3, LogC3, V-Log, Canon Log, F-Log, ACEScct; none from DoRF or the EMoR), one curve in the three "
        "channels, 5 and 7 brackets 2 EV apart, chosen and run once after the EMoR prior was built.");
  return md;
}

// Per shape, the sets each method brings within 1.5x of the known merge (median and p90,
// one global scale).
std::string WithinCounts(const std::vector<SetRow>& rows, const std::vector<std::string>& shape_order) {
  std::string md =
      "\n| shape | sets within 1.5x (median and p90): weighted | debevec | robertson | auto | auto without the EMoR prior |\n"
      "|---|---|---|---|---|---|\n";
  const char* methods[5] = {"weighted", "debevec", "robertson", "auto", "auto-no-prior"};
  for (const std::string& shape : shape_order) {
    int total = 0, within[5] = {0, 0, 0, 0, 0};
    for (const SetRow& r : rows) {
      if (r.shape_name != shape) continue;
      ++total;
      for (int m = 0; m < 5; ++m) within[m] += r.Within(methods[m], false);
    }
    md += "| " + shape + " |";
    for (int m = 0; m < 5; ++m) md += " " + std::to_string(within[m]) + " / " + std::to_string(total) + " |";
    md += "\n";
  }
  return md;
}

std::string Markdown(const std::vector<CaseResult>& cases) {
  std::vector<SetRow> rows, held_out;
  for (SetRow& r : Rows(cases)) (IsHeldOut(r.shape) ? held_out : rows).push_back(std::move(r));
  std::string scene = "?";
  for (const CaseResult& c : cases)
    if (c.extra.contains("scene")) scene = c.extra["scene"].get<std::string>();
  std::string md =
      "# Camera-response recovery vs the known-response merge\n\n"
      "`skycal bench --suite capture-response` (bench/src/capture_response_suite.cc). Scene: " + scene +
      "; 8-bit brackets, times 1/60 s x 2^(EV (i - (n-1)/2)), photon + read noise (10000 e- full well, 3 e-) and 0.6 DN "
      "of code noise, clipping at full scale. Error: |merged / scale - truth| / truth over the pixels some bracket "
      "measured well (every channel), after one global scale (median ratio), in percent, median / p90. `x`: weighted "
      "/ known. weighted: MergeOptions' defaults (lambda 3e5, 8000 samples per channel, 5 reweighting passes, codes "
      "3..252). `auto`: weighted's curves, then one debevec curve for the three channels when the channels' curves have "
      "one shape (the shape difference, RMS of ln f over codes 3..252, at most 0.15). Timings are noisy (shared 2-core machine).\n\n"
      "| shape | brackets | EV apart | known median / p90 | weighted median / p90 | x median / x p90 | debevec | robertson | "
      "weighted ms | auto median / p90 | auto chose (shape difference) |\n|---|---|---|---|---|---|---|---|---|---|---|\n";
  auto mp = [](const SetRow& r, const std::string& m) { return Pct(r.Get(m, "median")) + " / " + Pct(r.Get(m, "p90")); };
  double worst_median = 0.0, worst_p90 = 0.0;
  for (const SetRow& r : rows) {
    const auto w = r.by_method.find("weighted");
    md += "| " + r.shape_name + " | " + std::to_string(r.n) + " | " + FormatG(r.ev) + " | " + mp(r, "known") + " | " +
          mp(r, "weighted") + " | " + Fixed2(r.Get("weighted", "median") / r.Get("known", "median")) + " / " +
          Fixed2(r.Get("weighted", "p90") / r.Get("known", "p90")) + " | " + mp(r, "debevec") + " | " + mp(r, "robertson") +
          " | " + (w == r.by_method.end() ? "-" : std::to_string(static_cast<int>(w->second->time.median_ms))) + " | " +
          mp(r, "auto") + " | ";
    const auto a = r.by_method.find("auto");
    if (a != r.by_method.end() && a->second->extra.contains("chose"))
      md += a->second->extra["chose"].get<std::string>() + " (" + FormatG(a->second->extra.value("shape_difference", NAN), 3) + ")";
    md += " |\n";
    worst_median = std::max(worst_median, r.Get("weighted", "median") / r.Get("known", "median"));
    worst_p90 = std::max(worst_p90, r.Get("weighted", "p90") / r.Get("known", "p90"));
  }
  std::vector<std::string> shape_order;
  for (const SetRow& r : rows)
    if (std::find(shape_order.begin(), shape_order.end(), r.shape_name) == shape_order.end()) shape_order.push_back(r.shape_name);
  md += WithinCounts(rows, shape_order);
  char worst[128];
  std::snprintf(worst, sizeof worst, "\nWorst weighted / known: median x%.2f, p90 x%.2f (target: 1.5).\n", worst_median, worst_p90);
  md += worst;
  md += "\n## After one scale per channel (the balance a colour chart fixes)\n\n"
        "Each channel divided by its own median ratio before the error is taken, for the known merge and the "
        "recovered ones alike. When the channels' curves differ, a channel's radiance scale is a gauge the "
        "brackets cannot fix (scaling E_c and the curve's argument together leaves every code unchanged): the "
        "merge fixes it by extrapolating each channel's top code, and the error of that extrapolation is a "
        "colour imbalance, which `skycal chart` / `capture --chart` corrects. This is the suite's error (the worse "
        "of the two ratios).\n\n"
        "| shape | sets within 1.5x: weighted | debevec | robertson | auto | auto without the EMoR prior | "
        "worst weighted / known (median, p90) | worst auto / known (median, p90) |\n|---|---|---|---|---|---|---|---|\n";
  for (const std::string& shape : shape_order) {
    int total = 0, w = 0, d = 0, rb = 0, au = 0, an = 0;
    double wm = 0.0, wp = 0.0, am = 0.0, ap = 0.0;
    for (const SetRow& r : rows) {
      if (r.shape_name != shape) continue;
      ++total, w += r.Within("weighted", true), d += r.Within("debevec", true), rb += r.Within("robertson", true),
          au += r.Within("auto", true), an += r.Within("auto-no-prior", true);
      wm = std::max(wm, r.Get("weighted", "median_balanced") / r.Get("known", "median_balanced"));
      wp = std::max(wp, r.Get("weighted", "p90_balanced") / r.Get("known", "p90_balanced"));
      am = std::max(am, r.Get("auto", "median_balanced") / r.Get("known", "median_balanced"));
      ap = std::max(ap, r.Get("auto", "p90_balanced") / r.Get("known", "p90_balanced"));
    }
    char line[320];
    std::snprintf(line, sizeof line, "| %s | %d / %d | %d / %d | %d / %d | %d / %d | %d / %d | x%.2f, x%.2f | x%.2f, x%.2f |\n",
                  shape.c_str(), w, total, d, total, rb, total, au, total, an, total, wm, wp, am, ap);
    md += line;
  }
  md += HeldOutSections(held_out);
  return md;
}

}  // namespace

namespace {

// Why a grid case is skipped ("": run): the held-out family at 5 and 7 brackets 2 EV apart
// only (and without robertson); --quick: three bracket sets and the first three held-out curves.
std::string SkipReason(const Settings& st, bool quick) {
  const std::string shape = Get(st, "shape"), n = Get(st, "brackets"), ev = Get(st, "ev");
  if (IsHeldOut(shape)) {
    if (Get(st, "method") == "robertson") return "held-out families: known, auto (with and without the prior), weighted, debevec";
    if (ev != "2" || (n != "5" && n != "7")) return "held-out family: 5 and 7 brackets 2 EV apart";
    if (quick && (n != "5" || HeldOutIndex(shape) > 3)) return "--quick: the first three curves of each held-out family, 5 brackets";
    return "";
  }
  if (!quick) return "";
  const bool kept = (n == "5" && ev == "2") || (n == "3" && ev == "3") || (n == "9" && ev == "1");
  return kept ? "" : "--quick: three bracket sets";
}

}  // namespace

Suite CaptureResponseSuite() {
  Suite s;
  s.name = "capture-response";
  s.summary = "camera-response recovery on 6 unseen tone curves x 3..9 brackets x 1..3 EV, and 12 held-out EMoR curves "
              "x 5, 7 brackets 2 EV (sunset 1024x512; quick 512x256, 3 bracket sets, 3 EMoR curves): method vs the "
              "known-response merge";
  s.error_metric = "worse of median and p90 rel error after one scale per channel, as a multiple of the known-response merge's";
  s.error_axis = "x known-response merge";
  s.markdown = Markdown;
  // No Pareto front: the cases are different bracket sets and curves, and the known-response
  // merge (the floor every case is divided by) is not a choice a user has; the methods are
  // compared per set, in the tables.
  s.pareto = false;
  s.run = [](const SuiteOptions& o) {
    Grid grid;
    grid.axes = {{"shape", ShapeNames(), "log-s"},
                 {"brackets", {"3", "5", "7", "9"}, "7"},
                 {"ev", {"1", "2", "3"}, "2"},
                 {"method", {kMethods[0], kMethods[1], kMethods[2], kMethods[3], kMethods[4], kMethods[5]},
                  capture::ResponseModelName(capture::MergeOptions{}.response)}};
    grid.skip = [quick = o.quick](const Settings& st) { return SkipReason(st, quick); };
    std::string source;
    const ImageRGB scene = o.quick ? synthetic::LoadBracketScene(512, 256, &source) : synthetic::LoadBracketScene(1024, 512, &source);
    const std::string scene_label = source + " at " + std::to_string(scene.width) + "x" + std::to_string(scene.height);
    const auto shapes = Shapes();
    // The grid varies the method fastest: one bracket set serves its five methods.
    std::string set_key;
    std::unique_ptr<synthetic::SyntheticBrackets> set;
    synthetic::ShapeMergeError known;  // the set's known-response merge (the floor)
    return RunGrid("capture-response", grid, o, [&](CaseResult& c) {
      const std::string& shape = Get(c.settings, "shape");
      const int n = std::stoi(Get(c.settings, "brackets"));
      const double ev = std::stod(Get(c.settings, "ev"));
      const std::string key = shape + "/" + std::to_string(n) + "/" + Get(c.settings, "ev");
      const auto it = std::find_if(shapes.begin(), shapes.end(), [&](const auto& p) { return p.first == shape; });
      if (key != set_key) {
        synthetic::ShapeBracketSpec spec;
        spec.brackets = n;
        spec.ev_step = ev;
        set = std::make_unique<synthetic::SyntheticBrackets>(synthetic::MakeShapeBrackets(scene, it->second, spec));
        set_key = key;
        capture::MergeOptions truth;
        truth.response_curve = set->truth_response;
        known = synthetic::EvaluateShapeMerge(capture::MergeBrackets(set->brackets, truth).radiance, *set);
      }
      const std::string& method = Get(c.settings, "method");
      capture::MergeOptions mo;
      if (method == "known") {
        mo.response_curve = set->truth_response;
      } else if (method == "auto-no-prior") {
        mo.response = capture::ResponseModel::kAuto;
        mo.emor_prior = false;
      } else {
        mo.response = capture::ParseResponseModel(method, "method");
      }
      capture::MergeResult merged;
      c.time = Measure([&] { merged = capture::MergeBrackets(set->brackets, mo); }, 0, o.Repeats(1));
      const synthetic::ShapeMergeError e = synthetic::EvaluateShapeMerge(merged.radiance, *set);
      c.extra = {{"shape_name", it->second.name},
                 {"scene", scene_label},
                 {"median", e.median},
                 {"p90", e.p90},
                 {"median_balanced", e.median_balanced},
                 {"p90_balanced", e.p90_balanced},
                 {"channel_balance", e.channel},
                 {"warnings", merged.report["warnings"].size()}};
      c.error = std::max(e.median_balanced / known.median_balanced, e.p90_balanced / known.p90_balanced);
      const auto& cal = merged.report["response"].value("calibration", nlohmann::json::object());
      if (cal.contains("auto")) {
        c.extra["chose"] = cal["auto"]["chose"];
        c.extra["shape_difference"] = cal["auto"]["channel_shape_difference"];
      }
      if (cal.contains("emor_prior") && cal["emor_prior"].is_object()) {
        c.extra["emor_prior_used"] = cal["emor_prior"].value("used", false);
        if (cal["emor_prior"].contains("moved_ln")) c.extra["emor_prior_moved_ln"] = cal["emor_prior"]["moved_ln"];
      }
    });
  };
  return s;
}

}  // namespace skycal::bench
