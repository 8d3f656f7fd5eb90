#include "skycal/capture/optical_flow.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "skycal/capture/latlong_frame.h"
#include "skycal/capture/zenith_cap.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/atomic_output_group.h"
#include "skycal/core/output_kind.h"
#include "skycal/core/error.h"
#include "skycal/core/png_io_opencv.h"
#include "skycal/core/exr_io.h"
#include "skycal/core/file_safety.h"
#include "skycal/core/luminance.h"
#include "skycal/core/math_constants.h"

namespace skycal::capture {
namespace {

void Log(const std::string& message) { std::cerr << "[flow] " << message << std::endl; }

double LogLuminance(const ImageRGB& img, size_t i) {
  const double l = skycal::Rec709Luminance<double>(img.pixels[3 * i], img.pixels[3 * i + 1], img.pixels[3 * i + 2]);
  return std::log(std::max(std::isfinite(l) ? l : 0.0, 1e-30));
}

// Log luminance over [lo, hi] to 8 bits, padded by `pad` columns each side with the
// longitude wrapped (period width - 1: the seam column is stored twice).
cv::Mat Tonemapped(const ImageRGB& img, double lo, double hi, int pad) {
  const int w = img.width, h = img.height, period = w - 1;
  cv::Mat out(h, period + 2 * pad, CV_8UC1);
  for (int y = 0; y < h; ++y)
    for (int j = 0; j < out.cols; ++j) {
      const int x = (((j - pad) % period) + period) % period;
      const double v = (LogLuminance(img, static_cast<size_t>(y) * w + x) - lo) / (hi - lo);
      out.at<uint8_t>(y, j) = static_cast<uint8_t>(std::lround(255.0 * std::clamp(v, 0.0, 1.0)));
    }
  return out;
}

// The frame seen in the zenith cap's polar view: log luminance (bilinear in the lat-long,
// longitude wrapping with period width - 1, rows clamped) over [lo, hi] to 8 bits.
cv::Mat PolarTonemapped(const ImageRGB& img, const ZenithCap& cap, double lo, double hi) {
  const int w = img.width, h = img.height, period = w - 1;
  std::vector<double> logs(static_cast<size_t>(w) * h);
  for (size_t i = 0; i < logs.size(); ++i) logs[i] = LogLuminance(img, i);
  cv::Mat out(cap.size, cap.size, CV_8UC1);
  for (int py = 0; py < cap.size; ++py)
    for (int px = 0; px < cap.size; ++px) {
      const std::array<double, 2> p = latlong::PixelPosition(cap.PolarDirection(px, py), w, h);
      const double y = std::clamp(p[1], 0.0, h - 1.0), fx = std::floor(p[0]), fy = std::floor(y);
      const double tx = p[0] - fx, ty = y - fy;
      const int x0 = ((static_cast<int>(fx) % period) + period) % period, x1 = (x0 + 1) % period;
      const size_t r0 = static_cast<size_t>(fy) * w, r1 = static_cast<size_t>(std::min(static_cast<int>(fy) + 1, h - 1)) * w;
      const double l = (1 - ty) * ((1 - tx) * logs[r0 + x0] + tx * logs[r0 + x1]) + ty * ((1 - tx) * logs[r1 + x0] + tx * logs[r1 + x1]);
      out.at<uint8_t>(py, px) = static_cast<uint8_t>(std::lround(255.0 * std::clamp((l - lo) / (hi - lo), 0.0, 1.0)));
    }
  return out;
}

cv::Vec2f SampleFlow(const cv::Mat& flow, double x, double y) {
  x = std::clamp(x, 0.0, flow.cols - 1.0);
  y = std::clamp(y, 0.0, flow.rows - 1.0);
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const int x1 = std::min(x0 + 1, flow.cols - 1), y1 = std::min(y0 + 1, flow.rows - 1);
  const float tx = static_cast<float>(x - x0), ty = static_cast<float>(y - y0);
  return (1 - ty) * ((1 - tx) * flow.at<cv::Vec2f>(y0, x0) + tx * flow.at<cv::Vec2f>(y0, x1)) +
         ty * ((1 - tx) * flow.at<cv::Vec2f>(y1, x0) + tx * flow.at<cv::Vec2f>(y1, x1));
}

// Near the zenith a lat-long turns a drift into a sideways sweep and a swirl (a cloud
// crossing the zenith moves half the image's width): DIS's patches cannot follow it there
// (measured on wind-moved clouds above 45 deg: median 3.1 px, p90 56 px). There the flow
// is found in the zenith cap's polar view, where the drift is a translation, and each
// lat-long pixel's motion is its polar motion mapped back: p -> direction -> polar q,
// q + flow(q) -> direction -> lat-long p'. Elevations 40..50 deg blend the two smoothly;
// the polar view reaches 60 deg from the zenith so DIS has context beyond the blend.
// The polar view is oversampled 3x (3 polar pixels per lat-long row's angle): near the
// zenith a lat-long row holds its whole width of samples around a small circle, detail a
// 1x view throws away. Measured on wind-moved clouds above 45 deg (tests/flow_wind_test.cc,
// end-point error median / p90 in 1x polar pixels; motion median 7.1 px): 1x 1.32 / 2.10,
// 1.5x 0.81 / 1.59, 2x 0.53 / 1.35, 3x 0.37 / 1.04, 4x 0.35 / 1.22; the lat-long alone
// 2.49 / 6.96.
constexpr double kCapRadiusDeg = 60.0, kCapBlendFromDeg = 40.0, kCapBlendToDeg = 50.0, kCapOversample = 3.0;

void ZenithCapFlow(const ImageRGB& a, const ImageRGB& b, double lo, double hi, std::vector<float>* out) {
  const int w = a.width, h = a.height;
  const ZenithCap cap(w, h, kCapRadiusDeg, kCapOversample);
  const cv::Mat pa = PolarTonemapped(a, cap, lo, hi), pb = PolarTonemapped(b, cap, lo, hi);
  cv::Ptr<cv::DISOpticalFlow> dis = cv::DISOpticalFlow::create(cv::DISOpticalFlow::PRESET_MEDIUM);
  cv::Mat polar;
  dis->calc(pa, pb, polar);
  const double period = w - 1;
  for (int y = 0; y < h; ++y) {
    const double elevation = latlong::Latitude(y, h) * 180.0 / kPi;
    if (elevation <= kCapBlendFromDeg) break;  // rows run from the zenith down
    const double t = std::min(1.0, (elevation - kCapBlendFromDeg) / (kCapBlendToDeg - kCapBlendFromDeg));
    const double s = t * t * (3.0 - 2.0 * t);  // smoothstep: no seam in the vectors
    for (int x = 0; x < w; ++x) {
      const std::array<double, 2> q = cap.PolarPosition(latlong::PixelDirection(x, y, w, h));
      const cv::Vec2f f = SampleFlow(polar, q[0], q[1]);
      const std::array<double, 2> p = latlong::PixelPosition(cap.PolarDirection(q[0] + f[0], q[1] + f[1]), w, h);
      double dx = p[0] - x;
      dx -= period * std::round(dx / period);
      const size_t i = 2 * (static_cast<size_t>(y) * w + x);
      (*out)[i] = static_cast<float>((1.0 - s) * (*out)[i] + s * dx);
      (*out)[i + 1] = static_cast<float>((1.0 - s) * (*out)[i + 1] + s * (p[1] - y));
    }
  }
}

}  // namespace

bool FlowOptions::IsValid(std::string* why) const {
  if (a.empty() || b.empty()) {
    *why = "FlowOptions::a and FlowOptions::b are required (two consecutive frames)";
    return false;
  }
  if (out.size() < 5 || out.substr(out.size() - 4) != ".exr") {
    *why = "FlowOptions::out = " + out + " (expected a path ending in .exr; V.png and V.json are written beside it)";
    return false;
  }
  if (scale < 1 || scale > 16) {
    *why = "FlowOptions::scale = " + std::to_string(scale) + " (expected an integer in [1, 16]: 1 / scale of the frames' size)";
    return false;
  }
  return true;
}

std::vector<float> DenseFlow(const ImageRGB& a, const ImageRGB& b, bool zenith_cap) {
  // One tonemapping for both frames (brightness constancy): the 0.5th..99.5th percentile of
  // their log luminance, so a change of exposure between frames is not read as motion of
  // the whole sky to 8 bits but as what it is.
  std::vector<double> logs;
  const size_t n = static_cast<size_t>(a.width) * a.height;
  for (size_t i = 0; i < n; i += std::max<size_t>(1, n / 50000)) {
    logs.push_back(LogLuminance(a, i));
    logs.push_back(LogLuminance(b, i));
  }
  std::sort(logs.begin(), logs.end());
  const double lo = logs[logs.size() / 200], hi = std::max(logs[logs.size() - 1 - logs.size() / 200], lo + 1e-6);
  const int pad = std::max(8, a.width / 8);
  const cv::Mat ia = Tonemapped(a, lo, hi, pad), ib = Tonemapped(b, lo, hi, pad);
  cv::Ptr<cv::DISOpticalFlow> dis = cv::DISOpticalFlow::create(cv::DISOpticalFlow::PRESET_MEDIUM);
  cv::Mat flow;
  dis->calc(ia, ib, flow);
  std::vector<float> out(2 * n);
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) {
      const cv::Vec2f f = flow.at<cv::Vec2f>(y, x + pad);
      out[2 * (static_cast<size_t>(y) * a.width + x)] = f[0];
      out[2 * (static_cast<size_t>(y) * a.width + x) + 1] = f[1];
    }
  if (zenith_cap) ZenithCapFlow(a, b, lo, hi, &out);
  return out;
}

