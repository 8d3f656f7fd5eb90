// The fit's model options on a command line, registered once for every verb that fits:
// `skycal fit` and `skycal batch` (which forwards them to each frame's fit). The options
// that name references, their sun or time, probes and outputs stay with each verb.
#pragma once
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "command_line.h"
#include "skycal/fit/fit_options.h"

namespace skycal::cli {

// What the command line holds before it becomes FitOptions (texts parsed after CLI11).
struct FitOptionArgs {
  std::optional<std::string> model, backend, loss, pyramid;
  bool no_haziness = false, no_ground_albedo = false, no_linear_start = false, quiet = false;
};

// Registers --model --backend --mask --init --absolute --sun-cone --clip-fraction --loss
// --loss-scale --no-linear-start --linear-width --polish --pyramid --max-iterations
// --smoothness --prior-weight --no-haziness --numeric-derivatives --quiet --probe-weight
// --probe-quadrature --no-ground-albedo. Targets must outlive Parse.
void RegisterFitOptionArgs(VerbCommandLine& cl, FitOptionArgs* args, fit::FitOptions* fit, std::string* init_preset);

// After Parse: the texts and negated flags into `fit`. Throws skycal::Error naming the option.
void ApplyFitOptionArgs(const FitOptionArgs& args, fit::FitOptions* fit);

// FitOptions::IsValid's message with each field written as the flag that sets it
// ("FitOptions::sun_cone_deg = 90 (...)" -> "--sun-cone 90 (...)"), for every verb that fits.
std::string WithFitFlags(const std::string& message);

// The options a fit ran with, as fit.json and the preset's provenance record them
// (controllers::ResolvedFitOptionsJson; batch's identity records them too).
nlohmann::json ResolvedFitOptionsJson(const fit::FitOptions& fo);

}  // namespace skycal::cli
