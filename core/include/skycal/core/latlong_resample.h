// A lat-long box-filtered down to any smaller size: each output pixel the mean of the input
// area it covers, an input pixel counted by the fraction of it inside (pixel edges at
// i / width, as core/latlong.h puts centres at (i + 0.5) / width). Photos come at any size
// (6000x3000, 1000x500), and the cloud statistics and the weather inversion work at fixed
// widths; an integer factor is the plain block mean. Values are row-major with `channels`
// interleaved per pixel. Throws skycal::Error naming the sizes for an empty or larger output
// or values that are not width * height * channels.
#pragma once
#include <vector>

namespace skycal {

std::vector<float> AreaDownsampleLatLong(const std::vector<float>& values, int width, int height, int channels,
                                         int out_width, int out_height);

// The same mean over the input pixels whose every channel is positive and finite (radiance a
// fit can take the log of: import zeroes non-finite pixels, and a plain mean would darken the
// area around one); an output pixel that covers none is 0 in every channel.
std::vector<float> AreaDownsampleLatLongOfPositive(const std::vector<float>& values, int width, int height, int channels,
                                                   int out_width, int out_height);

}  // namespace skycal