namespace {

// The two directions' vectors in texture space (u: fraction of the width's longitude span,
// v: of the height), area-averaged to qw x qh, with each component's range.
struct QuantizedFlow {
  cv::Mat vectors;  // CV_32FC4: forward u, v, backward u, v
  double mins[4], maxs[4];
};

QuantizedFlow TextureSpaceFlow(const std::vector<float>& fwd, const std::vector<float>& bwd, int w, int h, int qw, int qh) {
  cv::Mat full(h, w, CV_32FC4);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = 2 * (static_cast<size_t>(y) * w + x);
      full.at<cv::Vec4f>(y, x) = {fwd[i] / (w - 1.0f), fwd[i + 1] / (h - 1.0f), bwd[i] / (w - 1.0f), bwd[i + 1] / (h - 1.0f)};
    }
  QuantizedFlow q;
  cv::resize(full, q.vectors, cv::Size(qw, qh), 0, 0, cv::INTER_AREA);
  for (int c = 0; c < 4; ++c) {
    q.mins[c] = INFINITY;
    q.maxs[c] = -INFINITY;
    for (int y = 0; y < qh; ++y)
      for (int x = 0; x < qw; ++x) {
        q.mins[c] = std::min(q.mins[c], static_cast<double>(q.vectors.at<cv::Vec4f>(y, x)[c]));
        q.maxs[c] = std::max(q.maxs[c], static_cast<double>(q.vectors.at<cv::Vec4f>(y, x)[c]));
      }
  }
  return q;
}

