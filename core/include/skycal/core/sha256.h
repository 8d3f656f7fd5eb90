// SHA-256 (FIPS 180-4) of a file's bytes, as lowercase hex: the content hash recorded in
// provenance so a preset names exactly which references it was fitted to.
#pragma once
#include <string>

namespace skycal {
std::string Sha256Hex(const std::string& bytes);
std::string Sha256OfFile(const std::string& path);  // throws skycal::Error if unreadable
}  // namespace skycal
