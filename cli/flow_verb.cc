#include "flow_verb.h"

#include <string>
#include <vector>

#include "command_line.h"
#include "skycal/core/error.h"
#include "verb_common.h"

namespace skycal::cli {

nlohmann::json RunFlowImpl(const FlowOptions& o) {
  // The library names FlowOptions' fields; the user set them with these flags.
  static const FieldFlag kFlags[] = {{"FlowOptions::a", "frame A.exr"},
                                     {"FlowOptions::b", "frame B.exr"},
                                     {"FlowOptions::out", "--out"},
                                     {"FlowOptions::scale", "--scale"}};
  std::string why;
  if (!o.IsValid(&why)) throw Error(FieldsAsFlags(why, kFlags));
  try {
    return capture::WriteFlowVectors(o);
  } catch (const Error& e) {
    throw Error(FieldsAsFlags(e.what(), kFlags));
  }
}

FlowOptions ParseFlowArgs(int argc, char** argv) {
  VerbCommandLine cl("flow",
                     "skycal flow: motion vectors between two consecutive time-lapse frames (quarter resolution,\n"
                     "forward and backward, 8-bit with a per-frame range in a JSON sidecar)",
                     "  skycal flow A.exr B.exr --out V.exr [--scale 4] [--json]",
                     "Writes V.exr (float: R,G forward u,v; backward.u, backward.v), V.png (8-bit RGBA) and\n"
                     "V.json (per-component min/max: value = min + (max - min) * code / 255). Units: texture\n"
                     "space (u a fraction of the width, v of the height). OpenCV DIS on log luminance.");
  FlowOptions o;
  // The two frames lead (`skycal flow A.exr B.exr --out V.exr`); the options follow.
  std::vector<std::string> frames;
  std::vector<char*> rest;
  int i = 0;
  for (; i < argc && argv[i][0] != '-'; ++i) frames.emplace_back(argv[i]);
  for (; i < argc; ++i) rest.push_back(argv[i]);
  cl.Text("--out", &o.out, "V.exr", "the float vectors (V.png and V.json beside it)");
  cl.Integer("--scale", &o.scale, 1, 16, "expected an integer in [1, 16]", "N", "vectors at 1/N of the frames' size (default 4)");
  bool json = false;
  cl.Flag("--json", &json, "print the sidecar as a JSON summary on stdout");
  cl.Parse(static_cast<int>(rest.size()), rest.data());
  if (frames.size() != 2) throw Error("expected two frames, A.exr B.exr; found " + std::to_string(frames.size()));
  o.a = frames[0];
  o.b = frames[1];
  return o;
}

int RunFlow(int argc, char** argv) {
  return RunVerb("flow", WantsJson(argc, argv), [&]() { return RunFlowImpl(ParseFlowArgs(argc, argv)); });
}

}  // namespace skycal::cli
