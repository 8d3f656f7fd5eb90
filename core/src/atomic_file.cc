#include "skycal/core/atomic_file.h"
#include "skycal/core/atomic_output_group.h"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "skycal/core/error.h"
#include "skycal/core/output_kind.h"

namespace skycal {
namespace fs = std::filesystem;

namespace {
// One counter for every temporary name of this process: an AtomicOutput and a group's
// staging directory for the same destination never share a name.
std::atomic<int> temporary_counter{0};

std::string TemporaryName(const fs::path& dir, const fs::path& final_path) {
  std::string name = ".";  // built by append: GCC 12's -Wrestrict misfires on "." + std::string&&
  name += final_path.filename().string();
  name += ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(temporary_counter++);
  return (dir / name).string();
}

fs::path DirectoryOf(const fs::path& p) { return p.parent_path().empty() ? fs::path(".") : p.parent_path(); }
}  // namespace

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
  temp_path_ = TemporaryName(dir, p);
  RemoveStaleTemporaries(dir.string());
  guard_ = std::make_unique<TemporaryGuard>(temp_path_);
}

AtomicOutput::~AtomicOutput() {
  if (!committed_) std::remove(temp_path_.c_str());
}

void AtomicOutput::Commit() {
  InterruptCleanupCriticalSection hold;  // the move and its record together
  if (std::rename(temp_path_.c_str(), final_path_.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    std::remove(temp_path_.c_str());
    throw Error(final_path_ + ": could not move the finished file into place (" + why + ")");
  }
  committed_ = true;
  NoteCommittedOutput(final_path_);
}

struct AtomicOutputGroup::Entry {
  std::string final_path;
  fs::path staging;                       // the hidden staging directory
  std::unique_ptr<TemporaryGuard> guard;  // removes it on interruption
  fs::path staged() const { return staging / fs::path(final_path).filename(); }
  fs::path previous() const { return staging / ".previous"; }  // hard link to the replaced file
};

AtomicOutputGroup::AtomicOutputGroup() = default;

AtomicOutputGroup::~AtomicOutputGroup() {
  std::error_code ec;
  for (const Entry& e : entries_) fs::remove_all(e.staging, ec);
}

std::string AtomicOutputGroup::Add(const std::string& final_path) {
  { AtomicOutput probe(final_path); }  // the destination's checks; writes nothing
  Entry e;
  e.final_path = final_path;
  e.staging = TemporaryName(DirectoryOf(final_path), final_path);
  std::error_code ec;
  if (!fs::create_directory(e.staging, ec)) {
    throw Error(final_path + ": cannot create the staging directory '" + e.staging.string() + "' (" +
                (ec ? ec.message() : std::string("it exists")) + ")");
  }
  e.guard = std::make_unique<TemporaryGuard>(e.staging.string());
  entries_.push_back(std::move(e));
  return entries_.back().staged().string();
}

void AtomicOutputGroup::Commit() {
  InterruptCleanupCriticalSection hold;
  std::error_code ec;
  for (const Entry& e : entries_) {
    if (!fs::is_regular_file(e.staged(), ec)) throw Error(e.final_path + ": was not written (nothing was replaced)");
    // A link, not a rename: the previous file stays at its place until the new one replaces it.
    if (fs::is_regular_file(e.final_path, ec)) {
      fs::create_hard_link(e.final_path, e.previous(), ec);
      if (ec) fs::copy_file(e.final_path, e.previous(), ec);
      if (ec) throw Error(e.final_path + ": cannot keep the previous file while replacing it (" + ec.message() + ")");
    }
  }
  for (size_t i = 0; i < entries_.size(); ++i) {
    if (std::rename(entries_[i].staged().c_str(), entries_[i].final_path.c_str()) == 0) continue;
    const std::string why = std::strerror(errno);
    for (size_t j = 0; j < i; ++j) {  // undo: the previous file back, or no file where there was none
      const Entry& e = entries_[j];
      if (fs::exists(e.previous(), ec)) {
        std::rename(e.previous().c_str(), e.final_path.c_str());
      } else {
        fs::remove(e.final_path, ec);
      }
    }
    throw Error(entries_[i].final_path + ": could not move the finished file into place (" + why +
                "); the other files of this output were put back as they were");
  }
  for (const Entry& e : entries_) NoteCommittedOutput(e.final_path);
}

std::string AtomicOutputGroup::Unstaged(std::string message) const {
  for (const Entry& e : entries_) {
    const std::string staged = e.staged().string();
    for (size_t at = message.find(staged); at != std::string::npos; at = message.find(staged, at + e.final_path.size()))
      message.replace(at, staged.size(), e.final_path);
  }
  return message;
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

// One read into a string sized from the file (a stream buffer copied into an ostringstream
// touches every byte three times: the cloud noise cache is 34 MB).
std::string ReadFile(const std::string& path) {
  std::ifstream f(path, std::ios::binary | std::ios::ate);
  if (!f) throw Error(path + ": cannot open for reading (" + std::strerror(errno) + ")");
  const std::streamoff size = f.tellg();
  if (size < 0) throw Error(path + ": cannot tell its size");
  std::string bytes(static_cast<size_t>(size), '\0');
  f.seekg(0);
  if (!f.read(bytes.data(), size)) throw Error(path + ": read failed (" + std::strerror(errno) + ")");
  if (f.peek() != std::char_traits<char>::eof()) throw Error(path + ": the file grew while it was read");
  return bytes;
}

}  // namespace skycal
