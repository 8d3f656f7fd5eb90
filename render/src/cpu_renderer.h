// The CPU reference renderer: the shared model source in double precision, rows split
// over the hardware threads.
#pragma once
#include <memory>

#include "skycal/render/renderer.h"

namespace skycal::render {
std::unique_ptr<SkyRenderer> CreateCpuRenderer();
}
