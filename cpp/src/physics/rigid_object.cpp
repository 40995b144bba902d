#include <mgn/core/error.hpp>
#include <mgn/physics/rigid_object.hpp>

#include <LinearMath/btConvexHullComputer.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace mgn {

PrincipalFrame principal_frame(const RigidObject& o, const std::string& context) {
  const Mat3d I = 0.5 * (o.inertia + o.inertia.transpose());
  if (!o.inertia.allFinite() ||
      (o.inertia - o.inertia.transpose()).norm() > 1e-6 * o.inertia.norm())
    throw_error<InvalidArgument>(context, ": inertia must be a finite symmetric 3x3 matrix");
  Eigen::SelfAdjointEigenSolver<Mat3d> es(I);
  PrincipalFrame p;
  p.moments = es.eigenvalues();
  if (!(p.moments.minCoeff() > 0))
    throw_error<InvalidArgument>(context, ": inertia must be positive definite, got eigenvalues ",
                                 p.moments.transpose());
  Mat3d R = es.eigenvectors();
  if (R.determinant() < 0) R.col(2) *= -1.0;
  p.X_OB.linear() = R;
  p.X_OB.translation() = o.com;
  return p;
}

std::vector<Vec3d> spread_support_points(const std::vector<Vec3d>& points, int n) {
  constexpr double kPi = 3.14159265358979323846;
  std::vector<Vec3d> out;
  std::vector<char> used(points.size(), 0);
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / n;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    const Vec3d d(r * std::cos(golden * i), r * std::sin(golden * i), z);
    std::size_t best = 0;
    for (std::size_t k = 1; k < points.size(); ++k) {
      if (points[k].dot(d) > points[best].dot(d)) best = k;
    }
    if (!used[best]) {
      used[best] = 1;
      out.push_back(points[best]);
    }
  }
  return out;
}

namespace {

/// Face planes n.x <= d (n unit, outward) and vertices of the convex hull of a point set.
struct Planes {
  std::vector<Vec3d> normals;
  std::vector<double> offsets;
  std::vector<Vec3d> vertices;
  std::vector<std::vector<int>> face_points;  ///< per plane: indices of the input points on it
};

Planes hull_planes(const std::vector<Vec3d>& points) {
  std::vector<double> coords;
  coords.reserve(3 * points.size());
  for (const Vec3d& p : points) coords.insert(coords.end(), {p.x(), p.y(), p.z()});
  btConvexHullComputer hc;
  hc.compute(coords.data(), static_cast<int>(3 * sizeof(double)), static_cast<int>(points.size()),
             0.0, 0.0);
  Planes out;
  for (int k = 0; k < hc.vertices.size(); ++k)
    out.vertices.emplace_back(hc.vertices[k].x(), hc.vertices[k].y(), hc.vertices[k].z());
  for (int f = 0; f < hc.faces.size(); ++f) {
    // Newell normal of the face polygon (outward: counter-clockwise seen from outside).
    const btConvexHullComputer::Edge* first = &hc.edges[hc.faces[f]];
    const btConvexHullComputer::Edge* e = first;
    Vec3d n = Vec3d::Zero(), centre = Vec3d::Zero();
    int count = 0;
    do {
      const Vec3d u = out.vertices[static_cast<std::size_t>(e->getSourceVertex())];
      const Vec3d v = out.vertices[static_cast<std::size_t>(e->getTargetVertex())];
      n += Vec3d((u.y() - v.y()) * (u.z() + v.z()), (u.z() - v.z()) * (u.x() + v.x()),
                 (u.x() - v.x()) * (u.y() + v.y()));
      centre += u;
      ++count;
      e = e->getNextEdgeOfFace();
    } while (e != first && count < 100000);
    const double len = n.norm();
    if (!(len > 0)) continue;
    n /= len;
    out.normals.push_back(n);
    out.offsets.push_back(n.dot(centre / count));
    std::vector<int> on;
    e = first;
    int guard = 0;
    do {
      on.push_back(hc.original_vertex_index[e->getSourceVertex()]);
      e = e->getNextEdgeOfFace();
    } while (e != first && ++guard < 100000);
    out.face_points.push_back(std::move(on));
  }
  // Every hull vertex on the inner side of every plane (float rounding of the hull computer).
  for (std::size_t f = 0; f < out.normals.size(); ++f)
    for (const Vec3d& v : out.vertices)
      out.offsets[f] = std::max(out.offsets[f], out.normals[f].dot(v));
  return out;
}

/// Vertices of the intersection of the planes `chosen` (of `all`), through the dual hull about
/// the interior point c; empty if the intersection is unbounded (or degenerate).
std::vector<Vec3d> polytope_vertices(const Planes& all, const std::vector<std::size_t>& chosen,
                                     const Vec3d& c) {
  std::vector<Vec3d> dual;
  for (std::size_t f : chosen) {
    const double h = all.offsets[f] - all.normals[f].dot(c);  // > 0: c is interior
    dual.push_back(all.normals[f] / h);
  }
  if (dual.size() < 4) return {};
  const Planes d = hull_planes(dual);
  std::vector<Vec3d> out;
  const double scale = [&] {
    double s = 0;
    for (const Vec3d& q : dual) s = std::max(s, q.norm());
    return s;
  }();
  for (std::size_t k = 0; k < d.normals.size(); ++k) {
    // A dual face m.q = e is the primal vertex x with (x - c).q = 1, i.e. x = c + m / e; the
    // origin (c) must lie strictly inside the dual hull, else the intersection is unbounded.
    if (!(d.offsets[k] > 1e-9 * scale)) return {};
    // The vertex is where the planes of the dual face's points meet: solved in double precision
    // (least squares over them; exact for three) rather than from the single-precision dual hull.
    Mat3d A = Mat3d::Zero();
    Vec3d b = Vec3d::Zero();
    for (int q : d.face_points[k]) {
      const std::size_t f = chosen[static_cast<std::size_t>(q)];
      A += all.normals[f] * all.normals[f].transpose();
      b += all.normals[f] * all.offsets[f];
    }
    const Vec3d guess = c + d.normals[k] / d.offsets[k];
    const Vec3d x = A.ldlt().solve(b);
    out.push_back(
        x.allFinite() && (x - guess).norm() < 1e-3 * (1.0 / scale + guess.norm()) ? x : guess);
  }
  return out;
}

}  // namespace

