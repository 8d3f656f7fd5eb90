// The CPU cloud renderers: the shared model in double (the reference) or float (the
// shader's arithmetic, for the per-pixel parity test), rows interleaved over threads.
#include <algorithm>
#include <atomic>
#include <thread>

#include "resolved_clouds.h"

namespace skycal::clouds {
namespace {

template <typename Model, typename Shade>
CloudImage RenderWith(const CpuCloudTextures& textures, const Shade& shade, int width, int height, int threads) {
  using S = typename Model::Scalar;
  CloudImage image;
  image.radiance = ImageRGB(width, height);
  image.transmittance.assign(static_cast<size_t>(width) * height, 1.0f);
  const LatLongTrig trig = MakeLatLongTrig(width, height);
  std::atomic<long long> samples{0};
  auto work = [&](int first_row) {
    Model m(textures);
    long long n = 0;
    for (int y = first_row; y < height; y += threads) {
      const S sin_lat = S(trig.sin_lat[y]), cos_lat = S(trig.cos_lat[y]);
      for (int x = 0; x < width; ++x) {
        // The shader's arithmetic: float table entries multiplied in the scalar type.
        const typename Model::vec3 view(S(trig.sin_lon[x]) * cos_lat, sin_lat, S(trig.cos_lon[x]) * cos_lat);
        const auto r = m.cloud_march(view, shade);
        const size_t i = static_cast<size_t>(y) * width + x;
        image.radiance.pixels[3 * i + 0] = static_cast<float>(r.radiance.x);
        image.radiance.pixels[3 * i + 1] = static_cast<float>(r.radiance.y);
        image.radiance.pixels[3 * i + 2] = static_cast<float>(r.radiance.z);
        image.transmittance[i] = static_cast<float>(r.transmittance);
        n += r.full_samples;
      }
    }
    samples += n;
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(work, t);
  work(0);
  for (auto& t : pool) t.join();
  image.full_samples = samples;
  return image;
}

class CpuCloudRenderer final : public CloudRenderer {
 public:
  CpuCloudRenderer(CloudPrecision precision, int threads)
      : precision_(precision),
        threads_(threads > 0 ? threads : static_cast<int>(std::max(1u, std::min(std::thread::hardware_concurrency(), 64u)))) {}

  CloudImage Render(const CloudScene& scene, const CloudRenderRequest& request) override {
    const CloudShadeD shade = ResolveCloudShade(scene, request);
    const CpuCloudTextures textures(*scene.noise, *scene.weather);
    const int threads = std::min(threads_, request.height);
    if (precision_ == CloudPrecision::kDouble) {
      return RenderWith<CloudModelD>(textures, shade, request.width, request.height, threads);
    }
    return RenderWith<CloudModelF>(textures, ToFloat(shade), request.width, request.height, threads);
  }
  std::string Describe() const override {
    return std::string("cpu clouds (") + (precision_ == CloudPrecision::kDouble ? "double reference" : "float") + ", " +
           std::to_string(threads_) + " threads)";
  }

 private:
  CloudPrecision precision_;
  int threads_;
};

}  // namespace

std::vector<CloudImage> CloudRenderer::RenderEach(const CloudScene& scene, const std::vector<const CloudParams*>& params,
                                                  const CloudRenderRequest& request) {
  std::vector<CloudImage> images;
  for (const CloudParams* p : params) {
    CloudScene s = scene;
    s.params = p;
    images.push_back(Render(s, request));
  }
  return images;
}

std::unique_ptr<CloudRenderer> CreateCpuCloudRenderer(CloudPrecision precision, int threads) {
  return std::make_unique<CpuCloudRenderer>(precision, threads);
}

}  // namespace skycal::clouds
