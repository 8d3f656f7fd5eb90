// The pieces the controllers' figures are made of (the fit's report.png and panels,
// calibrate's compare.png): 8-bit RGB to an OpenCV matrix, the diverging error map, a
// labelled panel, the colour bar, and the PNG written atomically.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace skycal::controllers::figure {

inline constexpr int kPanelWidth = 512;  // pixels per panel (images are area-resampled to it)

// Interleaved 8-bit RGB (row 0 on top, color::ToDisplay8's layout) as a BGR matrix.
cv::Mat ToMat(const std::vector<uint8_t>& rgb, int w, int h);
// Diverging map: -1 blue, 0 white, +1 red (BGR); t is clamped to [-1, 1].
cv::Vec3b Diverging(double t);
// `img` resized to kPanelWidth x kPanelWidth / 2 under a dark strip carrying `label`.
cv::Mat Panel(const cv::Mat& img, const std::string& label);
// The diverging scale, kPanelWidth wide, labelled -range..+range in percent.
cv::Mat ColourBar(double range);
// Encodes and writes atomically; throws skycal::Error naming the file.
void WritePng(const std::string& path, const cv::Mat& m);

}  // namespace skycal::controllers::figure
