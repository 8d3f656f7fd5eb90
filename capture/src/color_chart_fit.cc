// The ColorChecker reference, the 3x3 fit (OpenCV ccm) and its JSON form.
#include <cmath>
#include <numeric>

#include <opencv2/core.hpp>
#include <opencv2/mcc/ccm.hpp>

#include "skycal/capture/color_chart.h"
#include "skycal/core/error.h"
#include "skycal/core/luminance.h"
#include "skycal/core/sha256.h"

namespace skycal::capture {
namespace {

// X-Rite's published sRGB values of the ColorChecker Classic (8-bit; as listed in X-Rite's
// "ColorChecker Classic" data and reproduced in the ColorChecker article of Wikipedia).
// tests/color_chart_test.cc checks them against OpenCV's own ColorChecker 2005 CIELAB (D50)
// table (BabelColor's averages): mean CIEDE2000 under 2.5 (two measurement sets of a physical
// chart differ by about that), so a mistyped value would show.
constexpr int kSrgb8[kChartPatches][3] = {
    {115, 82, 68},   {194, 150, 130}, {98, 122, 157},  {87, 108, 67},   {133, 128, 177}, {103, 189, 170},
    {214, 126, 44},  {80, 91, 166},   {193, 90, 99},   {94, 60, 108},   {157, 188, 64},  {224, 163, 46},
    {56, 61, 150},   {70, 148, 73},   {175, 54, 60},   {231, 199, 31},  {187, 86, 149},  {8, 133, 161},
    {243, 243, 242}, {200, 200, 200}, {160, 160, 160}, {122, 122, 121}, {85, 85, 85},    {52, 52, 52}};
constexpr const char* kNames[kChartPatches] = {
    "dark skin", "light skin", "blue sky",  "foliage",      "blue flower", "bluish green",
    "orange",    "purplish blue", "moderate red", "purple", "yellow green", "orange yellow",
    "blue",      "green",      "red",       "yellow",       "magenta",     "cyan",
    "white 9.5", "neutral 8",  "neutral 6.5", "neutral 5",  "neutral 3.5", "black 2"};

double Rec709Y(const Rgb& c) { return Rec709Luminance(c); }

}  // namespace

const ChartColors& ColorCheckerLinearRec709() {
  static const ChartColors table = [] {
    ChartColors t{};
    for (int i = 0; i < kChartPatches; ++i)
      for (int c = 0; c < 3; ++c) t[i][c] = SrgbDecode(kSrgb8[i][c] / 255.0);
    return t;
  }();
  return table;
}

const char* ColorCheckerPatchName(int index) { return index >= 0 && index < kChartPatches ? kNames[index] : "?"; }

double NeutralLuminance(const ChartColors& rgb) {
  double s = 0.0;
  for (int i = 18; i < 24; ++i) s += Rec709Y(rgb[i]);
  return s / 6.0;
}

std::array<double, kChartPatches> ChartDeltaE2000(const ChartColors& rgb) {
  const ChartColors& ref = ColorCheckerLinearRec709();
  const double scale = NeutralLuminance(ref) / NeutralLuminance(rgb);
  std::array<double, kChartPatches> de{};
  for (int i = 0; i < kChartPatches; ++i) {
    const Rgb v = {rgb[i][0] * scale, rgb[i][1] * scale, rgb[i][2] * scale};
    de[i] = DeltaE2000(LinearRec709ToLab(v), LinearRec709ToLab(ref[i]));
  }
  return de;
}

Rgb Apply(const Matrix3& m, const Rgb& v) {
  return {m[0] * v[0] + m[1] * v[1] + m[2] * v[2], m[3] * v[0] + m[4] * v[1] + m[5] * v[2],
          m[6] * v[0] + m[7] * v[1] + m[8] * v[2]};
}

Matrix3 MultiplyMatrices(const Matrix3& a, const Matrix3& b) {
  Matrix3 r{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) r[3 * i + j] += a[3 * i + k] * b[3 * k + j];
  return r;
}

void ApplyColorCorrection(const Matrix3& m, ImageRGB* image) {
  float* p = image->pixels.data();
  const size_t n = image->pixels.size() / 3;
  for (size_t i = 0; i < n; ++i, p += 3) {
    const Rgb v = Apply(m, {p[0], p[1], p[2]});
    for (int c = 0; c < 3; ++c) p[c] = static_cast<float>(v[c]);
  }
}

ColorCorrection FitColorCorrection(const ChartColors& measured) {
  double max_value = 0.0;
  for (int i = 0; i < kChartPatches; ++i) {
    for (int c = 0; c < 3; ++c) {
      if (!std::isfinite(measured[i][c]) || measured[i][c] <= 0.0) {
        throw Error(std::string("colour chart: patch ") + std::to_string(i + 1) + " (" + kNames[i] +
                    ") has a non-positive or non-finite mean " + std::to_string(measured[i][c]) +
                    " in channel " + "RGB"[c] + "; expected linear camera values > 0");
      }
      max_value = std::max(max_value, measured[i][c]);
    }
  }
  // ccm masks patches outside (0, 0.98) as saturated: bring the brightest channel to 0.9.
  const double pre = 0.9 / max_value;
  cv::Mat src(kChartPatches, 1, CV_64FC3), ref(kChartPatches, 1, CV_64FC3);
  const ChartColors& reference = ColorCheckerLinearRec709();
  for (int i = 0; i < kChartPatches; ++i) {
    src.at<cv::Vec3d>(i) = cv::Vec3d(measured[i][0] * pre, measured[i][1] * pre, measured[i][2] * pre);
    ref.at<cv::Vec3d>(i) = cv::Vec3d(reference[i][0], reference[i][1], reference[i][2]);
  }
  cv::ccm::ColorCorrectionModel model(src, ref, cv::ccm::COLOR_SPACE_sRGBL);
  model.setColorSpace(cv::ccm::COLOR_SPACE_sRGB);  // the target: its linear form, Rec.709 primaries, D65
  model.setCCM_TYPE(cv::ccm::CCM_3x3);
  model.setLinear(cv::ccm::LINEARIZATION_IDENTITY);
  model.setDistance(cv::ccm::DISTANCE_CIE2000);
  model.setInitialMethod(cv::ccm::INITIAL_METHOD_LEAST_SQUARE);
  model.run();
  const cv::Mat ccm = model.getCCM();  // row vectors: dst = src * ccm
  ColorCorrection out;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) out.matrix[3 * i + j] = ccm.at<double>(j, i) * pre;
  // Keep the frame's scale: the neutral patches' mean camera value becomes their luminance.
  double camera_neutral = 0.0, corrected_neutral = 0.0;
  for (int i = 18; i < 24; ++i) {
    camera_neutral += (measured[i][0] + measured[i][1] + measured[i][2]) / 3.0;
    corrected_neutral += Rec709Y(Apply(out.matrix, measured[i]));
  }
  for (double& m : out.matrix) m *= camera_neutral / corrected_neutral;
  ChartColors corrected{};
  for (int i = 0; i < kChartPatches; ++i) corrected[i] = Apply(out.matrix, measured[i]);
  out.delta_e_before = ChartDeltaE2000(measured);
  out.delta_e_after = ChartDeltaE2000(corrected);
  out.ccm_loss = model.getLoss();
  return out;
}

