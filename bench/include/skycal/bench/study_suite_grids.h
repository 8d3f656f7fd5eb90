// The grids of the suites that replaced the last study programs (fit-cie-study: bench_cie;
// sky-segmentation: bench_sky_segmentation; capture-chart, capture-stars:
// bench_chart_stars), public so tests/bench_test.cc can check them without running them.
#pragma once
#include <string>
#include <vector>

#include "skycal/bench/grid.h"

namespace skycal::bench {

// fit-cie-study: model (ffxv, ffxv-iso: the default, ffxv+overcast); each case fits every
// type at every elevation (the sun at azimuth 0) on width x width/2 references.
struct CieStudyPlan {
  Grid grid;
  int width = 256;
  std::vector<int> types;               // CIE sky types, 1..15
  std::vector<double> elevations_deg;   // sun elevations
};
CieStudyPlan FitCieStudyPlan(bool quick);

// sky-segmentation: grabcut (on: the default SkyMaskOptions; off: the candidate mask alone)
// on `frames` of datasets/real, scored against datasets/masks where a hand mask exists.
struct SkySegmentationPlan {
  Grid grid;
  std::vector<std::string> frames;      // datasets/real/<frame>.exr
  std::vector<std::string> hand_masks;  // datasets/masks/<file>, "" where none (same order)
};
SkySegmentationPlan SkySegmentationGridPlan(bool quick);

// capture-chart: frame (real skies) x cast (a known 3x3 matrix): one chart fit each, the
// default ChartOptions (one setting: no time/error trade-off).
struct ChartCast {
  std::string name;
  double m[9];
};
const std::vector<ChartCast>& ChartCasts();
Grid CaptureChartGrid(bool quick);

// capture-stars: scene (synthetic stars over a rendered twilight in one band of peak
// excess, "x<lo>-<hi>"; or "night": datasets/real/night.exr), the default StarOptions.
Grid CaptureStarsGrid(bool quick);

}  // namespace skycal::bench
