// `skycal compare`: the game's image of a sky against the photograph, in the two numbers of
// core/appearance.h (per-pixel log RMSE, appearance error), with the per-band statistics.
#pragma once
#include <string>

#include <nlohmann/json.hpp>

#include "skycal/core/appearance.h"

namespace skycal::cli {

struct CompareVerbOptions {
  std::string photo;  // lat-long EXR, required
  std::string game;   // lat-long EXR of the same size (e.g. `skycal render --clouds`), required
  std::string mask;   // optional sky mask EXR (R > 0.5 is sky), e.g. from `skycal mask`
  double exposure = 1.0;  // the game image is multiplied by it first (fit.json's exposure)
  // Pixels within this many degrees of the game file's sunDirection are left out (0: none):
  // calibrate's comparison, fit.json's calibration.game_sun_cone_deg.
  double sun_cone_deg = 0.0;
  appearance::Options options;
};

nlohmann::json RunCompareImpl(const CompareVerbOptions& options);
CompareVerbOptions ParseCompareArgs(int argc, char** argv);
int RunCompare(int argc, char** argv);

}  // namespace skycal::cli
