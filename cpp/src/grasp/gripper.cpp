#include <mgn/core/error.hpp>
#include <mgn/geometry/primitives.hpp>
#include <mgn/grasp/gripper.hpp>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace mgn {

namespace {
void require_positive(const char* field, double value) {
  if (!(value > 0.0) || !std::isfinite(value)) {
    throw_error<InvalidArgument>("ParallelJawGripper.", field,
                                 ": expected a finite value > 0, got ", value);
  }
}

Mesh box_at(const Vec3d& size, const Vec3d& centre) {
  Pose X = Pose::Identity();
  X.translation() = centre;
  return make_box(size).transformed(X);
}
}  // namespace

void ParallelJawGripper::validate() const {
  require_positive("max_opening", max_opening);
  require_positive("flange_to_tip", flange_to_tip);
  require_positive("contact_from_tip", contact_from_tip);
  require_positive("collision_margin", collision_margin);
  require_positive("friction", friction);
  const int num_meshes =
      !palm_mesh.empty() + !finger_left_mesh.empty() + !finger_right_mesh.empty();
  if (num_meshes != 0 && num_meshes != 3) {
    throw_error<InvalidArgument>(
        "ParallelJawGripper: palm_mesh, finger_left_mesh and finger_right_mesh must all be set "
        "(mesh gripper) or all be empty (box gripper); got ",
        num_meshes, " of 3");
  }
  if (num_meshes == 3) {
    if (!(contact_from_tip < flange_to_tip)) {
      throw_error<InvalidArgument>("ParallelJawGripper.contact_from_tip (", contact_from_tip,
                                   " m) must be < flange_to_tip (", flange_to_tip, " m)");
    }
    return;
  }
  for (int i = 0; i < 3; ++i) {
    require_positive("finger_size", finger_size[i]);
    require_positive("palm_size", palm_size[i]);
  }
  if (contact_from_tip >= finger_size.z()) {
    throw_error<InvalidArgument>("ParallelJawGripper.contact_from_tip (", contact_from_tip,
                                 " m) must be < the finger length finger_size.z (", finger_size.z(),
                                 " m)");
  }
  if (finger_size.z() + palm_size.z() > flange_to_tip + 1e-12) {
    throw_error<InvalidArgument>(
        "ParallelJawGripper: finger length + palm height (", finger_size.z() + palm_size.z(),
        " m) must fit between the flange and the fingertip (flange_to_tip = ", flange_to_tip,
        " m)");
  }
}

double ParallelJawGripper::collision_opening(double width) const {
  if (!std::isfinite(width) || width < 0.0) {
    throw_error<InvalidArgument>("collision_opening: width must be finite and >= 0 m, got ", width);
  }
  return std::min(width + collision_margin, max_opening);
}

GripperMeshes gripper_meshes(const ParallelJawGripper& g, double opening) {
  g.validate();
  if (!std::isfinite(opening) || opening < 0.0 || opening > g.max_opening + 1e-12) {
    throw_error<InvalidArgument>("gripper_meshes: opening must be in [0, max_opening = ",
                                 g.max_opening, "] m, got ", opening);
  }
  GripperMeshes out;
  if (g.has_meshes()) {
    out.palm = g.palm_mesh;
    out.finger_left = g.finger_left_mesh.transformed(finger_offset(0, opening));
    out.finger_right = g.finger_right_mesh.transformed(finger_offset(1, opening));
  } else {
    const Vec3d& f = g.finger_size;
    const double finger_z = g.flange_to_tip - 0.5 * f.z();
    const double finger_x = 0.5 * opening + 0.5 * f.x();
    out.finger_left = box_at(f, Vec3d(-finger_x, 0.0, finger_z));
    out.finger_right = box_at(f, Vec3d(finger_x, 0.0, finger_z));
    out.palm =
        box_at(g.palm_size, Vec3d(0.0, 0.0, g.flange_to_tip - f.z() - 0.5 * g.palm_size.z()));
  }
  out.palm.set_name("palm");
  out.finger_left.set_name("finger_left");
  out.finger_right.set_name("finger_right");
  return out;
}

Pose finger_offset(int side, double opening) {
  if (side != 0 && side != 1) {
    throw_error<InvalidArgument>("finger_offset: side must be 0 (left) or 1 (right), got ", side);
  }
  if (!std::isfinite(opening) || opening < 0.0) {
    throw_error<InvalidArgument>("finger_offset: opening must be finite and >= 0 m, got ", opening);
  }
  Pose X = Pose::Identity();
  X.translation().x() = (side == 0 ? -0.5 : 0.5) * opening;
  return X;
}

Mat3d grasp_rotation(const ParallelJawGrasp& grasp) {
  const Vec3d& v = grasp.closing;
  const Vec3d& a = grasp.approach;
  if (!v.allFinite() || !a.allFinite() || std::abs(v.norm() - 1.0) > 1e-6 ||
      std::abs(a.norm() - 1.0) > 1e-6) {
    throw_error<InvalidArgument>(
        "ParallelJawGrasp: closing and approach must be finite unit vectors");
  }
  if (std::abs(v.dot(a)) > 1e-6) {
    throw_error<InvalidArgument>(
        "ParallelJawGrasp: closing and approach must be perpendicular, |v.a| = ",
        std::abs(v.dot(a)));
  }
  Mat3d R;
  R.col(0) = v;
  R.col(1) = a.cross(v);
  R.col(2) = a;
  return R;
}

Pose hand_pose(const ParallelJawGrasp& grasp, const ParallelJawGripper& gripper) {
  if (!grasp.p1.allFinite() || !std::isfinite(grasp.width) || grasp.width < 0.0) {
    throw_error<InvalidArgument>("ParallelJawGrasp: p1 must be finite and width finite and >= 0");
  }
  Pose X = Pose::Identity();
  X.linear() = grasp_rotation(grasp);
  X.translation() =
      grasp.p1 + 0.5 * grasp.width * grasp.closing - gripper.grasp_depth() * grasp.approach;
  return X;
}

}  // namespace mgn
