#include "stars_verb.h"

#include <filesystem>

#include "command_line.h"
#include "finite_output.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "verb_common.h"

namespace skycal::cli {

namespace {
bool EndsWithExr(const std::string& p) { return p.size() > 4 && p.substr(p.size() - 4) == ".exr"; }
}  // namespace

bool StarsOptions::IsValid(std::string* why) const {
  if (reference.empty()) {
    *why = "--reference: required (a night frame, *.exr)";
    return false;
  }
  if (!EndsWithExr(out)) {
    *why = "--out: expected a path ending in .exr";
    return false;
  }
  if (!mask_out.empty() && !EndsWithExr(mask_out)) {
    *why = "--mask-out: expected a path ending in .exr";
    return false;
  }
  if (!mask_out.empty() && mask_out == out) {
    *why = "--mask-out: the same path as --out";
    return false;
  }
  if (removal.IsValid(why)) return true;
  *why = WithStarFlags(*why);
  return false;
}

nlohmann::json RunStarsImpl(const StarsOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  std::vector<NamedPath> outputs = {{"--out", o.out}};
  if (!o.mask_out.empty()) outputs.push_back({"--mask-out", o.mask_out});
  RefuseOutputsOverInputs(outputs, {{"--reference", o.reference}});
  for (const auto& p : outputs) AtomicOutput probe(p.path);  // unwritable: refused before the work
  const ExrRGB in = ReadExrRGB(o.reference);
  std::vector<ExrPlane> planes;  // the frame's other channels (masks), kept as they were
  for (const std::string& c : in.channels) {
    if (c == "R" || c == "G" || c == "B") continue;
    int w = 0, h = 0;
    planes.push_back({c, ReadExrChannel(o.reference, c, &w, &h)});
  }
  Log("stars", "finding stars in " + o.reference + " (" + std::to_string(in.image.width) + "x" +
                   std::to_string(in.image.height) + ")");
  capture::StarRemovalResult r = capture::RemoveStars(in.image, o.removal);
  PrepareImageForWrite("stars", o.out, &r.image, false);
  ExrAttributes attrs = in.attributes;
  attrs.floats["skycalStarsRemoved"] = static_cast<float>(r.stars);
  if (!o.mask_out.empty()) {
    ImageRGB mask(in.image.width, in.image.height);
    for (size_t i = 0; i < r.mask.size(); ++i) mask.pixels[3 * i] = mask.pixels[3 * i + 1] = mask.pixels[3 * i + 2] = r.mask[i];
    WriteExrRGB(o.mask_out, mask, {});
  }
  try {
    WriteExrRGBWithPlanes(o.out, r.image, planes, attrs);
  } catch (...) {
    if (!o.mask_out.empty()) std::filesystem::remove(o.mask_out);  // both or neither
    throw;
  }
  Log("stars", "removed " + std::to_string(r.stars) + " stars (" + std::to_string(r.pixels_replaced) +
                   " pixels replaced; " + std::to_string(r.rejected_large) + " groups too large, " +
                   std::to_string(r.rejected_clustered) + " not isolated) -> " + o.out);
  nlohmann::json j = r.ToJson();
  j["out"] = o.out;
  j["mask_out"] = o.mask_out;
  j["reference"] = o.reference;
  return j;
}

std::string WithStarFlags(const std::string& message) {
  static const FieldFlag kFlags[] = {{"StarRemovalOptions::window_px", "--star-window"},
                                     {"StarRemovalOptions::threshold_sigma", "--star-sigma"},
                                     {"StarRemovalOptions::min_contrast", "--star-contrast"},
                                     {"StarRemovalOptions::max_star_pixels", "--star-max-pixels"}};
  return FieldsAsFlags(message, kFlags);
}

void RegisterStarOptions(VerbCommandLine& cl, capture::StarRemovalOptions* o) {
  cl.Integer("--star-window", &o->window_px, 3, 31, "expected an odd number of pixels in [3, 31]", "PX",
             "median window side, pixels (default 7)");
  cl.Number("--star-sigma", &o->threshold_sigma, "K", "a star's peak exceeds the local median by K x the noise (default 6)");
  cl.Number("--star-contrast", &o->min_contrast, "C", "... and by C relative to it (default 0.5: 50% above)");
  cl.Integer("--star-max-pixels", &o->max_star_pixels, 1, 400, "expected an integer in [1, 400]", "N",
             "larger groups of bright pixels are not stars (default 12; x up to 4 near a lat-long's pole)");
}

StarsOptions ParseStarsArgs(int argc, char** argv) {
  VerbCommandLine cl("stars", "skycal stars: remove the stars of a night frame (median-based), count and mask them",
                     "  skycal stars --reference NIGHT.exr --out CLEAN.exr [--mask-out STARS.exr]\n"
                     "               [--star-window PX] [--star-sigma K] [--star-contrast C] [--star-max-pixels N] [--json]",
                     "A star: a group of at most N pixels (4 wide and tall) above the local median by K sigma and C,\n"
                     "with no other such pixel within 2 px. It and a 1-pixel halo become the median of the window's\n"
                     "other pixels; every other pixel is written unchanged.");
  StarsOptions o;
  bool json = false;
  cl.Text("--reference", &o.reference, "NIGHT.exr", "the frame (required); its other channels and attributes are kept");
  cl.Text("--out", &o.out, "CLEAN.exr", "the frame without its stars (required); attribute skycalStarsRemoved");
  cl.Text("--mask-out", &o.mask_out, "STARS.exr", "R = G = B = 1 where a pixel was replaced, else 0");
  RegisterStarOptions(cl, &o.removal);
  cl.Flag("--json", &json, "print a JSON summary on stdout (the log goes to stderr)");
  cl.Parse(argc, argv);
  return o;
}

int RunStars(int argc, char** argv) {
  return RunVerb("stars", WantsJson(argc, argv), [&]() { return RunStarsImpl(ParseStarsArgs(argc, argv)); });
}

}  // namespace skycal::cli
