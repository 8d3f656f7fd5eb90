// Automatic sky segmentation (capture/sky_segmentation.h) on the real skies: precision and
// recall of the non-sky class against the hand masks (sunrise, sunset), the share of
// non-sky found on the frames without hand masks (sky, dawn, city), time per frame, and a
// picture per frame (tone-mapped frame | automatic mask over it | hand mask over it).
//
// Usage: bench_sky_segmentation [OUT_MD] [PICTURE_DIR]
//   defaults: bench/results/sky_segmentation.md, datasets/results/
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "skycal/capture/latlong_frame.h"
#include "skycal/capture/sky_segmentation.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/latlong.h"

namespace {

using skycal::ImageRGB;

// Log-luminance tone map to 8-bit BGR (the 1st..99.5th percentile of log luminance).
cv::Mat ToneMap(const ImageRGB& f) {
  std::vector<float> v;
  for (size_t i = 0; i < f.pixels.size() / 3; ++i) {
    const float y = 0.2126f * f.pixels[3 * i] + 0.7152f * f.pixels[3 * i + 1] + 0.0722f * f.pixels[3 * i + 2];
    if (y > 0.0f && std::isfinite(y)) v.push_back(std::log(y));
  }
  std::sort(v.begin(), v.end());
  const float lo = v[static_cast<size_t>(0.01 * (v.size() - 1))], hi = v[static_cast<size_t>(0.995 * (v.size() - 1))];
  cv::Mat img(f.height, f.width, CV_8UC3);
  for (int y = 0; y < f.height; ++y)
    for (int x = 0; x < f.width; ++x) {
      const float r = f.at(x, y, 0), g = f.at(x, y, 1), b = f.at(x, y, 2);
      const float Y = 0.2126f * r + 0.7152f * g + 0.0722f * b;
      const float t = (Y > 0.0f && std::isfinite(Y)) ? std::clamp((std::log(Y) - lo) / (hi - lo), 0.0f, 1.0f) : 0.0f;
      const float k = Y > 0.0f ? 255.0f * std::pow(t, 1.0f) / Y : 0.0f;
      auto& p = img.at<cv::Vec3b>(y, x);
      p[0] = cv::saturate_cast<uchar>(b * k);
      p[1] = cv::saturate_cast<uchar>(g * k);
      p[2] = cv::saturate_cast<uchar>(r * k);
    }
  return img;
}

// Non-sky pixels (mask < 0.5) tinted red over the frame.
cv::Mat Overlay(const cv::Mat& frame, const std::vector<float>& sky) {
  cv::Mat out = frame.clone();
  for (int y = 0; y < out.rows; ++y)
    for (int x = 0; x < out.cols; ++x)
      if (sky[static_cast<size_t>(y) * out.cols + x] < 0.5f) {
        auto& p = out.at<cv::Vec3b>(y, x);
        p = cv::Vec3b(static_cast<uchar>(p[0] / 3), static_cast<uchar>(p[1] / 3), static_cast<uchar>(90 + p[2] / 2));
      }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string root = SKYCAL_SOURCE_DIR;
  const std::string out_md = argc > 1 ? argv[1] : root + "/bench/results/sky_segmentation.md";
  const std::string pic_dir = argc > 2 ? argv[2] : root + "/datasets/results";
  struct Case {
    std::string name, hand_mask;
  };
  const std::vector<Case> cases = {{"sunrise", "sunrise_mask.exr"}, {"sunset", "sunset_mask.exr"},
                                   {"sky", ""},                     {"dawn", ""},
                                   {"city", ""}};
  std::ostringstream md;
  md << "# Automatic sky segmentation against the hand masks\n\n"
     << "`build/bench/bench_sky_segmentation` (capture/sky_segmentation.h, default `SkyMaskOptions`).\n"
     << "Precision and recall of the NON-SKY class above the horizon (elevation > 0), against the\n"
     << "hand masks of `datasets/masks` (R < 0.5: not sky); in brackets above 3.3 deg (the hand masks\n"
     << "exclude the lowest 3.3 deg wholesale: haze, fog, the far shore). Below the horizon both are non-sky by\n"
     << "construction and are left out of the counts. Times: one run on the shared 2-core machine\n"
     << "(noisy). Pictures: `datasets/results/sky_segmentation_<name>.png` (frame | automatic mask,\n"
     << "non-sky red | hand mask where there is one).\n\n"
     << "| frame | size | precision | recall | IoU | non-sky above horizon (auto) | hand | ground-connected / floating candidates | time (ms) |\n"
     << "|---|---|---|---|---|---|---|---|---|\n";
  int failures = 0;
  for (const Case& c : cases) {
    const std::string path = root + "/datasets/real/" + c.name + ".exr";
    if (!std::filesystem::exists(path)) {
      std::fprintf(stderr, "%s: missing (run datasets/fetch_real_skies.sh --with-npm)\n", path.c_str());
      ++failures;
      continue;
    }
    try {
      const auto frame = skycal::capture::ReadLatLongFrame(path);
      const auto t0 = std::chrono::steady_clock::now();
      const auto mask = skycal::capture::EstimateSkyMask(frame.radiance, frame.sun_direction, {});
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      const int w = frame.radiance.width, h = frame.radiance.height;
      const cv::Mat tone = ToneMap(frame.radiance);
      std::vector<cv::Mat> panels = {tone, Overlay(tone, mask.sky)};
      std::string precision = "-", recall = "-", iou = "-", hand = "-";
      if (!c.hand_mask.empty()) {
        int mw = 0, mh = 0;
        const auto ref = skycal::ReadExrChannel(root + "/datasets/masks/" + c.hand_mask, "R", &mw, &mh);
        const auto s = skycal::capture::ScoreNonSky(mask, ref, mw, mh, 0.0);
        char buf[64];
        std::snprintf(buf, sizeof buf, "%.3f", s.precision);
        precision = buf;
        std::snprintf(buf, sizeof buf, "%.3f", s.recall);
        recall = buf;
        std::snprintf(buf, sizeof buf, "%.3f", s.iou);
        iou = buf;
        hand = std::to_string(s.true_non_sky + s.missed_non_sky);
        // Above 3.3 deg: the hand masks exclude the lowest 3.3 deg wholesale (haze, far shore),
        // a convention rather than objects; this score isolates the objects.
        const auto a = skycal::capture::ScoreNonSky(mask, ref, mw, mh, 3.3);
        std::snprintf(buf, sizeof buf, " (%.3f)", a.precision);
        precision += buf;
        std::snprintf(buf, sizeof buf, " (%.3f)", a.recall);
        recall += buf;
        panels.push_back(Overlay(tone, ref));
      }
      cv::Mat picture;
      cv::vconcat(panels, picture);
      // At most 512 pixels wide (area-averaged): small files for the repository.
      if (picture.cols > 512) cv::resize(picture, picture, cv::Size(512, picture.rows * 512 / picture.cols), 0, 0, cv::INTER_AREA);
      cv::imwrite(pic_dir + "/sky_segmentation_" + c.name + ".png", picture);
      md << "| " << c.name << " | " << w << "x" << h << " | " << precision << " | " << recall << " | " << iou << " | "
         << mask.non_sky_above_horizon << " (" << std::lround(100.0 * mask.non_sky_above_horizon / mask.above_horizon)
         << "%) | " << hand << " | " << mask.ground_connected_candidates << " / " << mask.floating_candidates << " | "
         << std::lround(ms) << " |\n";
      std::fprintf(stderr, "%s: precision %s recall %s, %.0f ms\n", c.name.c_str(), precision.c_str(), recall.c_str(),
                   ms);
    } catch (const skycal::Error& e) {
      std::fprintf(stderr, "%s: %s\n", c.name.c_str(), e.what());
      ++failures;
    }
  }
  std::ofstream(out_md) << md.str();
  std::fprintf(stderr, "wrote %s\n", out_md.c_str());
  return failures ? 1 : 0;
}
