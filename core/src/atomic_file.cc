#include "skycal/core/atomic_file.h"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "skycal/core/error.h"
#include "skycal/core/output_kind.h"

namespace skycal {
namespace fs = std::filesystem;

AtomicOutput::AtomicOutput(std::string final_path) : final_path_(std::move(final_path)) {
  if (final_path_.empty()) throw Error("output path is empty: expected a file name");
  const fs::path p(final_path_);
  fs::path dir = p.parent_path();
  if (dir.empty()) dir = ".";
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    if (fs::exists(dir, ec)) throw Error(final_path_ + ": cannot write, '" + dir.string() + "' is not a directory");
    throw Error(final_path_ + ": cannot write, directory '" + dir.string() + "' does not exist");
  }
  if (fs::is_directory(p, ec)) {
    throw Error(final_path_ + ": cannot write, it is a directory (expected a file path)");
  }
  if (::access(dir.c_str(), W_OK) != 0) {
    throw Error(final_path_ + ": cannot write, directory '" + dir.string() +
                "' is not writable (" + std::strerror(errno) + ")");
  }
  RefuseReplacingAnotherKind(final_path_);
  static std::atomic<int> counter{0};
  temp_path_ = (dir / ("." + p.filename().string() + ".tmp-" + std::to_string(::getpid()) +
                       "-" + std::to_string(counter++)))
                   .string();
  RemoveStaleTemporaries(dir.string());
  guard_ = std::make_unique<TemporaryGuard>(temp_path_);
}

AtomicOutput::~AtomicOutput() {
  if (!committed_) std::remove(temp_path_.c_str());
}

void AtomicOutput::Commit() {
  if (std::rename(temp_path_.c_str(), final_path_.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    std::remove(temp_path_.c_str());
    throw Error(final_path_ + ": could not move the finished file into place (" + why + ")");
  }
  committed_ = true;
}

void WriteFileAtomically(const std::string& path, const std::string& contents) {
  AtomicOutput out(path);
  {
    std::ofstream f(out.temp_path(), std::ios::binary);
    f << contents;
    f.flush();
    if (!f) throw Error(path + ": write failed (" + std::strerror(errno) + ")");
  }
  out.Commit();
}

std::string ReadFile(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw Error(path + ": cannot open for reading (" + std::strerror(errno) + ")");
  std::ostringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

}  // namespace skycal
