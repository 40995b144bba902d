// Bindings of mgn/scene/layout: label images in (numpy, no copy when already of the right dtype
// and C-contiguous), a LayoutArrays of numpy arrays out; GIL released during the work.
#include <mgn/scene/layout.hpp>

#include <string>

#include "exceptions.hpp"
#include "numpy_conv.hpp"

namespace py = pybind11;
using namespace mgn::py_conv;

namespace mgn::py_bind {

namespace {

template <typename T>
CArray<T> as_array(const py::handle& obj, const char* arg, const char* expected) {
  try {
    return py::cast<CArray<T>>(obj);
  } catch (const py::cast_error&) {
    throw_error<InvalidArgument>("compute_layout: ", arg, ": expected ", expected);
  }
}

/// Layout as numpy arrays (moved, no copies); the relations as parallel arrays.
struct LayoutArrays {
  py::array relation, rel_parent, rel_child, rel_depth_diff, rel_edge_size, rel_seen_px;
  py::array visible_px, visible, layer, num_regions, complete, total_covered_edge, order;
  int num_layers = 0;
  double max_occlusion = 0.0;
  bool classes_unique = true;
  int difficulty = 1;
};

}  // namespace

void bind_scene_layout(py::module_& m) {
  py::class_<LayoutArrays>(m, "LayoutArrays",
                           "compute_layout() result (mgn/scene/layout.hpp): 0-based object "
                           "indices; rel_* are the relations sorted by (child, parent).")
      .def_readonly("relation", &LayoutArrays::relation, "(N,N) int8 relation matrix")
      .def_readonly("rel_parent", &LayoutArrays::rel_parent, "(R,) int32 0-based")
      .def_readonly("rel_child", &LayoutArrays::rel_child, "(R,) int32 0-based")
      .def_readonly("rel_depth_diff", &LayoutArrays::rel_depth_diff, "(R,) float64 m")
      .def_readonly("rel_edge_size", &LayoutArrays::rel_edge_size, "(R,) int32 px")
      .def_readonly("rel_seen_px", &LayoutArrays::rel_seen_px, "(R,) int64 px")
      .def_readonly("visible_px", &LayoutArrays::visible_px, "(N,) int64")
      .def_readonly("visible", &LayoutArrays::visible, "(N,) bool")
      .def_readonly("layer", &LayoutArrays::layer, "(N,) int8")
      .def_readonly("num_regions", &LayoutArrays::num_regions, "(N,) int32")
      .def_readonly("complete", &LayoutArrays::complete, "(N,) bool")
      .def_readonly("total_covered_edge", &LayoutArrays::total_covered_edge, "(N,) int64 px")
      .def_readonly("order", &LayoutArrays::order, "picking order, int32 1-based ids")
      .def_readonly("num_layers", &LayoutArrays::num_layers)
      .def_readonly("max_occlusion", &LayoutArrays::max_occlusion)
      .def_readonly("classes_unique", &LayoutArrays::classes_unique)
      .def_readonly("difficulty", &LayoutArrays::difficulty, "1..5");

  const LayoutOptions defaults;
  m.def(
      "compute_layout",
      [](const py::handle& visible_obj, const py::handle& amodal_obj, const py::handle& depth_obj,
         const py::handle& categories_obj, const py::handle& occlusion_obj, int min_overlap_px,
         double min_overlap_fraction, int min_region_px, double min_region_fraction,
         double max_occlusion_level1, int num_threads) {
        const auto visible = as_array<std::int32_t>(visible_obj, "visible", "(H, W) int32 ids");
        const auto amodal = as_array<std::uint8_t>(amodal_obj, "amodal", "(N, H, W) uint8 masks");
        const auto depth = as_array<float>(depth_obj, "depth", "(H, W) float32 depth in m");
        const auto categories =
            as_array<std::int32_t>(categories_obj, "categories", "(N,) int32 category ids");
        const auto occlusion =
            as_array<double>(occlusion_obj, "occlusion", "(N,) float64 occlusion rates");
        if (visible.ndim() != 2)
          throw_error<InvalidArgument>("compute_layout: visible: expected shape (H, W), got ",
                                       shape_of(visible));
        const auto H = visible.shape(0), W = visible.shape(1);
        if (amodal.ndim() != 3 || amodal.shape(1) != H || amodal.shape(2) != W)
          throw_error<InvalidArgument>("compute_layout: amodal: expected shape (N, ", H, ", ", W,
                                       "), got ", shape_of(amodal));
        const auto N = amodal.shape(0);
        if (depth.ndim() != 2 || depth.shape(0) != H || depth.shape(1) != W)
          throw_error<InvalidArgument>("compute_layout: depth: expected shape (", H, ", ", W,
                                       "), got ", shape_of(depth));
        if (categories.ndim() != 1 || categories.shape(0) != N)
          throw_error<InvalidArgument>("compute_layout: categories: expected shape (", N,
                                       ",), got ", shape_of(categories));
        if (occlusion.ndim() != 1 || occlusion.shape(0) != N)
          throw_error<InvalidArgument>("compute_layout: occlusion: expected shape (", N, ",), got ",
                                       shape_of(occlusion));
        LayoutImages im;
        im.height = static_cast<int>(H);
        im.width = static_cast<int>(W);
        im.num_objects = static_cast<int>(N);
        im.visible = visible.data();
        im.amodal = amodal.data();
        im.depth = depth.data();
        im.categories = categories.data();
        im.occlusion = occlusion.data();
        LayoutOptions o;
        o.min_overlap_px = min_overlap_px;
        o.min_overlap_fraction = min_overlap_fraction;
        o.min_region_px = min_region_px;
        o.min_region_fraction = min_region_fraction;
        o.max_occlusion_level1 = max_occlusion_level1;
        o.num_threads = num_threads;
        Layout L;
        {
          py::gil_scoped_release release;
          L = compute_layout(im, o);
        }
        const std::size_t R = L.relations.size();
        std::vector<std::int32_t> parent(R), child(R), edge(R);
        std::vector<double> ddiff(R);
        std::vector<std::int64_t> seen(R);
        for (std::size_t k = 0; k < R; ++k) {
          parent[k] = L.relations[k].parent;
          child[k] = L.relations[k].child;
          edge[k] = L.relations[k].edge_size;
          ddiff[k] = L.relations[k].depth_diff;
          seen[k] = L.relations[k].seen_px;
        }
        LayoutArrays out;
        out.relation = to_numpy(std::move(L.relation)).attr("reshape")(N, N);
        out.rel_parent = to_numpy(std::move(parent));
        out.rel_child = to_numpy(std::move(child));
        out.rel_depth_diff = to_numpy(std::move(ddiff));
        out.rel_edge_size = to_numpy(std::move(edge));
        out.rel_seen_px = to_numpy(std::move(seen));
        out.visible_px = to_numpy(std::move(L.visible_px));
        out.visible = to_bool_numpy(std::move(L.visible));
        out.layer = to_numpy(std::move(L.layer));
        out.num_regions = to_numpy(std::move(L.num_regions));
        out.complete = to_bool_numpy(std::move(L.complete));
        out.total_covered_edge = to_numpy(std::move(L.total_covered_edge));
        out.order = to_numpy(std::move(L.order));
        out.num_layers = L.num_layers;
        out.max_occlusion = L.max_occlusion;
        out.classes_unique = L.classes_unique;
        out.difficulty = L.difficulty;
        return out;
      },
      py::arg("visible"), py::arg("amodal"), py::arg("depth"), py::arg("categories"),
      py::arg("occlusion"), py::arg("min_overlap_px") = defaults.min_overlap_px,
      py::arg("min_overlap_fraction") = defaults.min_overlap_fraction,
      py::arg("min_region_px") = defaults.min_region_px,
      py::arg("min_region_fraction") = defaults.min_region_fraction,
      py::arg("max_occlusion_level1") = defaults.max_occlusion_level1,
      py::arg("num_threads") = defaults.num_threads,
      "Layout labels of one view (see mgn/scene/layout.hpp); use "
      "mgn.view_labels.layout.compute_layout.");
}

}  // namespace mgn::py_bind