// The three encodings of one QuantizedFlow: 8-bit codes over each component's range, the
// float forward vectors as RGB and the backward ones as extra EXR planes.
struct EncodedFlow {
  cv::Mat codes;  // CV_8UC4, BGRA as OpenCV writes it
  ImageRGB rgb;
  std::vector<ExrPlane> planes;
};

EncodedFlow EncodeFlow(const QuantizedFlow& q) {
  const int qw = q.vectors.cols, qh = q.vectors.rows;
  EncodedFlow e{cv::Mat(qh, qw, CV_8UC4), ImageRGB(qw, qh),
                {{"backward.u", std::vector<float>(static_cast<size_t>(qw) * qh)},
                 {"backward.v", std::vector<float>(static_cast<size_t>(qw) * qh)}}};
  for (int y = 0; y < qh; ++y)
    for (int x = 0; x < qw; ++x) {
      const cv::Vec4f v = q.vectors.at<cv::Vec4f>(y, x);
      cv::Vec4b c8;
      for (int c = 0; c < 4; ++c) {
        const double span = q.maxs[c] - q.mins[c];
        c8[c] = static_cast<uint8_t>(span > 0.0 ? std::lround(255.0 * (v[c] - q.mins[c]) / span) : 0);
      }
      // OpenCV writes BGRA: R forward u, G forward v, B backward u, A backward v in the file.
      e.codes.at<cv::Vec4b>(y, x) = {c8[2], c8[1], c8[0], c8[3]};
      e.rgb.at(x, y, 0) = v[0];
      e.rgb.at(x, y, 1) = v[1];
      const size_t i = static_cast<size_t>(y) * qw + x;
      e.planes[0].values[i] = v[2];
      e.planes[1].values[i] = v[3];
    }
  return e;
}

