// Cascaded shadow map maths: see cascade_math.h for the contracts; the fit is written as a
// numbered procedure above fit_cascade().
#include "runtime/math/cascade_math.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include <glm/gtc/matrix_transform.hpp>

#include "runtime/result/result.h"

namespace kaskad {
namespace {

using glm::dmat4;
using glm::dvec2;
using glm::dvec3;
using glm::dvec4;

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

bool finite(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// A light-space rectangle, the x/y extent of a light frustum.
struct Rect {
  double min_x, max_x, min_y, max_y;
};

// A depth range along the light, with "nothing found" as an explicit state.
struct Range {
  double near = std::numeric_limits<double>::infinity();
  double far = -std::numeric_limits<double>::infinity();
  bool empty() const { return !(near <= far); }
  void add(double depth_near, double depth_far) {
    near = std::min(near, depth_near);
    far = std::max(far, depth_far);
  }
};

NearFar to_near_far(const Range& r) {
  if (r.empty()) return {};
  return {static_cast<float>(r.near), static_cast<float>(r.far), false};
}

// light_view_matrix in double: the fits use it so that large world coordinates and thin slices
// (near = 1e-4) keep their precision until the final float matrices.
dmat4 light_view_d(const glm::vec3& direction, const glm::vec3& origin) {
  const dvec3 f = glm::normalize(dvec3(direction));
  const dvec3 up = dvec3(light_up_vector(glm::vec3(f)));
  const dvec3 s = glm::normalize(glm::cross(f, up));
  const dvec3 u = glm::cross(s, f);
  const dvec3 o(origin);
  dmat4 m(1.0);  // rows s, u, -f: glm::lookAt's layout
  for (int c = 0; c < 3; ++c) {
    m[c][0] = s[c];
    m[c][1] = u[c];
    m[c][2] = -f[c];
  }
  m[3][0] = -glm::dot(s, o);
  m[3][1] = -glm::dot(u, o);
  m[3][2] = glm::dot(f, o);
  return m;
}

dvec3 transform_point(const dmat4& m, const dvec3& p) {
  return dvec3(m * dvec4(p, 1.0));
}

// S0 step 1 in view space (P0..P3 at d_near, P4..P7 at d_far), then M_cam.
std::array<dvec3, 8> corners_world_d(const glm::mat4& camera_world, double half_h_near,
                                     double half_h_far, double aspect, double d_near,
                                     double d_far) {
  const dmat4 cam(camera_world);
  std::array<dvec3, 8> out;
  for (int plane = 0; plane < 2; ++plane) {
    const double d = plane == 0 ? d_near : d_far;
    const double h = plane == 0 ? half_h_near : half_h_far;
    const double w = h * aspect;
    const dvec3 p[4] = {{-w, h, -d}, {w, h, -d}, {w, -h, -d}, {-w, -h, -d}};
    for (int j = 0; j < 4; ++j) out[4 * plane + j] = transform_point(cam, p[j]);
  }
  return out;
}

std::array<dvec3, 8> corners_world_d(const CameraSlice& s) {
  if (s.projection == Projection::orthographic) {
    const double h = 0.5 * static_cast<double>(s.ortho_height);
    return corners_world_d(s.camera_world, h, h, s.aspect, s.near, s.far);
  }
  const double t = std::tan(0.5 * static_cast<double>(s.fov_y_rad));
  return corners_world_d(s.camera_world, s.near * t, s.far * t, s.aspect, s.near, s.far);
}

std::array<glm::vec3, 8> to_float(const std::array<dvec3, 8>& c) {
  std::array<glm::vec3, 8> out;
  for (int j = 0; j < 8; ++j) out[j] = glm::vec3(c[j]);
  return out;
}

// The bounding sphere of the slice, in double. Perspective: the 8 corners lie on two circles
// around the view axis, radius a_n = d_n k at depth d_n and a_f = d_f k at d_f, with
// k = tan(fov/2) sqrt(1 + aspect^2). The sphere through both circles is centred at depth c with
//   (c - d_n)^2 + a_n^2 = (d_f - c)^2 + a_f^2,  i.e.  c = (d_n + d_f)(1 + k^2) / 2;
// when c > d_f the far circle alone bounds the slice (c = d_f, r = a_f). Only shape parameters
// enter r (see the header).
void sphere_d(const CameraSlice& s, dvec3& center, double& radius) {
  const double dn = s.near, df = s.far, a = s.aspect;
  double c;
  if (s.projection == Projection::orthographic) {
    const double h = 0.5 * static_cast<double>(s.ortho_height);
    c = 0.5 * (dn + df);
    radius = std::sqrt(h * h * (1.0 + a * a) + 0.25 * (df - dn) * (df - dn));
  } else {
    const double t = std::tan(0.5 * static_cast<double>(s.fov_y_rad));
    const double k2 = t * t * (1.0 + a * a);
    c = 0.5 * (dn + df) * (1.0 + k2);
    if (c >= df) {
      c = df;
      radius = df * std::sqrt(k2);
    } else {
      radius = std::sqrt((df - c) * (df - c) + df * df * k2);
    }
  }
  center = transform_point(dmat4(s.camera_world), dvec3(0.0, 0.0, -c));
}

// ---- S2 ComputeNearAndFar ----

// A convex polygon of at most 3 + 4 vertices (a triangle clipped by 4 planes adds one per plane).
struct Poly {
  std::array<dvec3, 8> v;
  int n = 0;
};

// Keeps the part of `p` where sign * (v[axis] - bound) >= 0 (Sutherland-Hodgman, one plane).
void clip_polygon(Poly& p, int axis, double bound, double sign) {
  Poly out;
  for (int i = 0; i < p.n; ++i) {
    const dvec3& a = p.v[i];
    const dvec3& b = p.v[(i + 1) % p.n];
    const double da = sign * (a[axis] - bound);
    const double db = sign * (b[axis] - bound);
    if (da >= 0.0) out.v[out.n++] = a;
    if ((da >= 0.0) != (db >= 0.0)) {
      const double t = da / (da - db);
      dvec3 x = a + t * (b - a);
      x[axis] = bound;  // exactly on the plane despite rounding
      out.v[out.n++] = x;
    }
  }
  p = out;
}

// A box in light view space from its centre and half-extent through the view (Arvo's box
// transform; transform_point() drops w, so the map is affine whatever the matrix): one
// transform instead of eight corners. The corners' bounds differ from centre +- extent by
// rounding only, which `slack` bounds.
struct LightBounds {
  dvec3 centre, extent;
  double slack;
  // The depth range (depth = -z) of the whole box, widened by the slack: the range of any part
  // of the box lies within it.
  Range depths() const {
    Range r;
    r.add(-(centre.z + extent.z) - slack, -(centre.z - extent.z) + slack);
    return r;
  }
};

LightBounds light_bounds(const dmat4& light_view, const Aabb& box) {
  const dvec3 lo(box.min), hi(box.max);
  LightBounds b;
  b.centre = transform_point(light_view, 0.5 * (lo + hi));
  const dvec3 half = 0.5 * (hi - lo);
  b.extent = dvec3(0.0);
  double terms = 1.0;  // a bound on the magnitudes each coordinate sums
  for (int row = 0; row < 3; ++row) {
    terms += std::abs(light_view[3][row]) + std::abs(b.centre[row]);
    for (int col = 0; col < 3; ++col) {
      b.extent[row] += std::abs(light_view[col][row]) * half[col];
      terms += std::abs(light_view[col][row]) * std::max(std::abs(lo[col]), std::abs(hi[col]));
    }
  }
  b.slack = 1e-9 * terms;
  return b;
}

// Depth range (along the light) of non-empty `box`, whose light_bounds() are `b`, inside the
// light-space prism over `r`.
Range box_range_in_rect(const dmat4& light_view, const Aabb& box, const LightBounds& b,
                        const Rect& r) {
  Range out;
  if (!(r.min_x <= r.max_x) || !(r.min_y <= r.max_y)) return out;
  // 0. Most boxes of a large scene miss a cascade's rectangle: reject them from the box's
  //    light-space bounds, one transform instead of eight corners.
  const double ex = b.extent.x + b.slack, ey = b.extent.y + b.slack;
  if (b.centre.x + ex < r.min_x || b.centre.x - ex > r.max_x || b.centre.y + ey < r.min_y ||
      b.centre.y - ey > r.max_y)
    return out;
  // 1. The 8 corners in light view space (corner i: bit 0 = x, bit 1 = y, bit 2 = z).
  std::array<dvec3, 8> c;
  for (int i = 0; i < 8; ++i) {
    const dvec3 w{(i & 1) ? box.max.x : box.min.x, (i & 2) ? box.max.y : box.min.y,
                  (i & 4) ? box.max.z : box.min.z};
    c[i] = transform_point(light_view, w);
  }
  // The light-space box of the corners: it may still miss the rectangle by rounding.
  dvec3 lo = c[0], hi = c[0];
  for (const dvec3& p : c) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  if (hi.x < r.min_x || lo.x > r.max_x || hi.y < r.min_y || lo.y > r.max_y) return out;
  // Wholly inside the rectangle: nothing is clipped, the corners are the vertices.
  if (lo.x >= r.min_x && hi.x <= r.max_x && lo.y >= r.min_y && hi.y <= r.max_y) {
    out.add(-hi.z, -lo.z);
    return out;
  }
  // 2. The 6 faces as 12 triangles, each clipped against the 4 side planes; 3. min/max z of the
  //    clipped vertices (depth = -z).
  static constexpr int kFaces[6][4] = {{0, 2, 6, 4}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                       {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 5, 7, 6}};
  for (const auto& f : kFaces) {
    for (int t = 0; t < 2; ++t) {
      Poly p;
      p.n = 3;
      p.v[0] = c[f[0]];
      p.v[1] = c[f[t + 1]];
      p.v[2] = c[f[t + 2]];
      clip_polygon(p, 0, r.min_x, 1.0);
      clip_polygon(p, 0, r.max_x, -1.0);
      clip_polygon(p, 1, r.min_y, 1.0);
      clip_polygon(p, 1, r.max_y, -1.0);
      for (int i = 0; i < p.n; ++i) out.add(-p.v[i].z, -p.v[i].z);
    }
  }
  return out;
}

Range box_range_in_rect(const dmat4& light_view, const Aabb& box, const Rect& r) {
  if (box.empty()) return {};
  return box_range_in_rect(light_view, box, light_bounds(light_view, box), r);
}

// tighten_near_far in double; see the header for the rules.
Range tighten_d(const dmat4& light_view, std::span<const Aabb> casters,
                std::span<const Aabb> receivers, const Rect& r, double slice_near,
                double slice_far) {
  // 1. Receivers: the parts inside the slice volume (rectangle x [slice_near, slice_far]).
  //    A box whose whole depth range lies within the range found so far cannot widen it.
  Range out;
  for (const Aabb& b : receivers) {
    if (b.empty()) continue;
    const LightBounds bounds = light_bounds(light_view, b);
    const Range whole = bounds.depths();
    if (!out.empty() && whole.near >= out.near && whole.far <= out.far) continue;
    const Range range = box_range_in_rect(light_view, b, bounds, r);
    if (range.empty() || range.far < slice_near || range.near > slice_far) continue;
    out.add(std::max(range.near, slice_near), std::min(range.far, slice_far));
  }
  if (out.empty()) return out;
  // 2. Casters inside the rectangle whose nearest point is in front of the farthest receiver
  //    point can shadow it: pull the near plane back to them (S0 step 3). A caster whose whole
  //    box lies behind the near plane found so far cannot pull it.
  for (const Aabb& b : casters) {
    if (b.empty()) continue;
    const LightBounds bounds = light_bounds(light_view, b);
    if (bounds.depths().near >= out.near) continue;
    const Range range = box_range_in_rect(light_view, b, bounds, r);
    if (!range.empty() && range.near < out.far) out.near = std::min(out.near, range.near);
  }
  return out;
}

// Widens [lo, hi] to at least `min_extent`, symmetrically (S0 step 5's S = 2 / (max - min) and
// glm::ortho divide by it).
void guard_extent(double& lo, double& hi, double min_extent) {
  if (hi - lo < min_extent) {
    const double mid = 0.5 * (lo + hi);
    lo = mid - 0.5 * min_extent;
    hi = mid + 0.5 * min_extent;
  }
}

double scale_eps(double a, double b) {
  return 1e-6 * std::max({1.0, std::abs(a), std::abs(b)});
}

}  // namespace

// ---- Splits ----

std::vector<float> split_distances(SplitScheme scheme, int count, float near, float far,
                                   float lambda) {
  KASKAD_CHECK(count >= 1 && count <= kMaxCascades,
               "count must be in [1, 8], was " + std::to_string(count));
  KASKAD_CHECK(std::isfinite(near) && std::isfinite(far) && near > 0.0f && near < far,
               "need 0 < near < far, both finite; was near " + num(near) + ", far " + num(far));
  KASKAD_CHECK(lambda >= 0.0f && lambda <= 1.0f, "lambda must be in [0, 1], was " + num(lambda));
  const double dn = near, df = far, n = count;
  std::vector<float> d(static_cast<size_t>(count) + 1);
  d.front() = near;  // exact ends, no rounding drift
  d.back() = far;
  for (int i = 1; i < count; ++i) {
    const double uniform = dn + (df - dn) * (i / n);   // S0 eq. (1)
    const double log = dn * std::pow(df / dn, i / n);  // S0 eq. (2)
    double v = uniform;
    if (scheme == SplitScheme::log || scheme == SplitScheme::automatic) v = log;
    if (scheme == SplitScheme::mixed) v = lambda * log + (1.0 - lambda) * uniform;  // S0 eq. (3)
    // Strictly increasing even when rounding to float merges two neighbours.
    d[i] = std::max(static_cast<float>(v),
                    std::nextafter(d[i - 1], std::numeric_limits<float>::infinity()));
  }
  KASKAD_CHECK(d[count - 1] < far, "near " + num(near) + " and far " + num(far) +
                                       " are too close for " + std::to_string(count) +
                                       " distinct splits");
  return d;
}

// ---- Slices ----

std::array<glm::vec3, 8> slice_corners_world(const glm::mat4& camera_world, float fov_y_rad,
                                             float aspect, float d_near, float d_far) {
  const double t = std::tan(0.5 * static_cast<double>(fov_y_rad));
  return to_float(corners_world_d(camera_world, d_near * t, d_far * t, aspect, d_near, d_far));
}

std::array<glm::vec3, 8> slice_corners_world_ortho(const glm::mat4& camera_world,
                                                   float ortho_height, float aspect, float d_near,
                                                   float d_far) {
  const double h = 0.5 * static_cast<double>(ortho_height);
  return to_float(corners_world_d(camera_world, h, h, aspect, d_near, d_far));
}

std::array<glm::vec3, 8> slice_corners_world(const CameraSlice& slice) {
  return to_float(corners_world_d(slice));
}

BoundingSphere slice_bounding_sphere(const CameraSlice& slice) {
  dvec3 c;
  double r;
  sphere_d(slice, c, r);
  return {glm::vec3(c), static_cast<float>(r)};
}

// ---- Light ----

glm::mat4 light_view_matrix(const glm::vec3& light_dir, const glm::vec3& origin) {
  return glm::mat4(light_view_d(light_dir, origin));
}

// ---- Near / far ----

NearFar compute_near_far(const glm::mat4& light_view, const Aabb& scene_bounds, float min_x,
                         float max_x, float min_y, float max_y) {
  return to_near_far(
      box_range_in_rect(dmat4(light_view), scene_bounds, Rect{min_x, max_x, min_y, max_y}));
}

NearFar tighten_near_far(const glm::mat4& light_view, std::span<const Aabb> casters,
                         std::span<const Aabb> receivers, float min_x, float max_x, float min_y,
                         float max_y, float slice_near, float slice_far) {
  return to_near_far(tighten_d(dmat4(light_view), casters, receivers,
                               Rect{min_x, max_x, min_y, max_y}, slice_near, slice_far));
}

// ---- Fit ----
//
// Procedure (the numbers are this function's; S0's steps are cited):
//  1. The slice's 8 corners in world space (S0 step 1, M_cam) and in light view space
//     (S0 step 2, P'_j = M_light M_cam P_j).
//  2. The x/y rectangle of the light frustum:
//     crop   - M_Lprj's window from the beam radius R around the light axis, or from the scene
//              box's light-space extent when R = 0 (S0 step 4); P''_j = M_Lprj P'_j and their
//              x/y min/max are the crop (S0 step 5), optionally clipped to M_Lprj's [-1, 1]^2.
//     stable - the slice's bounding sphere (centre c, radius r from the shape only); texel size
//              u = 2r / (map_size - 1); min = floor((c.xy - r) / u) * u, max = min + map_size * u
//              (S2 texel snapping; the map is one texel larger than the 2r fitted area, so the
//              snap never uncovers the sphere and texels stay exactly u wide).
//  3. Depths: the slice's own range (crop: the corners; stable: c.z -+ r), combined with the
//     geometry inside the rectangle (S0 step 3 pull-back to casters, S2 ComputeNearAndFar or per
//     object bounds) as DepthFit says, plus a small margin against rounding at the planes;
//     stable: then snapped outwards to whole steps of r / 2.
//  4. The projection: crop  M_proj = M_crop * M_Lprj (S0 step 5, T = -(max + min) / 2,
//     S = 2 / (max - min)); stable  ortho(min, max, near, far).
CascadeFit fit_cascade(const CameraSlice& slice, const LightFrame& light,
                       const CascadeFitOptions& options, const ShadowGeometry& geometry) {
  {
    const std::string s = validate_camera_slice(slice);
    KASKAD_CHECK(s.empty(), "slice: " + s);
    const std::string l = validate_light_frame(light);
    KASKAD_CHECK(l.empty(), "light: " + l);
  }
  KASKAD_CHECK(options.map_size >= 2,
               "map_size must be >= 2, was " + std::to_string(options.map_size));
  KASKAD_CHECK(std::isfinite(options.beam_radius) && options.beam_radius >= 0.0f,
               "beam_radius must be finite and >= 0, was " + num(options.beam_radius));
  const bool crop = options.mode == FitMode::crop;
  const double map_size = options.map_size;
  CascadeFit out;

  // 1. Corners, world -> light view.
  const dmat4 view = light_view_d(light.direction, light.origin);
  const std::array<dvec3, 8> world = corners_world_d(slice);
  dvec3 lo(std::numeric_limits<double>::infinity()), hi(-lo);
  for (const dvec3& p : world) {
    const dvec3 q = transform_point(view, p);
    lo = glm::min(lo, q);
    hi = glm::max(hi, q);
  }

  // 2. Rectangle and the slice's depth range.
  Rect rect{};
  double slice_near = 0.0, slice_far = 0.0;
  double depth_step = 0.0;  // stable only
  dvec2 lprj_min(0.0), lprj_max(0.0), crop_min(0.0), crop_max(0.0);  // crop only
  if (crop) {
    slice_near = -hi.z;
    slice_far = -lo.z;
    // S0 step 4: M_Lprj's window.
    if (options.beam_radius > 0.0f) {
      lprj_min = dvec2(-static_cast<double>(options.beam_radius));
      lprj_max = -lprj_min;
    } else if (!geometry.scene.empty()) {
      const Aabb ls = geometry.scene.transformed(glm::mat4(view));
      lprj_min = dvec2(ls.min);
      lprj_max = dvec2(ls.max);
    } else {
      lprj_min = dvec2(lo);
      lprj_max = dvec2(hi);
    }
    for (int a = 0; a < 2; ++a)
      guard_extent(lprj_min[a], lprj_max[a], scale_eps(lprj_min[a], lprj_max[a]));
    // S0 step 5: x/y of P''_j = M_Lprj P'_j (the window maps affinely, increasing, so the corner
    // min/max map to the P'' min/max).
    const dvec2 scale = 2.0 / (lprj_max - lprj_min);
    crop_min = (dvec2(lo) - lprj_min) * scale - 1.0;
    crop_max = (dvec2(hi) - lprj_min) * scale - 1.0;
    if (options.clip_to_light_bounds) {
      const dvec2 cmin = glm::max(crop_min, dvec2(-1.0));
      const dvec2 cmax = glm::min(crop_max, dvec2(1.0));
      if (cmin.x <= cmax.x && cmin.y <= cmax.y) {
        crop_min = cmin;
        crop_max = cmax;
      } else {
        out.empty = true;  // the slice is outside the beam: unlit, keep the unclipped crop
      }
    }
    for (int a = 0; a < 2; ++a) guard_extent(crop_min[a], crop_max[a], 1e-6);
    const dvec2 rmin = lprj_min + (crop_min + 1.0) / scale;
    const dvec2 rmax = lprj_min + (crop_max + 1.0) / scale;
    rect = {rmin.x, rmax.x, rmin.y, rmax.y};
    out.world_units_per_texel =
        static_cast<float>(std::max(rmax.x - rmin.x, rmax.y - rmin.y) / map_size);
  } else {
    dvec3 center;
    double r;
    sphere_d(slice, center, r);
    const dvec3 c = transform_point(view, center);
    const double u = 2.0 * r / (map_size - 1.0);
    const dvec2 smin = glm::floor((dvec2(c) - r) / u) * u;
    const dvec2 smax = smin + map_size * u;
    rect = {smin.x, smax.x, smin.y, smax.y};
    slice_near = -c.z - r;
    slice_far = -c.z + r;
    depth_step = 0.5 * r;
    out.world_units_per_texel = static_cast<float>(u);
  }

  // 3. Depth range.
  Range geo;
  bool has_geometry = true;
  if (!geometry.casters.empty() || !geometry.receivers.empty()) {
    geo = tighten_d(view, geometry.casters, geometry.receivers, rect, slice_near, slice_far);
  } else if (!geometry.scene.empty()) {
    geo = box_range_in_rect(view, geometry.scene, rect);  // S2 ComputeNearAndFar
    if (!geo.empty() && (geo.far < slice_near || geo.near > slice_far)) geo = Range{};
    if (!geo.empty()) geo.far = std::min(geo.far, slice_far);  // receivers end with the slice
  } else {
    has_geometry = false;
  }
  if (has_geometry && geo.empty()) out.empty = true;
  double near = slice_near, far = slice_far;
  if (has_geometry && !geo.empty()) {
    if (options.depth == DepthFit::tight) {
      near = geo.near;
      far = geo.far;
    } else {
      near = std::min(near, geo.near);  // S0 step 3: casters in front of the slice stay inside
    }
  }
  const double pad = 1e-4 * (far - near) + scale_eps(near, far);
  near -= pad;
  far += pad;
  // Stable: the depth range is snapped outwards to whole steps of r / 2 (its span at most 3r
  // where it would be 2r), as the rectangle is to whole texels. A camera moving through the
  // scene then changes the cascade's matrix by whole texels of translation only, most frames,
  // and the renderer scrolls the layer instead of redrawing it (ShadowMapPass): the depth it
  // kept is the depth it would draw. A 24-bit map over the wider range still resolves microns.
  if (!crop && depth_step > 0.0) {
    near = std::floor(near / depth_step) * depth_step;
    far = std::ceil(far / depth_step) * depth_step;
  }

  // 4. Projection.
  dmat4 proj;
  if (crop) {
    const dmat4 lprj =
        glm::ortho(lprj_min.x, lprj_max.x, lprj_min.y, lprj_max.y, near, far);  // M_Lprj,i
    const dvec2 t = -0.5 * (crop_max + crop_min);
    const dvec2 s = 2.0 / (crop_max - crop_min);
    dmat4 m_crop(1.0);  // S0 step 5: [[Sx,0,0,Sx Tx],[0,Sy,0,Sy Ty],[0,0,1,0],[0,0,0,1]]
    m_crop[0][0] = s.x;
    m_crop[1][1] = s.y;
    m_crop[3][0] = s.x * t.x;
    m_crop[3][1] = s.y * t.y;
    proj = m_crop * lprj;  // M_proj,i = M_crop,i * M_Lprj,i
  } else {
    proj = glm::ortho(rect.min_x, rect.max_x, rect.min_y, rect.max_y, near, far);
  }
  out.view = glm::mat4(view);
  out.proj = glm::mat4(proj);
  out.near = static_cast<float>(near);
  out.far = static_cast<float>(far);
  out.ortho_min = glm::vec2(static_cast<float>(rect.min_x), static_cast<float>(rect.min_y));
  out.ortho_max = glm::vec2(static_cast<float>(rect.max_x), static_cast<float>(rect.max_y));
  return out;
}

// ---- Shading helpers ----

int select_cascade_by_depth(std::span<const float> D, float view_depth) {
  for (size_t i = 0; i + 1 < D.size(); ++i)
    if (D[i] <= view_depth && view_depth < D[i + 1]) return static_cast<int>(i);
  return -1;
}

int select_cascade_by_map(std::span<const glm::mat4> light_view_proj, const glm::vec3& world_pos,
                          float border_ndc) {
  const float lim = 1.0f - border_ndc;
  for (size_t i = 0; i < light_view_proj.size(); ++i) {
    const glm::vec4 clip = light_view_proj[i] * glm::vec4(world_pos, 1.0f);
    const glm::vec3 ndc = glm::vec3(clip) / clip.w;
    if (std::abs(ndc.x) <= lim && std::abs(ndc.y) <= lim && std::abs(ndc.z) <= 1.0f)
      return static_cast<int>(i);
  }
  return -1;
}

float cascade_blend_weight(std::span<const float> D, int cascade, float view_depth,
                           float blend_band) {
  if (cascade < 0 || static_cast<size_t>(cascade) + 2 >= D.size() || !(blend_band > 0.0f))
    return 0.0f;  // the last cascade has nothing to blend into
  const float end = D[cascade + 1];
  const float start = end - std::min(blend_band, 1.0f) * (end - D[cascade]);
  if (!(view_depth > start)) return 0.0f;
  return std::clamp((view_depth - start) / (end - start), 0.0f, 1.0f);
}

float cascade_blend_weight_map(const glm::vec3& ndc, float blend_band, float border_ndc) {
  if (!(blend_band > 0.0f)) return 0.0f;
  const float edge = std::max(std::abs(ndc.x), std::abs(ndc.y));
  const float limit = 1.0f - border_ndc;  // where the cascade stops being selected
  const float start = limit - std::min(blend_band, 1.0f) * limit;
  return std::clamp((edge - start) / (limit - start), 0.0f, 1.0f);
}

glm::mat4 shadow_bias_matrix() {
  glm::mat4 m(0.5f);                         // diagonal 0.5, 0.5, 0.5, 0.5
  m[3] = glm::vec4(0.5f, 0.5f, 0.5f, 1.0f);  // S0: last column (.5, .5, .5, 1)
  return m;
}

// ---- Validation ----

std::string validate_transform(const glm::mat4& m) {
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) {
      const float v = m[c][r];
      if (std::isnan(v))
        return "element [" + std::to_string(c) + "][" + std::to_string(r) + "] is NaN";
      if (std::isinf(v))
        return "element [" + std::to_string(c) + "][" + std::to_string(r) + "] is " +
               (v > 0 ? "+inf" : "-inf");
    }
  return {};
}

std::string validate_camera_slice(const CameraSlice& s) {
  if (std::string e = validate_transform(s.camera_world); !e.empty()) return "camera_world " + e;
  const glm::mat4& m = s.camera_world;
  if (std::abs(m[0][3]) > 1e-5f || std::abs(m[1][3]) > 1e-5f || std::abs(m[2][3]) > 1e-5f ||
      std::abs(m[3][3] - 1.0f) > 1e-5f)
    return "camera_world is not affine (last row must be 0 0 0 1)";
  for (int c = 0; c < 3; ++c) {
    const float len = glm::length(glm::vec3(m[c]));
    if (std::abs(len - 1.0f) > 1e-3f)
      return "camera_world is not rigid: column " + std::to_string(c) + " has length " + num(len);
    for (int o = c + 1; o < 3; ++o)
      if (std::abs(glm::dot(glm::vec3(m[c]), glm::vec3(m[o]))) > 1e-3f)
        return "camera_world is not rigid: columns " + std::to_string(c) + " and " +
               std::to_string(o) + " are not orthogonal";
  }
  if (s.projection == Projection::perspective) {
    if (!(s.fov_y_rad > 0.0f && s.fov_y_rad < 3.14159f))
      return "fov_y_rad must be in (0, pi), was " + num(s.fov_y_rad);
  } else if (s.projection == Projection::orthographic) {
    if (!(s.ortho_height > 0.0f && std::isfinite(s.ortho_height)))
      return "ortho_height must be finite and > 0, was " + num(s.ortho_height);
  } else {
    return "projection must be perspective or orthographic, was " +
           std::to_string(static_cast<int>(s.projection));
  }
  if (!(s.aspect > 0.0f && std::isfinite(s.aspect)))
    return "aspect must be finite and > 0, was " + num(s.aspect);
  if (!(s.near >= 0.0f && std::isfinite(s.near)))
    return "near must be finite and >= 0, was " + num(s.near);
  if (!(s.far > s.near && std::isfinite(s.far)))
    return "far must be finite and > near (" + num(s.near) + "), was " + num(s.far);
  return {};
}

std::string validate_light_frame(const LightFrame& light) {
  if (!finite(light.direction)) return "direction is not finite";
  if (!(glm::length(light.direction) > 0.0f)) return "direction has zero length";
  if (!finite(light.origin)) return "origin is not finite";
  return {};
}

}  // namespace kaskad
