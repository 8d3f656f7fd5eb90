// The verbs' command-line parser (cli/command_line.h on CLI11, and the value converters of
// cli/option_values.h) on fuzzed argument vectors. The input is split at newlines into at
// most 32 arguments; one option of every kind the verbs register is declared (text,
// optional text, number, optional number, bounded integer, flag, repeatable, list), and
// the text values then go through the converters the verbs apply ("X,Y,Z", "WxH", number
// lists, integers). Parsing must reject bad input only with skycal::Error (or ask for help);
// anything else that escapes, or a crash inside CLI11, is a finding.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "command_line.h"
#include "fuzz_support.h"
#include "option_values.h"

namespace {

std::vector<std::string> SplitArguments(const uint8_t* data, size_t size) {
  std::vector<std::string> args(1);
  for (size_t i = 0; i < size && args.size() <= 32; ++i) {
    if (data[i] == '\n') {
      args.emplace_back();
    } else {
      args.back().push_back(static_cast<char>(data[i]));
    }
  }
  if (args.size() > 32) args.resize(32);
  return args;
}

void ParseOnce(std::vector<std::string>& args) {
  using skycal::cli::VerbCommandLine;
  VerbCommandLine cl("fuzz", "skycal fuzz: every kind of option", "  skycal fuzz [options]");
  std::string out, size = "64x32", sun_dir;
  std::optional<std::string> preset;
  double exposure = 0.0;
  std::optional<double> elevation;
  int width = 512;
  bool json = false;
  std::vector<std::string> references, brackets;
  std::string list;
  cl.Text("--out", &out, "OUT.exr", "output");
  cl.Text("--size", &size, "WxH", "size");
  cl.Text("--sun-dir", &sun_dir, "X,Y,Z", "sun");
  cl.Text("--list", &list, "A,B,C", "numbers");
  cl.Text("--preset", &preset, "P.json", "preset");
  cl.Number("--exposure", &exposure, "EV", "stops");
  cl.Number("--sun-elevation", &elevation, "DEG", "degrees");
  cl.Integer("--width", &width, 16, 16384, "expected an even width in [16, 16384]", "W", "width");
  cl.Flag("--json", &json, "json");
  cl.Repeatable("--reference", &references, "REF.exr", "references");
  cl.List("--brackets", &brackets, "IMG", "brackets");
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  try {
    cl.Parse(static_cast<int>(argv.size()), argv.data());
  } catch (const skycal::cli::HelpRequested& h) {
    if (h.help().empty()) std::abort();  // help must say something
    return;
  }
  if (!sun_dir.empty()) skycal::cli::ParseVec3(sun_dir, "sun-dir");
  skycal::cli::ParseSize(size, "size");
  if (!list.empty()) skycal::cli::ParseNumberList(list, "list");
  if (!out.empty()) skycal::cli::ParseInteger(out, "out");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::vector<std::string> args = SplitArguments(data, size);
  skycal::fuzz::ExpectOnlySkycalErrors([&] { ParseOnce(args); });
  return 0;
}
