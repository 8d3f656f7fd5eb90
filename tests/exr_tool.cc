// A small EXR helper for scripts/hostile_sweep.sh: counts the non-finite values of EXR files
// (every channel) and writes crafted frames (a constant, NaN or inf; a cropped data window).
//   skycal_exr_tool count FILE...      prints "FILE N" per file (N = non-finite values; -1: unreadable)
//   skycal_exr_tool fill FILE W H V    a W x H RGB float frame of value V (nan, inf, -inf or a number)
//   skycal_exr_tool crop FILE          a 64 x 32 display window holding a 32 x 32 data window
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "skycal/core/exr_io.h"

namespace {

long long CountNonFinite(const std::string& path) {
  try {
    const skycal::ExrRGB e = skycal::ReadExrRGB(path);
    long long n = 0;
    for (float v : e.image.pixels) n += std::isfinite(v) ? 0 : 1;
    for (const std::string& c : e.channels) {
      if (c == "R" || c == "G" || c == "B") continue;
      int w = 0, h = 0;
      for (float v : skycal::ReadExrChannel(path, c, &w, &h)) n += std::isfinite(v) ? 0 : 1;
    }
    return n;
  } catch (const std::exception&) {
    return -1;
  }
}

void WriteWindowed(const std::string& path, const Imath::Box2i& display, const Imath::Box2i& data, float value) {
  Imf::Header header(display, data);
  for (const char* c : {"R", "G", "B"}) header.channels().insert(c, Imf::Channel(Imf::FLOAT));
  const int w = data.max.x - data.min.x + 1, h = data.max.y - data.min.y + 1;
  std::vector<float> px(static_cast<size_t>(w) * h * 3, value);
  Imf::OutputFile file(path.c_str(), header);
  Imf::FrameBuffer fb;
  for (int c = 0; c < 3; ++c) {
    char* base = reinterpret_cast<char*>(px.data() + c) -
                 (static_cast<ptrdiff_t>(data.min.x) + static_cast<ptrdiff_t>(data.min.y) * w) * 3 * sizeof(float);
    fb.insert(std::string(1, "RGB"[c]), Imf::Slice(Imf::FLOAT, base, 3 * sizeof(float), 3 * sizeof(float) * w));
  }
  file.setFrameBuffer(fb);
  file.writePixels(h);
}

}  // namespace

int main(int argc, char** argv) {
  const std::string cmd = argc > 1 ? argv[1] : "";
  if (cmd == "count" && argc > 2) {
    int worst = 0;
    for (int i = 2; i < argc; ++i) {
      const long long n = CountNonFinite(argv[i]);
      std::printf("%s %lld\n", argv[i], n);
      worst = n != 0 ? 1 : worst;
    }
    return worst;
  }
  if (cmd == "fill" && argc == 6) {
    const int w = std::atoi(argv[3]), h = std::atoi(argv[4]);
    const float v = std::strtof(argv[5], nullptr);  // strtof reads nan, inf, -inf
    const Imath::Box2i box(Imath::V2i(0, 0), Imath::V2i(w - 1, h - 1));
    WriteWindowed(argv[2], box, box, v);
    return 0;
  }
  if (cmd == "crop" && argc == 3) {
    WriteWindowed(argv[2], Imath::Box2i(Imath::V2i(0, 0), Imath::V2i(63, 31)),
                  Imath::Box2i(Imath::V2i(0, 0), Imath::V2i(31, 31)), 1.0f);
    return 0;
  }
  std::fprintf(stderr, "usage: skycal_exr_tool count FILE... | fill FILE W H V | crop FILE\n");
  return 2;
}