namespace {
nlohmann::json DeltaESummary(const std::array<double, kChartPatches>& de) {
  const double mean = std::accumulate(de.begin(), de.end(), 0.0) / kChartPatches;
  return {{"mean", mean}, {"max", *std::max_element(de.begin(), de.end())}, {"per_patch", de}};
}
}  // namespace

nlohmann::json ColorCorrectionToJson(const ColorCorrection& c) {
  nlohmann::json patches = nlohmann::json::array();
  for (int i = 0; i < kChartPatches; ++i) patches.push_back(kNames[i]);
  return {{"format", "skycal.color_correction"},
          {"version", 1},
          {"matrix", c.matrix},
          {"matrix_meaning", "row-major 3x3, linear camera RGB -> scene-linear Rec.709 (D65), out = M * in"},
          {"label", c.label},
          {"source", c.source},
          {"sha256", c.source_sha256},
          {"delta_e2000",
           {{"meaning", "CIEDE2000 per ColorChecker patch against X-Rite's published sRGB values, exposure "
                        "normalised on the neutral patches 19-24"},
            {"patches", patches},
            {"before", DeltaESummary(c.delta_e_before)},
            {"after", DeltaESummary(c.delta_e_after)}}},
          {"ccm_loss", c.ccm_loss},
          {"detection", c.detection}};
}

