// The lat-long pixel <-> direction mapping, written once in the GLSL/C++ common subset
// (rules in glsl_compat.h). Included by sky_model.glsl.h (the shaders and the renderers'
// C++ model) and, compiled in double, by core/src/latlong.cc: core/latlong.h's Latitude,
// Longitude and directions are these functions. Needs SC_PI from the including context.
//
// Lat-long pixel centres follow OpenEXR's envmap LatLong convention (core/latlong.h):
// latitude +pi/2 at row 0, longitude +pi at column 0 and -pi at column width - 1; y and x
// are pixel coordinates, centres at integers (continuous positions between them). The
// angles come from exact numerators, lat = pi (h - 1 - 2y) / (2 (h - 1)); the textbook
// pi (0.5 - y / (h - 1)) loses ~3e-5 relative precision near the horizon in float.
Scalar latlong_latitude(Scalar y, int height) {
  return (Scalar(height - 1) - Scalar(2.0) * y) * (Scalar(0.5 * SC_PI) / Scalar(height - 1));
}
Scalar latlong_longitude(Scalar x, int width) {
  return (Scalar(width - 1) - Scalar(2.0) * x) * (Scalar(SC_PI) / Scalar(width - 1));
}
// Direction from the sines and cosines of latitude and longitude: +Y up, longitude 0 ->
// +Z, longitude +pi/2 -> +X. The GPU takes them from per-row and per-column tables the
// host fills in double precision: shader sin/cos carry ~1e-6 absolute error (lavapipe;
// 2^-11 is all Vulkan guarantees), which a peaked Mie phase (g = 0.99) would turn into
// ~1e-3 relative radiance error near the sun.
vec3 latlong_direction_from_trig(Scalar sin_lat, Scalar cos_lat, Scalar sin_lon, Scalar cos_lon) {
  return vec3(sin_lon * cos_lat, sin_lat, cos_lon * cos_lat);
}
