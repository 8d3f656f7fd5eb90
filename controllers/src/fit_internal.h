// What the fit controller's stages share: the log and the bundled presets. The input list
// of a preset is game_clouds.h's PresetFileInputs; the floor under which a reference is
// refused is core's RequireValidShare (finite_pixels.h).
#pragma once
#include <cstdint>
#include <iostream>
#include <string>
#include <vector>

#include "skycal/controllers/game_clouds.h"
#include "skycal/core/data_dir.h"
#include "skycal/core/error.h"
#include "skycal/core/file_safety.h"
#include "skycal/core/finite_pixels.h"
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

}  // namespace skycal::controllers
