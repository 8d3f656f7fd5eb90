// Radiance pictures (RGBE): the reader of radiance_io.h.
#include "skycal/core/radiance_io.h"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

#include "skycal/core/error.h"
#include "skycal/core/file_safety.h"
#include "skycal/core/format_number.h"

namespace skycal {
namespace {

constexpr size_t kMaxHeaderBytes = 64 * 1024;
// The adaptive run-length scheme covers widths 8..0x7fff; others are always flat.
constexpr int kMinRunLengthWidth = 8, kMaxRunLengthWidth = 0x7fff;
constexpr int kMaxRun = 127;  // a run's count byte is 128 + n, n <= 127

struct Cursor {
  const std::vector<unsigned char>& bytes;
  size_t at = 0;
  size_t left() const { return bytes.size() - at; }
};

// One header line (without its newline); false at the end of the bytes or past the limit.
bool NextLine(Cursor* c, std::string* line) {
  line->clear();
  while (c->at < c->bytes.size() && c->at < kMaxHeaderBytes) {
    const char ch = static_cast<char>(c->bytes[c->at++]);
    if (ch == '\n') return true;
    line->push_back(ch);
  }
  return false;
}

// A positive finite number from the text after "NAME=", else an error naming the line.
double PositiveNumber(const std::string& text, const std::string& name, const std::string& line) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || !std::isfinite(v) || !(v > 0.0))
    throw Error(name + ": header line '" + line + "' (expected a positive number)");
  return v;
}

void ReadHeaderLine(const std::string& line, const std::string& name, RadianceHeader* h) {
  if (line.rfind("FORMAT=", 0) == 0) {
    h->format = line.substr(7);
    while (!h->format.empty() && (h->format.back() == ' ' || h->format.back() == '\r')) h->format.pop_back();
    if (h->format != "32-bit_rle_rgbe")
      throw Error(name + ": FORMAT=" + h->format + " (expected 32-bit_rle_rgbe; CIE XYZ pictures are not read)");
  } else if (line.rfind("EXPOSURE=", 0) == 0) {
    h->exposure *= PositiveNumber(line.substr(9), name, line);
  } else if (line.rfind("COLORCORR=", 0) == 0) {
    std::istringstream s(line.substr(10));
    for (double& c : h->colour_correction) {
      std::string word;
      s >> word;
      c *= PositiveNumber(word, name, line);
    }
  } else if (line.rfind("PRIMARIES=", 0) == 0) {
    h->primaries = line.substr(10);
  }
  // The lines multiply: their product must stay a usable divisor too.
  for (double m : {h->exposure, h->colour_correction[0], h->colour_correction[1], h->colour_correction[2]})
    if (!std::isnormal(m))
      throw Error(name + ": header line '" + line + "' makes the product of the EXPOSURE or COLORCORR lines " +
                  FormatNumber(m) + " (expected a positive normal number)");
}

// The resolution string: "-Y H +X W" (top row first) or "+Y H +X W" (bottom row first).
void ReadResolution(const std::string& line, const std::string& name, int* width, int* height, bool* bottom_up) {
  std::istringstream s(line);
  std::string y_axis, x_axis, extra;
  long long h = 0, w = 0;
  if (!(s >> y_axis >> h >> x_axis >> w) || (s >> extra) || (y_axis != "-Y" && y_axis != "+Y") || x_axis != "+X")
    throw Error(name + ": resolution string '" + line +
                "' (expected '-Y H +X W' or '+Y H +X W'; rotated or mirrored pictures are not read)");
  CheckImageSize(w, h, name);
  *width = static_cast<int>(w);
  *height = static_cast<int>(h);
  *bottom_up = y_axis == "+Y";
}

RadianceHeader ReadHeader(Cursor* c, const std::string& name, int* width, int* height, bool* bottom_up) {
  std::string line;
  if (!NextLine(c, &line) || line.rfind("#?", 0) != 0)
    throw Error(name + ": not a Radiance picture (expected its first line to start with '#?', e.g. #?RADIANCE)");
  RadianceHeader h;
  while (true) {
    if (!NextLine(c, &line))
      throw Error(name + ": the header has no blank line within its first " + std::to_string(kMaxHeaderBytes / 1024) +
                  " KiB (truncated, or not a Radiance picture)");
    if (line.empty() || line == "\r") break;
    ReadHeaderLine(line, name, &h);
  }
  if (!NextLine(c, &line)) throw Error(name + ": no resolution string after the header (truncated)");
  h.resolution = line;
  ReadResolution(line, name, width, height, bottom_up);
  return h;
}

// The fewest bytes a scanline of `width` pixels can take: the run-length scheme's 4-byte
// marker and runs of at most 127 in each of 4 components, else 4 bytes a pixel.
size_t MinScanlineBytes(int width) {
  if (width < kMinRunLengthWidth || width > kMaxRunLengthWidth) return 4 * static_cast<size_t>(width);
  return 4 + 4 * 2 * static_cast<size_t>((width + kMaxRun - 1) / kMaxRun);
}

