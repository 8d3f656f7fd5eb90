// `skycal flow`: dense motion vectors between two consecutive frames of a time-lapse
// (capture/optical_flow.h does the work; this verb parses and prints).
#pragma once
#include <nlohmann/json.hpp>

#include "skycal/capture/optical_flow.h"

namespace skycal::cli {

using capture::FlowOptions;

nlohmann::json RunFlowImpl(const FlowOptions& options);
FlowOptions ParseFlowArgs(int argc, char** argv);
int RunFlow(int argc, char** argv);

}  // namespace skycal::cli
