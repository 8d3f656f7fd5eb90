// Texture reads of the cloud model with exact filtering weights computed here, in the
// shared source (the LUT's rule: no hardware filtering in anything the fit differentiates
// or the parity test compares). The backend supplies one hook,
//   Texel4 cloud_texel4(int texture, int texel)
// every channel of texel number `texel` (row-major, x fastest, as
// clouds/include/skycal/clouds/cloud_textures.h lays them out; unused channels 0): C++
// reads the CloudNoise and WeatherMap vectors; GLSL reads vec4 texel buffers with
// texelFetch (the host pads 3-channel textures to 4): one 16-byte load per texel and lane
// (lavapipe compiles storage-buffer loads at per-lane indices into scalar loops per lane
// and component, which were ~90% of its render time). Every texture wraps (tiles).
//
// The one exception: a shader compiled with CLOUD_HARDWARE_FILTER defines the three readers
// below itself (sample_base_noise, sample_detail_fbm, sample_image) with
// textureLod on sampled images, the hardware's linear filter and repeat addressing, as a
// game samples its noise (clouds_latlong.comp). Same texels, same wrap, same texel-centre
// convention; the weights carry the device's subTexelPrecisionBits of fraction instead of
// float's (docs/cloud-model.md, "Sampled images": the parity it keeps with this source).

// Texture sizes (CloudNoise::kBaseSize etc.; the C++ side checks them with static_asserts).
SC_CONST_INT(CLOUD_BASE_SIZE, 128)
SC_CONST_INT(CLOUD_DETAIL_SIZE, 32)
SC_CONST_INT(CLOUD_CURL_SIZE, 128)
SC_CONST_INT(CLOUD_TEX_BASE, 0)     // 128^3 x 4
SC_CONST_INT(CLOUD_TEX_DETAIL, 1)   // 32^3 x 3
SC_CONST_INT(CLOUD_TEX_CURL, 2)     // 128^2 x 3
SC_CONST_INT(CLOUD_TEX_WEATHER, 3)  // width x height x 3
// Packed views of the noise for the density, each one vec4 per texel (cloud_noise_packing.h
// builds them from the CloudNoise arrays; the C++ hook packs on the fly, the shader reads
// them uploaded). A trilinear read of the packed base is 4 texel loads instead of 8, of the
// packed detail 2 instead of 8: the march's body loads 24 -> 14 texels a sample.
//   BASE_PAIRS   texel (x, y, z): (R, fbm) of texel x and of texel x + 1 (wrapped), with
//                fbm = G 0.625 + B 0.25 + A 0.125 formed in float per texel;
//   DETAIL_QUADS texel (x, y, z): the detail fbm R 0.625 + G 0.25 + B 0.125 of texels
//                (x, y), (x + 1, y), (x, y + 1), (x + 1, y + 1) at slice z (wrapped).
// The filter is linear, so filtering the per-texel fbm equals the fbm of filtered channels
// up to float rounding (a few ulps).
SC_CONST_INT(CLOUD_TEX_BASE_PAIRS, 4)
SC_CONST_INT(CLOUD_TEX_DETAIL_QUADS, 5)

#ifndef CLOUD_TEXEL4_DECLARED  // the shader declares it before its hook
struct Texel4 {
  Scalar r;
  Scalar g;
  Scalar b;
  Scalar a;
};
#endif

// One axis of a wrapped linear filter: texel coordinate u (texel centres at i + 0.5)
// -> the two texel indices and the weight of the second. n is a power of two (the noise
// sizes are; ValidateCloudTextures checks the weather map's), so the wrap is a mask of the
// floor's two's-complement bits: no division and no fix-ups (lavapipe runs ten of these per
// density sample). f = t - floor(t) is exact in float, as was t mod n - floor(t mod n):
// the same weights and texels as the modulo form.
struct WrapAxis {
  int i0;
  int i1;
  Scalar f;
};

WrapAxis wrap_axis(Scalar u, int n) {
  Scalar t = u - Scalar(0.5);
  Scalar fl = floor(t);
  WrapAxis w;
  w.f = t - fl;
  w.i0 = floor_to_int(fl) & (n - 1);
  w.i1 = (w.i0 + 1) & (n - 1);
  return w;
}

// A trilinear read's texels and weights at texel coordinates (u, v, w) of an n^3 volume:
// the wrapped indices per axis and the 8 weights in the order the readers sum them (z, then
// y, then x; each weight the product gz gy gx).
struct Trilinear {
  WrapAxis x;
  WrapAxis y;
  WrapAxis z;
  Scalar w000;
  Scalar w001;
  Scalar w010;
  Scalar w011;
  Scalar w100;
  Scalar w101;
  Scalar w110;
  Scalar w111;
};

Trilinear trilinear_setup(Scalar u, Scalar v, Scalar w, int n) {
  Trilinear t;
  t.x = wrap_axis(u, n);
  t.y = wrap_axis(v, n);
  t.z = wrap_axis(w, n);
  Scalar gx0 = Scalar(1.0) - t.x.f;
  Scalar gy0 = Scalar(1.0) - t.y.f;
  Scalar gz0 = Scalar(1.0) - t.z.f;
  t.w000 = gz0 * gy0 * gx0;
  t.w001 = gz0 * gy0 * t.x.f;
  t.w010 = gz0 * t.y.f * gx0;
  t.w011 = gz0 * t.y.f * t.x.f;
  t.w100 = t.z.f * gy0 * gx0;
  t.w101 = t.z.f * gy0 * t.x.f;
  t.w110 = t.z.f * t.y.f * gx0;
  t.w111 = t.z.f * t.y.f * t.x.f;
  return t;
}

