// Loads an HTML file in headless Chromium (Debian's `chromium`) and reports what a person
// would see: console errors and uncaught exceptions, every <img> (decoded size, place on
// the page) and a screenshot of the whole page. Talks the DevTools protocol over
// --remote-debugging-pipe (JSON messages separated by NUL on file descriptors 3 and 4), so
// no WebSocket client or Node package is needed.
#pragma once
#include <optional>
#include <string>
#include <vector>

namespace skycal::testing {

struct PageImage {
  std::string cls, alt;
  int natural_width = 0, natural_height = 0;
  double x = 0, y = 0, width = 0, height = 0;  // CSS pixels, page coordinates
};

struct PageReport {
  std::vector<std::string> errors;  // console.error/assert, uncaught exceptions, log entries of level error
  std::vector<PageImage> images;
  int page_width = 0, page_height = 0;
  std::string screenshot_png;       // the whole page, `screenshot_scale` device pixels per CSS pixel
  double screenshot_scale = 1.0;
  std::string browser;              // Browser.getVersion's product
};

// nullopt with *why when Chromium cannot run here (not installed, or it does not answer the
// first protocol request); any later failure throws std::runtime_error. `scale`: of the
// screenshot (0.5 halves each side: a tall page encodes 4x faster).
std::optional<PageReport> LoadPageInChromium(const std::string& html_path, const std::string& profile_dir,
                                             std::string* why, double scale = 1.0);

// Fraction of the pixels of `png` inside the rectangle that differ (any channel by more than
// 24 of 255) from the rectangle's most common colour: 0 for a blank area.
double InkFraction(const std::string& png, double x, double y, double width, double height);
// The same for an image of the page (its rectangle scaled to the screenshot).
double InkFraction(const PageReport& page, const PageImage& im);

}  // namespace skycal::testing
