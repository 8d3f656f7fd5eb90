// Several files of one output written atomically as a unit (AtomicOutput makes one file
// atomic; this makes a set of them so).
#pragma once
#include <memory>
#include <string>
#include <vector>

namespace skycal {

// The files of one output committed together or not at all (a render's EXR and its preview
// PNG; a flow's EXR, PNG and sidecar). Each file is written complete under its own name in a
// hidden staging directory beside its destination (`.<name>.tmp-<pid>-<n>/<name>`, so the
// writers' extension checks and their own temp-and-rename work unchanged); nothing at the
// destinations changes before Commit(). Commit() keeps a hard link to each file it will
// replace, then renames every staged file into place, holding off interruption
// (InterruptCleanupCriticalSection); if a rename fails, the files already moved are put
// back (the previous file, or none), so the destinations hold every new file or every old
// one. The staging directories are removed on failure, on interruption and after Commit.
class AtomicOutputGroup {
 public:
  AtomicOutputGroup();
  ~AtomicOutputGroup();
  AtomicOutputGroup(const AtomicOutputGroup&) = delete;
  AtomicOutputGroup& operator=(const AtomicOutputGroup&) = delete;

  // Checks `final_path` as AtomicOutput does (directory exists and is writable, not a
  // directory, no file of another kind) and returns the staged path to write it at.
  // Throws skycal::Error naming the path.
  std::string Add(const std::string& final_path);
  void Commit();  // throws skycal::Error naming the file that could not be moved
  // `message` with every staged path replaced by its destination: a writer's error names
  // the file the user asked for.
  std::string Unstaged(std::string message) const;

 private:
  struct Entry;
  std::vector<Entry> entries_;
};

}  // namespace skycal
