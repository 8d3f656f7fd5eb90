// The plan of the `fit-cloud-stats` and `cloud-stats-noise` suites (the retired
// bench_cloud_stats program's seed pairs and shape-noise analysis), public so
// tests/bench_test.cc can check it without rendering.
#pragma once
#include <string>
#include <vector>

#include "skycal/bench/grid.h"

namespace skycal::bench {

// One configuration of the unknown-shapes cloud lighting fit (cloudfit/include/skycal/cloudfit/cloud_stats.h),
// as one of the program's results files reported it. 0 in width/renders/iterations: the
// CloudStatsOptions default.
struct CloudStatsConfig {
  std::string name;             // the `config` axis value
  int width = 0;                // render width (px; height = width / 2)
  int references = 1;           // references per fit (> 1: no control pair)
  int model_maps = 1;           // weather maps the model pools (shape draws per evaluation)
  int model_renders = 0;        // model renders per evaluation
  int max_iterations = 0;
  std::vector<std::string> fitted;  // empty: the options' default
  int noise_draws = 0;          // whitening draws (0: bin-share weights)
  int model_noises = 1;         // noise textures the model cycles through
  std::string results_file;     // bench/results/<file>.md the program wrote for it ("" for none)
  std::string program_args;     // the retired program's arguments after PAIRS STEM
  // The whitening's covariance (CloudStatsOptions::noise_covariance: "diagonal" or "full",
  // λ estimated), the noise textures its draws cycle through (seeds 7001..7000+N; 0: the
  // model's one texture), and the fitted extinction's start as a multiple of the truth.
  std::string covariance = "diagonal";
  int draw_noises = 0;
  double extinction_start = 1.3;
};

struct CloudStatsPlan {
  Grid grid;                             // one axis, `config`; default: `default`
  std::vector<CloudStatsConfig> configs;  // the grid's values, in order
  int pairs = 5;                         // unknown-shape seed pairs per case (k = 1..pairs)
  int width_override = 0;                // --quick: every config at this width (0: the config's)
  int iteration_cap = 0;                 // --quick: at most this many iterations (0: none)
};
// Full: 9 configurations x 5 pairs; --quick: `default` and `gls-2params`, 1 pair + the
// control at 64x32, at most 2 iterations.
CloudStatsPlan FitCloudStatsPlan(bool quick);
// fit-cloud-stats-gls: the full GLS against the diagonal whitening on the same draws (24
// weather maps x 6 noise textures), 5 pairs + the control at 64x32: extinction + ambient
// from above (1.3x) and below (0.7x) the true extinction, ambient alone, albedo + ambient
// The test-* cases are cheaper settings tried for the recovery test (2 model renders, 8 draws
// over 2 noise textures, at most 4 iterations; too wide a spread: the test runs diag-ambient's);
// --quick runs only them, 5 pairs each.
CloudStatsPlan FitCloudStatsGlsPlan(bool quick);
// The configuration named `name` of `plan`; throws skycal::Error when absent.
const CloudStatsConfig& FindCloudStatsConfig(const CloudStatsPlan& plan, const std::string& name);

// cloud-stats-noise: shape draws, render width, model maps (full: the program's defaults).
struct CloudStatsNoisePlan {
  int draws = 48, width = 64, model_maps = 4;
};
CloudStatsNoisePlan CloudStatsNoiseGridPlan(bool quick);

}  // namespace skycal::bench
