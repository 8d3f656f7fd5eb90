#include "skycal/report/report.h"

#include <algorithm>
#include <chrono>
#include <ctime>
#include <filesystem>

#include "sections.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "skycal/core/file_safety.h"
#include "skycal/core/output_kind.h"
#include "skycal/core/version.h"
#include "skycal/report/html.h"
#include "sources.h"

namespace skycal::report {
namespace fs = std::filesystem;
namespace {

constexpr const char* kStyle = R"(
body { font: 14px/1.4 sans-serif; margin: 24px; color: #222; background: #fff; max-width: 1640px; }
h1 { font-size: 22px; } h2 { font-size: 19px; border-bottom: 1px solid #ccc; margin-top: 36px; }
h3 { font-size: 16px; margin-top: 22px; } h4 { font-size: 14px; }
table { border-collapse: collapse; margin: 8px 0; } td, th { border: 1px solid #ddd; padding: 3px 7px; vertical-align: top; }
th { background: #f2f2f2; text-align: left; } table.kv td:first-child { color: #555; white-space: nowrap; }
.triptych { display: flex; gap: 10px; max-width: 1560px; } .triptych figure { flex: 1 1 0; min-width: 0; }
figure { margin: 0; } figcaption { font-size: 12px; color: #555; max-width: 512px; }
img.image { display: block; width: 100%; max-width: 512px; height: auto; border: 1px solid #999; }
img.wide { display: block; width: 100%; max-width: 1560px; height: auto; border: 1px solid #999; }
img.plot { display: block; width: 660px; max-width: 100%; height: auto; border: 1px solid #ddd; }
.plots { display: flex; flex-wrap: wrap; gap: 12px; }
.bar { display: inline-block; width: 90px; height: 10px; vertical-align: middle;
       background: linear-gradient(to right, rgb(30,90,190), #fff, rgb(200,40,30)); border: 1px solid #999; }
.note { color: #555; font-size: 13px; } ul.warn li { color: #8a4b00; }
.scroll { overflow-x: auto; max-width: 100%; } pre { background: #f6f6f6; padding: 8px; overflow-x: auto; }
nav li { margin: 2px 0; }
)";

std::string UtcNow() {
  const std::time_t t = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

// Every file the page is made from (the output must not replace one).
std::vector<NamedPath> InputsOf(const Sources& s) {
  std::vector<NamedPath> in;
  if (s.wind) in.push_back({"day.json", s.wind->json_path});
  for (const FitRecord& f : s.fits) {
    in.push_back({"fit.json", f.json_path});
    in.push_back({"preset.json", (fs::path(f.dir) / "preset.json").string()});
    if (!f.sheet_png.empty()) in.push_back({"report.png", f.sheet_png});
    if (!f.compare_png.empty()) in.push_back({"compare.png", f.compare_png});
    for (const ReferenceRecord& r : f.references) {
      for (const std::string* p : {&r.image_reference, &r.image_fit, &r.image_error}) {
        if (!p->empty()) in.push_back({"fit image", *p});
      }
    }
  }
  for (const ExportRecord& e : s.exports) {
    in.push_back({"manifest.json", e.json_path});
    in.push_back({"keyframes.json", (fs::path(e.dir) / "keyframes.json").string()});
  }
  for (const BenchRecord& b : s.benches) {
    in.push_back({"results.json", b.json_path});
    for (const BenchSuiteRecord& su : b.suites) {
      if (!su.plot_path.empty()) in.push_back({"bench plot", su.plot_path});
    }
  }
  return in;
}

}  // namespace

bool ReportOptions::IsValid(std::string* why) const {
  if (max_fit_sections < 1) {
    *why = "ReportOptions::max_fit_sections = " + std::to_string(max_fit_sections) + " (expected >= 1)";
    return false;
  }
  if (max_depth < 0 || max_depth > 8) {
    *why = "ReportOptions::max_depth = " + std::to_string(max_depth) +
           " (expected directory levels searched below DIR in [0, 8])";
    return false;
  }
  if (!out_path.empty() && fs::is_directory(out_path)) {
    *why = "ReportOptions::out_path = " + out_path + ": is a directory (expected the HTML file to write)";
    return false;
  }
  if (!out_path.empty()) {
    try {
      RequireExtension("ReportOptions::out_path =", out_path, {".html", ".htm"}, "the HTML report");
    } catch (const Error& e) {
      *why = e.what();
      return false;
    }
  }
  return true;
}

ReportSummary WriteReport(const std::string& dir, const ReportOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  fs::path root = fs::absolute(dir).lexically_normal();
  if (root.filename().empty()) root = root.parent_path();
  const std::string out_path = o.out_path.empty() ? (root / "report.html").string() : o.out_path;
  const Sources s = FindSources(root.string(), o.max_depth);
  RefuseOutputsOverInputs({{"ReportOptions::out_path", out_path}}, InputsOf(s));

  PageCounts counts;
  ReportSummary sum;
  std::string body, nav;
  if (s.wind) {
    body += WindSection(*s.wind);
    nav += "<li><a href=\"#wind\">the day's wind</a></li>\n";
  }
  const std::string day = DaySection(s.fits, &counts);
  if (!day.empty()) {
    body += day;
    nav += "<li><a href=\"#day\">the day: time-of-day plots</a></li>\n";
    sum.day = true;
  }
  // Fits shown in full: all, or max_fit_sections evenly spaced (first and last included).
  const size_t n_fits = s.fits.size(), shown = std::min(n_fits, static_cast<size_t>(o.max_fit_sections));
  std::vector<size_t> full;
  for (size_t k = 0; k < shown; ++k) full.push_back(shown == 1 ? 0 : (k * (n_fits - 1) + (shown - 1) / 2) / (shown - 1));
  if (shown < n_fits) {
    body += "<p class=\"note\">" + std::to_string(shown) + " of " + std::to_string(n_fits) +
            " fits are shown in full below, evenly spaced; every fit is in the day's plots and table.</p>\n";
  }
  for (size_t i : full) {
    const std::string anchor = "fit-" + std::to_string(i + 1);
    body += FitSection(s.fits[i], anchor, &counts);
    nav += "<li><a href=\"#" + anchor + "\">fit " + EscapeHtml(s.fits[i].label) + "</a></li>\n";
  }
  for (const FitRecord& f : s.fits) sum.frames += static_cast<int>(f.references.size());
  sum.fit_sections = static_cast<int>(full.size());
  for (size_t i = 0; i < s.exports.size(); ++i) {
    const std::string anchor = "export-" + std::to_string(i + 1);
    body += ExportSection(s.exports[i], anchor, &counts);
    nav += "<li><a href=\"#" + anchor + "\">game tables " + EscapeHtml(s.exports[i].label) + "</a></li>\n";
  }
  for (size_t i = 0; i < s.benches.size(); ++i) {
    const std::string anchor = "bench-" + std::to_string(i + 1);
    body += BenchSection(s.benches[i], anchor, &counts);
    nav += "<li><a href=\"#" + anchor + "\">benchmark " + EscapeHtml(s.benches[i].label) + "</a></li>\n";
  }
  const std::string name = DisplayName(root);
  const std::string title = o.title.empty() ? "skycal report: " + name : o.title;
  // The comment marks the page as skycal's: a later --out may replace it, nothing else
  // (output_kind.h, RefuseReplacingAnotherKind).
  std::string html = "<!DOCTYPE html>\n<!-- Written by skycal report -->\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>" + EscapeHtml(title) +
                     "</title>\n<style>" + kStyle + "</style>\n</head>\n<body>\n<h1>" + EscapeHtml(title) + "</h1>\n";
  html += "<p class=\"note\">Written by skycal " + std::string(kSkycalVersion) + " at " + UtcNow() + " from " +
          EscapeHtml(name) + ": " + std::to_string(s.fits.size()) + " fit(s), " + std::to_string(s.exports.size()) +
          " export(s), " + std::to_string(s.benches.size()) +
          " benchmark run(s). One self-contained file: images and plots are embedded; plots drawn by PLplot.</p>\n";
  html += "<nav><ul>\n" + nav + "</ul></nav>\n" + body + "</body>\n</html>\n";
  WriteFileAtomically(out_path, html);

  sum.path = out_path;
  sum.fits = static_cast<int>(s.fits.size());
  sum.exports = static_cast<int>(s.exports.size());
  sum.benches = static_cast<int>(s.benches.size());
  sum.images = counts.images;
  sum.plots = counts.plots;
  sum.plots_skipped = counts.plots_skipped;
  sum.plots_skipped_why = counts.plots_skipped_why;
  sum.bytes = static_cast<long long>(html.size());
  return sum;
}

}  // namespace skycal::report
