#include "figure_panels.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <opencv2/imgproc.hpp>

#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "skycal/core/png_io_opencv.h"

namespace skycal::controllers::figure {
namespace {

constexpr int kLabel = 26;  // label strip height (pixels)

}  // namespace

cv::Mat ToMat(const std::vector<uint8_t>& rgb, int w, int h) {
  cv::Mat m(h, w, CV_8UC3);
  for (int i = 0; i < w * h; ++i) {
    m.data[3 * i + 0] = rgb[3 * i + 2];  // OpenCV stores BGR
    m.data[3 * i + 1] = rgb[3 * i + 1];
    m.data[3 * i + 2] = rgb[3 * i + 0];
  }
  return m;
}

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
  const std::vector<uint8_t> png = EncodePngFromMat(m, path);
  WriteFileAtomically(path, std::string(png.begin(), png.end()));
}

}  // namespace skycal::controllers::figure
