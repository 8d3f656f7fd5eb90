#include "skycal/core/file_safety.h"
#include "skycal/core/output_kind.h"

#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <filesystem>
#include <fstream>

#include "skycal/core/error.h"

namespace skycal {
namespace fs = std::filesystem;

namespace {

std::string LowerExtension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

// Empty when the existing regular file at `path` is of the kind its extension names.
std::string KindMismatch(const std::string& path, const std::string& ext) {
  if (ext == ".exr") return LeadingBytes(path, 4) == std::string("\x76\x2f\x31\x01", 4) ? "" : "not an OpenEXR file";
  if (ext == ".png") return LeadingBytes(path, 8) == "\x89PNG\r\n\x1a\n" ? "" : "not a PNG file";
  if (ext == ".json") {
    const std::string h = LeadingBytes(path, 4096);
    const size_t at = h.find_first_not_of(" \t\r\n");
    return at != std::string::npos && (h[at] == '{' || h[at] == '[') ? "" : "not a JSON file";
  }
  if (ext == ".html" || ext == ".htm") {
    // The report's first lines hold the marker; 64 KiB covers the style sheet before it.
    return LeadingBytes(path, 65536).find("Written by skycal") != std::string::npos ? "" : "an HTML page skycal did not write";
  }
  return "";
}

}  // namespace

std::string LeadingBytes(const std::string& path, size_t n) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return "";
  std::ifstream f(path, std::ios::binary);
  std::string s(n, '\0');
  f.read(s.data(), static_cast<std::streamsize>(n));
  s.resize(static_cast<size_t>(std::max<std::streamsize>(f.gcount(), 0)));
  return s;
}

std::string NotAFileWhy(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    if (errno == ELOOP) return "a symlink loop";
    if (errno == EACCES) return "permission denied";
    struct stat lst {};
    return ::lstat(path.c_str(), &lst) == 0 ? "a dangling symlink (its target does not exist)" : "no such file";
  }
  if (S_ISDIR(st.st_mode)) return "is a directory";
  return "is not a regular file (a FIFO, socket or device)";
}

void RefuseReplacingAnotherKind(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return;  // nothing there (or a dangling link): nothing lost
  if (S_ISDIR(st.st_mode)) return;             // the writers' own checks name directories
  if (!S_ISREG(st.st_mode)) {
    throw Error(path + ": refusing to replace it, it exists and is not a regular file (a FIFO, socket or device); "
                       "choose another output path");
  }
  const std::string ext = LowerExtension(path);
  const std::string mismatch = KindMismatch(path, ext);
  if (!mismatch.empty()) {
    throw Error(path + ": refusing to replace it, the existing file is " + mismatch + " (its name says " + ext +
                "); remove it or choose another output path");
  }
}

void RefuseMismatchedExtension(const std::string& path, const std::string& extension, const std::string& what) {
  const std::string ext = LowerExtension(path);
  if (ext == extension || (extension == ".html" && ext == ".htm")) return;
  for (const char* known : {".exr", ".png", ".jpg", ".jpeg", ".tif", ".tiff", ".hdr", ".bmp", ".webp", ".svg", ".json",
                            ".html", ".htm", ".csv", ".txt", ".md", ".cube", ".ocio", ".yaml"}) {
    if (ext == known) {
      throw Error(path + ": " + what + " is written here, but the name ends in " + ext + " (expected a name ending in " +
                  extension + ")");
    }
  }
}

void RequireExtension(const std::string& role, const std::string& path, const std::vector<std::string>& extensions,
                      const std::string& what) {
  const std::string ext = LowerExtension(path);
  for (const std::string& e : extensions) {
    if (ext == e) return;
  }
  std::string list;
  for (const std::string& e : extensions) list += (list.empty() ? "" : " or ") + e;
  throw Error(role + " " + path + ": " + what + " is written there, expected a name ending in " + list);
}

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
