#include "verb_common.h"

#include <cstring>
#include <iostream>

#include "skycal/core/error.h"

namespace skycal::cli {

void Log(const std::string& verb, const std::string& message) { std::cerr << "[" << verb << "] " << message << std::endl; }

int RunVerb(const std::string& verb, bool json, const std::function<nlohmann::json()>& body) {
  std::string error;
  try {
    nlohmann::json summary = body();
    summary["ok"] = true;
    summary["verb"] = verb;
    if (json) std::cout << summary.dump(2) << std::endl;
    return 0;
  } catch (const Error& e) {
    error = e.what();
  } catch (const std::exception& e) {
    error = std::string("internal error: ") + e.what();
  }
  std::cerr << "skycal " << verb << ": error: " << error << std::endl;
  if (json) std::cout << nlohmann::json{{"ok", false}, {"verb", verb}, {"error", error}}.dump(2) << std::endl;
  return 1;
}

bool WantsHelp(int argc, char** argv) {
  for (int i = 0; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--help") || !std::strcmp(argv[i], "-h")) return true;
  }
  return false;
}

bool WantsJson(int argc, char** argv) {
  for (int i = 0; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--json")) return true;
  }
  return false;
}

}  // namespace skycal::cli
