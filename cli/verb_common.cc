#include "verb_common.h"

#include <cctype>
#include <cerrno>
#include <cstring>
#include <iostream>

#include "command_line.h"
#include "skycal/core/error.h"

namespace skycal::cli {

std::string FieldsAsFlags(std::string message, std::span<const FieldFlag> table) {
  auto is_name = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; };
  for (const FieldFlag& e : table) {
    const std::string field = e.field, flag = e.flag;
    for (size_t at = message.find(field); at != std::string::npos; at = message.find(field, at)) {
      const size_t end = at + field.size();
      if (end < message.size() && is_name(message[end])) {
        at = end;
        continue;
      }
      const bool valued = message.compare(end, 3, " = ") == 0;
      message.replace(at, valued ? field.size() + 3 : field.size(), valued ? flag + " " : flag);
      at += flag.size();
    }
  }
  return message;
}

void Log(const std::string& verb, const std::string& message) { std::cerr << "[" << verb << "] " << message << std::endl; }

int RunVerb(const std::string& verb, bool json, const std::function<nlohmann::json()>& body) {
  std::string error;
  try {
    nlohmann::json summary = body();
    // A verb that ran but found what it was asked to check (a benchmark regression) says
    // so with "verb_failed": the summary is still printed, the exit code is 1.
    const auto flag = summary.find("verb_failed");
    const bool failed = flag != summary.end() && flag->is_boolean() && flag->get<bool>();
    summary["ok"] = !failed;
    summary["verb"] = verb;
    if (json) {
      std::cout << summary.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) << std::endl;
      if (!std::cout) {  // a full disk, a closed stdout or a pipe nobody reads (SIGPIPE is ignored)
        std::cerr << "skycal " << verb << ": error: the run finished (its files are written) but the JSON summary "
                  << "could not be written to standard output (" << std::strerror(errno) << ")" << std::endl;
        return 1;
      }
    }
    return failed ? 1 : 0;
  } catch (const HelpRequested& help) {
    std::cout << help.help();
    return 0;
  } catch (const Error& e) {
    error = e.what();
  } catch (const std::exception& e) {
    error = std::string("internal error: ") + e.what();
  }
  std::cerr << "skycal " << verb << ": error: " << error << std::endl;
  if (json) {
    std::cout << nlohmann::json{{"ok", false}, {"verb", verb}, {"error", error}}.dump(
                     2, ' ', false, nlohmann::json::error_handler_t::replace)
              << std::endl;
  }
  return 1;
}

bool WantsJson(int argc, char** argv) {
  for (int i = 0; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--json")) return true;
  }
  return false;
}

}  // namespace skycal::cli
