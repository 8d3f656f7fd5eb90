// The report's sections as HTML fragments (every text from a file escaped): the day's
// time-of-day plots, one fit, one export, one bench run.
#pragma once
#include <string>
#include <vector>

#include "sources.h"

namespace skycal::report {

// Counts what went into the page (for ReportSummary and the log).
struct PageCounts {
  int images = 0, plots = 0;
  int plots_skipped = 0;          // PLplot cannot draw here (plot_devices.h)
  std::string plots_skipped_why;  // the cause, once
};

// Every frame of the fits (one per reference) over time of day, or over frame order when a
// frame has no time: sun illuminance, haziness, exposure, error. Empty when fewer than 2 frames.
std::string DaySection(const std::vector<FitRecord>& fits, PageCounts* counts);

// The day's wind (calibrate's day.json): the wind, and per pair of frames how far the earlier
// frame's map moved by it predicts the later photo's clouds.
std::string WindSection(const WindRecord& w);
std::string FitSection(const FitRecord& fit, const std::string& anchor, PageCounts* counts);
std::string ExportSection(const ExportRecord& e, const std::string& anchor, PageCounts* counts);
std::string BenchSection(const BenchRecord& b, const std::string& anchor, PageCounts* counts);

// <img> of a PNG file, embedded; throws skycal::Error naming the file when it is not a PNG
// that decodes. `cls` marks it for the page's CSS and the browser test ("image" or "plot").
std::string EmbedPng(const std::string& path, const std::string& alt, const std::string& cls, PageCounts* counts);

}  // namespace skycal::report
