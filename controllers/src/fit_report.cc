#include "fit_report.h"

#include <opencv2/imgcodecs.hpp>
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
namespace {

constexpr int kPanelWidth = 512;  // pixels per panel (images are area-resampled to it)
constexpr int kLabel = 26;        // label strip height

cv::Mat ToMat(const std::vector<uint8_t>& rgb, int w, int h) {
  cv::Mat m(h, w, CV_8UC3);
  for (int i = 0; i < w * h; ++i) {
    m.data[3 * i + 0] = rgb[3 * i + 2];  // OpenCV stores BGR
    m.data[3 * i + 1] = rgb[3 * i + 1];
    m.data[3 * i + 2] = rgb[3 * i + 0];
  }
  return m;
}

// Diverging map: -1 blue, 0 white, +1 red (BGR).
cv::Vec3b Diverging(double t) {
  t = std::clamp(t, -1.0, 1.0);
  const double a = std::abs(t);
  const auto mixc = [&](double full) { return static_cast<uint8_t>(std::lround(255.0 * (1.0 - a) + full * a)); };
  if (t >= 0) return {mixc(30.0), mixc(40.0), mixc(200.0)};
  return {mixc(190.0), mixc(90.0), mixc(30.0)};
}

cv::Mat Panel(const cv::Mat& img, const std::string& label) {
  cv::Mat resized;
  const int h = kPanelWidth / 2;
  cv::resize(img, resized, cv::Size(kPanelWidth, h), 0, 0, img.cols > kPanelWidth ? cv::INTER_AREA : cv::INTER_NEAREST);
  cv::Mat out(h + kLabel, kPanelWidth, CV_8UC3, cv::Scalar(32, 32, 32));
  resized.copyTo(out(cv::Rect(0, kLabel, kPanelWidth, h)));
  cv::putText(out, label, cv::Point(6, 18), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(235, 235, 235), 1, cv::LINE_AA);
  return out;
}

cv::Mat ColourBar(double range) {
  cv::Mat bar(40, kPanelWidth, CV_8UC3, cv::Scalar(32, 32, 32));
  for (int x = 0; x < kPanelWidth - 40; ++x) {
    const cv::Vec3b c = Diverging(2.0 * x / (kPanelWidth - 41) - 1.0);
    for (int y = 4; y < 18; ++y) bar.at<cv::Vec3b>(y, x + 20) = c;
  }
  for (int k = 0; k <= 4; ++k) {
    const double v = (-1.0 + 0.5 * k) * range * 100.0;
    char buf[32];
    std::snprintf(buf, sizeof buf, "%+.0f%%", v);
    const int x = 20 + k * (kPanelWidth - 41) / 4;
    cv::putText(bar, buf, cv::Point(std::max(0, x - 16), 34), cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(235, 235, 235), 1,
                cv::LINE_AA);
  }
  return bar;
}

void WritePng(const std::string& path, const cv::Mat& m) {
  std::vector<uint8_t> png;
  if (!cv::imencode(".png", m, png)) throw Error(path + ": PNG encoding failed");
  WriteFileAtomically(path, std::string(png.begin(), png.end()));
}

}  // namespace

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
