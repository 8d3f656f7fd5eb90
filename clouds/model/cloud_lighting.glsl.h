// Cloud lighting: the terms the fit (docs/cloud-fitting.md) tunes, written smooth (no max/branch kinks
// in the parameters) so that a ceres::Jet instantiation has meaningful derivatives.
// Sources: Schneider 2015 (Beer's law, Henyey-Greenstein silver lining, Beer-Powder with
// its view-angle fade, rain absorption, ambient rising with height); Hillaire 2016,
// "Physically Based Sky, Atmosphere and Cloud Rendering in Frostbite" (energy-conserving
// integration, multiple-scattering octaves after Wrenninge et al.).

SC_CONST(CLOUD_PI, 3.14159265358979323846)
SC_CONST_INT(CLOUD_INTEGRATION_ENERGY_CONSERVING, 0)
SC_CONST_INT(CLOUD_INTEGRATION_HZD_SIMPLE, 1)

// Henyey-Greenstein, normalised over the sphere:
//   (1 - g^2) / (4 pi (1 + g^2 - 2 g mu)^1.5),
// the denominator as (1 - g)^2 + 2 g (1 - mu) with 1 - mu from |v - s|^2 / 2 (no
// cancellation near the sun in float; see sky_model.glsl.h's Cornette-Shanks).
Scalar phase_hg(Scalar one_minus_mu, Scalar g) {
  Scalar one_minus_g = Scalar(1.0) - g;
  Scalar d = one_minus_g * one_minus_g + Scalar(2.0) * g * one_minus_mu;
  return (Scalar(1.0) - g * g) / (Scalar(4.0 * CLOUD_PI) * d * sqrt(d));
}

// Two lobes: forward (g1) and silver lining (g2), blended linearly (still normalised).
Scalar phase_two_lobe(Scalar one_minus_mu, Scalar g1, Scalar g2, Scalar blend) {
  return mix(phase_hg(one_minus_mu, g1), phase_hg(one_minus_mu, g2), blend);
}

// Schneider 2015's Beer-Powder: 2 exp(-d) (1 - exp(-2d)), optical depth d toward the sun.
// Dark edges where little cloud lies toward the sun (in-scattering needs depth).
Scalar beer_powder(Scalar d) {
  return Scalar(2.0) * exp(-d) * (Scalar(1.0) - exp(Scalar(-2.0) * d));
}

// Sun light reaching a sample through optical depth tau: Beer's law blended toward
// Beer-Powder by strength x view fade; the fade (1 - mu) / 2 is strongest looking away
// from the sun, where HZD shows the dark edges (toward the sun, silver lining wins).
Scalar sun_attenuation(Scalar tau, Scalar one_minus_mu, CloudShadeParams p) {
  Scalar fade = mix(Scalar(1.0), Scalar(0.5) * one_minus_mu, p.powder_view_fade);
  return mix(exp(-tau), beer_powder(tau), p.powder_strength * fade);
}

// In-scattered sun light per unit scattering coefficient (cd/m^2 per 1/m... i.e. the
// phase-weighted, attenuated illuminance), summed over octaves i = 0..ms_octaves with
// scattering b^i, extinction a^i and phase g c^i (Hillaire 2016 after Wrenninge et al.).
vec3 sun_inscatter(Scalar tau, Scalar one_minus_mu, CloudShadeParams p) {
  Scalar total = Scalar(0.0);
  Scalar a = Scalar(1.0);
  Scalar b = Scalar(1.0);
  Scalar c = Scalar(1.0);
  for (int i = 0; i <= p.ms_octaves; ++i) {
    total = total + b * phase_two_lobe(one_minus_mu, p.g1 * c, p.g2 * c, p.phase_blend) * sun_attenuation(tau * a, one_minus_mu, p);
    a = a * p.ms_a;
    b = b * p.ms_b;
    c = c * p.ms_c;
  }
  return p.sun_illuminance * total;
}

// The same sum with what depends only on the view and the parameters taken once per ray
// (the march lights up to ~900 samples a ray): each octave's phase and the powder's weight.
// sun_inscatter_ray(tau, sun_ray(one_minus_mu, p), p) is sun_inscatter(tau, one_minus_mu, p)
// with exp(-2d) formed as exp(-d)^2 (one exp per octave less; equal to a few float ulps).
SC_CONST_INT(CLOUD_MS_OCTAVES_MAX, 4)  // the ms_octaves field's upper bound (cloud_params.cc)

