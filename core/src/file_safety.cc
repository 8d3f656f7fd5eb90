#include "skycal/core/file_safety.h"

#include <sys/stat.h>

#include <filesystem>

#include "skycal/core/error.h"

namespace skycal {
namespace fs = std::filesystem;

bool SameFile(const std::string& a, const std::string& b) {
  struct stat sa {}, sb {};
  if (::stat(a.c_str(), &sa) != 0 || ::stat(b.c_str(), &sb) != 0) return false;
  return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

void RefuseOutputsOverInputs(const std::vector<NamedPath>& outputs, const std::vector<NamedPath>& inputs) {
  for (const NamedPath& out : outputs) {
    for (const NamedPath& in : inputs) {
      if (!SameFile(out.path, in.path)) continue;
      throw Error(out.role + " " + out.path + " is the same file as " + in.role + " " + in.path +
                  ": refusing to overwrite an input (choose another output path)");
    }
  }
}

namespace {

// The path with every existing prefix resolved (symlinks, "..", "."), absolute.
fs::path Resolved(const std::string& p) {
  std::error_code ec;
  fs::path r = fs::weakly_canonical(fs::absolute(p), ec);
  return ec ? fs::absolute(p).lexically_normal() : r;
}

bool IsInside(const fs::path& child, const fs::path& dir) {
  auto c = child.begin();
  for (auto d = dir.begin(); d != dir.end(); ++d, ++c) {
    if (d->empty()) continue;  // a trailing separator
    if (c == child.end() || *c != *d) return false;
  }
  return true;
}

}  // namespace

void RefuseInputsInsideDirectory(const NamedPath& dir, const std::vector<NamedPath>& inputs) {
  const fs::path d = Resolved(dir.path);
  for (const NamedPath& in : inputs) {
    if (in.path.empty()) continue;
    if (!IsInside(Resolved(in.path), d)) continue;
    throw Error(dir.role + " " + dir.path + " holds " + in.role + " " + in.path +
                ": refusing to replace a directory that an input lives in (choose another output directory)");
  }
}

}  // namespace skycal
