#include "chart_verb.h"

#include "command_line.h"
#include "option_values.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "skycal/core/json_file.h"
#include "skycal/core/format_number.h"
#include "verb_common.h"

namespace skycal::cli {

bool ChartVerbOptions::IsValid(std::string* why) const {
  if (image.empty()) {
    *why = "--image: required (a photograph or EXR of a ColorChecker Classic)";
    return false;
  }
  if (out.size() < 6 || out.substr(out.size() - 5) != ".json") {
    *why = "--out: expected a path ending in .json";
    return false;
  }
  if (response != capture::ResponseModel::kLinear && response != capture::ResponseModel::kSrgb) {
    *why = "--response: expected linear or srgb (a chart image is one exposure: no curve can be recovered from it)";
    return false;
  }
  if (!chart.IsValid(why)) return false;
  return true;
}

std::array<double, 8> ParseChartCorners(const std::string& text, const std::string& option) {
  const std::vector<double> v = ParseNumberList(text, option);
  if (v.size() != 8) {
    throw Error(option + ": expected 8 numbers X1,Y1,...,X4,Y4 in pixels (the corner at patch 1, dark skin, first, "
                "then clockwise), got " + std::to_string(v.size()));
  }
  std::array<double, 8> c{};
  std::copy(v.begin(), v.end(), c.begin());
  return c;
}

nlohmann::json RunChartImpl(const ChartVerbOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  RefuseOutputsOverInputs({{"--out", o.out}}, {{"--image", o.image}});
  { AtomicOutput probe(o.out); }  // fail on an unwritable output before the work
  std::vector<float> response;
  if (o.response == capture::ResponseModel::kSrgb) {
    response.resize(256 * 3);
    for (int k = 0; k < 256; ++k)
      for (int c = 0; c < 3; ++c) response[3 * k + c] = static_cast<float>(capture::SrgbDecode(k / 255.0));
  }
  const capture::ColorCorrection c = capture::CorrectionFromChartImage(o.image, response, o.chart, o.label);
  WriteJsonFileAtomically(o.out, capture::ColorCorrectionToJson(c));  // refuses CORRECTION.csv and the like
  const nlohmann::json summary = ChartSummary(c);
  Log("chart", "wrote " + o.out + ": mean CIEDE2000 " + FormatNumber(summary["delta_e2000_before"]["mean"].get<double>()) +
                   " -> " + FormatNumber(summary["delta_e2000_after"]["mean"].get<double>()) + " (" +
                   summary["detection"].get<std::string>() + ")");
  nlohmann::json out = summary;
  out["out"] = o.out;
  return out;
}

ChartVerbOptions ParseChartArgs(int argc, char** argv) {
  VerbCommandLine cl("chart",
                     "skycal chart: a colour-chart correction (camera RGB -> scene-linear Rec.709) from an image of a "
                     "ColorChecker Classic",
                     "  skycal chart --image CHART.exr|CHART.png --out CORRECTION.json [--response linear|srgb]\n"
                     "               [--chart-corners X1,Y1,...,X4,Y4] [--label TEXT] [--json]",
                     "The chart is found by OpenCV mcc unless --chart-corners gives it. Apply the result with\n"
                     "skycal capture --color-correction CORRECTION.json.");
  ChartVerbOptions o;
  std::optional<std::string> response, corners;
  bool json = false;
  cl.Text("--image", &o.image, "IMG",
          "the chart through the camera (and filter) to correct: an EXR (linear) or an\n"
          "8/16-bit image (required)");
  cl.Text("--out", &o.out, "CORRECTION.json", "the correction (required)");
  cl.Text("--response", &response, "NAME", "code values of an 8/16-bit image: linear (default, raw developed) or srgb");
  cl.Text("--chart-corners", &corners, "X1,Y1,...",
          "the chart's outer corners in pixels, the one at patch 1 (dark skin) first,\n"
          "then clockwise (patches 6, 24, 19); default: detected");
  cl.Text("--label", &o.label, "TEXT", "which exposure set the chart belongs to, e.g. nd or no-nd (stored)");
  cl.Flag("--json", &json, "print a JSON summary on stdout (the log goes to stderr)");
  cl.Parse(argc, argv);
  if (response) o.response = capture::ParseResponseModel(*response, "--response");
  if (corners) o.chart.corners = ParseChartCorners(*corners, "--chart-corners");
  return o;
}

int RunChart(int argc, char** argv) {
  return RunVerb("chart", WantsJson(argc, argv), [&]() { return RunChartImpl(ParseChartArgs(argc, argv)); });
}

}  // namespace skycal::cli
