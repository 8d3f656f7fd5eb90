#include "staged_directory.h"

#include <unistd.h>

#include "skycal/core/error.h"

namespace skycal::cli {
namespace fs = std::filesystem;

StagedDirectory::StagedDirectory(const std::string& dir, const std::string& option, const std::string& marker_file)
    : final_(fs::absolute(dir)) {
  std::error_code ec;
  if (dir.empty()) throw Error(option + ": expected a directory path");
  if (!fs::is_directory(final_.parent_path(), ec)) {
    throw Error(option + " " + dir + ": parent directory '" + final_.parent_path().string() + "' does not exist");
  }
  if (fs::exists(final_, ec)) {
    if (!fs::is_directory(final_, ec)) throw Error(option + " " + dir + ": exists and is not a directory");
    if (!fs::is_empty(final_, ec) && !fs::exists(final_ / marker_file, ec)) {
      throw Error(option + " " + dir + ": directory exists and holds files that are not a previous skycal output (no " +
                  marker_file + "); refusing to overwrite");
    }
  }
  staging_ = final_.parent_path() / ("." + final_.filename().string() + ".tmp-" + std::to_string(::getpid()));
  fs::remove_all(staging_, ec);
  if (!fs::create_directories(staging_, ec)) {
    throw Error(option + " " + dir + ": cannot create a staging directory beside it (" + ec.message() + ")");
  }
}

StagedDirectory::~StagedDirectory() {
  std::error_code ec;
  if (!committed_) fs::remove_all(staging_, ec);
}

void StagedDirectory::Commit() {
  std::error_code ec;
  if (fs::exists(final_, ec)) fs::remove_all(final_, ec);
  fs::rename(staging_, final_, ec);
  if (ec) throw Error(final_.string() + ": could not move the finished output into place (" + ec.message() + ")");
  committed_ = true;
}

}  // namespace skycal::cli
