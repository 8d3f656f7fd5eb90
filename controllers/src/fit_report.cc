#include "fit_report.h"

#include "figure_panels.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "skycal/capture/sun_detect.h"
#include "skycal/color/preview.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"

namespace skycal::controllers {
using figure::ColourBar;
using figure::Diverging;
using figure::kPanelWidth;
using figure::Panel;
using figure::ToMat;
using figure::WritePng;

namespace {

// The three panels of one reference at its own size (BGR, 8 bit): reference and fit through
// the same OCIO view and exposure, and the signed relative luminance error.
struct FitReportImages {
  cv::Mat reference, fit, error;
};

FitReportImages MakeFitReportImages(const fit::Reference& ref, const ImageRGB& fitted, double error_range) {
  const int w = ref.radiance.width, h = ref.radiance.height;
  // One exposure for both: automatic on the reference's sky pixels.
  ImageRGB sky_only(w, h);
  for (size_t i = 0; i < ref.pixel_class.size(); ++i) {
    if (ref.pixel_class[i] != fit::PixelClass::kSky) continue;
    for (int c = 0; c < 3; ++c) sky_only.pixels[3 * i + c] = ref.radiance.pixels[3 * i + c];
  }
  color::PreviewOptions po;
  color::PreviewReport auto_report;
  color::ToDisplay8(sky_only, po, &auto_report);
  // The exposure is applied here, in double, rather than through po.exposure_ev: a
  // reference in a camera's raw units can need more than the preview's +-64 stops.
  const double gain = std::exp2(auto_report.exposure_ev);
  auto exposed = [gain](ImageRGB img) {
    for (float& v : img.pixels) v = static_cast<float>(v * gain);
    return img;
  };
  po.exposure_ev = 0.0;
  FitReportImages out;
  out.reference = ToMat(color::ToDisplay8(exposed(ref.radiance), po, nullptr), w, h);
  out.fit = ToMat(color::ToDisplay8(exposed(fitted), po, nullptr), w, h);
  out.error = cv::Mat(h, w, CV_8UC3);
  for (int i = 0; i < w * h; ++i) {
    if (ref.pixel_class[i] != fit::PixelClass::kSky) {
      out.error.at<cv::Vec3b>(i / w, i % w) = {70, 70, 70};
      continue;
    }
    const double lr = capture::Luminance(&ref.radiance.pixels[3 * i]);
    const double lf = capture::Luminance(&fitted.pixels[3 * i]);
    out.error.at<cv::Vec3b>(i / w, i % w) = Diverging((lf - lr) / lr / error_range);
  }
  return out;
}

}  // namespace

void WriteFitReport(const std::string& png_path, const std::vector<fit::Reference>& refs, const fit::FitResult& result,
                    double error_range) {
  std::vector<cv::Mat> rows;
  for (size_t r = 0; r < refs.size(); ++r) {
    const fit::Reference& ref = refs[r];
    const FitReportImages im = MakeFitReportImages(ref, result.references[r].rendered, error_range);
    char stats[160];
    std::snprintf(stats, sizeof stats, "error (fit-ref)/ref, rel RMSE %.2f%%, log RMSE %.4f",
                  100.0 * result.references[r].errors.rel_rmse, result.references[r].errors.log_rmse);
    cv::Mat row;
    cv::hconcat(std::vector<cv::Mat>{Panel(im.reference, "reference: " + ref.name),
                                     Panel(im.fit, "fit (" + std::string(render::ToString(result.preset.variant)) + ")"),
                                     Panel(im.error, stats)},
                row);
    rows.push_back(row);
  }
  cv::Mat bar_row(40, 3 * kPanelWidth, CV_8UC3, cv::Scalar(32, 32, 32));
  ColourBar(error_range).copyTo(bar_row(cv::Rect(2 * kPanelWidth, 0, kPanelWidth, 40)));
  cv::putText(bar_row, "grey: not fitted (below horizon, sun cone, invalid, clipped, user mask)", cv::Point(8, 24),
              cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(200, 200, 200), 1, cv::LINE_AA);
  rows.push_back(bar_row);
  cv::Mat sheet;
  cv::vconcat(rows, sheet);
  WritePng(png_path, sheet);
}

std::vector<std::string> WriteFitPanels(const std::string& dir, const std::vector<fit::Reference>& refs,
                                        const fit::FitResult& result, double error_range) {
  std::vector<std::string> written;
  for (size_t r = 0; r < refs.size(); ++r) {
    const FitReportImages im = MakeFitReportImages(refs[r], result.references[r].rendered, error_range);
    for (const auto& [kind, mat] : {std::pair<const char*, const cv::Mat*>{"reference", &im.reference},
                                    {"fit", &im.fit}, {"error", &im.error}}) {
      cv::Mat small;
      const int w = std::min(kPanelWidth, mat->cols);
      cv::resize(*mat, small, cv::Size(w, w / 2), 0, 0, mat->cols > w ? cv::INTER_AREA : cv::INTER_NEAREST);
      const std::string path = dir + "/" + refs[r].name + "." + kind + ".png";
      WritePng(path, small);
      written.push_back(path);
    }
  }
  return written;
}

}  // namespace skycal::controllers
