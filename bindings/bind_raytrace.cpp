#include <pybind11/eigen.h>
#include <pybind11/stl.h>
#include <mgn/raytrace/ray_scene.hpp>

#include "exceptions.hpp"
#include "numpy_conv.hpp"

namespace py = pybind11;
using namespace mgn::py_conv;

namespace mgn::py_bind {

namespace {

CastOptions cast_options(float tnear, float tfar, bool coherent, int num_threads) {
  CastOptions o;
  o.tnear = tnear;
  o.tfar = tfar;
  o.coherent = coherent;
  o.num_threads = num_threads;
  return o;
}

/// RayHits as numpy arrays (moved, no copies).
struct HitArrays {
  py::array distance, points, normals, instance_ids, face_ids, barycentric;
};

/// RayAllHits as numpy arrays (moved, no copies).
struct AllHitArrays {
  py::array offsets, distance, points, normals, instance_ids, face_ids, ray_ids;
};

}  // namespace

void bind_raytrace(py::module_& m) {
  py::class_<HitArrays>(m, "RayHits",
                        "RayScene.intersect() result (mgn/raytrace/ray_scene.hpp), world frame; "
                        "misses have distance inf and ids -1.")
      .def_readonly("distance", &HitArrays::distance, "(N,) float32 m")
      .def_readonly("points", &HitArrays::points, "(N,3) float32")
      .def_readonly("normals", &HitArrays::normals,
                    "(N,3) float32 unit geometric normal, outward for CCW faces")
      .def_readonly("instance_ids", &HitArrays::instance_ids, "(N,) int32")
      .def_readonly("face_ids", &HitArrays::face_ids, "(N,) int32 face index within its mesh")
      .def_readonly("barycentric", &HitArrays::barycentric,
                    "(N,2) float32 (u, v): p = (1-u-v) v0 + u v1 + v v2");
  py::class_<AllHitArrays>(m, "RayAllHits",
                           "RayScene.intersect_all() result: the hits of ray i are entries "
                           "offsets[i] .. offsets[i+1]-1, sorted by distance.")
      .def_readonly("offsets", &AllHitArrays::offsets, "(N+1,) int64")
      .def_readonly("distance", &AllHitArrays::distance, "(H,) float32 m")
      .def_readonly("points", &AllHitArrays::points, "(H,3) float32")
      .def_readonly("normals", &AllHitArrays::normals, "(H,3) float32")
      .def_readonly("instance_ids", &AllHitArrays::instance_ids, "(H,) int32")
      .def_readonly("face_ids", &AllHitArrays::face_ids, "(H,) int32")
      .def_readonly("ray_ids", &AllHitArrays::ray_ids, "(H,) int32 ray of each hit");

  py::class_<RayScene>(m, "RayScene", "Immutable Embree scene of meshes placed in the world frame.")
      .def(py::init([](const std::vector<const Mesh*>& meshes, const py::object& poses,
                       const py::object& instance_ids) {
             std::vector<Pose> X;
             if (!poses.is_none()) {
               X = to_poses(poses, "poses");
               if (X.size() != meshes.size()) {
                 throw_error<InvalidArgument>("RayScene: got ", meshes.size(), " meshes and ",
                                              X.size(), " poses; expected one pose per mesh");
               }
             }
             std::vector<std::int32_t> ids;
             if (!instance_ids.is_none()) {
               ids = instance_ids.cast<std::vector<std::int32_t>>();
               if (ids.size() != meshes.size()) {
                 throw_error<InvalidArgument>("RayScene: got ", meshes.size(), " meshes and ",
                                              ids.size(),
                                              " instance ids; expected one id per mesh");
               }
             }
             std::vector<RayGeometry> geoms(meshes.size());
             for (std::size_t i = 0; i < meshes.size(); ++i) {
               geoms[i].mesh = meshes[i];
               if (!X.empty()) geoms[i].X_WO = X[i];
               geoms[i].instance_id = ids.empty() ? static_cast<std::int32_t>(i) : ids[i];
             }
             py::gil_scoped_release release;
             return std::make_unique<RayScene>(geoms);
           }),
           py::arg("meshes"), py::arg("poses") = py::none(), py::arg("instance_ids") = py::none())
      .def_property_readonly("num_geometries", &RayScene::num_geometries)
      .def_property_readonly("num_triangles", &RayScene::num_triangles)
      .def_property_readonly("bounds",
                             [](const RayScene& s) {
                               Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> b =
                                   s.bounds();
                               return to_numpy(std::move(b));
                             })
      .def(
          "intersect",
          [](const RayScene& s, const py::handle& origins, const py::handle& directions,
             float tnear, float tfar, bool coherent, int num_threads) {
            const Points3f o = to_rows<float, 3>(origins, "origins");
            const Points3f d = to_rows<float, 3>(directions, "directions");
            RayHits h;
            {
              py::gil_scoped_release release;
              h = s.intersect(o, d, cast_options(tnear, tfar, coherent, num_threads));
            }
            return HitArrays{to_numpy(std::move(h.distance)), to_numpy(std::move(h.points)),
                             to_numpy(std::move(h.normals)),  to_numpy(std::move(h.instance_ids)),
                             to_numpy(std::move(h.face_ids)), to_numpy(std::move(h.barycentric))};
          },
          py::arg("origins"), py::arg("directions"), py::arg("tnear") = CastOptions{}.tnear,
          py::arg("tfar") = CastOptions{}.tfar, py::arg("coherent") = CastOptions{}.coherent,
          py::arg("num_threads") = CastOptions{}.num_threads)
      .def(
          "intersect_ids",
          [](const RayScene& s, const py::handle& origins, const py::handle& directions,
             float tnear, float tfar, bool coherent, int num_threads) {
            const Points3f o = to_rows<float, 3>(origins, "origins");
            const Points3f d = to_rows<float, 3>(directions, "directions");
            RayHitIds h;
            {
              py::gil_scoped_release release;
              h = s.intersect_ids(o, d, cast_options(tnear, tfar, coherent, num_threads));
            }
            return py::make_tuple(to_numpy(std::move(h.instance_ids)),
                                  to_numpy(std::move(h.face_ids)));
          },
          py::arg("origins"), py::arg("directions"), py::arg("tnear") = CastOptions{}.tnear,
          py::arg("tfar") = CastOptions{}.tfar, py::arg("coherent") = CastOptions{}.coherent,
          py::arg("num_threads") = CastOptions{}.num_threads)
      .def(
          "occluded",
          [](const RayScene& s, const py::handle& origins, const py::handle& directions,
             float tnear, float tfar, bool coherent, int num_threads) {
            const Points3f o = to_rows<float, 3>(origins, "origins");
            const Points3f d = to_rows<float, 3>(directions, "directions");
            std::vector<std::uint8_t> hit;
            {
              py::gil_scoped_release release;
              hit = s.occluded(o, d, cast_options(tnear, tfar, coherent, num_threads));
            }
            return to_bool_numpy(std::move(hit));
          },
          py::arg("origins"), py::arg("directions"), py::arg("tnear") = CastOptions{}.tnear,
          py::arg("tfar") = CastOptions{}.tfar, py::arg("coherent") = CastOptions{}.coherent,
          py::arg("num_threads") = CastOptions{}.num_threads)
      .def(
          "intersect_all",
          [](const RayScene& s, const py::handle& origins, const py::handle& directions,
             int max_hits, float tnear, float tfar, int num_threads) {
            const Points3f o = to_rows<float, 3>(origins, "origins");
            const Points3f d = to_rows<float, 3>(directions, "directions");
            RayAllHits h;
            {
              py::gil_scoped_release release;
              h = s.intersect_all(o, d, max_hits, cast_options(tnear, tfar, false, num_threads));
            }
            return AllHitArrays{
                to_numpy(std::move(h.offsets)),      to_numpy(std::move(h.distance)),
                to_numpy(std::move(h.points)),       to_numpy(std::move(h.normals)),
                to_numpy(std::move(h.instance_ids)), to_numpy(std::move(h.face_ids)),
                to_numpy(std::move(h.ray_ids))};
          },
          py::arg("origins"), py::arg("directions"), py::arg("max_hits_per_ray") = 64,
          py::arg("tnear") = CastOptions{}.tnear, py::arg("tfar") = CastOptions{}.tfar,
          py::arg("num_threads") = CastOptions{}.num_threads);

  m.def(
      "camera_rays",
      [](const Mat3d& K, int width, int height, const py::handle& X_WC) {
        const Pose X = to_pose(X_WC, "X_WC");
        Points3f o, d;
        camera_rays(K, width, height, X, o, d);
        return py::make_tuple(to_numpy(std::move(o)), to_numpy(std::move(d)));
      },
      py::arg("K"), py::arg("width"), py::arg("height"), py::arg("X_WC"));
}

}  // namespace mgn::py_bind
