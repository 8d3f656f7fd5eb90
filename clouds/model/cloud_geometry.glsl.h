// The cloud layer's geometry: a spherical shell [R + bottom, R + top] around a planet of
// radius R (Schneider 2015: the layer follows the planet's curvature, so clouds sink below
// the horizon with distance; a smaller R exaggerates that). Positions are camera-relative
// metres (x, z horizontal, y up along the camera's vertical); the planet's centre sits at
// (0, -(R + camera_height), 0). Written to keep float precise: R ~ 6.4e6 m would leave
// half-metre steps in |p| - R, so altitudes and ray-sphere roots are formed from
// differences that never subtract two numbers near R.

// Altitude above the ground of the camera-relative point (x, y, z):
// (R + a)^2 = x^2 + z^2 + (R + q)^2 with q = camera_height + y gives
// a = (2 R q + q^2 + rho^2) / (sqrt((R + q)^2 + rho^2) + R).
Scalar cloud_altitude(vec3 pos, CloudShadeParams p) {
  Scalar q = p.camera_height + pos.y;
  Scalar rho2 = pos.x * pos.x + pos.z * pos.z;
  Scalar rq = p.planet_radius + q;
  return (Scalar(2.0) * p.planet_radius * q + q * q + rho2) / (sqrt(rq * rq + rho2) + p.planet_radius);
}

// Roots of t^2 + 2 b t + c = 0 for a ray from the camera along view (b = (R + h_cam) v.y,
// c = (R + h_cam)^2 - (R + h)^2 = (h_cam - h)(2R + h_cam + h)), the sphere of altitude h.
struct SphereHit {
  int hit;      // 0: the line misses the sphere
  Scalar near;  // smaller root
  Scalar far;   // larger root
};

SphereHit sphere_hit(Scalar view_y, Scalar altitude, CloudShadeParams p) {
  Scalar b = (p.planet_radius + p.camera_height) * view_y;
  Scalar c = (p.camera_height - altitude) * (Scalar(2.0) * p.planet_radius + p.camera_height + altitude);
  Scalar disc = b * b - c;
  SphereHit s;
  s.hit = disc >= Scalar(0.0) ? 1 : 0;
  Scalar root = sqrt(max(disc, Scalar(0.0)));
  // Numerically stable pair: q = -(b + sign(b) root), roots q and c / q.
  Scalar q = b >= Scalar(0.0) ? -(b + root) : -(b - root);
  Scalar r1 = q;
  Scalar r2 = q != Scalar(0.0) ? c / q : Scalar(0.0);
  s.near = min(r1, r2);
  s.far = max(r1, r2);
  return s;
}

// The part of the view ray inside the layer, [t0, t1] in metres (t1 <= t0: none), cut at
// the draw distance and where the ray meets the ground first.
struct CloudSegment {
  Scalar t0;
  Scalar t1;
};

CloudSegment cloud_segment(vec3 view, CloudShadeParams p) {
  SphereHit ground = sphere_hit(view.y, Scalar(0.0), p);
  SphereHit bottom = sphere_hit(view.y, p.layer_bottom, p);
  SphereHit top = sphere_hit(view.y, p.layer_top, p);
  Scalar ground_t = (ground.hit == 1 && ground.near > Scalar(0.0)) ? ground.near : Scalar(1e30);
  CloudSegment s;
  s.t0 = Scalar(0.0);
  s.t1 = Scalar(0.0);
  if (p.camera_height < p.layer_bottom) {
    // Below the layer: from the bottom sphere's far root to the top's, unless the ground comes first.
    s.t0 = bottom.far;
    s.t1 = top.far;
    if (ground_t < s.t0) s.t1 = s.t0;
  } else if (p.camera_height <= p.layer_top) {
    // Inside: to the top, or down to the bottom sphere.
    s.t1 = top.far;
    if (bottom.hit == 1 && bottom.near > Scalar(0.0)) s.t1 = bottom.near;
  } else {
    // Above: in through the top, out through the bottom (or the top again).
    if (top.hit == 1 && top.near > Scalar(0.0)) {
      s.t0 = top.near;
      s.t1 = top.far;
      if (bottom.hit == 1 && bottom.near > Scalar(0.0)) s.t1 = bottom.near;
    }
  }
  s.t1 = min(s.t1, p.draw_distance);
  return s;
}
