// The ray march of Schneider 2015 with each optimisation switchable (for measurement):
//   - samples: steps_zenith looking up rising to steps_horizon at the horizon (64 -> 128),
//     spread evenly over the ray's part inside the layer (midpoint rule);
//   - cheap march: base-shape-only samples cheap_step_factor x longer until the base
//     density is non-zero; step back one cheap step, then full samples; back to cheap after
//     empty_to_cheap empty full samples;
//   - stop once the opacity reaches opacity_threshold (~1);
//   - light: light_samples in a cone toward the sun, the last far away (distant
//     shadowing); cheap light samples once the opacity exceeds cheap_light_opacity.
// HZD's temporal reprojection (1 of 16 pixels per frame) is a real-time amortisation a
// still render does not need: every pixel is marched fully here.
//
// Output: in-scattered radiance (cd/m^2) and transmittance along the view; the host
// composites L = L_sky T + L_cloud (clouds/include/skycal/clouds/composite.h).


struct CloudResult {
  vec3 radiance;          // cd/m^2
  Scalar transmittance;   // 1
  int full_samples;       // full-density samples taken (for measurement)
  int iterations;         // march iterations, one density sample each (for measurement:
                          // lavapipe runs 8 pixels' loops in lockstep, docs/benchmarks.md)
};

// A fixed kernel of 6 unit-ish offsets spreading the light samples over the cone
// (deterministic: a still render, and both backends take the same positions).
vec3 cone_kernel(int i) {
  if (i == 0) return vec3(Scalar(0.38), Scalar(-0.41), Scalar(0.83));
  if (i == 1) return vec3(Scalar(-0.75), Scalar(0.29), Scalar(0.59));
  if (i == 2) return vec3(Scalar(0.21), Scalar(0.92), Scalar(-0.33));
  if (i == 3) return vec3(Scalar(-0.52), Scalar(-0.66), Scalar(-0.54));
  if (i == 4) return vec3(Scalar(0.87), Scalar(0.15), Scalar(-0.47));
  return vec3(Scalar(-0.12), Scalar(-0.30), Scalar(-0.95));
}

// Light sample i (0 .. light_samples - 1) of the primary sample at `pos`: in the cone
// toward the sun, light_step apart, the last one far_light_distance away (distant
// shadowing) when far_light is on.
vec3 light_sample_position(vec3 pos, int i, CloudShadeParams p) {
  int far = (p.far_light == 1 && i == p.light_samples - 1) ? 1 : 0;
  Scalar along = far == 1 ? p.far_light_distance : p.light_step * (Scalar(i) + Scalar(0.5));
  Scalar spread = far == 1 ? Scalar(0.0) : p.light_step * Scalar(i + 1) * p.cone_spread;
  return pos + p.sun_dir * along + cone_kernel(i) * spread;
}

// The optional 2D alto/cirrus sheet: a thin layer at cirrus_altitude whose vertical optical
// depth is cirrus_depth x a pattern remapped by the coverage, scrolling with the wind.
// Schneider 2015 describes the cirro clouds as "big arcing bands and little puffs" and the
// alto ones as "bandy or puffy", drawn as tiling, scrolling 2D textures. The pattern here:
// bands, the base noise's Perlin-Worley stretched 8x along x (one tile long, their width its
// cells across: ~1/8 to 1/4 of cirrus_tile), eroded at their edges by puffs, the detail fbm
// at 1/8 of the tile (cells of 1/16 to 1/64 of it). Single scattering in an optically thin sheet lit by the
// unattenuated sun and the sky: L = (E_sun phase + ambient) albedo (1 - T),
// T = exp(-tau / mu) with mu the cosine of the ray at the sheet.
SC_CONST(CLOUD_CIRRUS_STRETCH, 8.0)   // band length / width
SC_CONST(CLOUD_CIRRUS_PUFFS, 8.0)     // puff noise tiles per cirrus tile

// The sheet's pattern in [0, 1] at camera-relative (x, z) metres, before the coverage.
Scalar cirrus_pattern(Scalar x, Scalar z, CloudShadeParams p) {
  Scalar u = (x + p.wind_x) / p.cirrus_tile;
  Scalar v = (z + p.wind_z) / p.cirrus_tile;
  // The base's R on its first slice (v = 0.5 texels: weight 1 on row 0), read from the packed
  // pairs the density reads: no texture of the whole base is needed on the device.
  Scalar bands = sample_base_noise(u * (Scalar(CLOUD_BASE_SIZE) / Scalar(CLOUD_CIRRUS_STRETCH)), Scalar(0.5),
                                   v * Scalar(CLOUD_BASE_SIZE)).r;
  Scalar puffs_scale = Scalar(CLOUD_CIRRUS_PUFFS) * Scalar(CLOUD_DETAIL_SIZE);
  Scalar puffs = sample_detail_fbm(u * puffs_scale, Scalar(0.5), v * puffs_scale);
  // The puffs erode the bands (as the detail noise erodes the volumetric clouds' edges):
  // a band's core stays whole, its edges break into puffs.
  return saturate1(remap(bands, Scalar(0.5) * puffs, Scalar(1.0), Scalar(0.0), Scalar(1.0)));
}

