#version 450
// Test shader for gpu::ComputePipeline (tests/compute_pipeline_test.cc): out[i] =
// in[i] * scale + offset, with `offset` a specialization constant and `scale` and the
// element count in a uniform block. Exercises all three resource kinds the renderers use.
layout(local_size_x = 64) in;
layout(constant_id = 0) const uint kOffset = 0u;
layout(std140, set = 0, binding = 0) uniform Params { vec4 scale; uvec4 count; } P;
layout(std430, set = 0, binding = 1) readonly buffer In { float in_values[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Out { float out_values[]; };
void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= P.count.x) return;
  out_values[i] = in_values[i] * P.scale.x + float(kOffset);
}
