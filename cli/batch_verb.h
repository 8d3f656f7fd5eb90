// `skycal batch`: a time-lapse day fitted frame by frame (batch/batch.h does the work; this
// verb parses, fills the batch's hooks with the fit verb and its own parser, and prints).
#pragma once
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "skycal/batch/batch.h"

namespace skycal::cli {

using batch::BatchEngine;
using batch::BatchOptions;

nlohmann::json RunBatchImpl(const BatchOptions& options);
// Parses the arguments after the verb (no I/O). Throws HelpRequested (command_line.h) for
// --help, skycal::Error naming the option on a bad command line.
BatchOptions ParseBatchArgs(int argc, char** argv);
BatchOptions ParseBatchArgs(const std::vector<std::string>& args);
int RunBatch(int argc, char** argv);

}  // namespace skycal::cli
