// bench_fit --decisions: what each of the fit's skip decisions saves, measured by
// switching it off through FitOptions on a few 512x256 skies from the default preset,
// and its error change. Writes fit_decisions.md and fit_decisions.json into out_dir.
#pragma once
#include <filesystem>

#include "skycal/render/preset.h"

namespace skycal::bench {

void WriteDecisionTable(const render::Preset& start, const std::filesystem::path& scratch,
                        const std::filesystem::path& out_dir);

}  // namespace skycal::bench
