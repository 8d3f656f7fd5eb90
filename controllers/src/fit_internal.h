// What the fit controller's stages share: the log, the bundled presets, the input list of a
// preset and the floor under which a reference is refused.
#pragma once
#include <cstdint>
#include <iostream>
#include <string>
#include <vector>

#include "skycal/controllers/game_clouds.h"
#include "skycal/core/data_dir.h"
#include "skycal/core/error.h"
#include "skycal/core/file_safety.h"
#include "skycal/core/format_number.h"
#include "skycal/render/preset.h"

namespace skycal::controllers {

// Progress on stderr, one line each, prefixed as `skycal fit` always printed it.
inline void FitLog(const std::string& message) { std::cerr << "[fit] " << message << std::endl; }

// The bundled presets (core/data_dir.h): the clear sky the fit starts from and the cloud mask
// compares against, and the cloudy one the cloud statistics start from (game_clouds.h's
// DefaultCloudyPresetPath).
inline std::string DefaultClearPresetPath() { return DataPath("datasets/presets/default_clear.json"); }

// The cloud noise seed every render uses (`skycal render --clouds`; the noise is cached by it).
inline constexpr uint64_t kRenderCloudNoiseSeed = kCloudNoiseSeed;

// A preset as inputs for file_safety.h: its JSON (role `field`) and every LUT EXR it names.
inline std::vector<NamedPath> PresetInputs(const std::string& field, const std::string& preset_json) {
  std::vector<NamedPath> inputs;
  const std::vector<std::string> files = render::PresetFiles(preset_json);
  for (size_t i = 0; i < files.size(); ++i) inputs.push_back({i == 0 ? field : field + " " + preset_json + "'s LUT", files[i]});
  return inputs;
}

// A reference with fewer than 1% of its pixels valid is refused (the same floor every verb
// applies to an input frame: below it a fit rests on a handful of pixels). Throws
// skycal::Error naming the file, the counts and what a valid pixel is.
inline void RequireValidShare(const std::string& path, long long valid, long long total, const std::string& what) {
  constexpr double kMinValidShare = 0.01;
  if (total > 0 && static_cast<double>(valid) >= kMinValidShare * static_cast<double>(total)) return;
  throw Error(path + ": only " + std::to_string(valid) + " of " + std::to_string(total) + " pixels are valid (" + what +
              "); at least " + FormatNumber(100.0 * kMinValidShare) +
              "% are needed: an all-NaN, all-zero or negative frame is not a usable sky");
}

}  // namespace skycal::controllers
