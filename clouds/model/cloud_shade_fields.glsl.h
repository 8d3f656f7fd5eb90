// The fields of CloudShadeParams as an X-macro list: the struct (cloud_shade_params.glsl.h),
// the host's double -> float conversion and the shader's parameter buffer are generated
// from this one list, so they cannot drift apart. SC_FIELD: a Scalar, SC_FIELD_VEC3: vec3,
// SC_FIELD_INT: int (stored as a float in the parameter buffer: exact below 2^24).
// Units: metres, seconds, lux (illuminance), cd/m^2 (radiance); directions are unit
// vectors in the lat-long frame (+Y up).
  // Geometry: a spherical shell around a planet of radius R; the camera stands on the
  // local vertical at camera_height above the ground.
  SC_FIELD(planet_radius)      // m
  SC_FIELD(layer_bottom)       // m above the ground
  SC_FIELD(layer_top)          // m above the ground
  SC_FIELD(camera_height)      // m above the ground
  SC_FIELD(draw_distance)      // m along the ray (HZD: 35 km)
  SC_FIELD(weather_extent)     // m covered by the weather map along x and z
  SC_FIELD(base_tile)          // m covered by one tile of the 128^3 base noise
  SC_FIELD(detail_tile)        // m covered by one tile of the 32^3 detail noise
  SC_FIELD(curl_tile)          // m covered by one tile of the 128^2 curl noise
  SC_FIELD(curl_strength)      // m of horizontal displacement at the layer bottom
  SC_FIELD(wind_x)             // m: wind offset (velocity x time) along x
  SC_FIELD(wind_z)             // m: wind offset along z
  // Shape.
  SC_FIELD(coverage_scale)     // 1: multiplies the final coverage (0: no clouds)
  SC_FIELD(erosion)            // 1: strength of the detail erosion
  SC_FIELD(height_shaping)     // 1: 1 = HZD height gradients, 0 = uniform slab (tests)
  SC_FIELD(horizon_rule)       // 0 or 1
  SC_FIELD(horizon_start)      // m: bias toward cumulus begins
  SC_FIELD(horizon_end)        // m: bias complete
  SC_FIELD(horizon_coverage)   // 1: coverage the bias tends to (type: cumulus, 0.5)
  // The optional 2D alto/cirrus layer above the volumetric one (Schneider 2015: scrolling
  // textures above 4 km).
  SC_FIELD(cirrus_coverage)    // 1: 0 switches the layer off
  SC_FIELD(cirrus_altitude)    // m above the ground
  SC_FIELD(cirrus_depth)       // 1: vertical optical depth where the pattern is 1
  SC_FIELD(cirrus_tile)        // m covered by one tile of its pattern
  // Lighting.
  SC_FIELD(extinction)         // 1/m per unit density
  SC_FIELD(albedo)             // 1: scattering / extinction
  SC_FIELD(g1)                 // HG asymmetry of the forward lobe
  SC_FIELD(g2)                 // HG asymmetry of the silver-lining lobe
  SC_FIELD(phase_blend)        // 1: weight of the g2 lobe
  SC_FIELD(powder_strength)    // 1
  SC_FIELD(powder_view_fade)   // 1
  SC_FIELD(rain_absorption)    // 1: extra absorption per unit precipitation, relative to extinction
  SC_FIELD(ambient_strength)   // 1
  SC_FIELD(ambient_height_bias)  // 1: ambient at the layer bottom = 1 - bias, at the top 1
  SC_FIELD(ground_bounce)      // 1
  SC_FIELD(ms_a)               // extinction factor per octave
  SC_FIELD(ms_b)               // scattering factor per octave
  SC_FIELD(ms_c)               // phase-g factor per octave
  SC_FIELD(atmosphere_blend)   // m: e-folding distance of the blend toward the atmosphere colour
  SC_FIELD_VEC3(sun_dir)              // unit, toward the sun
  SC_FIELD_VEC3(sun_illuminance)      // lux per channel at the ground (sun_illuminance x tint x transmittance)
  SC_FIELD_VEC3(sky_irradiance_up)    // lux: irradiance of the clear sky on an upward plane (SH-9)
  SC_FIELD_VEC3(ground_radiance)      // cd/m^2: the lit ground below the layer
  // clear-sky radiance SH-9 coefficients, cd/m^2 (render::ProjectSh9's order and basis)
  SC_FIELD_VEC3(sh0)
  SC_FIELD_VEC3(sh1)
  SC_FIELD_VEC3(sh2)
  SC_FIELD_VEC3(sh3)
  SC_FIELD_VEC3(sh4)
  SC_FIELD_VEC3(sh5)
  SC_FIELD_VEC3(sh6)
  SC_FIELD_VEC3(sh7)
  SC_FIELD_VEC3(sh8)
  SC_FIELD_INT(weather_width)         // texels
  SC_FIELD_INT(weather_height)        // texels
  SC_FIELD_INT(ms_octaves)            // extra multiple-scattering octaves (0: single scattering)
  SC_FIELD_INT(integration)           // CLOUD_INTEGRATION_*
  // March (each optimisation switchable; 0 off, 1 on).
  SC_FIELD_INT(steps_zenith)          // primary samples looking straight up
  SC_FIELD_INT(steps_horizon)         // primary samples at the horizon
  SC_FIELD_INT(light_samples)         // samples toward the sun (the last one far when far_light)
  SC_FIELD_INT(cheap_march)           // base-shape-only long steps until the base density is non-zero
  SC_FIELD_INT(step_back)             // one step back when the cheap march finds cloud
  SC_FIELD_INT(empty_to_cheap)        // back to cheap after this many empty full samples (0: never)
  SC_FIELD_INT(opacity_stop)          // stop when the transmittance falls below 1 - opacity_threshold
  SC_FIELD_INT(cheap_light)           // cheap (base-shape-only) light samples once the opacity exceeds cheap_light_opacity
  SC_FIELD_INT(far_light)             // last light sample far away (distant shadowing)
  SC_FIELD(cheap_step_factor)  // cheap step = this x the full step
  SC_FIELD(opacity_threshold)  // ~1
  SC_FIELD(cheap_light_opacity)  // HZD: 0.3
  SC_FIELD(light_step)         // m between light samples in the cone
  SC_FIELD(far_light_distance) // m to the far light sample
  SC_FIELD(cone_spread)        // light cone half-width per metre along the light ray (HZD-style: 0.3)
