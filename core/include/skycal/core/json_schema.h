// Strict reading of the project's JSON files (presets, rigs, probe samples): an unknown
// key is an error that names the file, the field and the nearest valid name, because a
// misspelt key would otherwise be ignored silently and its default used.
#pragma once
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

namespace skycal {

// "origin: field 'prefix.key'" — the form every JSON error message uses.
std::string JsonField(const std::string& origin, const std::string& field);

// The name in `names` closest to `key` by edit distance (insertions, deletions,
// substitutions and adjacent swaps), if it is within max(2, |key| / 3) edits; else "".
std::string NearestName(const std::string& key, const std::vector<std::string>& names);

// Throws skycal::Error for the first key of `object` not in `allowed`:
//   "p.json: field 'parameters.hazines': unknown key (did you mean 'haziness_g'? expected one of ...)"
// Throws too when `object` is not a JSON object.
void RequireKnownKeys(const nlohmann::json& object, const std::vector<std::string>& allowed, const std::string& origin,
                      const std::string& prefix);

// The file's "format_version": must be present, an integer, and `expected`. Older or newer
// files are refused with what to do about it (`remedy`, e.g. "re-run skycal probe-extract").
void RequireFormatVersion(const nlohmann::json& doc, int expected, const std::string& origin, const std::string& remedy);

}  // namespace skycal
