// JSON files: parse with errors that name the file and the byte where parsing failed;
// write atomically, pretty-printed.
#pragma once
#include <nlohmann/json_fwd.hpp>
#include <string>

namespace skycal {

nlohmann::json ReadJsonFile(const std::string& path);
void WriteJsonFileAtomically(const std::string& path, const nlohmann::json& value);

}  // namespace skycal