std::vector<Vec3d> outer_hull_vertices(const std::vector<Vec3d>& points, int max_vertices,
                                       double tolerance, double* max_excess) {
  constexpr const char* fn = "outer_hull_vertices";
  if (max_vertices < 8)
    throw_error<InvalidArgument>(fn, ": max_vertices must be >= 8, got ", max_vertices);
  if (!(std::isfinite(tolerance) && tolerance >= 0))
    throw_error<InvalidArgument>(fn, ": tolerance must be finite and >= 0 m, got ", tolerance);
  if (points.size() < 4)
    throw_error<InvalidArgument>(fn, ": expected at least 4 points, got ", points.size());
  for (const Vec3d& p : points)
    if (!p.allFinite()) throw_error<InvalidArgument>(fn, ": points must be finite");
  if (max_excess) *max_excess = 0.0;
  const Planes hull = hull_planes(points);
  if (hull.normals.size() < 4)
    throw_error<InvalidArgument>(fn, ": the points span no volume (expected a solid)");
  if (hull.vertices.size() <= static_cast<std::size_t>(max_vertices)) return hull.vertices;
  Vec3d c = Vec3d::Zero();
  for (const Vec3d& v : hull.vertices) c += v;
  c /= double(hull.vertices.size());

  auto excess = [&](const Vec3d& x, std::size_t* arg) {
    double best = -1e300;
    for (std::size_t f = 0; f < hull.normals.size(); ++f) {
      const double e = hull.normals[f].dot(x) - hull.offsets[f];
      if (e > best) best = e, *arg = f;
    }
    return best;
  };
  // Start: the face that reaches farthest along each of 14 directions (axes and diagonals).
  std::vector<std::size_t> chosen;
  std::vector<char> in(hull.normals.size(), 0);
  auto add = [&](std::size_t f) {
    if (!in[f]) in[f] = 1, chosen.push_back(f);
  };
  for (int sx = -1; sx <= 1; ++sx)
    for (int sy = -1; sy <= 1; ++sy)
      for (int sz = -1; sz <= 1; ++sz) {
        const int nz = (sx != 0) + (sy != 0) + (sz != 0);
        if (nz != 1 && nz != 3) continue;
        const Vec3d dir = Vec3d(sx, sy, sz).normalized();
        std::size_t best = 0;
        for (std::size_t f = 1; f < hull.normals.size(); ++f)
          if (hull.normals[f].dot(dir) > hull.normals[best].dot(dir)) best = f;
        add(best);
      }
  std::vector<Vec3d> vertices = polytope_vertices(hull, chosen, c);
  // Unbounded start (a very flat or thin hull): add the faces along the open directions.
  for (std::size_t f = 0; vertices.empty() && f < hull.normals.size(); ++f) {
    add(f);
    if (chosen.size() >= 4) vertices = polytope_vertices(hull, chosen, c);
  }
  if (vertices.empty() || vertices.size() > static_cast<std::size_t>(max_vertices))
    return hull.vertices;  // the budget cannot bound it: the exact hull
  double worst = 0.0;
  while (true) {
    std::size_t arg_vertex = 0, arg_face = 0;
    worst = -1e300;
    for (std::size_t k = 0; k < vertices.size(); ++k) {
      std::size_t f = 0;
      const double e = excess(vertices[k], &f);
      if (e > worst) worst = e, arg_vertex = k, arg_face = f;
    }
    (void)arg_vertex;
    if (worst <= tolerance || in[arg_face]) break;
    std::vector<std::size_t> next = chosen;
    next.push_back(arg_face);
    std::vector<Vec3d> more = polytope_vertices(hull, next, c);
    if (more.empty() || more.size() > static_cast<std::size_t>(max_vertices)) break;
    in[arg_face] = 1;
    chosen = std::move(next);
    vertices = std::move(more);
  }
  // Vertices where more than three planes nearly meet are only least-squares exact: move every
  // vertex out from c by 1e-4 of its distance (micrometres) so their hull surely contains the
  // points.
  worst = 0.0;
  for (Vec3d& v : vertices) {
    v = c + (1.0 + 1e-4) * (v - c);
    std::size_t f = 0;
    worst = std::max(worst, excess(v, &f));
  }
  if (max_excess) *max_excess = worst;
  return vertices;
}

}  // namespace mgn
