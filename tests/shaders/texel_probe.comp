#version 450
// Test shader for gpu::ComputePipeline's uniform texel buffers (tests/compute_pipeline_test.cc):
// out[i] = dot(texel[i], weights), texel i of a samplerBuffer of vec4 read with texelFetch
// at a per-invocation index (reversed, so the lanes of one SIMD vector read scattered texels).
layout(local_size_x = 64) in;
layout(std140, set = 0, binding = 0) uniform Params { vec4 weights; uvec4 count; } P;
layout(set = 0, binding = 1) uniform samplerBuffer texels;
layout(std430, set = 0, binding = 2) writeonly buffer Out { float out_values[]; };
void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= P.count.x) return;
  out_values[i] = dot(texelFetch(texels, int(P.count.x - 1u - i)), P.weights);
}