CloudResult cirrus_sheet(vec3 view, Scalar one_minus_mu, CloudShadeParams p) {
  CloudResult c;
  c.radiance = vec3(Scalar(0.0));
  c.transmittance = Scalar(1.0);
  c.full_samples = 0;
  c.iterations = 0;
  if (!(p.cirrus_coverage > Scalar(0.0)) || p.camera_height >= p.cirrus_altitude) return c;
  SphereHit hit = sphere_hit(view.y, p.cirrus_altitude, p);
  SphereHit ground = sphere_hit(view.y, Scalar(0.0), p);
  if (ground.hit == 1 && ground.near > Scalar(0.0)) return c;
  Scalar t = hit.far;
  vec3 pos = view * t;
  Scalar raw = cirrus_pattern(pos.x, pos.z, p);
  Scalar pattern = saturate1((raw - (Scalar(1.0) - p.cirrus_coverage)) / max(p.cirrus_coverage, Scalar(1e-6))) * p.cirrus_coverage;
  Scalar mu = ((p.planet_radius + p.camera_height) * view.y + t) / (p.planet_radius + p.cirrus_altitude);
  Scalar tau = p.cirrus_depth * pattern / max(mu, Scalar(0.02));
  c.transmittance = exp(-tau);
  vec3 light = p.sun_illuminance * phase_two_lobe(one_minus_mu, p.g1, p.g2, p.phase_blend) + ambient_inscatter(Scalar(1.0), p);
  c.radiance = light * (p.albedo * (Scalar(1.0) - c.transmittance));
  // The atmosphere's colour takes over with distance, as for the volumetric clouds.
  Scalar f = Scalar(1.0) - exp(-t / p.atmosphere_blend);
  vec3 sky_view = sky_sh_radiance(normalize(vec3(view.x, max(view.y, Scalar(0.02)), view.z)), p);
  c.radiance = mix(c.radiance, sky_view * (Scalar(1.0) - c.transmittance), f);
  return c;
}

