// `skycal chart`: fit a colour-chart correction (capture/color_chart.h) from an image of an
// X-Rite ColorChecker Classic and write it as JSON for `skycal capture --color-correction`
// (Forza Horizon 3 shot one chart with the ND filter and one without: one JSON each).
#pragma once
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "skycal/capture/capture_pipeline.h"
#include "skycal/capture/color_chart.h"
#include "skycal/capture/hdr_merge.h"

namespace skycal::cli {

struct ChartVerbOptions {
  std::string image;                 // EXR (linear) or 8/16-bit image
  std::string out;                   // *.json
  std::string label;                 // e.g. "nd", "no-nd"
  capture::ResponseModel response = capture::ResponseModel::kLinear;  // 8/16-bit codes: linear or srgb
  capture::ChartOptions chart;
  bool IsValid(std::string* why) const;
};

// Writes the correction atomically and returns the summary. Throws skycal::Error (nothing
// written): chart not found, clipped, bad options.
nlohmann::json RunChartImpl(const ChartVerbOptions& options);
ChartVerbOptions ParseChartArgs(int argc, char** argv);
int RunChart(int argc, char** argv);

// "X1,Y1,...,X4,Y4" -> corners; throws skycal::Error naming `option`.
std::array<double, 8> ParseChartCorners(const std::string& text, const std::string& option);
// The correction's summary for a verb's JSON and log: label, source, matrix, mean/max DeltaE.
using capture::ChartSummary;  // capture/capture_pipeline.h

}  // namespace skycal::cli
