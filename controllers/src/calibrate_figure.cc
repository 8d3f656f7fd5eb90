#include "calibrate_figure.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "skycal/color/preview.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "skycal/core/luminance.h"

namespace skycal::controllers {
namespace {

constexpr int kLabelPx = 22;  // the strip above each panel for its label

cv::Mat Panel(const std::vector<uint8_t>& rgb, int w, int h, const std::string& label) {
  cv::Mat m(h + kLabelPx, w, CV_8UC3, cv::Scalar(255, 255, 255));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = (static_cast<size_t>(y) * w + x) * 3;
      m.at<cv::Vec3b>(y + kLabelPx, x) = {rgb[i + 2], rgb[i + 1], rgb[i]};  // OpenCV is BGR
    }
  cv::putText(m, label, {4, kLabelPx - 6}, cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  return m;
}

// Blue (game darker) - white - red (game brighter) for t in [-1, 1].
std::array<uint8_t, 3> Diverging(double t) {
  t = std::clamp(t, -1.0, 1.0);
  const auto c = [](double v) { return static_cast<uint8_t>(std::lround(255.0 * std::clamp(v, 0.0, 1.0))); };
  return t >= 0 ? std::array<uint8_t, 3>{255, c(1.0 - t), c(1.0 - t)} : std::array<uint8_t, 3>{c(1.0 + t), c(1.0 + t), 255};
}

}  // namespace

void WriteComparisonFigure(const std::string& path, const ImageRGB& photo, const ImageRGB& game,
                           const std::vector<float>& sky, double range) {
  const int w = photo.width, h = photo.height;
  const size_t n = static_cast<size_t>(w) * h;
  if (game.width != w || game.height != h || sky.size() != n) throw Error(path + ": the images differ in size");
  ImageRGB sky_only(w, h);
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) sky_only.pixels[3 * i + c] = sky[i] >= 0.5f ? photo.pixels[3 * i + c] : 0.0f;
  color::PreviewOptions po;
  color::PreviewReport auto_exposure;
  color::ToDisplay8(sky_only, po, &auto_exposure);
  po.exposure_ev = auto_exposure.exposure_ev;
  std::vector<uint8_t> error(3 * n, 110);
  for (size_t i = 0; i < n; ++i) {
    const double yp = Rec709Luminance<double>(photo.pixels[3 * i], photo.pixels[3 * i + 1], photo.pixels[3 * i + 2]);
    const double yg = Rec709Luminance<double>(game.pixels[3 * i], game.pixels[3 * i + 1], game.pixels[3 * i + 2]);
    if (!(sky[i] >= 0.5f) || !(yp > 0.0) || !(yg > 0.0)) continue;
    const auto c = Diverging(std::log(yg / yp) / range);
    std::copy(c.begin(), c.end(), error.begin() + static_cast<std::ptrdiff_t>(3 * i));
  }
  cv::Mat figure;
  cv::hconcat(std::vector<cv::Mat>{Panel(color::ToDisplay8(photo, po, nullptr), w, h, "photo"),
                                   Panel(color::ToDisplay8(game, po, nullptr), w, h, "game (calibrated preset)"),
                                   Panel(error, w, h, "ln(game/photo): blue -" + std::to_string(range).substr(0, 3) +
                                                          ", red +" + std::to_string(range).substr(0, 3))},
              figure);
  std::vector<uint8_t> bytes;
  if (!cv::imencode(".png", figure, bytes)) throw Error(path + ": PNG encoding failed");
  WriteFileAtomically(path, std::string(bytes.begin(), bytes.end()));
}

}  // namespace skycal::controllers
