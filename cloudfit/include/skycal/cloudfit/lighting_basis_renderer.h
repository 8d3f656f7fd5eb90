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
// is then a weighted sum of cached images, not a march. The sun's illuminance E enters every
// image affinely too (the direct term; the lit ground, which also enters the sky's SH-9 that
// the ambient and the aerial-perspective blend read): with set_sun_scale(s) != 1 the same
// three marches at E / 2 give L(E / 2), and L(s E) = L(E) + 2 (s - 1) (L(E) - L(E / 2)) lights
// the clouds with s x the preset's sun (fit --clouds stats fits s). Any other change (extinction, phase, powder, the
// preset, the wind time, the weather map, the size or the march) renders the basis anew
// through the wrapped renderer.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "skycal/clouds/cloud_renderer.h"

namespace skycal::render {
struct Preset;
}

namespace skycal::cloudfit {

class LightingBasisCloudRenderer final : public clouds::CloudRenderer {
 public:
  // `inner` does the marches and must outlive this. `max_entries` bases are kept (the
  // oldest dropped first): one per draw of shapes (weather map x wind time) per reference.
  explicit LightingBasisCloudRenderer(clouds::CloudRenderer& inner, int max_entries = 64);
  ~LightingBasisCloudRenderer() override;
  clouds::CloudImage Render(const clouds::CloudScene& scene, const clouds::CloudRenderRequest& request) override;
  std::string Describe() const override;

  // The factor on the scene preset's sun illuminance every later render is synthesized with
  // (> 0; 1: the preset's own sun, no fourth march). Throws skycal::Error when not > 0.
  void set_sun_scale(double s);
  double sun_scale() const { return sun_scale_; }

  long long marches() const { return marches_; }          // renders of the wrapped renderer
  long long synthesized() const { return synthesized_; }  // renders answered from a cached basis

 private:
  struct Basis {
    clouds::CloudScene scene;            // pointers as given (identity of preset, noise, weather)
    clouds::CloudParams params;          // with albedo and ambient_strength zeroed
    clouds::CloudRenderRequest request;
    clouds::CloudImage c, d, a;          // C; D; A (radiance only in d and a)
    // The same at half the preset's sun (made when a sun scale != 1 first needs it).
    std::unique_ptr<render::Preset> half_sun;
    std::unique_ptr<Basis> half;
  };
  std::unique_ptr<Basis> March(const clouds::CloudScene& scene, const clouds::CloudRenderRequest& request);
  clouds::CloudRenderer& inner_;
  int max_entries_;
  std::vector<std::unique_ptr<Basis>> cache_;
  long long marches_ = 0, synthesized_ = 0;
  double sun_scale_ = 1.0;
};

}  // namespace skycal::cloudfit
