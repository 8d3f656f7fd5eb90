#include "skycal/core/exr_io.h"

#include <Iex.h>
#include <ImfChannelList.h>
#include <ImfEnvmapAttribute.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfMultiPartInputFile.h>
#include <ImfPartType.h>
#include <ImfOutputFile.h>
#include <ImfStandardAttributes.h>
#include <ImfStringAttribute.h>
#include <ImfFloatAttribute.h>
#include <ImfVecAttribute.h>
#include <half.h>

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <utility>

#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "skycal/core/file_safety.h"
#include "skycal/core/output_kind.h"

namespace skycal {
namespace {

const char* const kChannels[3] = {"R", "G", "B"};

// What the readers accept before touching pixels: one flat (scanline or tiled) part whose
// data window is within the size limit. A multi-part file would silently mean part 0 and a
// deep file would be flattened in a way skycal does not choose, so both are refused with
// what the file holds. Returns the data window's width and height.
std::pair<int, int> CheckReadableLayout(const std::string& path) {
  Imf::MultiPartInputFile parts(path.c_str());
  if (parts.parts() > 1) {
    std::string names;
    for (int i = 0; i < parts.parts(); ++i) {
      const Imf::Header& h = parts.header(i);
      names += (i ? ", " : "") + (h.hasName() ? "'" + h.name() + "'" : "#" + std::to_string(i));
    }
    throw Error(path + ": a multi-part EXR with " + std::to_string(parts.parts()) + " parts (" + names +
                "): skycal reads single-part images; save the part you mean as its own file (e.g. exrmultipart -separate)");
  }
  const Imf::Header& h = parts.header(0);
  if (h.hasType() && Imf::isDeepData(h.type())) {
    throw Error(path + ": a deep EXR (" + h.type() + "): skycal reads flat images; flatten it first");
  }
  const Imath::Box2i dw = h.dataWindow();
  const long long w = static_cast<long long>(dw.max.x) - dw.min.x + 1, hh = static_cast<long long>(dw.max.y) - dw.min.y + 1;
  if (w <= 0 || hh <= 0) throw Error(path + ": empty data window");
  CheckImageSize(w, hh, path);
  // A data window that is not the display window is a crop or a render region: read as a
  // whole panorama it would put every pixel at the wrong direction. Refused, not guessed.
  const Imath::Box2i disp = h.displayWindow();
  if (dw != disp) {
    auto box = [](const Imath::Box2i& b) {
      return "(" + std::to_string(b.min.x) + ", " + std::to_string(b.min.y) + ") - (" + std::to_string(b.max.x) + ", " +
             std::to_string(b.max.y) + ")";
    };
    throw Error(path + ": the data window " + box(dw) + " differs from the display window " + box(disp) +
                ": a cropped or offset image (a render region) is not a whole frame; write the full display window "
                "(e.g. oiiotool IN --fullpixels -o OUT)");
  }
  return {static_cast<int>(w), static_cast<int>(hh)};
}

void AddAttributes(Imf::Header& header, const ExrAttributes& a) {
  for (const auto& [name, value] : a.strings) header.insert(name, Imf::StringAttribute(value));
  for (const auto& [name, value] : a.floats) header.insert(name, Imf::FloatAttribute(value));
  for (const auto& [name, v] : a.v3fs) {
    header.insert(name, Imf::V3fAttribute(Imath::V3f(v[0], v[1], v[2])));
  }
  if (a.envmap_latlong) Imf::addEnvmap(header, Imf::ENVMAP_LATLONG);
}

ExrAttributes CollectAttributes(const Imf::Header& header) {
  ExrAttributes a;
  for (auto it = header.begin(); it != header.end(); ++it) {
    const std::string name = it.name();
    // Required header attributes are the image's geometry, not metadata.
    if (name == "pixelAspectRatio" || name == "screenWindowWidth" || name == "screenWindowCenter") continue;
    const Imf::Attribute& attr = it.attribute();
    if (const auto* s = dynamic_cast<const Imf::StringAttribute*>(&attr)) {
      a.strings[name] = s->value();
    } else if (const auto* f = dynamic_cast<const Imf::FloatAttribute*>(&attr)) {
      a.floats[name] = f->value();
    } else if (const auto* v = dynamic_cast<const Imf::V3fAttribute*>(&attr)) {
      a.v3fs[name] = {v->value().x, v->value().y, v->value().z};
    } else {
      a.other_types[name] = attr.typeName();
    }
  }
  a.envmap_latlong = Imf::hasEnvmap(header) && Imf::envmap(header) == Imf::ENVMAP_LATLONG;
  return a;
}

// OpenEXR 3.1 allocates an attribute's value at the size the header claims before reading
// it (for a type it does not know), so a file of a few hundred bytes can make it allocate
// up to 2 GiB (fuzz/exr_frame_fuzzer: 1.6 GB, 38 s per file under ASan). This walks the
// header(s) first and refuses an attribute that claims more bytes than the file has left.
// Anything else odd (bad magic, unterminated names) is left to OpenEXR's own message.
// A chlist value: entries (name, 0, 16 bytes of type and sampling) up to an empty name,
// all within `size` bytes.
bool ChannelListFits(std::ifstream& f, int32_t size) {
  long long used = 0;
  for (;;) {
    long long name_length = 0;
    char c = 0;
    while (used + name_length < size && f.get(c) && c != 0) ++name_length;
    if (!f || c != 0 || used + name_length >= size) return false;
    used += name_length + 1;
    if (name_length == 0) return used == size;
    if (used + 16 > size) return false;
    f.seekg(16, std::ios::cur);
    used += 16;
  }
}

// Byte sizes of OpenEXR's fixed-size attribute types (the OpenEXR file layout
// documentation's attribute table); 0 for variable-size or unknown types.
int FixedAttributeSize(const std::string& type) {
  static const std::map<std::string, int> sizes = {
      {"box2i", 16},   {"box2f", 16}, {"chromaticities", 32}, {"compression", 1}, {"double", 8},
      {"envmap", 1},   {"float", 4},  {"int", 4},             {"keycode", 28},    {"lineOrder", 1},
      {"m33f", 36},    {"m33d", 72},  {"m44f", 64},           {"m44d", 128},      {"rational", 8},
      {"tiledesc", 9}, {"timecode", 8}, {"v2i", 8},           {"v2f", 8},         {"v2d", 16},
      {"v3i", 12},     {"v3f", 12},   {"v3d", 24},            {"deepImageState", 1}};
  const auto it = sizes.find(type);
  return it == sizes.end() ? 0 : it->second;
}

void CheckAttributeSizes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  f.seekg(0, std::ios::end);
  const long long file_size = f.tellg();
  f.seekg(0);
  unsigned char start[8];
  if (!f.read(reinterpret_cast<char*>(start), 8)) return;
  if (start[0] != 0x76 || start[1] != 0x2f || start[2] != 0x31 || start[3] != 0x01) return;
  const bool multipart = start[5] & 0x10;  // version field bit 12
  auto read_name = [&](std::string* s) {
    s->clear();
    for (char c; f.get(c);) {
      if (c == 0) return true;
      if (s->size() == 255) return false;  // longer than the format allows
      s->push_back(c);
    }
    return false;
  };
  for (;;) {  // one header, or a multi-part file's headers up to the empty one
    int attributes = 0;
    std::string name, type;
    while (read_name(&name) && !name.empty()) {
      unsigned char n[4];
      if (!read_name(&type) || !f.read(reinterpret_cast<char*>(n), 4)) return;
      const int32_t size = static_cast<int32_t>(n[0] | n[1] << 8 | n[2] << 16 | static_cast<uint32_t>(n[3]) << 24);
      const long long left = file_size - f.tellg();
      if (size < 0 || size > left) {
        throw Error(path + ": damaged OpenEXR header: attribute '" + name + "' claims " + std::to_string(size) +
                    " bytes, the file has " + std::to_string(left) + " left");
      }
      const std::streampos value_start = f.tellg();
      // Fixed-size types are read by OpenEXR at their own size whatever the declared size
      // says, so a mismatch shifts the parse of everything after it (fuzz/exr_frame_fuzzer:
      // a 465-byte file with a 3-byte box2i made OpenEXR allocate ~2 GB).
      if (const int fixed = FixedAttributeSize(type); fixed > 0 && fixed != size) {
        throw Error(path + ": damaged OpenEXR header: attribute '" + name + "' (" + type + ") declares " +
                    std::to_string(size) + " bytes, its type has " + std::to_string(fixed));
      }
      // OpenEXR parses these two types by their own contents, not the declared size, and
      // reads on past it when they disagree (fuzz/exr_frame_fuzzer: a chlist running past
      // its 51 bytes led OpenEXR to a 2 GB allocation), so their contents must fit it.
      if (type == "chlist" && !ChannelListFits(f, size)) {
        throw Error(path + ": damaged OpenEXR header: channel list '" + name + "' overruns its " + std::to_string(size) + " bytes");
      }
      if (type == "preview") {
        unsigned char wh[8];
        const bool ok = size >= 8 && f.read(reinterpret_cast<char*>(wh), 8);
        const auto le = [&](int at) { return static_cast<uint32_t>(wh[at] | wh[at + 1] << 8 | wh[at + 2] << 16) | static_cast<uint32_t>(wh[at + 3]) << 24; };
        if (!ok || 8 + 4ull * le(0) * le(4) != static_cast<unsigned long long>(size)) {
          throw Error(path + ": damaged OpenEXR header: preview '" + name + "' does not match its " + std::to_string(size) + " bytes");
        }
      }
      f.clear();
      f.seekg(value_start + static_cast<std::streamoff>(size));
      ++attributes;
    }
    if (!f || !multipart || attributes == 0) return;
  }
}

// Holds OpenEXR's own header checks to the readers' limits (exr_io.h), once per process,
// so a header's claims are refused before OpenEXR allocates its line-offset table or tile
// buffers from them.
void LimitOpenExrAllocations() {
  static const bool once = [] {
    // 4x our own side limit: a header between the two gets skycal's message (with its
    // size, CheckImageSize), one beyond is refused by OpenEXR before its line-offset
    // table (8 bytes per scanline block: <= 1 MiB here) is allocated.
    Imf::Header::setMaxImageSize(4 * kMaxExrSide, 4 * kMaxExrSide);
    Imf::Header::setMaxTileSize(kMaxExrTileSide, kMaxExrTileSide);
    return true;
  }();
  (void)once;
}

}  // namespace

