#include "calibrate_figure.h"

#include <algorithm>
#include <cmath>

#include <opencv2/core.hpp>

#include "figure_panels.h"
#include "skycal/color/preview.h"
#include "skycal/core/error.h"
#include "skycal/core/format_number.h"
#include "skycal/core/latlong_resample.h"
#include "skycal/core/luminance.h"

namespace skycal::controllers {
namespace {

// `im` averaged in linear light down to a panel's size when it is larger: the OCIO view
// transform then runs on a panel's pixels, not the photo's (three full-size transforms took
// more than a second at 2048x1024).
ImageRGB ToPanelSize(const ImageRGB& im) {
  if (im.width <= figure::kPanelWidth) return im;
  ImageRGB out(figure::kPanelWidth, std::max(1, figure::kPanelWidth * im.height / im.width));
  out.pixels = AreaDownsampleLatLong(im.pixels, im.width, im.height, 3, out.width, out.height);
  return out;
}

}  // namespace

void WriteComparisonFigure(const std::string& path, const ImageRGB& photo, const ImageRGB& game,
                           const std::vector<float>& sky, double range) {
  const int w = photo.width, h = photo.height;
  const size_t n = static_cast<size_t>(w) * h;
  if (game.width != w || game.height != h || sky.size() != n) throw Error(path + ": the images differ in size");
  ImageRGB sky_only(w, h);  // one automatic exposure for both images: the photo's sky's
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) sky_only.pixels[3 * i + c] = sky[i] >= 0.5f ? photo.pixels[3 * i + c] : 0.0f;
  color::PreviewOptions po;
  color::PreviewReport auto_exposure;
  color::ToDisplay8(ToPanelSize(sky_only), po, &auto_exposure);
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
  const ImageRGB photo_panel = ToPanelSize(photo), game_panel = ToPanelSize(game);
  const int pw = photo_panel.width, ph = photo_panel.height;
  cv::hconcat(std::vector<cv::Mat>{figure::Panel(figure::ToMat(color::ToDisplay8(photo_panel, po, nullptr), pw, ph), "photo"),
                                   figure::Panel(figure::ToMat(color::ToDisplay8(game_panel, po, nullptr), pw, ph),
                                                 "game: the calibrated preset as the game renders it"),
                                   figure::Panel(error, "game / photo: blue x" + factor(-range) + ", white 1, red x" +
                                                            factor(range))},
              sheet);
  figure::WritePng(path, sheet);
}

}  // namespace skycal::controllers
