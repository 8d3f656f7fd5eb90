#include "skycal/core/json_file.h"

#include <sys/stat.h>

#include <nlohmann/json.hpp>

#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "skycal/core/output_kind.h"

namespace skycal {

nlohmann::json ReadJsonFile(const std::string& path) {
  // A FIFO or device would block the read (or never end): only a regular file is JSON here.
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) {
    throw Error(path + ": " + (S_ISDIR(st.st_mode) ? "is a directory" : "is not a regular file (a FIFO, socket or device)") +
                ", expected a JSON file");
  }
  const std::string text = ReadFile(path);
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw Error(path + ": not valid JSON (byte " + std::to_string(e.byte) + "): " + e.what());
  }
}

void WriteJsonFileAtomically(const std::string& path, const nlohmann::json& value) {
  RefuseMismatchedExtension(path, ".json", "JSON");
  // Strings that are not UTF-8 (a file name in another encoding) are written with U+FFFD
  // in place of the bad bytes rather than failing after the work is done.
  WriteFileAtomically(path, value.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
}

}  // namespace skycal
