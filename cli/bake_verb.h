// `skycal bake`: a preset whose LUTs come from a physically based single-scattering
// atmosphere (render/atmosphere_bake.h). The bundled default preset is made with it.
#pragma once
#include <string>

#include <nlohmann/json.hpp>

#include "skycal/render/atmosphere_bake.h"
#include "skycal/render/preset.h"

namespace skycal::cli {

struct BakeOptions {
  render::AtmosphereOptions atmosphere;
  render::LutGrid grid;
  render::ModelVariant variant = render::ModelVariant::kFfxv;
  double haziness_g = 0.8;   // Cornette-Shanks g written into the preset
  std::string name = "default_clear";
  std::string out_json;      // preset JSON path; LUT EXRs go beside it
};

nlohmann::json RunBakeImpl(const BakeOptions& options);
// Parses the arguments after the verb (no I/O). Throws HelpRequested (command_line.h) for
// --help, skycal::Error naming the option on a bad command line.
BakeOptions ParseBakeArgs(int argc, char** argv);
int RunBake(int argc, char** argv);

}  // namespace skycal::cli
