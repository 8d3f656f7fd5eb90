#include "skycal/core/staged_directory.h"

#include <unistd.h>

#include <algorithm>
#include <set>

#include "skycal/core/error.h"
#include "skycal/core/json_file.h"

#include <nlohmann/json.hpp>

namespace skycal {
namespace fs = std::filesystem;
namespace {

// ".<name><tag><pid>": built by append (GCC 12's -Wrestrict misfires on "." + std::string&&).
std::string HiddenSibling(const fs::path& p, const char* tag) {
  std::string name = ".";
  name += p.filename().string();
  name += tag;
  name += std::to_string(::getpid());
  return name;
}

// Files (not directories) below `dir`, as generic relative paths, sorted; with `folders`,
// the directories too, each with a trailing '/'.
std::vector<std::string> FilesBelow(const fs::path& dir, bool folders = false) {
  std::vector<std::string> files;
  for (auto it = fs::recursive_directory_iterator(dir); it != fs::recursive_directory_iterator(); ++it) {
    const std::string rel = fs::relative(it->path(), dir).generic_string();
    if (!it->is_directory()) files.push_back(rel);
    else if (folders && !it->is_symlink()) files.push_back(rel + "/");
  }
  std::sort(files.begin(), files.end());
  return files;
}

// Throws unless `dir` is empty or this verb's own earlier output holding nothing else.
void RequireReplaceable(const fs::path& dir, const std::string& shown, const std::string& verb) {
  std::error_code ec;
  if (fs::is_empty(dir, ec)) return;
  const std::string how = "; choose another directory, or delete it yourself if it is yours to delete";
  if (!fs::exists(dir / kOutputMarker, ec)) {
    throw Error(shown + ": directory exists and is not an earlier `skycal " + verb + "` output (no " + kOutputMarker +
                "): refusing to replace it" + how);
  }
  nlohmann::json marker;
  try {
    marker = ReadJsonFile((dir / kOutputMarker).string());
  } catch (const Error& e) {
    throw Error(shown + ": its " + kOutputMarker + " cannot be read (" + e.what() + "): refusing to replace it" + how);
  }
  if (!marker.is_object() || marker.value("verb", "") != verb || !marker.contains("files") || !marker["files"].is_array()) {
    throw Error(shown + ": " + kOutputMarker + " does not record a `skycal " + verb + "` output: refusing to replace it" + how);
  }
  std::set<std::string> listed{kOutputMarker};
  for (const auto& f : marker["files"]) {
    if (f.is_string()) listed.insert(f.get<std::string>());
  }
  for (const std::string& f : FilesBelow(dir)) {
    if (!listed.count(f)) {
      throw Error(shown + ": holds '" + f + "', which the earlier `skycal " + verb +
                  "` run did not write: refusing to replace the directory and lose it" + how);
    }
  }
  // Folders (empty ones too) and symbolic links to folders are not files: a folder holding
  // none of the listed files, and any link, are the user's.
  for (auto it = fs::recursive_directory_iterator(dir); it != fs::recursive_directory_iterator(); ++it) {
    const std::string rel = it->path().lexically_relative(dir).generic_string();  // a link's own name
    const bool link = it->is_symlink(), folder = !link && it->is_directory();
    if (!link && !folder) continue;
    bool ours = false;
    // A folder the marker lists (rel + "/"), or, in a marker from before folders were
    // listed, one holding a listed file.
    for (const std::string& f : listed) ours = ours || (folder && f.rfind(rel + "/", 0) == 0);
    if (!ours) {
      throw Error(shown + ": holds the " + (link ? "symbolic link '" : "folder '") + rel + "', which the earlier `skycal " +
                  verb + "` run did not make: refusing to replace the directory and lose it" + how);
    }
  }
}

}  // namespace

StagedDirectory::StagedDirectory(const std::string& dir, const std::string& option, const std::string& verb,
                                 const std::vector<NamedPath>& inputs)
    : option_(option), verb_(verb) {
  if (dir.empty()) throw Error(option + ": expected a directory path");
  final_ = fs::absolute(dir).lexically_normal();
  if (final_.filename().empty()) final_ = final_.parent_path();  // "out/" -> "out"
  const std::string shown = option + " " + dir;
  std::error_code ec;
  if (!fs::is_directory(final_.parent_path(), ec)) {
    throw Error(shown + ": parent directory '" + final_.parent_path().string() + "' does not exist");
  }
  RefuseInputsInsideDirectory({option, dir}, inputs);
  if (fs::exists(fs::symlink_status(final_, ec))) {
    if (fs::is_symlink(fs::symlink_status(final_, ec))) throw Error(shown + ": is a symbolic link: refusing to replace it");
    if (!fs::is_directory(final_, ec)) throw Error(shown + ": exists and is not a directory");
    RequireReplaceable(final_, shown, verb);
  }
  RemoveStaleTemporaries(final_.parent_path().string());
  staging_ = final_.parent_path() / HiddenSibling(final_, ".tmp-");
  guard_ = std::make_unique<TemporaryGuard>(staging_.string());
  fs::remove_all(staging_, ec);
  if (!fs::create_directories(staging_, ec)) {
    throw Error(shown + ": cannot create a staging directory beside it (" + ec.message() + ")");
  }
}

StagedDirectory::~StagedDirectory() {
  std::error_code ec;
  if (!committed_) fs::remove_all(staging_, ec);
}

void StagedDirectory::Commit() {
  WriteJsonFileAtomically((staging_ / kOutputMarker).string(),
                          {{"verb", verb_}, {"files", FilesBelow(staging_, true)},
                           {"note", "written by skycal: a later `skycal " + verb_ +
                                        " --out` may replace this directory only while it holds just these files"}});
  const fs::path old = final_.parent_path() / HiddenSibling(final_, ".old-");
  std::error_code ec;
  {
    // The watcher waits for this block: the destination is never left missing.
    InterruptCleanupCriticalSection whole;
    TemporaryGuard old_guard(old.string());
    const bool replacing = fs::exists(final_, ec);
    if (replacing) {
      fs::rename(final_, old, ec);
      if (ec) throw Error(final_.string() + ": could not move the earlier output aside (" + ec.message() + ")");
    }
    fs::rename(staging_, final_, ec);
    if (ec) {
      std::error_code back;
      if (replacing) fs::rename(old, final_, back);
      throw Error(final_.string() + ": could not move the finished output into place (" + ec.message() + ")");
    }
    committed_ = true;
    NoteCommittedOutput(final_.string());
    if (replacing) fs::remove_all(old, ec);
  }
}

}  // namespace skycal
