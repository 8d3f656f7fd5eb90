// A cloud renderer for fits that change only the cloud lighting's linear part: the
// scattering albedo a and the ambient strength k. The march (clouds/model/cloud_march.glsl.h)
// adds per step the source (E_sun x phase x attenuation + k x ambient(h) + ground(h)) x a x
// extinction x density, and the transmittance depends on the extinction alone; the
// aerial-perspective blend mixes in the sky's colour x (1 - T), independent of a and k. So
// every pixel's cloud radiance is affine in (a, a k):
//     L(a, k) = C + a (D + k A)
// with C the blend's sky share, D the sun and ground light, A the sky ambient (each an image
// of the same shapes, light and march). Three renders of one draw of shapes give C, D and A
// exactly: (a = 0, k = 0) -> C, (1, 0) -> C + D, (1, 1) -> C + D + A. Every other (a, k)
// is then a weighted sum of cached images, not a march. Any other change (extinction, phase,
// powder, the sun, the wind time, the weather map, the size or the march) renders the basis
// anew through the wrapped renderer.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "skycal/clouds/cloud_renderer.h"

namespace skycal::cli {

class LightingBasisCloudRenderer final : public clouds::CloudRenderer {
 public:
  // `inner` does the marches and must outlive this. `max_entries` bases are kept (the
  // oldest dropped first): one per draw of shapes (weather map x wind time) per reference.
  explicit LightingBasisCloudRenderer(clouds::CloudRenderer& inner, int max_entries = 64);
  clouds::CloudImage Render(const clouds::CloudScene& scene, const clouds::CloudRenderRequest& request) override;
  std::string Describe() const override;

  long long marches() const { return marches_; }          // renders of the wrapped renderer
  long long synthesized() const { return synthesized_; }  // renders answered from a cached basis

 private:
  struct Basis {
    clouds::CloudScene scene;            // pointers as given (identity of preset, noise, weather)
    clouds::CloudParams params;          // with albedo and ambient_strength zeroed
    clouds::CloudRenderRequest request;
    clouds::CloudImage c, d, a;          // C; D; A (radiance only in d and a)
  };
  clouds::CloudRenderer& inner_;
  int max_entries_;
  std::vector<std::unique_ptr<Basis>> cache_;
  long long marches_ = 0, synthesized_ = 0;
};

}  // namespace skycal::cli
