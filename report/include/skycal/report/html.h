// The HTML report's text primitives: escaping of any text read from files (names, decisions,
// warnings) and base64 data URIs for the embedded images, so the page is one file.
#pragma once
#include <string>
#include <string_view>

namespace skycal::report {

// Escapes &, <, >, " and ' (safe in element text and in double- or single-quoted attribute
// values). Bytes that are not valid UTF-8 become U+FFFD, so a non-UTF-8 file name cannot
// break the page's encoding.
std::string EscapeHtml(std::string_view text);

// RFC 4648 base64 (with padding).
std::string Base64Encode(std::string_view bytes);
// Decodes RFC 4648 base64 (padding optional, no whitespace). Throws skycal::Error on a
// character outside the alphabet or a bad length.
std::string Base64Decode(std::string_view text);

// "data:<mime>;base64,<...>".
std::string DataUri(std::string_view mime, std::string_view bytes);

// A number for the page: `digits` significant digits, "–" for NaN / missing.
std::string FormatNumber(double v, int digits = 4);

}  // namespace skycal::report
