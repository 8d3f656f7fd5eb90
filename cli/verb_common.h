// What every verb shares: the log (stderr), the JSON summary (stdout with --json) and the
// mapping of errors to exit codes (0 success, 1 failure).
#pragma once
#include <functional>
#include <string>

#include <nlohmann/json.hpp>

namespace skycal::cli {

// Human log line on stderr, prefixed with the verb.
void Log(const std::string& verb, const std::string& message);

// Runs `body` (which parses and executes, returning the summary), prints the summary as
// JSON on stdout when `json` is set, maps skycal::Error and other exceptions to a message
// on stderr and exit code 1. With --json a failure also prints {"ok": false, "error": ...}.
int RunVerb(const std::string& verb, bool json, const std::function<nlohmann::json()>& body);

bool WantsHelp(int argc, char** argv);
bool WantsJson(int argc, char** argv);

}  // namespace skycal::cli
