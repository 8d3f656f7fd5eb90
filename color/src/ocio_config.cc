#include "ocio_config.h"

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>

#include "skycal/color/preview.h"
#include "skycal/core/data_dir.h"
#include "skycal/core/error.h"

namespace skycal::color {

std::string DefaultConfigPath() {
  const char* env = std::getenv("OCIO");
  if (env != nullptr && env[0] != '\0') return env;
  return DataPath("config/skycal.ocio");  // the bundled config (core/data_dir.h)
}

namespace detail {
namespace {

// "a, b, c" for error messages.
template <typename CountFn, typename NameFn>
std::string JoinNames(CountFn count, NameFn name) {
  std::string out;
  const int n = count();
  for (int i = 0; i < n; ++i) {
    // Appended piecewise: `"'" + std::string(...)` trips a GCC 12 -Wrestrict false positive.
    if (i > 0) out += ", ";
    out += '\'';
    out += name(i);
    out += '\'';
  }
  return out.empty() ? "(none)" : out;
}

}  // namespace

LoadedConfig LoadConfig(const std::string& path_in) {
  LoadedConfig cfg;
  cfg.path = path_in.empty() ? DefaultConfigPath() : path_in;
  // Check the file ourselves first: OCIO's own message for a missing file is terse.
  std::error_code ec;
  if (!std::filesystem::is_regular_file(cfg.path, ec)) {
    throw Error("OCIO config '" + cfg.path + "': no such file (set $OCIO or pass a config path)");
  }
  if (!std::ifstream(cfg.path)) {
    throw Error("OCIO config '" + cfg.path + "': cannot open for reading (" +
                std::strerror(errno) + ")");
  }
  // One parse per file version and process: parsing and validating the config, and the
  // processors OCIO caches inside it, cost each preview tens of milliseconds, and a
  // calibration writes a handful. Keyed by the file's time and size, so an edited config is
  // read again.
  struct Version {
    std::filesystem::file_time_type time;
    std::uintmax_t size = 0;
    OCIO::ConstConfigRcPtr config;
  };
  static std::mutex mutex;
  static std::map<std::string, Version> loaded;
  std::error_code time_ec, size_ec;
  const auto time = std::filesystem::last_write_time(cfg.path, time_ec);
  const std::uintmax_t size = std::filesystem::file_size(cfg.path, size_ec);
  const bool versioned = !time_ec && !size_ec;
  std::lock_guard<std::mutex> lock(mutex);
  const auto it = loaded.find(cfg.path);
  if (versioned && it != loaded.end() && it->second.time == time && it->second.size == size) {
    cfg.config = it->second.config;
    return cfg;
  }
  try {
    cfg.config = OCIO::Config::CreateFromFile(cfg.path.c_str());
    cfg.config->validate();
  } catch (const OCIO::Exception& e) {
    throw Error("OCIO config '" + cfg.path + "': cannot load (" + e.what() + ")");
  }
  if (versioned) loaded[cfg.path] = Version{time, size, cfg.config};
  return cfg;
}

void RequireColorSpace(const LoadedConfig& cfg, const std::string& name, const char* what) {
  // getColorSpace() also resolves roles and aliases, which callers may use.
  if (!name.empty() && cfg.config->getColorSpace(name.c_str()) != nullptr) return;
  const auto& c = cfg.config;
  const std::string known = JoinNames(
      [&] { return c->getNumColorSpaces(OCIO::SEARCH_REFERENCE_SPACE_ALL, OCIO::COLORSPACE_ALL); },
      [&](int i) {
        return c->getColorSpaceNameByIndex(OCIO::SEARCH_REFERENCE_SPACE_ALL,
                                           OCIO::COLORSPACE_ALL, i);
      });
  throw Error("OCIO config '" + cfg.path + "': unknown " + what + " colour space '" + name +
              "' (known: " + known + ")");
}

std::string ResolveView(const LoadedConfig& cfg, const std::string& display,
                        const std::string& view) {
  const auto& c = cfg.config;
  if (display.empty() || c->getDisplayAllByName(display.c_str()) < 0) {
    const std::string known = JoinNames([&] { return c->getNumDisplaysAll(); },
                                        [&](int i) { return c->getDisplayAll(i); });
    throw Error("OCIO config '" + cfg.path + "': unknown display '" + display +
                "' (known: " + known + ")");
  }
  std::string resolved = view;
  if (resolved.empty()) {
    const char* def = c->getDefaultView(display.c_str());
    resolved = def != nullptr ? def : "";
  }
  // A view exists when it names a display colour space or a view transform's target.
  const char* cs = resolved.empty()
                       ? ""
                       : c->getDisplayViewColorSpaceName(display.c_str(), resolved.c_str());
  if (cs == nullptr || cs[0] == '\0') {
    const std::string known =
        JoinNames([&] { return c->getNumViews(display.c_str()); },
                  [&](int i) { return c->getView(display.c_str(), i); });
    throw Error("OCIO config '" + cfg.path + "': display '" + display + "' has no view '" +
                resolved + "' (known: " + known + ")");
  }
  return resolved;
}

void ApplyInPlace(const OCIO::ConstProcessorRcPtr& processor, ImageRGB& image) {
  if (image.empty()) return;
  // Packed RGB float, no alpha: exactly ImageRGB's layout, so no copy is needed.
  OCIO::PackedImageDesc desc(image.pixels.data(), image.width, image.height, 3);
  processor->getDefaultCPUProcessor()->apply(desc);
}

void RequireWellFormed(const ImageRGB& image, const std::string& context) {
  if (image.empty()) {
    throw Error(context + ": image is empty (" + std::to_string(image.width) + "x" +
                std::to_string(image.height) + ")");
  }
  const size_t expected = static_cast<size_t>(image.width) * image.height * 3;
  if (image.pixels.size() != expected) {
    throw Error(context + ": image buffer holds " + std::to_string(image.pixels.size()) +
                " floats, expected " + std::to_string(expected) + " for " +
                std::to_string(image.width) + "x" + std::to_string(image.height) + " RGB");
  }
}

}  // namespace detail
}  // namespace skycal::color
