// Can the brackets determine the camera response? A recovered curve is measured only at the
// codes that some pixel shows well exposed in two brackets: the exposure ratio between the
// two readings is what ties one code's ln f to another's (Debevec & Malik 1997, section
// 2.1). A code seen only in pixels that are black or clipped in every other bracket is tied
// to nothing: the curve there is the smoothness prior's interpolation, and a merge through
// it can be off by several percent with nothing else to show for it. That happens when the
// brackets are too far apart for the curve's slope: a steep mid-tone (many codes per stop)
// between a toe and a strong shoulder spans less than the bracket step, so no pixel is well
// exposed in the mid-tones and in a neighbouring bracket (the well-exposed ranges of
// neighbouring brackets do not overlap there). This check counts, per channel, the pixels
// well exposed in >= 2 brackets and, per code, how many of them show that code; it warns
// (naming the codes) instead of leaving a quiet error.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "camera_response.h"

namespace skycal::capture::detail {
namespace {

// The longest run of codes flagged in `bad` (first, last), or (-1, -1).
std::pair<int, int> LongestRun(const std::vector<bool>& bad) {
  std::pair<int, int> best{-1, -1};
  int start = -1;
  for (int z = 0; z <= static_cast<int>(bad.size()); ++z) {
    const bool b = z < static_cast<int>(bad.size()) && bad[z];
    if (b && start < 0) start = z;
    if (!b && start >= 0) {
      if (best.first < 0 || z - 1 - start > best.second - best.first) best = {start, z - 1};
      start = -1;
    }
  }
  return best;
}

}  // namespace

nlohmann::json ResponseDeterminacy(const std::vector<const BracketImage*>& images, const MergeOptions& o,
                                   std::vector<std::string>* warnings) {
  const BracketImage& first = *images.front();
  const WeightTable wt = MakeWeights(o, 255, true);
  const int lo = wt.low_code + 1, hi = wt.high_code - 1, fit_codes = hi - lo + 1;
  const long long total = static_cast<long long>(first.width) * first.height;
  const int stride = std::max(1, static_cast<int>(std::ceil(std::sqrt(double(total) / 65536.0))));
  nlohmann::json channels = nlohmann::json::array();
  const char* names[3] = {"R", "G", "B"};
  for (int c = 0; c < 3; ++c) {
    std::vector<long long> seen(256, 0), shown(256, 0);  // by linked pixels; by any pixel
    long long grid = 0, linked = 0;
    for (int y = stride / 2; y < first.height; y += stride)
      for (int x = stride / 2; x < first.width; x += stride, ++grid) {
        const size_t idx = first.index(x, y) + c;
        int good = 0;
        for (const BracketImage* img : images) good += wt.w[Code8(*img, idx)] > 0.0f;
        for (const BracketImage* img : images) {
          const int z = Code8(*img, idx);
          if (wt.w[z] > 0.0f) ++shown[z], seen[z] += good >= 2;
        }
        linked += good >= 2;
      }
    // A code is unlinked when pixels show it (well exposed, >= 2% of the average code's count
    // of linked readings, each linked pixel giving >= 2) but fewer than that many of them are
    // linked: the merge reads the curve there, the brackets do not measure it. Codes the scene
    // does not show (e.g. the darkest ones, when its darkest point is brighter) do not count.
    const double floor_count = std::max(1.0, 0.02 * 2.0 * double(linked) / fit_codes);
    std::vector<bool> unlinked(256, false);
    int unlinked_count = 0;
    for (int z = lo; z <= hi; ++z) unlinked_count += (unlinked[z] = shown[z] >= floor_count && seen[z] < floor_count);
    const auto run = LongestRun(unlinked);
    const double linked_fraction = grid > 0 ? double(linked) / double(grid) : 0.0;
    channels.push_back({{"channel", names[c]}, {"linked_pixel_fraction", linked_fraction},
                        {"unlinked_codes", unlinked_count},
                        {"longest_unlinked_run", run.first < 0 ? nlohmann::json() : nlohmann::json({run.first, run.second})}});
    std::ostringstream w;
    if (linked_fraction < 0.01) {
      w << "channel " << names[c] << ": only " << 100.0 * linked_fraction << "% of the pixels are well exposed (codes "
        << lo << ".." << hi << ") in two brackets: too few brackets, or too far apart for their well-exposed ranges "
        << "to overlap; the recovered curve is not determined by these brackets (give a known response)";
    } else if (unlinked_count >= std::max(5, fit_codes / 50)) {
      w << "channel " << names[c] << ": " << unlinked_count << " of the codes " << lo << ".." << hi
        << " (longest run " << run.first << ".." << run.second << ") are shown by pixels that are well exposed in no "
        << "second bracket, so the curve there is interpolated, not measured: the brackets are too far apart for "
        << "this curve's slope (add brackets in between, or give a known response)";
    }
    if (!w.str().empty() && warnings) warnings->push_back(w.str());
  }
  return {{"codes", {lo, hi}}, {"grid_stride", stride}, {"channels", channels}};
}

}  // namespace skycal::capture::detail
