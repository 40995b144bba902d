// Uses the installed headers and static library: builds a box, casts a ray, checks a collision.
#include <mgn/mgn.hpp>

#include <cmath>
#include <iostream>

int main() {
  const mgn::Mesh box = mgn::make_box(mgn::Vec3d(0.1, 0.1, 0.1));
  mgn::RayScene scene({mgn::RayGeometry{&box, mgn::Pose::Identity(), 1}});
  mgn::Points3f o(1, 3), d(1, 3);
  o << 0.0f, 0.0f, 1.0f;
  d << 0.0f, 0.0f, -1.0f;
  const mgn::RayHits hits = scene.intersect(o, d);
  const mgn::CollisionModel model(box);
  mgn::Pose shifted = mgn::Pose::Identity();
  shifted.translation() << 0.05, 0.0, 0.0;
  const bool touching = mgn::collide(model, mgn::Pose::Identity(), model, shifted);
  if (std::abs(hits.distance[0] - 0.95f) > 1e-5f || hits.instance_ids[0] != 1 || !touching) {
    std::cerr << "consumer FAILED: distance " << hits.distance[0] << "\n";
    return 1;
  }
  std::cout << "consumer ok: mgn " << mgn::version() << "\n";
  return 0;
}