ColorCorrection ColorCorrectionFromJson(const nlohmann::json& j, const std::string& what) {
  if (!j.is_object()) throw Error(what + ": expected a JSON object (skycal chart --out)");
  if (j.value("format", std::string()) != "skycal.color_correction") {
    throw Error(what + ": field 'format': expected \"skycal.color_correction\" (written by skycal chart --out)");
  }
  if (!j.contains("matrix") || !j["matrix"].is_array() || j["matrix"].size() != 9) {
    throw Error(what + ": field 'matrix': expected 9 numbers (row-major 3x3)");
  }
  ColorCorrection c;
  for (int i = 0; i < 9; ++i) {
    const auto& v = j["matrix"][i];
    if (!v.is_number() || !std::isfinite(v.get<double>())) {
      throw Error(what + ": field 'matrix[" + std::to_string(i) + "]': expected a finite number");
    }
    c.matrix[i] = v.get<double>();
  }
  const Matrix3& m = c.matrix;
  const double det = m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) +
                     m[2] * (m[3] * m[7] - m[4] * m[6]);
  if (!(std::abs(det) > 1e-9)) throw Error(what + ": field 'matrix': singular (determinant " + std::to_string(det) + ")");
  // The chart's CIEDE2000 as skycal chart measured it (for the frame's summary), when present.
  const nlohmann::json* de = j.contains("delta_e2000") ? &j["delta_e2000"] : nullptr;
  for (const char* when : {"before", "after"}) {
    if (!de || !de->contains(when) || !(*de)[when].contains("per_patch")) continue;
    const auto& v = (*de)[when]["per_patch"];
    if (!v.is_array() || v.size() != kChartPatches) {
      throw Error(what + ": field 'delta_e2000." + when + ".per_patch': expected 24 numbers");
    }
    auto& dst = std::string(when) == "before" ? c.delta_e_before : c.delta_e_after;
    for (int i = 0; i < kChartPatches; ++i) {
      if (!v[i].is_number()) throw Error(what + ": field 'delta_e2000." + when + ".per_patch[" + std::to_string(i) + "]': expected a number");
      dst[i] = v[i].get<double>();
    }
  }
  if (j.contains("detection") && j["detection"].is_object()) c.detection = j["detection"];
  c.label = j.value("label", std::string());
  c.source = j.value("source", std::string());
  c.source_sha256 = j.value("sha256", std::string());
  return c;
}

}  // namespace skycal::capture


namespace skycal::capture {

ColorCorrection CorrectionFromChartImage(const std::string& path, const std::vector<float>& response_curve,
                                         const ChartOptions& options, const std::string& label) {
  const ChartImage image = LoadChartImage(path, response_curve);
  const ChartDetection d = FindColorChecker(image, options);
  ColorCorrection c = FitColorCorrection(d.patches);
  c.source = path;
  c.source_sha256 = Sha256OfFile(path);
  c.label = label;
  c.detection = {{"method", d.method},
                 {"corners_px", d.corners},
                 {"detection_ev", d.detection_ev},
                 {"pixels_per_patch", d.pixels},
                 {"image_size", {image.linear.width, image.linear.height}}};
  return c;
}

}  // namespace skycal::capture