// Declared in output_kind.h; here, where EXR headers are read.
void RefuseReplacingAPresetLut(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return;
  std::string lut;
  try {
    const Imf::InputFile file(path.c_str());
    if (const auto* a = file.header().findTypedAttribute<Imf::StringAttribute>("skycalLut")) lut = a->value();
  } catch (const std::exception&) {
    return;  // not a readable EXR: AtomicOutput's kind check speaks for it
  }
  if (!lut.empty()) {
    throw Error(path + ": refusing to replace it, it is a preset's LUT table ('" + lut +
                "'); the preset would no longer load (choose another output path)");
  }
}

ExrWriteReport WriteExrRGB(const std::string& path, const ImageRGB& image,
                           const ExrAttributes& attributes, ExrPixelType type) {
  return WriteExrRGBWithPlanes(path, image, {}, attributes, type);
}

ExrWriteReport WriteExrRGBWithPlanes(const std::string& path, const ImageRGB& image, const std::vector<ExrPlane>& planes,
                                     const ExrAttributes& attributes, ExrPixelType type) {
  for (const ExrPlane& p : planes) {
    if (p.values.size() != static_cast<size_t>(image.width) * image.height) {
      throw Error(path + ": channel '" + p.name + "' has " + std::to_string(p.values.size()) + " values, expected " +
                  std::to_string(static_cast<size_t>(image.width) * image.height));
    }
    if (p.name == "R" || p.name == "G" || p.name == "B" || p.name.empty()) {
      throw Error(path + ": extra channel name '" + p.name + "' is reserved or empty");
    }
  }
  if (image.empty()) throw Error(path + ": refusing to write an empty image");
  RefuseMismatchedExtension(path, ".exr", "an OpenEXR image");
  if (!attributes.strings.count("skycalLut")) RefuseReplacingAPresetLut(path);
  AtomicOutput out(path);
  ExrWriteReport report;
  const size_t n = static_cast<size_t>(image.width) * image.height;
  std::vector<half> halves;
  if (type == ExrPixelType::kHalf) {
    halves.resize(n * 3);
    for (size_t i = 0; i < n * 3; ++i) {
      // Finite values beyond FP16's range are clamped to +-65504 (HALF_MAX), never +-inf.
      const float v = image.pixels[i];
      const bool over = std::isfinite(v) && std::abs(v) > HALF_MAX;
      halves[i] = half(over ? std::copysign(HALF_MAX, v) : v);
      report.half_overflow_count += over ? 1 : 0;
    }
  }
  try {
    Imf::Header header(image.width, image.height);
    header.compression() = Imf::ZIP_COMPRESSION;
    // zlib's fastest level: float pixels and LUTs barely compress further at the default
    // level, which costs a calibration a tenth of its time in deflate.
    header.zipCompressionLevel() = 1;
    const Imf::PixelType pt = type == ExrPixelType::kHalf ? Imf::HALF : Imf::FLOAT;
    for (const char* c : kChannels) header.channels().insert(c, Imf::Channel(pt));
    AddAttributes(header, attributes);
    Imf::FrameBuffer fb;
    for (int c = 0; c < 3; ++c) {
      char* base = type == ExrPixelType::kHalf
                       ? reinterpret_cast<char*>(halves.data() + c)
                       : reinterpret_cast<char*>(const_cast<float*>(image.pixels.data()) + c);
      const size_t elem = type == ExrPixelType::kHalf ? sizeof(half) : sizeof(float);
      fb.insert(kChannels[c], Imf::Slice(pt, base, 3 * elem, 3 * elem * image.width));
    }
    for (const ExrPlane& p : planes) {
      header.channels().insert(p.name, Imf::Channel(Imf::FLOAT));
      fb.insert(p.name, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(const_cast<float*>(p.values.data())), sizeof(float),
                                   sizeof(float) * static_cast<size_t>(image.width)));
    }
    Imf::OutputFile file(out.temp_path().c_str(), header);
    file.setFrameBuffer(fb);
    file.writePixels(image.height);
  } catch (const std::exception& e) {
    throw Error(path + ": could not write EXR (" + e.what() + ")");
  }
  out.Commit();
  return report;
}

