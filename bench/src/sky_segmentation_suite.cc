// Suite `sky-segmentation`: the automatic sky mask (capture/sky_segmentation.h, `skycal
// mask`) on the real skies — what the bench_sky_segmentation program measured
// (bench/results/sky_segmentation.md), now a suite of `skycal bench`.
//
// Precision and recall of the NON-SKY class above the horizon against the hand masks of
// datasets/masks (sunrise, sunset; R < 0.5: not sky), also above 3.3 deg (the hand masks
// exclude the lowest 3.3 deg wholesale: haze, the far shore); on the frames without hand
// masks (sky, dawn, city) the share of non-sky found. Grid: grabcut on (the default
// SkyMaskOptions) / off (the candidate mask alone: the refinement's cost and what it buys).
// Error: 1 - the mean IoU of the non-sky class over the hand-masked frames. Time: all the
// frames' EstimateSkyMask (loading excluded). --quick: the two hand-masked frames, one run.
// Needs datasets/real (datasets/fetch_real_skies.sh): without it each case is a clear error.
#include <chrono>
#include <cmath>
#include <filesystem>

#include "skycal/bench/study_suite_grids.h"
#include "skycal/capture/latlong_frame.h"
#include "skycal/capture/sky_segmentation.h"
#include "skycal/core/error.h"
#include "skycal/core/exr_io.h"
#include "suite_util.h"
#include "suites_internal.h"