CloudResult cloud_march(vec3 view, CloudShadeParams p) {
  CloudResult r;
  r.radiance = vec3(Scalar(0.0));
  r.transmittance = Scalar(1.0);
  r.full_samples = 0;
  r.iterations = 0;
  vec3 diff = view - p.sun_dir;
  Scalar one_minus_mu = Scalar(0.5) * dot(diff, diff);
  SunRay sun = sun_ray(one_minus_mu, p);
  CloudSegment seg = cloud_segment(view, p);
  if (!(seg.t1 > seg.t0)) return cirrus_sheet(view, one_minus_mu, p);  // nothing in front of the sheet
  Scalar up = view.y < Scalar(0.0) ? -view.y : view.y;
  int n = floor_to_int(mix(Scalar(p.steps_horizon), Scalar(p.steps_zenith), up) + Scalar(0.5));
  Scalar dt = (seg.t1 - seg.t0) / Scalar(n);
  Scalar cheap_dt = dt * p.cheap_step_factor;
  Scalar stop_below = Scalar(1.0) - p.opacity_threshold;

  Scalar t = seg.t0;  // start of the current step
  int cheap = p.cheap_march;
  int empty = 0;
  Scalar depth_sum = Scalar(0.0);    // opacity-weighted distance (atmosphere blend)
  Scalar weight_sum = Scalar(0.0);
  int guard = 8 * n + 64;            // primary iterations at most
  int it = 0;
  // One density sample per iteration: a primary sample (cheap or full) or one light sample
  // of the lit primary sample pending in lit_*; light_i >= 0 is the light sample this
  // iteration takes. Why not a light loop inside the primary one: lavapipe (Mesa 22.3)
  // executes both sides of every if under a lane mask, even when no lane takes it, and a
  // loop's body at least once, so every primary step paid for the full-density reads, one
  // light sample and the lighting whether or not any of its 8 lanes was in cloud (an empty
  // sky cost as much as a cloudy one). Here the texture reads appear once in the body; a
  // lane's light samples interleave with its neighbours' primary steps. The same
  // operations in the same order per pixel as the nested loops: both backends' results are
  // unchanged.
  int light_i = -1;
  int lit_cheap = 0;                 // the pending sample's light samples are cheap (base only)
  vec3 lit_pos = vec3(Scalar(0.0));
  Scalar lit_tm = Scalar(0.0);
  Scalar lit_alt = Scalar(0.0);
  Scalar lit_step = Scalar(0.0);
  Scalar lit_d = Scalar(0.0);
  Scalar lit_precipitation = Scalar(0.0);
  Scalar tau = Scalar(0.0);          // optical depth toward the sun of the pending sample
  int guard_all = guard * (p.light_samples + 1);
  for (int k = 0; k < guard_all; ++k) {
    r.iterations = k + 1;
    Scalar step = Scalar(0.0);
    Scalar tm = lit_tm;  // the horizon rule's distance: the primary sample's
    vec3 pos;
    if (light_i < 0) {
      if (!(it < guard) || !(t < seg.t1)) break;
      it = it + 1;
      // One weather + base evaluation serves both modes (on SIMD hardware, lanes in the
      // cheap and the full mode share it instead of running two copies).
      step = cheap == 1 ? cheap_dt : min(dt, seg.t1 - t);
      tm = cheap == 1 ? min(t + Scalar(0.5) * cheap_dt, seg.t1) : t + Scalar(0.5) * step;
      pos = view * tm;
    } else {
      pos = light_sample_position(lit_pos, light_i, p);
    }
    Scalar alt = cloud_altitude(pos, p);
    CloudWeather w = cloud_weather(pos.x, pos.z, tm, p);
    Scalar d = cloud_base_density(pos.x, pos.z, alt, w, p);
    int inside = (alt < p.layer_bottom || alt > p.layer_top) ? 0 : 1;
    int full = light_i < 0 ? 1 - cheap : (inside == 1 && lit_cheap == 0 ? 1 : 0);
    if (full == 1 && d > Scalar(0.0)) d = cloud_full_density(d, pos.x, pos.z, alt, p);
    int finish = 0;  // the pending sample's light samples are complete: light it
    if (light_i >= 0) {
      if (inside == 1) tau = tau + p.extinction * d * (Scalar(1.0) + p.rain_absorption * w.precipitation) * p.light_step;
      light_i = light_i + 1;
      if (light_i >= p.light_samples) {
        light_i = -1;
        finish = 1;
      }
    } else if (cheap == 1) {
      if (d > Scalar(0.0)) {
        cheap = 0;
        empty = 0;
        // With the step back, full samples resume at the previous cheap sample; without
        // it, at this one (what lies between them is skipped, as HZD's naive version did).
        t = p.step_back == 1 ? max(tm - cheap_dt, seg.t0) : tm;
      } else {
        t = t + cheap_dt;
      }
    } else {
      r.full_samples = r.full_samples + 1;
      if (d > Scalar(0.0)) {
        empty = 0;
        lit_pos = pos;
        lit_tm = tm;
        lit_alt = alt;
        lit_step = step;
        lit_d = d;
        lit_precipitation = w.precipitation;
        tau = Scalar(0.0);
        lit_cheap = (p.cheap_light == 1 && Scalar(1.0) - r.transmittance > p.cheap_light_opacity) ? 1 : 0;
        if (p.light_samples > 0) {
          light_i = 0;
        } else {
          finish = 1;
        }
      } else {
        empty = empty + 1;
        if (p.cheap_march == 1 && p.empty_to_cheap > 0 && empty >= p.empty_to_cheap) {
          cheap = 1;
          empty = 0;
        }
        t = t + step;
      }
    }
    if (finish == 1) {
      Scalar sigma_s = p.albedo * p.extinction * lit_d;
      Scalar sigma_t = p.extinction * lit_d * (Scalar(1.0) + p.rain_absorption * lit_precipitation);
      Scalar h = height_fraction(lit_alt, p);
      vec3 source = (sun_inscatter_ray(tau, sun, p) + ambient_inscatter(h, p)) * sigma_s;
      Scalar x = sigma_t * lit_step;
      Scalar step_t = exp(-x);
      r.radiance = r.radiance + source * (r.transmittance * lit_step * step_integral_factor(x, step_t, p));
      Scalar absorbed = r.transmittance * (Scalar(1.0) - step_t);
      depth_sum = depth_sum + absorbed * lit_tm;
      weight_sum = weight_sum + absorbed;
      r.transmittance = r.transmittance * step_t;
      if (p.opacity_stop == 1 && r.transmittance < stop_below) break;
      t = t + lit_step;
    }
  }
  // Aerial perspective: blend toward the clear sky's colour behind the cloud with the
  // cloud's mean distance (Schneider 2015: distant clouds take the atmosphere's colour).
  if (weight_sum > Scalar(0.0)) {
    Scalar f = Scalar(1.0) - exp(-(depth_sum / weight_sum) / p.atmosphere_blend);
    vec3 sky_view = sky_sh_radiance(normalize(vec3(view.x, max(view.y, Scalar(0.02)), view.z)), p);
    r.radiance = mix(r.radiance, sky_view * (Scalar(1.0) - r.transmittance), f);
  }
  // The sheet lies behind the volumetric layer (the camera is below both).
  CloudResult sheet = cirrus_sheet(view, one_minus_mu, p);
  r.radiance = r.radiance + sheet.radiance * r.transmittance;
  r.transmittance = r.transmittance * sheet.transmittance;
  return r;
}
