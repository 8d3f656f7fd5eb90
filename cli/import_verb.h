// `skycal import`: a published equirectangular HDR sky (any RGB(A) EXR, half or float,
// any compression) converted to a reference frame in the project's lat-long convention
// (core/latlong.h), with its provenance and, when known, its sun direction. The pipeline is
// controllers::ImportToFile (controllers/import_controller.h); the verb parses and prints.
#pragma once
#include <nlohmann/json.hpp>

#include "skycal/controllers/import_controller.h"

namespace skycal::cli {

// Converts, writes the frame atomically and returns the JSON summary. Throws skycal::Error
// (and writes nothing) on a bad input, an unwritable output, or --detect-sun without a
// distinct sun; the messages name the flags.
nlohmann::json RunImportImpl(const controllers::ImportOptions& options);
// Parses the arguments after the verb (no I/O). Throws HelpRequested (command_line.h) for
// --help, skycal::Error naming the option on a bad command line.
controllers::ImportOptions ParseImportArgs(int argc, char** argv);
int RunImport(int argc, char** argv);

}  // namespace skycal::cli
