// Cloud density after Schneider 2015, "The Real-time Volumetric Cloudscapes of Horizon
// Zero Dawn" (and its GPU Pro 7 chapter): base shape x height gradient by cloud type x
// coverage, reduced at the bottoms, eroded by the detail noise (inverted toward the base
// for wisps), distorted by curl noise, the weather map's precipitation pushing toward
// cumulonimbus at 70% coverage, the horizon rule beyond 15 km. Density is dimensionless
// (extinction = density x CloudShadeParams.extinction, 1/m). Positions are camera-relative
// metres: x, z horizontal (the weather map's axes), `altitude` above the ground.

SC_CONST(CLOUD_CUMULONIMBUS_COVERAGE, 0.7)  // HZD: precipitation pushes toward cumulonimbus at 70% coverage

Scalar remap(Scalar v, Scalar lo, Scalar hi, Scalar new_lo, Scalar new_hi) {
  return new_lo + (v - lo) / (hi - lo) * (new_hi - new_lo);
}

Scalar saturate1(Scalar v) { return clamp(v, Scalar(0.0), Scalar(1.0)); }

Scalar smooth_ramp(Scalar e0, Scalar e1, Scalar x) {
  Scalar t = saturate1((x - e0) / (e1 - e0));
  return t * t * (Scalar(3.0) - Scalar(2.0) * t);
}

// Height gradients of the three cloud types over the height fraction h in [0, 1] of the
// layer: rise from the base, fall toward the top (stratus thin and low, cumulus to about
// 60% of the layer, cumulonimbus to the top), blended by type (0 stratus, 0.5 cumulus,
// 1 cumulonimbus).
Scalar height_gradient(Scalar h, Scalar type) {
  Scalar stratus = smooth_ramp(Scalar(0.0), Scalar(0.08), h) * (Scalar(1.0) - smooth_ramp(Scalar(0.15), Scalar(0.3), h));
  Scalar cumulus = smooth_ramp(Scalar(0.0), Scalar(0.15), h) * (Scalar(1.0) - smooth_ramp(Scalar(0.4), Scalar(0.7), h));
  Scalar cumulonimbus = smooth_ramp(Scalar(0.0), Scalar(0.1), h) * (Scalar(1.0) - smooth_ramp(Scalar(0.7), Scalar(1.0), h));
  Scalar w_stratus = saturate1(Scalar(1.0) - Scalar(2.0) * type);
  Scalar w_cb = saturate1(Scalar(2.0) * type - Scalar(1.0));
  return stratus * w_stratus + cumulus * (Scalar(1.0) - w_stratus - w_cb) + cumulonimbus * w_cb;
}

// The weather at a horizontal position: coverage, precipitation, type (r, g, b), after
// the coverage scale, precipitation's push toward cumulonimbus and the horizon rule.
struct CloudWeather {
  Scalar coverage;
  Scalar precipitation;
  Scalar type;
};

CloudWeather cloud_weather(Scalar x, Scalar z, Scalar distance, CloudShadeParams p) {
  Scalar wx = x + p.wind_x;
  Scalar wz = z + p.wind_z;
  Texel4 t = sample_image(CLOUD_TEX_WEATHER, p.weather_width, p.weather_height,
                          (wx / p.weather_extent + Scalar(0.5)) * Scalar(p.weather_width),
                          (wz / p.weather_extent + Scalar(0.5)) * Scalar(p.weather_height));
  CloudWeather w;
  w.coverage = saturate1(t.r);
  w.precipitation = saturate1(t.g);
  w.type = saturate1(t.b);
  // Rain clouds are cumulonimbus of at least 70% coverage.
  w.coverage = mix(w.coverage, max(w.coverage, Scalar(CLOUD_CUMULONIMBUS_COVERAGE)), w.precipitation);
  w.type = mix(w.type, Scalar(1.0), w.precipitation);
  // Horizon rule: beyond horizon_start bias toward cumulus at horizon_coverage, complete at
  // horizon_end (the march ends at the draw distance, 35 km in HZD).
  Scalar bias = p.horizon_rule * smooth_ramp(p.horizon_start, p.horizon_end, distance);
  w.coverage = mix(w.coverage, p.horizon_coverage, bias);
  w.type = mix(w.type, Scalar(0.5), bias);
  // The scale applies last: 0 empties the sky, horizon rule and rain included.
  w.coverage = saturate1(w.coverage * p.coverage_scale);
  return w;
}

Scalar height_fraction(Scalar altitude, CloudShadeParams p) {
  return saturate1((altitude - p.layer_bottom) / (p.layer_top - p.layer_bottom));
}

// Base shape: Perlin-Worley dilated by the Worley fbm (R remapped from -(1 - fbm)..1),
// shaped by the height gradient, then the coverage (low coverage thins what remains) and
// a reduction toward the bottom. Zero means empty (the cheap march's test).
Scalar cloud_base_density(Scalar x, Scalar z, Scalar altitude, CloudWeather w, CloudShadeParams p) {
  Scalar h = height_fraction(altitude, p);
  Scalar s = Scalar(CLOUD_BASE_SIZE) / p.base_tile;
  BaseNoise n = sample_base_noise((x + p.wind_x) * s, altitude * s, (z + p.wind_z) * s);
  Scalar base = saturate1(remap(n.r, n.fbm - Scalar(1.0), Scalar(1.0), Scalar(0.0), Scalar(1.0)));
  Scalar shaping = mix(Scalar(1.0), height_gradient(h, w.type), p.height_shaping);
  base = base * shaping;
  // Coverage: what is below 1 - coverage vanishes; the rest is scaled by the coverage.
  // (max() keeps coverage 0 exactly empty instead of 0/0.)
  Scalar c = saturate1((base - (Scalar(1.0) - w.coverage)) / max(w.coverage, Scalar(1e-6))) * w.coverage;
  // Nothing outside the layer (the gradient already vanishes there unless shaping is off).
  Scalar inside = (altitude >= p.layer_bottom && altitude <= p.layer_top) ? Scalar(1.0) : Scalar(0.0);
  // Bottoms: density grows over the lowest 20% of the layer (wispy bases).
  return inside * c * mix(Scalar(1.0), smooth_ramp(Scalar(0.0), Scalar(0.2), h), p.height_shaping);
}

// Full density: the base eroded at the edges by the detail noise, whose fbm is inverted
// toward the base (wisps) and used as is above (billows), sampled at a curl-distorted
// position (more distortion toward the base).
Scalar cloud_full_density(Scalar base, Scalar x, Scalar z, Scalar altitude, CloudShadeParams p) {
  Scalar h = height_fraction(altitude, p);
  Scalar cs = Scalar(CLOUD_CURL_SIZE) / p.curl_tile;
  Texel4 curl = sample_image(CLOUD_TEX_CURL, CLOUD_CURL_SIZE, CLOUD_CURL_SIZE, (x + p.wind_x) * cs, (z + p.wind_z) * cs);
  Scalar k = p.curl_strength * (Scalar(1.0) - h);
  Scalar ds = Scalar(CLOUD_DETAIL_SIZE) / p.detail_tile;
  Scalar fbm = sample_detail_fbm((x + p.wind_x + curl.r * k) * ds, (altitude + curl.b * k) * ds,
                                 (z + p.wind_z + curl.g * k) * ds);
  Scalar modifier = mix(Scalar(1.0) - fbm, fbm, saturate1(h * Scalar(10.0)));
  return saturate1(remap(base, modifier * p.erosion, Scalar(1.0), Scalar(0.0), Scalar(1.0)));
}
