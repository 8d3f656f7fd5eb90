#include "cpu_renderer.h"

#include <algorithm>
#include <cmath>
#include <thread>
#include <vector>

#include "resolved_sky.h"

namespace skycal::render {
namespace {

class CpuRenderer final : public SkyRenderer {
 public:
  ImageRGB Render(const Preset& preset, const RenderRequest& request) override {
    const SkyParamsD params = ResolveSkyParams(preset, request);
    ImageRGB image(request.width, request.height);
    const CpuLutSource source{&preset.luts};
    const int threads = std::max(1u, std::min(std::thread::hardware_concurrency(), 64u));
    auto work = [&](int first_row) {
      CpuSkyModel m(source);
      for (int y = first_row; y < image.height; y += threads) {
        float* row = &image.pixels[image.index(0, y)];
        const double lat = m.latlong_latitude(y, image.height);
        const double sin_lat = std::sin(lat), cos_lat = std::cos(lat);
        for (int x = 0; x < image.width; ++x) {
          const double lon = m.latlong_longitude(x, image.width);
          const auto view = m.latlong_direction_from_trig(sin_lat, cos_lat, std::sin(lon), std::cos(lon));
          const auto l = m.radiance(view, params);
          row[3 * x + 0] = static_cast<float>(l.x);
          row[3 * x + 1] = static_cast<float>(l.y);
          row[3 * x + 2] = static_cast<float>(l.z);
        }
      }
    };
    std::vector<std::thread> pool;
    for (int t = 1; t < threads; ++t) pool.emplace_back(work, t);
    work(0);
    for (auto& t : pool) t.join();
    return image;
  }
  std::string Describe() const override {
    return "cpu reference (double precision, " + std::to_string(std::thread::hardware_concurrency()) + " threads)";
  }
};

}  // namespace

std::unique_ptr<SkyRenderer> CreateCpuRenderer() { return std::make_unique<CpuRenderer>(); }

}  // namespace skycal::render
