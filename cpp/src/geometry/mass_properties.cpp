#include <mgn/core/error.hpp>
#include <mgn/geometry/mass_properties.hpp>

#include <cmath>

namespace mgn {

namespace {

/// Integrals over a body relative to a reference point: measure (volume or area), first moment
/// and second moment tensor (integral of x x^T).
struct Moments {
  double measure = 0.0;
  Vec3d first = Vec3d::Zero();
  Mat3d second = Mat3d::Zero();
};

/// The moments summed over the triangles (a, b, c) of `mesh`, corners relative to `ref`: each
/// adds its weight w = weight(a, b, c) to the measure, w s / k_first to the first moment and
/// w / k_second (a aᵀ + b bᵀ + c cᵀ + s sᵀ) to the second, with s = a + b + c.
template <typename Weight>
Moments sum_moments(const Mesh& mesh, const Vec3d& ref, double k_first, double k_second,
                    const Weight& weight) {
  Moments m;
  const auto& V = mesh.vertices();
  const auto& F = mesh.faces();
  for (std::int64_t f = 0; f < F.rows(); ++f) {
    const Vec3d a = V.row(F(f, 0)).transpose().cast<double>() - ref;
    const Vec3d b = V.row(F(f, 1)).transpose().cast<double>() - ref;
    const Vec3d c = V.row(F(f, 2)).transpose().cast<double>() - ref;
    const double w = weight(a, b, c);
    const Vec3d s = a + b + c;
    m.measure += w;
    m.first += w * s / k_first;
    m.second += w / k_second *
                (a * a.transpose() + b * b.transpose() + c * c.transpose() + s * s.transpose());
  }
  return m;
}

Moments solid_moments(const Mesh& mesh, const Vec3d& ref) {
  // Divergence theorem over signed tetrahedra (ref, a, b, c). For a tetrahedron with vertices
  // p0..p3: integral of x x^T = V/20 * (sum p_i p_i^T + s s^T), s = sum p_i (Tonon 2004).
  Moments m = sum_moments(mesh, ref, 4.0, 20.0, [](const Vec3d& a, const Vec3d& b, const Vec3d& c) {
    return a.dot(b.cross(c)) / 6.0;
  });
  if (m.measure < 0.0) {  // wound inward: every integral flips sign
    m.measure = -m.measure;
    m.first = -m.first;
    m.second = -m.second;
  }
  return m;
}

Moments shell_moments(const Mesh& mesh, const Vec3d& ref) {
  // Thin lamina per triangle: integral of x x^T dA = A/12 * (sum p_i p_i^T + s s^T).
  return sum_moments(mesh, ref, 3.0, 12.0, [](const Vec3d& a, const Vec3d& b, const Vec3d& c) {
    return 0.5 * (b - a).cross(c - a).norm();
  });
}

}  // namespace

MassProperties compute_mass_properties(const Mesh& mesh, const MassOptions& options) {
  const char* fn = "compute_mass_properties";
  if (!(options.density > 0.0) || !std::isfinite(options.density)) {
    throw_error<InvalidArgument>(fn, ": density must be finite and > 0 kg/m^3, got ",
                                 options.density);
  }
  require_non_empty(mesh, fn);
  const MeshReport report = mesh.validate();
  const bool closed = report.is_watertight && report.is_winding_consistent;
  if (!closed && options.open_mesh == OpenMeshPolicy::Error) {
    throw_error<InvalidArgument>(
        fn, ": mesh '", mesh.name(), "' is not closed (", report.num_boundary_edges, " boundary, ",
        report.num_nonmanifold_edges, " non-manifold, ", report.num_misoriented_edges,
        " misoriented edges); expected a watertight mesh");
  }
  if (!closed && (!(options.shell_thickness > 0.0) || !std::isfinite(options.shell_thickness))) {
    throw_error<InvalidArgument>(fn, ": shell_thickness must be finite and > 0 m, got ",
                                 options.shell_thickness);
  }
  // Integrate about the bounding-box centre to limit cancellation far from the origin.
  const auto b = mesh.bounds();
  const Vec3d ref = 0.5 * (b.row(0) + b.row(1)).transpose();
  Moments m = closed ? solid_moments(mesh, ref) : shell_moments(mesh, ref);
  const double scale = closed ? options.density : options.density * options.shell_thickness;
  if (!(m.measure > 0.0)) {
    throw_error<InvalidArgument>(fn, ": mesh '", mesh.name(),
                                 "' encloses zero volume; expected a solid");
  }
  MassProperties out;
  out.is_exact = closed;
  out.volume = closed ? m.measure : m.measure * options.shell_thickness;
  out.mass = scale * m.measure;
  const Vec3d com_rel = m.first / m.measure;
  out.center_of_mass = ref + com_rel;
  // Inertia about ref, then shifted to the centre of mass (parallel axis theorem).
  const Mat3d C = scale * m.second;
  const Mat3d I_ref = C.trace() * Mat3d::Identity() - C;
  out.inertia = I_ref - out.mass * (com_rel.squaredNorm() * Mat3d::Identity() -
                                    com_rel * com_rel.transpose());
  out.inertia = 0.5 * (out.inertia + out.inertia.transpose());
  return out;
}

}  // namespace mgn
