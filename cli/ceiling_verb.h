// `skycal ceiling`: how well the model could fit a reference at best (the least-squares
// optimum of rel RMSE over the LUT for each g, minimised over g; fit/include/skycal/fit/
// ceiling.h), and with one free value per image row (the LUT resolution's cost). Set a
// fit's rel_rmse against it: a fit at its ceiling has done all the model allows.
#pragma once
#include <string>

#include <nlohmann/json.hpp>

#include "skycal/fit/fit_options.h"

namespace skycal::cli {

struct CeilingVerbOptions {
  std::string reference;     // lat-long EXR, required
  std::string init_preset;   // grid, overcast weight, start of the g scan (default: bundled)
  fit::FitOptions fit;       // variant, sun direction, masks (the fit's pixel classes)
};

nlohmann::json RunCeilingImpl(const CeilingVerbOptions& options);
// Parses the arguments after the verb (no I/O). Throws HelpRequested (command_line.h) for
// --help, skycal::Error naming the option on a bad command line.
CeilingVerbOptions ParseCeilingArgs(int argc, char** argv);
int RunCeiling(int argc, char** argv);

}  // namespace skycal::cli
