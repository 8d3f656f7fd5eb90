// The uniform block the sky shaders read, written once for GLSL and C++ (the macros are
// defined by render/shaders/*.comp and by render/src/sky_uniforms.h). Only vec4/ivec4
// members: their std140 layout is a plain array of 16-byte records, which the C++ side
// checks with static_asserts.
SC_UNIFORM_VEC4(sun_dir)        // xyz: unit vector toward the sun; w: unused
SC_UNIFORM_VEC4(model)          // x: haziness g; y: isotropic weight; z: overcast weight; w: overcast zenith cd/m^2
SC_UNIFORM_VEC4(sun_disc)       // x: 1 - cos(R); y: R (rad); z: limb-darkening u; w: unused
SC_UNIFORM_VEC4(sun_radiance)   // rgb: disc centre radiance, cd/m^2; w: unused
SC_UNIFORM_VEC4(ground)         // rgb: ground radiance, cd/m^2; w: unused
SC_UNIFORM_VEC4(lut_grid)       // x: 1 - cos(theta_max); yzw: unused
SC_UNIFORM_IVEC4(sizes)         // x: LUT columns (n_gamma); y: LUT rows (n_theta); z: image width; w: image height
SC_UNIFORM_IVEC4(order)         // x: workgroup row stride (gpu/workgroup_order.h); yzw: unused
