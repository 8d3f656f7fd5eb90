// SHA-256 by nettle (Debian's nettle-dev): a maintained, tested implementation rather than
// our own rounds; this file only adapts it to std::string in, lowercase hex out.
#include "skycal/core/sha256.h"

#include <nettle/sha2.h>

#include <cstdint>

#include "skycal/core/atomic_file.h"

namespace skycal {

std::string Sha256Hex(std::string_view bytes) {
  sha256_ctx ctx;
  sha256_init(&ctx);
  sha256_update(&ctx, bytes.size(), reinterpret_cast<const uint8_t*>(bytes.data()));
  uint8_t digest[SHA256_DIGEST_SIZE];
  sha256_digest(&ctx, SHA256_DIGEST_SIZE, digest);
  static constexpr char kHexDigits[] = "0123456789abcdef";
  std::string hex;
  hex.reserve(2 * SHA256_DIGEST_SIZE);
  for (uint8_t b : digest) {
    hex.push_back(kHexDigits[b >> 4]);
    hex.push_back(kHexDigits[b & 0xf]);
  }
  return hex;
}

std::string Sha256OfFile(const std::string& path) { return Sha256Hex(ReadFile(path)); }

}  // namespace skycal
