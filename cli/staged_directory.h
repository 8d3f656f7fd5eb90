// An output directory written atomically: everything goes into a hidden sibling staging
// directory, renamed into place by Commit(); on failure (destructor without Commit) the
// staging directory is removed and the destination is untouched.
#pragma once
#include <filesystem>
#include <string>

namespace skycal::cli {

class StagedDirectory {
 public:
  // `option` names the flag for messages (e.g. "--out"). An existing destination must be
  // empty or hold `marker_file` (a previous output of the same verb), else refused.
  StagedDirectory(const std::string& dir, const std::string& option, const std::string& marker_file);
  ~StagedDirectory();
  StagedDirectory(const StagedDirectory&) = delete;
  StagedDirectory& operator=(const StagedDirectory&) = delete;

  std::string operator/(const std::string& name) const { return (staging_ / name).string(); }
  const std::filesystem::path& staging() const { return staging_; }
  void Commit();

 private:
  std::filesystem::path final_, staging_;
  bool committed_ = false;
};

}  // namespace skycal::cli
