// `skycal export`: the game's tables from calibrated presets (export/game_export.h does the
// work; this verb parses and prints).
#pragma once
#include <nlohmann/json.hpp>

#include "skycal/export/game_export.h"

namespace skycal::cli {

using exporter::ExportOptions;

nlohmann::json RunExportImpl(const ExportOptions& options);
// Parses the arguments after the verb (no I/O). Throws HelpRequested (command_line.h) for
// --help, skycal::Error naming the option on a bad command line.
ExportOptions ParseExportArgs(int argc, char** argv);
int RunExport(int argc, char** argv);

}  // namespace skycal::cli
