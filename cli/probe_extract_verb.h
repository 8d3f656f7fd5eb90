// `skycal probe-extract`: the gray diffuse probe measured in a linear EXR photograph
// (controllers/probe_extract.h), written as a samples JSON for `skycal fit --probe`. The verb
// parses its flags into the controller's options, calls it and prints.
#pragma once
#include <nlohmann/json.hpp>

#include "skycal/controllers/probe_extract.h"

namespace skycal::cli {

// controllers::ExtractProbe with its messages naming flags rather than option fields.
nlohmann::json RunProbeExtractImpl(const controllers::ProbeExtractOptions& options);
// Parses the arguments after the verb (no I/O). Throws HelpRequested (command_line.h) for
// --help, skycal::Error naming the option on a bad command line.
controllers::ProbeExtractOptions ParseProbeExtractArgs(int argc, char** argv);
int RunProbeExtract(int argc, char** argv);

}  // namespace skycal::cli
