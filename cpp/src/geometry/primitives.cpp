#include <mgn/core/error.hpp>
#include <mgn/geometry/primitives.hpp>

#include <cmath>

namespace mgn {

namespace {
void require_positive(const char* fn, const char* what, double v) {
  if (!(v > 0.0) || !std::isfinite(v))
    throw_error<InvalidArgument>(fn, ": ", what, " must be finite and > 0, got ", v);
}
}  // namespace

Mesh make_box(const Vec3d& extents) {
  for (int k = 0; k < 3; ++k) require_positive("make_box", "extents", extents[k]);
  const Vec3d h = 0.5 * extents;
  Points3f v(8, 3);
  for (int i = 0; i < 8; ++i) {
    v.row(i) << static_cast<float>((i & 1) ? h.x() : -h.x()),
        static_cast<float>((i & 2) ? h.y() : -h.y()), static_cast<float>((i & 4) ? h.z() : -h.z());
  }
  Faces f(12, 3);
  f << 0, 2, 1, 1, 2, 3,  // -z
      4, 5, 6, 5, 7, 6,   // +z
      0, 1, 4, 1, 5, 4,   // -y
      2, 6, 3, 3, 6, 7,   // +y
      0, 4, 2, 2, 4, 6,   // -x
      1, 3, 5, 3, 7, 5;   // +x
  return Mesh(std::move(v), std::move(f), {}, {}, {}, "box");
}

Mesh make_sphere(double radius, int segments, int rings) {
  require_positive("make_sphere", "radius", radius);
  if (segments < 3 || rings < 2) {
    throw_error<InvalidArgument>("make_sphere: expected segments >= 3 and rings >= 2, got ",
                                 segments, " and ", rings);
  }
  // Poles are single vertices; ring r (1..rings-1) at polar angle pi*r/rings.
  const int n_ring_vertices = (rings - 1) * segments;
  Points3f v(n_ring_vertices + 2, 3);
  for (int r = 1; r < rings; ++r) {
    const double theta = M_PI * r / rings;
    for (int s = 0; s < segments; ++s) {
      const double phi = 2.0 * M_PI * s / segments;
      v.row((r - 1) * segments + s) << static_cast<float>(radius * std::sin(theta) * std::cos(phi)),
          static_cast<float>(radius * std::sin(theta) * std::sin(phi)),
          static_cast<float>(radius * std::cos(theta));
    }
  }
  const int north = n_ring_vertices, south = n_ring_vertices + 1;
  v.row(north) << 0.0f, 0.0f, static_cast<float>(radius);
  v.row(south) << 0.0f, 0.0f, static_cast<float>(-radius);
  Faces f(2 * segments * (rings - 1), 3);
  int k = 0;
  auto idx = [&](int r, int s) { return (r - 1) * segments + (s % segments); };
  for (int s = 0; s < segments; ++s) f.row(k++) << north, idx(1, s), idx(1, s + 1);
  for (int r = 1; r < rings - 1; ++r) {
    for (int s = 0; s < segments; ++s) {
      f.row(k++) << idx(r, s), idx(r + 1, s), idx(r + 1, s + 1);
      f.row(k++) << idx(r, s), idx(r + 1, s + 1), idx(r, s + 1);
    }
  }
  for (int s = 0; s < segments; ++s) f.row(k++) << south, idx(rings - 1, s + 1), idx(rings - 1, s);
  return Mesh(std::move(v), std::move(f), {}, {}, {}, "sphere");
}

Mesh make_cylinder(double radius, double height, int segments) {
  require_positive("make_cylinder", "radius", radius);
  require_positive("make_cylinder", "height", height);
  if (segments < 3)
    throw_error<InvalidArgument>("make_cylinder: expected segments >= 3, got ", segments);
  Points3f v(2 * segments + 2, 3);
  const float hz = static_cast<float>(0.5 * height);
  for (int s = 0; s < segments; ++s) {
    const double phi = 2.0 * M_PI * s / segments;
    const float x = static_cast<float>(radius * std::cos(phi)),
                y = static_cast<float>(radius * std::sin(phi));
    v.row(s) << x, y, -hz;
    v.row(segments + s) << x, y, hz;
  }
  const int bottom = 2 * segments, top = 2 * segments + 1;
  v.row(bottom) << 0.0f, 0.0f, -hz;
  v.row(top) << 0.0f, 0.0f, hz;
  Faces f(4 * segments, 3);
  int k = 0;
  for (int s = 0; s < segments; ++s) {
    const int s1 = (s + 1) % segments;
    f.row(k++) << s, s1, segments + s1;
    f.row(k++) << s, segments + s1, segments + s;
    f.row(k++) << bottom, s1, s;
    f.row(k++) << top, segments + s, segments + s1;
  }
  return Mesh(std::move(v), std::move(f), {}, {}, {}, "cylinder");
}

}  // namespace mgn
