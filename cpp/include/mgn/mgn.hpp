#pragma once
/// @file mgn.hpp  Convenience header: the whole public C++ API of mgn.

#include <mgn/collision/collision_model.hpp>
#include <mgn/core/build_info.hpp>
#include <mgn/core/error.hpp>
#include <mgn/core/parallel.hpp>
#include <mgn/core/rng.hpp>
#include <mgn/core/types.hpp>
#include <mgn/geometry/convex_decomposition.hpp>
#include <mgn/geometry/mass_properties.hpp>
#include <mgn/geometry/mesh.hpp>
#include <mgn/geometry/mesh_io.hpp>
#include <mgn/geometry/primitives.hpp>
#include <mgn/geometry/sampling.hpp>
#include <mgn/grasp/antipodal.hpp>
#include <mgn/grasp/cup.hpp>
#include <mgn/grasp/gripper.hpp>
#include <mgn/grasp/pj_wrench.hpp>
#include <mgn/grasp/seal_model.hpp>
#include <mgn/grasp/shake_test.hpp>
#include <mgn/grasp/wrench.hpp>
#include <mgn/raytrace/ray_scene.hpp>
#include <mgn/render/camera.hpp>
#include <mgn/render/depth_sensor.hpp>
#include <mgn/render/renderer.hpp>
#include <mgn/scene/drop.hpp>
#include <mgn/version.hpp>
