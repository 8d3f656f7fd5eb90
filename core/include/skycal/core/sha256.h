// SHA-256 (FIPS 180-4; computed by nettle) of bytes or a file, as 64 lowercase hex digits:
// the content hash recorded in provenance so a preset names exactly which references it was
// fitted to.
#pragma once
#include <string>
#include <string_view>

namespace skycal {
std::string Sha256Hex(std::string_view bytes);
std::string Sha256OfFile(const std::string& path);  // throws skycal::Error if unreadable
}  // namespace skycal
