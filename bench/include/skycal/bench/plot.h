// A suite's Pareto plot, time against error, drawn with PLplot (Debian libplplot-dev, the
// cairo driver package plplot-driver-cairo for the pngcairo and svgcairo devices): every
// case a point, dominated cases grey, the front blue and joined, the default ringed red.
// Axes are logarithmic where the values span more than a decade.
#pragma once
#include <string>
#include <vector>

#include "skycal/bench/case_result.h"

namespace skycal::bench {

struct ParetoPlot {
  std::string title;     // e.g. "render: sky backend x size"
  std::string subtitle;  // machine and commit
  std::string error_label;  // the y axis, with units
  std::vector<const CaseResult*> cases;  // finite time and error only are drawn
  std::vector<int> front;                // indices into cases
  int default_index = -1;                // -1: none
  // Short point labels (e.g. the setting values that differ from the default); empty: none.
  std::vector<std::string> labels;
};

// Writes `png_path` (1200x860) and `svg_path`. Throws skycal::Error when PLplot cannot open
// a device (the message names the missing driver package).
void WriteParetoPlot(const ParetoPlot& plot, const std::string& png_path, const std::string& svg_path);

}  // namespace skycal::bench