struct SunRay {
  Scalar phase[CLOUD_MS_OCTAVES_MAX + 1];  // scattering b^i x the phase of octave i, 1/sr
  Scalar powder;                           // powder_strength x the view fade
};

SunRay sun_ray(Scalar one_minus_mu, CloudShadeParams p) {
  SunRay r;
  Scalar b = Scalar(1.0);
  Scalar c = Scalar(1.0);
  for (int i = 0; i <= CLOUD_MS_OCTAVES_MAX; ++i) {
    r.phase[i] = b * phase_two_lobe(one_minus_mu, p.g1 * c, p.g2 * c, p.phase_blend);
    b = b * p.ms_b;
    c = c * p.ms_c;
  }
  r.powder = p.powder_strength * mix(Scalar(1.0), Scalar(0.5) * one_minus_mu, p.powder_view_fade);
  return r;
}

vec3 sun_inscatter_ray(Scalar tau, SunRay r, CloudShadeParams p) {
  Scalar total = Scalar(0.0);
  Scalar a = Scalar(1.0);
  for (int i = 0; i <= p.ms_octaves; ++i) {
    Scalar e = exp(-tau * a);
    total = total + r.phase[i] * mix(e, Scalar(2.0) * e * (Scalar(1.0) - e * e), r.powder);
    a = a * p.ms_a;
  }
  return p.sun_illuminance * total;
}

// Ambient in-scattering per unit scattering coefficient (cd/m^2): the clear sky's
// upward irradiance E_up as uniform radiance E_up / pi over the upper hemisphere, half of
// which an isotropic phase scatters toward the eye (E_up / (2 pi)), rising linearly with
// height in the layer (1 - bias at the bottom, 1 at the top: the cloud above occludes
// the sky); plus the lit ground's radiance from below, likewise halved, falling with
// height.
vec3 ambient_inscatter(Scalar h, CloudShadeParams p) {
  Scalar sky = p.ambient_strength * (Scalar(1.0) - p.ambient_height_bias + p.ambient_height_bias * h);
  Scalar ground = p.ground_bounce * (Scalar(1.0) - h);
  return p.sky_irradiance_up * (sky / Scalar(2.0 * CLOUD_PI)) + p.ground_radiance * (Scalar(0.5) * ground);
}

// Fraction of a step's source that reaches its start, (1 - exp(-x)) / x for x = sigma_t dt
// (energy-conserving, Hillaire 2016), or 1 (HZD's simple accumulation: source x dt, which
// over-counts thick steps). The series below 1e-3 avoids 0/0; the two sides agree to 1e-10.
// exp_minus_x is exp(-x), the step's transmittance the march has already formed (one exp
// a march iteration fewer: lavapipe evaluates this on every iteration, lit or not).
Scalar step_integral_factor(Scalar x, Scalar exp_minus_x, CloudShadeParams p) {
  Scalar energy = x < Scalar(1e-3) ? Scalar(1.0) - x * (Scalar(0.5) - x / Scalar(6.0)) : (Scalar(1.0) - exp_minus_x) / x;
  return p.integration == CLOUD_INTEGRATION_HZD_SIMPLE ? Scalar(1.0) : energy;
}

// The clear sky's radiance toward `dir` from its SH-9 (render/include/skycal/render/irradiance.h
// basis): the atmosphere colour distant clouds blend into.
vec3 sky_sh_radiance(vec3 dir, CloudShadeParams p) {
  Scalar x = dir.x;
  Scalar y = dir.y;
  Scalar z = dir.z;
  vec3 l = p.sh0 * Scalar(0.28209479177387814);
  l = l + p.sh1 * (Scalar(0.4886025119029199) * y) + p.sh2 * (Scalar(0.4886025119029199) * z) +
      p.sh3 * (Scalar(0.4886025119029199) * x);
  l = l + p.sh4 * (Scalar(1.0925484305920792) * x * y) + p.sh5 * (Scalar(1.0925484305920792) * y * z) +
      p.sh6 * (Scalar(0.31539156525252005) * (Scalar(3.0) * z * z - Scalar(1.0))) +
      p.sh7 * (Scalar(1.0925484305920792) * x * z) + p.sh8 * (Scalar(0.5462742152960396) * (x * x - y * y));
  return l;
}
