// Line and point charts for the report, drawn by PLplot (the project's plotting library,
// already used by skycal bench) through its svgcairo device; returns the SVG text, which the
// report embeds as an <img> data URI (text becomes glyph paths, so the page needs no fonts,
// and each SVG keeps its own ids).
#pragma once
#include <cmath>
#include <string>
#include <vector>

namespace skycal::report {

struct ChartSeries {
  std::string label;
  std::vector<double> x, y;  // non-finite points are left out (a line breaks there)
  bool line = true;          // false: points only
};

struct Chart {
  std::string title;
  std::string x_label, y_label;  // with units
  std::vector<ChartSeries> series;
  bool log_y = false;            // log10 axis (non-positive values left out)
  std::vector<std::string> notes;  // small lines under the plot
  double x_min = NAN, x_max = NAN;  // finite: the x range always shown (plots of one day share it)
};

// Throws skycal::Error when PLplot cannot write (the message names the driver package), or
// when no series has a finite point.
std::string ChartSvg(const Chart& chart);

}  // namespace skycal::report