std::vector<float> ReadExrChannel(const std::string& path, const std::string& channel, int* width, int* height) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw Error(path + ": " + NotAFileWhy(path) + " (expected an OpenEXR image)");
  LimitOpenExrAllocations();
  CheckAttributeSizes(path);
  try {
    const auto [w, h] = CheckReadableLayout(path);
    Imf::InputFile file(path.c_str());
    const Imath::Box2i dw = file.header().dataWindow();
    if (!file.header().channels().findChannel(channel)) throw Error(path + ": channel '" + channel + "' missing");
    std::vector<float> v(static_cast<size_t>(w) * h);
    Imf::FrameBuffer fb;
    char* base = reinterpret_cast<char*>(v.data()) -
                 (static_cast<ptrdiff_t>(dw.min.x) + static_cast<ptrdiff_t>(dw.min.y) * w) * static_cast<ptrdiff_t>(sizeof(float));
    fb.insert(channel, Imf::Slice(Imf::FLOAT, base, sizeof(float), sizeof(float) * static_cast<size_t>(w)));
    file.setFrameBuffer(fb);
    file.readPixels(dw.min.y, dw.max.y);
    *width = w;
    *height = h;
    return v;
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw Error(path + ": not a readable OpenEXR image (" + e.what() + ")");
  }
}

