// `skycal fit`: fit the sky model to reference skies; writes a calibrated preset, the fit
// renders, report.png and fit.json into an output directory, atomically.
#pragma once
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "skycal/fit/fit_options.h"

namespace skycal::cli {

struct FitVerbOptions {
  std::vector<std::string> references;  // lat-long EXRs
  std::string init_preset;              // empty: the bundled default preset
  std::string out_dir;                  // created atomically (must not hold other files)
  fit::FitOptions fit;
  bool IsValid(std::string* why) const;
};

nlohmann::json RunFitImpl(const FitVerbOptions& options);
int RunFit(int argc, char** argv);

}  // namespace skycal::cli