namespace skycal::bench {

namespace {

constexpr double kHandMaskFloorDeg = 3.3;  // the hand masks' own exclusion band above the horizon

std::string Root() { return SKYCAL_SOURCE_DIR; }

std::string Fixed3(const nlohmann::json& row, const std::string& key) {
  return row.contains(key) ? FormatFixed(row[key].get<double>(), 3) : "-";
}

}  // namespace

SkySegmentationPlan SkySegmentationGridPlan(bool quick) {
  SkySegmentationPlan p;
  p.grid.axes = {{"grabcut", {"on", "off"}, "on"}};
  p.frames = {"sunrise", "sunset"};
  p.hand_masks = {"sunrise_mask.exr", "sunset_mask.exr"};
  if (!quick)
    for (const char* f : {"sky", "dawn", "city"}) p.frames.push_back(f), p.hand_masks.push_back("");
  return p;
}

namespace {

std::string SkySegmentationMarkdown(const std::vector<CaseResult>& cases) {
  std::string md =
      "# Automatic sky segmentation against the hand masks\n\n"
      "`skycal bench --suite sky-segmentation` (bench/src/sky_segmentation_suite.cc; capture/sky_segmentation.h).\n"
      "Precision and recall of the NON-SKY class above the horizon (elevation > 0), against the hand masks of "
      "`datasets/masks` (R < 0.5: not sky); in brackets above 3.3 deg (the hand masks exclude the lowest 3.3 deg "
      "wholesale: haze, fog, the far shore). Below the horizon both are non-sky by construction and are left out of "
      "the counts. Error: 1 - the mean IoU over the hand-masked frames. Times: EstimateSkyMask alone (the frame's "
      "loading excluded), per frame from the last timed run.\n\n" +
      CaseTable(cases, "1 - mean IoU", {{"ms per frame (mean)", [](const CaseResult& c) { return ExtraNumber(c, "ms_per_frame_mean"); }}});
  for (const CaseResult& c : cases) {
    if (!c.extra.contains("frames")) continue;
    md += "\n## grabcut " + Get(c.settings, "grabcut") + (c.is_default ? " (the default)" : "") +
          "\n\n| frame | size | precision | recall | IoU | non-sky above horizon (auto) | hand | ground-connected / "
          "floating candidates | time (ms) |\n|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& r : c.extra["frames"]) {
      const bool hand = r.contains("precision");
      const double share = 100.0 * r["non_sky_above_horizon"].get<double>() / r["above_horizon"].get<double>();
      md += "| " + r["frame"].get<std::string>() + " | " + r["size"].get<std::string>() + " | " +
            (hand ? Fixed3(r, "precision") + " (" + Fixed3(r, "precision_above_3.3deg") + ")" : "-") + " | " +
            (hand ? Fixed3(r, "recall") + " (" + Fixed3(r, "recall_above_3.3deg") + ")" : "-") + " | " +
            (hand ? Fixed3(r, "iou") : "-") + " | " + std::to_string(r["non_sky_above_horizon"].get<long long>()) + " (" +
            std::to_string(std::lround(share)) + "%) | " +
            (hand ? std::to_string(r["hand_non_sky"].get<long long>()) : "-") + " | " +
            std::to_string(r["ground_connected_candidates"].get<long long>()) + " / " +
            std::to_string(r["floating_candidates"].get<long long>()) + " | " +
            std::to_string(std::lround(r["ms_last_run"].get<double>())) + " |\n";
    }
  }
  return md;
}

// A real frame and its hand mask (empty without one).
struct SegFrame {
  capture::LatLongFrame frame;
  std::vector<float> hand;
  int hand_w = 0, hand_h = 0;
};

std::vector<SegFrame> LoadSegFrames(const SkySegmentationPlan& plan) {
  std::vector<SegFrame> frames;
  for (size_t k = 0; k < plan.frames.size(); ++k) {
    const std::string path = Root() + "/datasets/real/" + plan.frames[k] + ".exr";
    if (!std::filesystem::exists(path))
      throw Error(path + ": missing (the real skies: run datasets/fetch_real_skies.sh)");
    SegFrame f{capture::ReadLatLongFrame(path), {}, 0, 0};
    if (!plan.hand_masks[k].empty())
      f.hand = ReadExrChannel(Root() + "/datasets/masks/" + plan.hand_masks[k], "R", &f.hand_w, &f.hand_h);
    frames.push_back(std::move(f));
  }
  return frames;
}

// Each frame's mask scored against its hand mask (where it has one): error, outcome and
// extra into c.
void ScoreSegCase(CaseResult& c, const SkySegmentationPlan& plan, const std::vector<SegFrame>& frames,
                  const std::vector<capture::SkyMask>& masks, const std::vector<double>& ms) {
  nlohmann::json rows = nlohmann::json::array();
  double iou_sum = 0.0, ms_sum = 0.0;
  int scored = 0;
  for (size_t k = 0; k < frames.size(); ++k) {
    const capture::SkyMask& m = masks[k];
    nlohmann::json r = {{"frame", plan.frames[k]},
                        {"size", std::to_string(m.width) + "x" + std::to_string(m.height)},
                        {"non_sky_above_horizon", m.non_sky_above_horizon},
                        {"above_horizon", m.above_horizon},
                        {"ground_connected_candidates", m.ground_connected_candidates},
                        {"floating_candidates", m.floating_candidates},
                        {"ms_last_run", ms[k]}};
    ms_sum += ms[k];
    if (!frames[k].hand.empty()) {
      const auto a = capture::ScoreNonSky(m, frames[k].hand, frames[k].hand_w, frames[k].hand_h, 0.0);
      const auto b = capture::ScoreNonSky(m, frames[k].hand, frames[k].hand_w, frames[k].hand_h, kHandMaskFloorDeg);
      r["precision"] = a.precision;
      r["recall"] = a.recall;
      r["iou"] = a.iou;
      r["hand_non_sky"] = a.true_non_sky + a.missed_non_sky;
      r["precision_above_3.3deg"] = b.precision;
      r["recall_above_3.3deg"] = b.recall;
      iou_sum += a.iou;
      ++scored;
    }
    rows.push_back(r);
  }
  c.error = 1.0 - iou_sum / scored;
  if (!std::isfinite(c.error)) {
    c.outcome = Outcome::kNonFinite;
    c.message = "non-finite IoU";
  }
  c.extra = {{"frames", rows}, {"ms_per_frame_mean", ms_sum / frames.size()}};
}

std::vector<CaseResult> RunSkySegmentation(const SuiteOptions& o) {
  const SkySegmentationPlan plan = SkySegmentationGridPlan(o.quick);
  return RunGrid("sky-segmentation", plan.grid, o, [&](CaseResult& c) {
    capture::SkyMaskOptions mo;
    mo.grabcut = Get(c.settings, "grabcut") == "on";
    const std::vector<SegFrame> frames = LoadSegFrames(plan);
    std::vector<capture::SkyMask> masks(frames.size());
    std::vector<double> ms(frames.size());
    c.time = Measure(
        [&] {
          for (size_t k = 0; k < frames.size(); ++k) {
            const auto t0 = std::chrono::steady_clock::now();
            masks[k] = capture::EstimateSkyMask(frames[k].frame.radiance, frames[k].frame.sun_direction, mo);
            ms[k] = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
          }
        },
        o.quick ? 0 : o.warmup, o.Repeats(o.quick ? 1 : 3));
    ScoreSegCase(c, plan, frames, masks, ms);
  });
}

}  // namespace

Suite SkySegmentationSuite() {
  Suite s;
  s.name = "sky-segmentation";
  s.summary = "the automatic sky mask on the real skies (sunrise, sunset against their hand masks; sky, dawn, city; "
              "--quick: the two hand-masked frames): grabcut on/off";
  s.error_metric = "1 - mean IoU of the non-sky class above the horizon against the hand masks (sunrise, sunset)";
  s.error_axis = "1 - mean non-sky IoU vs the hand masks";
  s.markdown = SkySegmentationMarkdown;
  s.run = RunSkySegmentation;
  return s;
}

}  // namespace skycal::bench