bool IsOpenExrFile(const std::string& path) { return LeadingBytes(path, 4) == std::string("\x76\x2f\x31\x01", 4); }

ExrRGB ReadExrRGB(const std::string& path) { return ReadExrRGB(path, nullptr); }

ExrRGB ReadExrRGB(const std::string& path, const std::function<void(int width, int height)>& check_size) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw Error(path + ": " + NotAFileWhy(path) + " (expected an OpenEXR image)");
  }
  ExrRGB result;
  LimitOpenExrAllocations();
  CheckAttributeSizes(path);
  try {
    const auto [w, h] = CheckReadableLayout(path);
    if (check_size) check_size(w, h);
    Imf::InputFile file(path.c_str());
    const Imf::Header& header = file.header();
    const Imath::Box2i dw = header.dataWindow();
    for (auto it = header.channels().begin(); it != header.channels().end(); ++it) {
      result.channels.push_back(it.name());
    }
    for (const char* c : kChannels) {
      if (!header.channels().findChannel(c)) {
        std::string have;
        for (const auto& n : result.channels) have += (have.empty() ? "" : ",") + n;
        throw Error(path + ": channel '" + c + "' missing (expected R, G, B; file has " +
                    (have.empty() ? std::string("none") : have) + ")");
      }
    }
    result.image = ImageRGB(w, h);
    Imf::FrameBuffer fb;
    for (int c = 0; c < 3; ++c) {
      // Slice base is offset so that (dw.min.x, dw.min.y) lands on pixels[0].
      char* base = reinterpret_cast<char*>(result.image.pixels.data() + c) -
                   (static_cast<ptrdiff_t>(dw.min.x) + static_cast<ptrdiff_t>(dw.min.y) * w) *
                       3 * static_cast<ptrdiff_t>(sizeof(float));
      fb.insert(kChannels[c], Imf::Slice(Imf::FLOAT, base, 3 * sizeof(float),
                                         3 * sizeof(float) * static_cast<size_t>(w)));
    }
    file.setFrameBuffer(fb);
    file.readPixels(dw.min.y, dw.max.y);
    result.attributes = CollectAttributes(header);
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw Error(path + ": not a readable OpenEXR image (" + e.what() + ")");
  }
  return result;
}