// One scanline of the adaptive run-length scheme (after its 4-byte marker) into rgbe.
void ReadRunLengthScanline(Cursor* c, int width, std::vector<unsigned char>* rgbe, const std::string& where) {
  for (int k = 0; k < 4; ++k) {
    int i = 0;
    while (i < width) {
      if (c->left() < 1) throw Error(where + " is truncated");
      int count = c->bytes[c->at++];
      const bool run = count > 128;
      if (run) count -= 128;
      if (count == 0 || count > width - i)
        throw Error(where + ": a run of " + std::to_string(count) + " at pixel " + std::to_string(i) + " of " +
                    std::to_string(width) + " (expected 1.." + std::to_string(width - i) + ")");
      if (c->left() < (run ? 1u : static_cast<size_t>(count))) throw Error(where + " is truncated");
      for (int z = 0; z < count; ++z, ++i) (*rgbe)[4 * i + k] = c->bytes[run ? c->at : c->at + z];
      c->at += run ? 1 : count;
    }
  }
}

// One scanline, run-length encoded or flat, as 4 bytes a pixel.
void ReadScanline(Cursor* c, int width, std::vector<unsigned char>* rgbe, const std::string& where) {
  const bool can_run = width >= kMinRunLengthWidth && width <= kMaxRunLengthWidth;
  if (can_run && c->left() >= 4 && c->bytes[c->at] == 2 && c->bytes[c->at + 1] == 2 && !(c->bytes[c->at + 2] & 0x80)) {
    const int length = (c->bytes[c->at + 2] << 8) | c->bytes[c->at + 3];
    if (length != width)
      throw Error(where + ": its run-length marker gives " + std::to_string(length) + " pixels (expected " +
                  std::to_string(width) + ")");
    c->at += 4;
    ReadRunLengthScanline(c, width, rgbe, where);
    return;
  }
  const size_t n = 4 * static_cast<size_t>(width);
  if (c->left() < n) throw Error(where + " is truncated");
  std::copy(c->bytes.begin() + static_cast<std::ptrdiff_t>(c->at), c->bytes.begin() + static_cast<std::ptrdiff_t>(c->at + n),
            rgbe->begin());
  c->at += n;
}

// A value beyond float (a huge pixel over a tiny EXPOSURE) is refused, not stored as Inf.
void StoreScanline(const std::vector<unsigned char>& rgbe, const RadianceHeader& h, int row, ImageRGB* image,
                   const std::string& where) {
  for (int x = 0; x < image->width; ++x) {
    const unsigned char* p = &rgbe[4 * static_cast<size_t>(x)];
    for (int ch = 0; ch < 3; ++ch) {
      const double v = p[3] == 0 ? 0.0 : std::ldexp(p[ch] + 0.5, p[3] - 136);
      const float f = static_cast<float>(v / (h.exposure * h.colour_correction[ch]));
      if (!std::isfinite(f))
        throw Error(where + ": pixel " + std::to_string(x) + " is " + FormatNumber(v) + " / (EXPOSURE x COLORCORR " +
                    FormatNumber(h.exposure * h.colour_correction[ch]) + "), beyond a float");
      image->at(x, row, ch) = f;
    }
  }
}

// Rec.709's primaries and D65 white as a PRIMARIES line gives them (x, y of R, G, B, white).
bool IsRec709(const std::string& primaries) {
  constexpr double kRec709[8] = {0.640, 0.330, 0.300, 0.600, 0.150, 0.060, 0.3127, 0.3290};
  std::istringstream s(primaries);
  for (double want : kRec709) {
    double v = 0.0;
    if (!(s >> v) || std::abs(v - want) > 0.002) return false;
  }
  return true;
}

}  // namespace

bool IsRadiancePicture(const std::string& path) { return LeadingBytes(path, 2) == "#?"; }

RadiancePicture DecodeRadiancePicture(const std::vector<unsigned char>& bytes, const std::string& name) {
  Cursor c{bytes};
  RadiancePicture pic;
  int width = 0, height = 0;
  bool bottom_up = false;
  pic.header = ReadHeader(&c, name, &width, &height, &bottom_up);
  const size_t need = MinScanlineBytes(width) * static_cast<size_t>(height);
  if (c.left() < need)
    throw Error(name + ": " + std::to_string(width) + " x " + std::to_string(height) + " pixels need at least " +
                std::to_string(need) + " bytes of scanlines, the file has " + std::to_string(c.left()) + " (truncated)");
  pic.image = ImageRGB(width, height);
  std::vector<unsigned char> rgbe(4 * static_cast<size_t>(width));
  for (int y = 0; y < height; ++y) {
    const std::string where = name + ": scanline " + std::to_string(y);
    ReadScanline(&c, width, &rgbe, where);
    StoreScanline(rgbe, pic.header, bottom_up ? height - 1 - y : y, &pic.image, where);
  }
  if (!pic.header.primaries.empty() && !IsRec709(pic.header.primaries))
    pic.warnings.push_back(name + ": PRIMARIES=" + pic.header.primaries +
                           " is not Rec.709's; the RGB values are read as Rec.709 (not converted)");
  return pic;
}

RadiancePicture ReadRadiancePicture(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::exists(path, ec) && !std::filesystem::is_regular_file(path, ec))
    throw Error(path + ": " + NotAFileWhy(path) + " (expected a Radiance picture)");
  std::ifstream f(path, std::ios::binary);
  if (!f) throw Error(path + ": cannot open for reading");
  std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  if (f.bad()) throw Error(path + ": read error");
  return DecodeRadiancePicture(bytes, path);
}

}  // namespace skycal
