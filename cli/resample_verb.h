// `skycal resample`: a uniform lat-long frame to horizon-biased rows for the game
// (core/row_mapping.h; Forza Horizon 3 gave the horizon about twice the vertical
// resolution and the top of the sky a quarter). The mapping is stored in the frame
// (`skycalRowMapping`), and `skycal fit` reads such a frame through its exact inverse.
#pragma once
#include <string>

#include <nlohmann/json.hpp>

namespace skycal::cli {

struct ResampleOptions {
  std::string in, out;            // EXR frames; out written atomically, never over in
  int nominal_height = 0;         // densities relative to a uniform frame this high; 0: the input's
  double horizon_density = 2.0;   // rows per degree at the horizon, x the nominal frame's
  double zenith_density = 0.25;   // at the zenith, x the nominal frame's
  double nadir_density = 0.25;    // at the nadir, x the nominal frame's
  bool half = false;              // 16-bit float output
  bool IsValid(std::string* why) const;  // names the option at fault
};

nlohmann::json RunResampleImpl(const ResampleOptions& options);
ResampleOptions ParseResampleArgs(int argc, char** argv);
int RunResample(int argc, char** argv);

}  // namespace skycal::cli
