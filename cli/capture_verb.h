// `skycal capture`: exposure brackets from a camera (or a rig of cameras) to a reference
// frame (capture/capture_pipeline.h does the work; this verb parses and prints).
#pragma once
#include <nlohmann/json.hpp>

#include "skycal/capture/capture_pipeline.h"

namespace skycal::cli {

using capture::CaptureOptions;

nlohmann::json RunCaptureImpl(const CaptureOptions& options);
// Parses the arguments after the verb (no I/O). Throws HelpRequested (command_line.h) for
// --help, skycal::Error naming the option on a bad command line.
CaptureOptions ParseCaptureArgs(int argc, char** argv);
int RunCapture(int argc, char** argv);

}  // namespace skycal::cli
