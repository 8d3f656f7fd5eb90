// Outputs never replace inputs. Every verb lists the files it reads and the files (or the
// directory) it will write, and asks here before writing anything: two paths name the
// same file when they resolve to the same device and inode (symlinks followed, hard
// links included), so `--out ball.exr` over `--image ./x/../ball.exr` or a symlink to it
// is caught as well as the literal repeat.
#pragma once
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

}  // namespace skycal
