// The cloud scene the clouds and stress suites render (private to skycal_bench): the
// bundled default_cloudy preset with its clouds section and weather map, noise seed 1.
#pragma once
#include "skycal/clouds/cloud_params.h"
#include "skycal/clouds/cloud_renderer.h"
#include "skycal/clouds/cloud_textures.h"
#include "skycal/render/preset.h"

namespace skycal::bench {

struct CloudBenchScene {
  render::Preset preset;
  clouds::CloudParams params;
  clouds::CloudNoise noise;
  clouds::WeatherMap weather;
  clouds::CloudScene View() const { return {&preset, &params, &noise, &weather}; }
};

// Throws skycal::Error when the bundled preset or its weather map is unreadable.
CloudBenchScene LoadDefaultCloudyScene();  // clouds_suite.cc

}  // namespace skycal::bench
