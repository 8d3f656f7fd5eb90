// Outputs never replace inputs. Every verb lists the files it reads and the files (or the
// directory) it will write, and asks here before writing anything: two paths name the
// same file when they resolve to the same device and inode (symlinks followed, hard
// links included), so `--out ball.exr` over `--image ./x/../ball.exr` or a symlink to it
// is caught as well as the literal repeat.
#pragma once
#include <cstddef>
#include <string>
#include <vector>

namespace skycal {

// A path and what it is to the user, for messages: "--image", "CaptureOptions::out", "preset LUT luts.rayleigh".
struct NamedPath {
  std::string role;
  std::string path;
};

// Throws skycal::Error naming both roles and paths when an output is the same file as an
// input. Outputs that do not exist yet cannot be an input and pass.
void RefuseOutputsOverInputs(const std::vector<NamedPath>& outputs, const std::vector<NamedPath>& inputs);

// Throws when an input lies inside `dir` (resolved, symlinks followed): a verb that replaces
// `dir` as a whole would delete or replace what it reads.
void RefuseInputsInsideDirectory(const NamedPath& dir, const std::vector<NamedPath>& inputs);

// True when both paths exist and are the same file (device and inode).
bool SameFile(const std::string& a, const std::string& b);

// The first `n` bytes of a regular file (fewer when it is shorter), for a format's magic
// number; empty for anything else. A FIFO or a device is never opened: a read there could
// wait forever.
std::string LeadingBytes(const std::string& path, size_t n);

// Why `path` is not a readable regular file, in the user's terms ("is a directory", "is not a
// regular file (a FIFO, socket or device)", "a dangling symlink ...", "no such file" only when
// nothing is there), for a reader's refusal.
std::string NotAFileWhy(const std::string& path);

}  // namespace skycal
