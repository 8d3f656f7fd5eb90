// Outputs are written to a temporary file beside the destination and renamed into
// place only when complete, so a failure never leaves a partial file behind.
#pragma once
#include <memory>
#include <string>

#include "skycal/core/interrupt_cleanup.h"

namespace skycal {

class AtomicOutput {
 public:
  // Checks that the destination's directory exists and is writable; throws skycal::Error
  // naming the path otherwise. The temporary file is `<dir>/.<name>.tmp-<pid>-<n>`; it is
  // registered for removal on SIGINT/SIGTERM/SIGHUP (interrupt_cleanup.h), and stale
  // temporaries of dead processes in `<dir>` are removed first.
  explicit AtomicOutput(std::string final_path);
  ~AtomicOutput();  // removes the temporary file unless Commit() succeeded
  AtomicOutput(const AtomicOutput&) = delete;
  AtomicOutput& operator=(const AtomicOutput&) = delete;

  const std::string& temp_path() const { return temp_path_; }
  const std::string& final_path() const { return final_path_; }
  void Commit();  // rename(2) temp -> final; throws skycal::Error on failure

 private:
  std::string final_path_;
  std::string temp_path_;
  bool committed_ = false;
  std::unique_ptr<TemporaryGuard> guard_;
};

// Writes `contents` to `path` atomically.
void WriteFileAtomically(const std::string& path, const std::string& contents);
// Reads a whole file; throws skycal::Error naming the file if it cannot be read.
std::string ReadFile(const std::string& path);

}  // namespace skycal
