// Radiance pictures (.hdr, .pic): the RGBE format many HDR skies are published in beside
// OpenEXR (Poly Haven offers both). Format: Greg Ward, "Real Pixels", Graphics Gems II
// (1991), and the Radiance reference's "Radiance file formats" (the header lines, the
// resolution string, and the scanlines: flat, or the adaptive run-length scheme of four
// separate component runs per scanline that Radiance's own writer uses for widths 8 to
// 32767). The original scheme's repeat pixels (1, 1, 1, n), which that writer stopped
// producing when the adaptive scheme replaced it, are read as the pixels they are, as
// Walter's rgbe.c and stb_image read them.
//
// Why a reader of the project's own and not a library's: OpenCV's imgcodecs reads RGBE but
// linking it costs every skycal process its start-up (about 0.13 s on these machines: 141
// shared libraries); Debian bookworm's stb_image 2.27 loops forever on a scanline whose run
// length is 0 at the end of a truncated file (CVE-2021-42715, unpatched in its libstb);
// OpenImageIO pulls in dozens of codecs. The format is small enough to read here, under the
// same fuzz harness and size limits as the EXR readers (fuzz/radiance_picture_fuzzer.cc).
//
// Values: each pixel is (mantissa + 0.5) x 2^(exponent - 136) per channel (the centre of the
// bin a truncating writer's byte stands for, as Radiance's own reader decodes it), divided by
// the product of the header's EXPOSURE lines and, per channel, its COLORCORR lines (the
// format's rule for recovering the values before those multipliers were applied). The RGB
// primaries are read as Rec.709, the project's working space, as HDR publishers write them;
// a PRIMARIES line that says otherwise is reported, not converted.
#pragma once
#include <array>
#include <string>
#include <vector>

#include "skycal/core/image.h"

namespace skycal {

struct RadianceHeader {
  std::string format = "32-bit_rle_rgbe";        // the FORMAT line (absent: rgbe, the format's default)
  double exposure = 1.0;                         // product of the EXPOSURE lines
  std::array<double, 3> colour_correction{1.0, 1.0, 1.0};  // product of the COLORCORR lines
  std::string primaries;                         // the PRIMARIES line's value, empty when absent
  std::string resolution;                        // the resolution string as written, e.g. "-Y 256 +X 512"
};

struct RadiancePicture {
  ImageRGB image;  // row 0 at the top (a "+Y" picture is flipped on reading)
  RadianceHeader header;
  std::vector<std::string> warnings;  // what was read but not applied (PRIMARIES other than Rec.709)
};

// True when the file starts with the Radiance magic ("#?RADIANCE" or "#?RGBE", or any "#?"
// program name, as the format allows). False for an unreadable file or anything but a
// regular file (a FIFO is never opened): the caller's reader then reports it.
bool IsRadiancePicture(const std::string& path);

// Reads the picture. Throws skycal::Error naming the file and what is wrong: not a Radiance
// picture, a header over 64 KiB or without its blank line, FORMAT other than
// 32-bit_rle_rgbe (32-bit_rle_xyze pictures are not read), an EXPOSURE or COLORCORR that is
// not a positive number (or whose lines multiply to no positive normal number, or divide a
// pixel beyond a float), a resolution string other than "-Y H +X W" or "+Y H +X W" (the
// rotated and mirrored layouts are refused), a size over core/image.h's limit or more
// pixels than the file's bytes can encode (checked before anything is allocated), and a
// scanline that is truncated or whose runs overrun it.
RadiancePicture ReadRadiancePicture(const std::string& path);
// The same from bytes in memory (`name` stands for the file in messages): the fuzz harness.
RadiancePicture DecodeRadiancePicture(const std::vector<unsigned char>& bytes, const std::string& name);

}  // namespace skycal
