#include "calibrate_figure.h"

#include <cmath>

#include <opencv2/core.hpp>

#include "figure_panels.h"
#include "skycal/color/preview.h"
#include "skycal/core/error.h"
#include "skycal/core/format_number.h"
#include "skycal/core/luminance.h"

namespace skycal::controllers {
namespace {

// `im` box-averaged in linear light by `f` (only the pixels `keep` says, when given: a block
// with none is 0): the OCIO view transform then runs on about a panel's pixels, not the
// photo's (three full-size transforms took more than a second at 2048x1024).
ImageRGB BoxAverage(const ImageRGB& im, int f, const std::vector<float>* keep = nullptr) {
  if (f <= 1 && !keep) return im;
  ImageRGB out(im.width / f, im.height / f);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x) {
      double sum[3] = {0.0, 0.0, 0.0}, n = 0.0;
      for (int dy = 0; dy < f; ++dy)
        for (int dx = 0; dx < f; ++dx) {
          const size_t i = static_cast<size_t>(y * f + dy) * im.width + (x * f + dx);
          if (keep && !((*keep)[i] >= 0.5f)) continue;
          for (int c = 0; c < 3; ++c) sum[c] += im.pixels[3 * i + c];
          n += 1.0;
        }
      for (int c = 0; c < 3; ++c)
        out.pixels[3 * (static_cast<size_t>(y) * out.width + x) + c] = n > 0.0 ? static_cast<float>(sum[c] / n) : 0.0f;
    }
  return out;
}

// The factor that brings a w x h lat-long to the panels' width (1 when none does exactly).
int PanelFactor(int w, int h) {
  const int f = w / figure::kPanelWidth;
  return f > 1 && w % figure::kPanelWidth == 0 && h % (figure::kPanelWidth / 2) == 0 ? f : 1;
}

}  // namespace

void WriteComparisonFigure(const std::string& path, const ImageRGB& photo, const ImageRGB& game,
                           const std::vector<float>& sky, double range) {
  const int w = photo.width, h = photo.height;
  const size_t n = static_cast<size_t>(w) * h;
  if (game.width != w || game.height != h || sky.size() != n) throw Error(path + ": the images differ in size");
  const int f = PanelFactor(w, h), pw = w / f, ph = h / f;
  color::PreviewOptions po;
  color::PreviewReport auto_exposure;  // one automatic exposure for both images: the photo's sky's
  color::ToDisplay8(BoxAverage(photo, f, &sky), po, &auto_exposure);
  po.exposure_ev = auto_exposure.exposure_ev;
  cv::Mat error(h, w, CV_8UC3, cv::Scalar(70, 70, 70));  // grey: not compared
  for (size_t i = 0; i < n; ++i) {
    const double yp = Rec709Luminance<double>(photo.pixels[3 * i], photo.pixels[3 * i + 1], photo.pixels[3 * i + 2]);
    const double yg = Rec709Luminance<double>(game.pixels[3 * i], game.pixels[3 * i + 1], game.pixels[3 * i + 2]);
    if (!(sky[i] >= 0.5f) || !(yp > 0.0) || !(yg > 0.0)) continue;
    error.at<cv::Vec3b>(static_cast<int>(i) / w, static_cast<int>(i) % w) = figure::Diverging(std::log(yg / yp) / range);
  }
  const auto factor = [](double v) { return FormatNumber(std::round(100.0 * std::exp(v)) / 100.0); };
  cv::Mat sheet;
  cv::hconcat(std::vector<cv::Mat>{figure::Panel(figure::ToMat(color::ToDisplay8(BoxAverage(photo, f), po, nullptr), pw, ph), "photo"),
                                   figure::Panel(figure::ToMat(color::ToDisplay8(BoxAverage(game, f), po, nullptr), pw, ph),
                                                 "game: the calibrated preset as the game renders it"),
                                   figure::Panel(error, "game / photo: blue x" + factor(-range) + ", white 1, red x" +
                                                            factor(range))},
              sheet);
  figure::WritePng(path, sheet);
}

}  // namespace skycal::controllers
