// Writes the seed corpus of exr_frame_fuzzer: tiny lat-long skies (a gradient and a bright
// sun spot, so sun detection has something to find) in the layouts a reader meets: float
// and half, scanline and tiled, several compressions, with and without sunDirection, a
// shifted data window, a non-2:1 image and a two-part file. Usage: make_exr_seeds OUT_DIR
#include <ImfChannelList.h>
#include <ImfEnvmapAttribute.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfMultiPartOutputFile.h>
#include <ImfOutputFile.h>
#include <ImfOutputPart.h>
#include <ImfPartType.h>
#include <ImfStandardAttributes.h>
#include <ImfTiledOutputFile.h>
#include <ImfVecAttribute.h>
#include <half.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace {

struct Layout {
  const char* name;
  int width, height;
  Imf::PixelType type;
  Imf::Compression compression;
  bool tiled, sun_attribute;
  int x0 = 0, y0 = 0;  // data window origin
};

// Sky radiance: brighter toward the horizon, a saturated spot for the sun at (w/4, h/4).
float Radiance(int x, int y, int w, int h, int c) {
  const float v = 1000.0f * (1.0f + static_cast<float>(y) / h) * (c == 2 ? 1.3f : 1.0f);
  return (x == w / 4 && y == h / 4) ? 60000.0f : v;
}

Imf::Header MakeHeader(const Layout& l) {
  Imath::Box2i dw(Imath::V2i(l.x0, l.y0), Imath::V2i(l.x0 + l.width - 1, l.y0 + l.height - 1));
  Imf::Header h(dw, dw);
  h.compression() = l.compression;
  for (const char* c : {"R", "G", "B"}) h.channels().insert(c, Imf::Channel(l.type));
  Imf::addEnvmap(h, Imf::ENVMAP_LATLONG);
  if (l.sun_attribute) h.insert("sunDirection", Imf::V3fAttribute(Imath::V3f(0.0f, 0.7071f, 0.7071f)));
  if (l.tiled) h.setTileDescription(Imf::TileDescription(8, 8, Imf::ONE_LEVEL));
  return h;
}

// Pixels of one layout, interleaved RGB in the layout's pixel type; `fb` points into them.
struct Pixels {
  std::vector<float> f;
  std::vector<half> h;
  Imf::FrameBuffer fb;
};

void Fill(const Layout& l, Pixels& p) {
  const size_t n = static_cast<size_t>(l.width) * l.height * 3;
  p.f.resize(n);
  p.h.resize(n);
  for (int y = 0; y < l.height; ++y)
    for (int x = 0; x < l.width; ++x)
      for (int c = 0; c < 3; ++c) {
        const size_t i = (static_cast<size_t>(y) * l.width + x) * 3 + c;
        p.f[i] = Radiance(x, y, l.width, l.height, c);
        p.h[i] = half(p.f[i]);
      }
  const size_t elem = l.type == Imf::HALF ? sizeof(half) : sizeof(float);
  char* base0 = l.type == Imf::HALF ? reinterpret_cast<char*>(p.h.data()) : reinterpret_cast<char*>(p.f.data());
  const ptrdiff_t origin = (static_cast<ptrdiff_t>(l.y0) * l.width + l.x0) * 3 * static_cast<ptrdiff_t>(elem);
  const char* names[3] = {"R", "G", "B"};
  for (int c = 0; c < 3; ++c) {
    p.fb.insert(names[c], Imf::Slice(l.type, base0 + c * elem - origin, 3 * elem, 3 * elem * l.width));
  }
}

void Write(const std::string& dir, const Layout& l) {
  Pixels p;
  Fill(l, p);
  const std::string path = dir + "/" + l.name + ".exr";
  const Imf::Header h = MakeHeader(l);
  if (l.tiled) {
    Imf::TiledOutputFile f(path.c_str(), h);
    f.setFrameBuffer(p.fb);
    f.writeTiles(0, f.numXTiles() - 1, 0, f.numYTiles() - 1);
  } else {
    Imf::OutputFile f(path.c_str(), h);
    f.setFrameBuffer(p.fb);
    f.writePixels(l.height);
  }
  std::printf("%s\n", path.c_str());
}

// Two scanline parts (same display window: a multi-part file requires it); readers that
// open Imf::InputFile see part 0.
void WriteMultiPart(const std::string& dir) {
  const Layout a{"multipart_a", 8, 4, Imf::HALF, Imf::ZIP_COMPRESSION, false, true};
  const Layout b{"multipart_b", 8, 4, Imf::FLOAT, Imf::RLE_COMPRESSION, false, false};
  std::vector<Imf::Header> headers = {MakeHeader(a), MakeHeader(b)};
  headers[0].setName("sky");
  headers[0].setType(Imf::SCANLINEIMAGE);
  headers[1].setName("mask");
  headers[1].setType(Imf::SCANLINEIMAGE);
  const std::string path = dir + "/multipart.exr";
  Imf::MultiPartOutputFile f(path.c_str(), headers.data(), 2);
  Pixels pa, pb;
  Fill(a, pa);
  Fill(b, pb);
  Imf::OutputPart p0(f, 0), p1(f, 1);
  p0.setFrameBuffer(pa.fb);
  p0.writePixels(a.height);
  p1.setFrameBuffer(pb.fb);
  p1.writePixels(b.height);
  std::printf("%s\n", path.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_exr_seeds OUT_DIR\n");
    return 2;
  }
  const std::string dir = argv[1];
  const Layout layouts[] = {
      {"float_8x4_sun_zip", 8, 4, Imf::FLOAT, Imf::ZIP_COMPRESSION, false, true},
      {"half_16x8_nosun_rle", 16, 8, Imf::HALF, Imf::RLE_COMPRESSION, false, false},
      {"half_16x8_sun_piz", 16, 8, Imf::HALF, Imf::PIZ_COMPRESSION, false, true},
      {"half_16x8_nosun_dwab", 16, 8, Imf::HALF, Imf::DWAB_COMPRESSION, false, false},
      {"float_8x4_nosun_none", 8, 4, Imf::FLOAT, Imf::NO_COMPRESSION, false, false},
      {"float_16x8_sun_tiled", 16, 8, Imf::FLOAT, Imf::ZIP_COMPRESSION, true, true},
      {"half_16x8_nosun_tiled", 16, 8, Imf::HALF, Imf::NO_COMPRESSION, true, false},
      {"float_8x4_sun_window", 8, 4, Imf::FLOAT, Imf::ZIPS_COMPRESSION, false, true, -3, 5},
      {"float_8x8_not_latlong", 8, 8, Imf::FLOAT, Imf::NO_COMPRESSION, false, true},
  };
  for (const Layout& l : layouts) Write(dir, l);
  WriteMultiPart(dir);
  return 0;
}