nlohmann::json FlowSidecar(const FlowOptions& o, const QuantizedFlow& q, int w, int h) {
  const char* names[4] = {"forward_u", "forward_v", "backward_u", "backward_v"};
  nlohmann::json components = nlohmann::json::array();
  for (int c = 0; c < 4; ++c) components.push_back({{"name", names[c]}, {"min", q.mins[c]}, {"max", q.maxs[c]}});
  return {{"format", "skycal-flow"},
          {"version", 1},
          {"a", o.a},
          {"b", o.b},
          {"frame_width", w},
          {"frame_height", h},
          {"width", q.vectors.cols},
          {"height", q.vectors.rows},
          {"units", "texture space: u as a fraction of the image width (a full turn of longitude), v of its height"},
          {"meaning", "forward: a(p) ~ b(p + forward(p)); backward: b(p) ~ a(p + backward(p))"},
          {"png_channels", {"R forward_u", "G forward_v", "B backward_u", "A backward_v"}},
          {"decode", "value = min + (max - min) * code / 255"},
          {"components", components}};
}

// Three files committed together (AtomicOutputGroup): a failure on any of them leaves the
// previous three, or none, in place.
void WriteFlowFiles(const std::string& exr, const std::string& png, const std::string& sidecar, const EncodedFlow& e,
                    const nlohmann::json& meta) {
  const std::vector<uint8_t> png_bytes = EncodePngFromMat(e.codes, png);
  ExrAttributes attrs;
  attrs.strings["skycalFlow"] = meta.dump();
  RefuseReplacingAPresetLut(exr);
  AtomicOutputGroup group;
  try {
    const std::string staged_exr = group.Add(exr), staged_png = group.Add(png), staged_sidecar = group.Add(sidecar);
    WriteExrRGBWithPlanes(staged_exr, e.rgb, e.planes, attrs);
    WriteFileAtomically(staged_png, std::string(png_bytes.begin(), png_bytes.end()));
    WriteFileAtomically(staged_sidecar, meta.dump(2) + "\n");
    group.Commit();
  } catch (const Error& err) {
    throw Error(group.Unstaged(err.what()));
  }
}

}  // namespace

nlohmann::json WriteFlowVectors(const FlowOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  const std::filesystem::path exr(o.out);
  const std::string png = std::filesystem::path(exr).replace_extension(".png").string();
  const std::string sidecar = std::filesystem::path(exr).replace_extension(".json").string();
  RefuseOutputsOverInputs({{"FlowOptions::out", o.out}, {"FlowOptions::out's 8-bit image", png}, {"FlowOptions::out's sidecar", sidecar}},
                          {{"frame A", o.a}, {"frame B", o.b}});
  const LatLongFrame fa = ReadLatLongFrame(o.a), fb = ReadLatLongFrame(o.b);
  const int w = fa.radiance.width, h = fa.radiance.height;
  if (fb.radiance.width != w || fb.radiance.height != h) {
    throw Error(o.b + ": frame is " + std::to_string(fb.radiance.width) + "x" + std::to_string(fb.radiance.height) +
                ", but " + o.a + " is " + std::to_string(w) + "x" + std::to_string(h) +
                ": consecutive frames of a time-lapse must share one size");
  }
  const int qw = std::max(2, w / o.scale), qh = std::max(2, h / o.scale);
  Log(o.a + " -> " + o.b + ": " + std::to_string(w) + "x" + std::to_string(h) + ", vectors at " + std::to_string(qw) +
      "x" + std::to_string(qh));
  const std::vector<float> fwd = DenseFlow(fa.radiance, fb.radiance), bwd = DenseFlow(fb.radiance, fa.radiance);
  const QuantizedFlow q = TextureSpaceFlow(fwd, bwd, w, h, qw, qh);
  const nlohmann::json meta = FlowSidecar(o, q, w, h);
  WriteFlowFiles(o.out, png, sidecar, EncodeFlow(q), meta);
  Log("wrote " + o.out + ", " + png + ", " + sidecar + " (forward u " + std::to_string(q.mins[0] * (w - 1)) + ".." +
      std::to_string(q.maxs[0] * (w - 1)) + " px)");
  nlohmann::json j = meta;
  j["out"] = o.out;
  j["png"] = png;
  j["sidecar"] = sidecar;
  return j;
}

}  // namespace skycal::capture