ExrHeaderInfo ReadExrHeader(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw Error(path + ": " + NotAFileWhy(path) + " (expected an OpenEXR image)");
  LimitOpenExrAllocations();
  CheckAttributeSizes(path);
  ExrHeaderInfo info;
  try {
    const auto [w, h] = CheckReadableLayout(path);
    Imf::InputFile file(path.c_str());
    for (const char* c : kChannels) {
      if (!file.header().channels().findChannel(c)) throw Error(path + ": channel '" + c + "' missing (expected R, G, B)");
    }
    info.width = w;
    info.height = h;
    info.attributes = CollectAttributes(file.header());
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw Error(path + ": not a readable OpenEXR image (" + e.what() + ")");
  }
  return info;
}

void CheckImageSize(long long width, long long height, const std::string& what) {
  if (width < 1 || height < 1) {
    throw Error(what + ": " + std::to_string(width) + " x " + std::to_string(height) + " pixels: expected a positive size");
  }
  if (width > kMaxImageWidth || height > kMaxImageHeight || width * height > std::min(kMaxImagePixels, kMaxExrPixels)) {
    throw Error(what + ": " + std::to_string(width) + " x " + std::to_string(height) +
                " pixels is larger than skycal's limit of " + std::to_string(kMaxImageWidth) + " x " +
                std::to_string(kMaxImageHeight) + " (a 32K lat-long); downsample it first");
  }
}

}  // namespace skycal
