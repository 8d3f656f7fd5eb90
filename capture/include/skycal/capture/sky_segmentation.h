// Automatic sky segmentation of a lat-long frame: what is not sky (buildings, trees,
// terrain, pylons, the ground or mirrored lower half) is found without a hand-drawn mask,
// so `skycal fit` and the cloud statistics see sky pixels only.
//
// The cues, each a statistic of the frame itself (no model, no training data):
//  - below the horizon: not sky (the lower half of a lat-long is ground, or in a published
//    panorama a reflection-like plane);
//  - darkness: objects against the sky are darker than the sky around them at the same
//    elevation. The reference is a high quantile of log luminance per image row within an
//    azimuth window (the bright side of the row), so the sun's side and the far side of a
//    twilight sky each get their own;
//  - texture: foliage, lattices and building edges have high local gradient energy of log
//    luminance at the pixel scale, the sky (clouds included) has little;
//  - ground connection: buildings, trees and terrain stand on the horizon, clouds float.
//    Candidates (dark, or textured and somewhat dark) are kept only where their connected
//    component reaches the lowest rows above the horizon, and is dark there (a cloud bank
//    that reaches the horizon fades into its haze);
//  - grabCut (OpenCV, Rother et al. 2004, "GrabCut: interactive foreground extraction")
//    seeded from the confident pixels of both classes refines the boundary by colour
//    models and an edge-aware smoothness term.
// Everything is measured against the hand masks in bench/results/sky_segmentation.md.
#pragma once
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "skycal/core/image.h"

namespace skycal::capture {

struct SkyMaskOptions {
  double horizon_deg = 0.0;            // elevation (deg) at and below which nothing is sky, [-10, 30]
  double darkness_quantile = 0.8;      // quantile of a row window's log luminance taken as the sky's, (0, 1)
  double darkness_window_deg = 60.0;   // azimuth width (deg) of that window, [5, 360]
  double darkness_threshold = 0.7;     // natural-log units below the sky's reference: a non-sky candidate, > 0
  double texture_sigma_px = 1.5;       // Gaussian scale (pixels) of the gradient-energy residual, [0.5, 8]
  double texture_threshold = 0.06;     // local RMS of log luminance about its blur: textured, > 0
  double textured_darkness = 0.2;      // a textured pixel must also be this much darker (log units), >= 0
  // A candidate component must reach this band above the horizon (deg, at least the lowest
  // row above it), [0, 45]. Buildings, trees and terrain stand on the ground and cross the
  // horizon; a cloud's base at the game's draw distance (1.5 km up, 35 km away) is ~2.3 deg
  // up, so a dark cloud mass over a cumulus bank is not grounded (4 deg grounded it).
  double ground_band_deg = 1.0;
  // ... and stand on it darkly: at least this share of a component's pixels in that band must
  // be darker than the sky's reference by darkness_threshold, [0, 1] (0: any contact grounds),
  // or 8 of them (a tree line merged with a wide hazy bank beside it keeps the trees).
  // Trees, buildings and pylons occlude the horizon and are dark where they meet it (a thin
  // mast: its one or two pixels in the ring of texture candidates around them, 0.2 of the
  // contact in the test); a cloud bank reaching the horizon is seen there through tens of
  // kilometres of haze, and only its texture makes it a candidate: none of its contact is
  // dark (bench/results/sky_segmentation.md, "Cloud banks on the horizon").
  double ground_dark_share = 0.1;
  double sun_exclusion_deg = 6.0;      // no candidates within this angle of the sun (glare, DWAB ringing), [0, 45]
  // Thin dark lines (wires, cables) joining the non-sky class they hang from: a pixel darker
  // than its 3x3 closing by this much (log units), connected to it; 0: off. [0, 10]
  double line_darkness = 0.05;
  bool grabcut = true;                 // refine with cv::grabCut
  int grabcut_iterations = 3;          // [1, 20]
  int dilate_px = 1;                   // grow the non-sky class by this many pixels (mixed edge pixels), [0, 16]
  // False and the field, its value and the expected range in *why.
  bool IsValid(std::string* why) const;
};

struct SkyMask {
  int width = 0, height = 0;
  std::vector<float> sky;         // per pixel: 1 sky, 0 not sky (the fit's --mask convention: R < 0.5 excludes)
  std::vector<float> confidence;  // per pixel in [0, 1]: 1 for seeds and below the horizon, lower near decisions
  long long non_sky_above_horizon = 0;  // pixels above the horizon classed as not sky
  long long above_horizon = 0;          // pixels above the horizon
  long long ground_connected_candidates = 0;  // candidate pixels kept by the ground-connection rule
  long long floating_candidates = 0;          // candidate pixels dropped by it (clouds, dark sky patches)
};

// `frame`: a lat-long (core/latlong.h convention). `sun_dir` (unit, toward the sun) if known.
// Invalid pixels (NaN, Inf, <= 0) are classed by their neighbourhood. Throws skycal::Error on
// invalid options or an empty frame.
SkyMask EstimateSkyMask(const ImageRGB& frame, const std::optional<std::array<double, 3>>& sun_dir,
                        const SkyMaskOptions& options);

// Precision and recall of the NON-SKY class against a reference mask (1 sky, 0 not sky; the
// hand masks' R), over the pixels above `min_elevation_deg` (the classes below the horizon
// are the same by construction, so they would only inflate the numbers).
struct SegmentationScore {
  long long true_non_sky = 0, false_non_sky = 0, missed_non_sky = 0, evaluated = 0;
  double precision = 0.0, recall = 0.0, iou = 0.0;
};
// Throws skycal::Error on a size mismatch.
SegmentationScore ScoreNonSky(const SkyMask& mask, const std::vector<float>& reference_sky, int width, int height,
                              double min_elevation_deg);

}  // namespace skycal::capture
