// Limits shared by the shaders and the C++ side (one source). The Vulkan renderer keeps a
// frame's LUT slice (3 tables x columns, vec4 each) in a uniform block of this size.
#define SC_MAX_LUT_COLUMNS 256
