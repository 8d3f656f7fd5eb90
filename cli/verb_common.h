// What every verb shares: the log (stderr), the JSON summary (stdout with --json) and the
// mapping of errors to exit codes (0 success, 1 failure).
#pragma once
#include <functional>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "skycal/core/file_safety.h"

namespace skycal::cli {

// Human log line on stderr, prefixed with the verb.
void Log(const std::string& verb, const std::string& message);

// Runs `body` (which parses and executes, returning the summary), prints the summary as
// JSON on stdout when `json` is set, maps skycal::Error and other exceptions to a message
// on stderr and exit code 1. With --json a failure also prints {"ok": false, "error": ...}.
// A HelpRequested from parsing (command_line.h) prints the help on stdout: exit 0. A summary
// with "verb_failed": true (the verb ran and found a failure it reports in the summary, e.g.
// `bench --compare` finding a regression) is printed with "ok": false and exits 1.
int RunVerb(const std::string& verb, bool json, const std::function<nlohmann::json()>& body);

// A library option's field as its error messages name it ("FitOptions::sun_cone_deg") and the
// flag that sets it ("--sun-cone"). The libraries name fields, never flags; each verb keeps the
// table of the fields it sets next to where it registers the flags.
struct FieldFlag {
  const char* field;
  const char* flag;
};

// `message` with every field of `table` written as its flag: "Struct::field = value" becomes
// "--flag value", a bare "Struct::field" becomes "--flag". A field matches only as a whole
// name (not followed by a letter, digit or '_'), so "X::width" leaves "X::width_px" alone.
std::string FieldsAsFlags(std::string message, std::span<const FieldFlag> table);

// --json among the arguments: known before parsing, so that a parse error is reported as JSON too.
bool WantsJson(int argc, char** argv);

}  // namespace skycal::cli