// The base noise's Perlin-Worley R and Worley fbm, trilinear (texels, weights and order of
// terms as Trilinear lays them out), from 4 loads of BASE_PAIRS.
struct BaseNoise {
  Scalar r;
  Scalar fbm;
};

#ifndef CLOUD_HARDWARE_FILTER
BaseNoise sample_base_noise(Scalar u, Scalar v, Scalar w) {
  int n = CLOUD_BASE_SIZE;
  Trilinear t = trilinear_setup(u, v, w, n);
  int z0 = t.z.i0 * n;
  int z1 = t.z.i1 * n;
  Texel4 t00 = cloud_texel4(CLOUD_TEX_BASE_PAIRS, (z0 + t.y.i0) * n + t.x.i0);
  Texel4 t01 = cloud_texel4(CLOUD_TEX_BASE_PAIRS, (z0 + t.y.i1) * n + t.x.i0);
  Texel4 t10 = cloud_texel4(CLOUD_TEX_BASE_PAIRS, (z1 + t.y.i0) * n + t.x.i0);
  Texel4 t11 = cloud_texel4(CLOUD_TEX_BASE_PAIRS, (z1 + t.y.i1) * n + t.x.i0);
  BaseNoise b;
  b.r = Scalar(0.0) + t.w000 * t00.r;
  b.r = b.r + t.w001 * t00.b;
  b.r = b.r + t.w010 * t01.r;
  b.r = b.r + t.w011 * t01.b;
  b.r = b.r + t.w100 * t10.r;
  b.r = b.r + t.w101 * t10.b;
  b.r = b.r + t.w110 * t11.r;
  b.r = b.r + t.w111 * t11.b;
  b.fbm = Scalar(0.0) + t.w000 * t00.g;
  b.fbm = b.fbm + t.w001 * t00.a;
  b.fbm = b.fbm + t.w010 * t01.g;
  b.fbm = b.fbm + t.w011 * t01.a;
  b.fbm = b.fbm + t.w100 * t10.g;
  b.fbm = b.fbm + t.w101 * t10.a;
  b.fbm = b.fbm + t.w110 * t11.g;
  b.fbm = b.fbm + t.w111 * t11.a;
  return b;
}

// The detail noise's fbm, trilinear (texels, weights and order of terms as above), from 2
// loads of DETAIL_QUADS.
Scalar sample_detail_fbm(Scalar u, Scalar v, Scalar w) {
  int n = CLOUD_DETAIL_SIZE;
  Trilinear t = trilinear_setup(u, v, w, n);
  Texel4 q0 = cloud_texel4(CLOUD_TEX_DETAIL_QUADS, (t.z.i0 * n + t.y.i0) * n + t.x.i0);
  Texel4 q1 = cloud_texel4(CLOUD_TEX_DETAIL_QUADS, (t.z.i1 * n + t.y.i0) * n + t.x.i0);
  Scalar f = Scalar(0.0) + t.w000 * q0.r;
  f = f + t.w001 * q0.g;
  f = f + t.w010 * q0.b;
  f = f + t.w011 * q0.a;
  f = f + t.w100 * q1.r;
  f = f + t.w101 * q1.g;
  f = f + t.w110 * q1.b;
  f = f + t.w111 * q1.a;
  return f;
}

Texel4 texel4_zero() {
  Texel4 t;
  t.r = Scalar(0.0);
  t.g = Scalar(0.0);
  t.b = Scalar(0.0);
  t.a = Scalar(0.0);
  return t;
}

// Adds weight x texel number `texel`.
Texel4 texel4_accumulate(Texel4 acc, int tex, int texel, Scalar weight) {
  Texel4 t = cloud_texel4(tex, texel);
  acc.r = acc.r + weight * t.r;
  acc.g = acc.g + weight * t.g;
  acc.b = acc.b + weight * t.b;
  acc.a = acc.a + weight * t.a;
  return acc;
}

// Bilinear read of a width x height image at texel coordinates (u, v).
Texel4 sample_image(int tex, int width, int height, Scalar u, Scalar v) {
  WrapAxis ax = wrap_axis(u, width);
  WrapAxis ay = wrap_axis(v, height);
  Texel4 acc = texel4_zero();
  Scalar gx0 = Scalar(1.0) - ax.f;
  Scalar gy0 = Scalar(1.0) - ay.f;
  acc = texel4_accumulate(acc, tex, (ay.i0 * width + ax.i0), gy0 * gx0);
  acc = texel4_accumulate(acc, tex, (ay.i0 * width + ax.i1), gy0 * ax.f);
  acc = texel4_accumulate(acc, tex, (ay.i1 * width + ax.i0), ay.f * gx0);
  acc = texel4_accumulate(acc, tex, (ay.i1 * width + ax.i1), ay.f * ax.f);
  return acc;
}
#endif  // CLOUD_HARDWARE_FILTER
