// `skycal calibrate`: photographs in, calibrated presets, game tables and a report out
// (controllers/calibrate.h); the verb parses, calls the controller and prints.
#pragma once
#include <nlohmann/json.hpp>

#include "skycal/controllers/calibrate.h"

namespace skycal::cli {

// Runs the controller; the summary lists every photo (its directory, or why it was not
// calibrated). Throws skycal::Error when no photo was calibrated or some were refused
// (after writing the ones that could be: the summary is printed first).
nlohmann::json RunCalibrateImpl(const controllers::CalibrateOptions& options);
// Parses the arguments after the verb (no I/O). Throws HelpRequested for --help,
// skycal::Error naming the option on a bad command line.
controllers::CalibrateOptions ParseCalibrateArgs(int argc, char** argv);
int RunCalibrate(int argc, char** argv);

}  // namespace skycal::cli
