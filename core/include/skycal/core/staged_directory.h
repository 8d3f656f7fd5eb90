// An output directory written atomically: everything goes into a hidden sibling staging
// directory, renamed into place by Commit(); on failure (destructor without Commit) or
// interruption (interrupt_cleanup.h) the staging directory is removed and the destination
// is untouched.
//
// Replacing an existing directory is allowed only when it is recognisably this verb's own
// earlier output and holds nothing else: Commit() writes a marker, `.skycal-output.json`,
// listing the verb and every file it wrote; a later run replaces the directory only if
// the marker names the same verb and every file in the directory is listed there. A
// directory that any input lives in is never replaced.
#pragma once
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "skycal/core/file_safety.h"
#include "skycal/core/interrupt_cleanup.h"

namespace skycal {

inline constexpr const char* kOutputMarker = ".skycal-output.json";

class StagedDirectory {
 public:
  // `option` names the option for messages (a library's field, "ExportOptions::out_dir", or a verb's flag); `verb` is written to the marker.
  // Throws skycal::Error, before anything is written, when `dir` cannot be replaced.
  StagedDirectory(const std::string& dir, const std::string& option, const std::string& verb,
                  const std::vector<NamedPath>& inputs);
  ~StagedDirectory();
  StagedDirectory(const StagedDirectory&) = delete;
  StagedDirectory& operator=(const StagedDirectory&) = delete;

  std::string operator/(const std::string& name) const { return (staging_ / name).string(); }
  const std::filesystem::path& staging() const { return staging_; }
  void Commit();

 private:
  std::filesystem::path final_, staging_;
  std::string option_, verb_;
  bool committed_ = false;
  std::unique_ptr<TemporaryGuard> guard_;
};

}  // namespace skycal
