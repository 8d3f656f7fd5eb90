// `skycal report`: one self-contained HTML page (images and plots embedded as data URIs, no
// scripts, no external resources) from skycal's output directories: a fit (fit.json, the
// per-reference PNGs, preset.json), several fits (a day: time-of-day plots), an export
// (manifest.json, keyframes.json) and a bench run (results.json, the Pareto plots). The
// verbs fit, export and bench call WriteReport on their staging directory; a batch over a
// time-lapse calls it on its output directory.
#pragma once
#include <string>

namespace skycal::report {

struct ReportOptions {
  std::string out_path;   // the HTML file; empty: DIR/report.html
  std::string title;      // empty: "skycal report: <DIR's name>"
  int max_depth = 3;      // how many directory levels below DIR are searched
  // A time-lapse day can hold thousands of fits: at most this many get their full section
  // (images, tables, convergence), evenly spaced in time; every fit is in the day's plots
  // and table.
  int max_fit_sections = 24;
  bool IsValid(std::string* why) const;
};

struct ReportSummary {
  std::string path;          // the HTML written
  int fits = 0, frames = 0;  // fit directories, references over all of them
  int fit_sections = 0;      // fits shown in full (<= max_fit_sections)
  int exports = 0, benches = 0;
  int images = 0, plots = 0;  // embedded PNGs, PLplot charts
  // Charts left out because PLplot cannot draw on this machine (plot_devices.h), and why;
  // the page says so where each would be.
  int plots_skipped = 0;
  std::string plots_skipped_why;
  bool day = false;           // the time-of-day section was written (2 or more frames)
  long long bytes = 0;
};

// Writes the page atomically (temporary file + rename). Throws skycal::Error naming the file
// and the field when an input is missing, unreadable or malformed (nothing is written then),
// when DIR holds no skycal output, or when the output would replace one of the inputs.
ReportSummary WriteReport(const std::string& dir, const ReportOptions& options);

}  // namespace skycal::report
