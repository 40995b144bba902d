#include "cmd_pj.hpp"

#include <mgn/mgn.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "cli_util.hpp"
#include "flat_yaml.hpp"

namespace mgn_cli {

const char* kPjUsage =
    "  pj --mesh MESH --out LABELS.json [--gripper G.yaml] [--points N] [--seed S]\n"
    "     [--density D] [--scale S] [--threads T]\n"
    "      Parallel-jaw labels of a watertight mesh (docs/models.md 5): N contact points (default\n"
    "      5000) sampled evenly, antipodal robust sampler, collision check, soft-finger wrench\n"
    "      score (density D kg/m^3, default 1000, gravity -z). S scales the mesh coordinates\n"
    "      (default 1; 0.001 for a file in millimetres). G is a gripper YAML as written by\n"
    "      mgn.hardware.ParallelJawGripper (default: the MetaGraspNet hand). Output JSON in SI\n"
    "      units (m): rows [a (3), v (3), p1 (3), w] with quality_score and score_wrench.\n";

namespace {

std::string dir_of(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? std::string(".") : path.substr(0, slash);
}

mgn::Vec3d vec3(const FlatYaml& y, const std::string& key, const mgn::Vec3d& fallback) {
  if (!y.has(key)) return fallback;
  const std::vector<double> v = y.numbers(key);
  if (v.size() != 3) {
    throw mgn::InvalidArgument("gripper YAML: key '" + key + "': expected 3 numbers, got " +
                               std::to_string(v.size()));
  }
  return mgn::Vec3d(v[0], v[1], v[2]);
}

/// The gripper of a YAML file written by mgn.hardware.ParallelJawGripper.to_yaml().
mgn::ParallelJawGripper read_gripper(const std::string& path) {
  const FlatYaml y = FlatYaml::load(path);
  y.require_known({"name", "max_opening", "flange_to_tip", "contact_from_tip", "collision_margin",
                   "finger_size", "palm_size", "friction", "palm_mesh", "finger_left_mesh",
                   "finger_right_mesh", "mesh_scale"});
  mgn::ParallelJawGripper g;
  g.name = y.string_or("name", g.name);
  g.max_opening = y.number_or("max_opening", g.max_opening);
  g.flange_to_tip = y.number_or("flange_to_tip", g.flange_to_tip);
  g.contact_from_tip = y.number_or("contact_from_tip", g.contact_from_tip);
  g.collision_margin = y.number_or("collision_margin", g.collision_margin);
  g.friction = y.number_or("friction", g.friction);
  g.finger_size = vec3(y, "finger_size", g.finger_size);
  g.palm_size = vec3(y, "palm_size", g.palm_size);
  mgn::LoadOptions load;
  load.scale = y.number_or("mesh_scale", 1.0);
  auto mesh = [&](const std::string& key) {
    if (!y.has(key) || y.is_null(key)) return mgn::Mesh();
    std::string p = y.string(key);
    if (!p.empty() && p[0] != '/') p = dir_of(path) + "/" + p;  // relative to the YAML file
    return mgn::load_mesh(p, load);
  };
  g.palm_mesh = mesh("palm_mesh");
  g.finger_left_mesh = mesh("finger_left_mesh");
  g.finger_right_mesh = mesh("finger_right_mesh");
  g.validate();
  return g;
}

}  // namespace

int cmd_pj(const std::vector<std::string>& args) {
  std::string mesh_path, gripper_path, out_path;
  int points = 5000, threads = 0;
  long long seed = 0;
  double density = 1000.0;
  double scale = 1.0;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (i + 1 >= args.size()) throw mgn::InvalidArgument("mgn-cli pj: " + a + " needs a value");
    const std::string& v = args[++i];
    if (a == "--mesh") {
      mesh_path = v;
    } else if (a == "--gripper") {
      gripper_path = v;
    } else if (a == "--out") {
      out_path = v;
    } else if (a == "--points") {
      points = to_int("mgn-cli pj: " + a, v);
    } else if (a == "--seed") {
      seed = to_int("mgn-cli pj: " + a, v);
    } else if (a == "--threads") {
      threads = to_int("mgn-cli pj: " + a, v);
    } else if (a == "--density") {
      density = to_double("mgn-cli pj: " + a, v);
    } else if (a == "--scale") {
      scale = to_double("mgn-cli pj: " + a, v);
    } else {
      throw mgn::InvalidArgument("mgn-cli pj: unknown option '" + a + "'");
    }
  }
  if (mesh_path.empty()) throw mgn::InvalidArgument("mgn-cli pj: missing --mesh MESH");
  if (out_path.empty()) throw mgn::InvalidArgument("mgn-cli pj: missing --out LABELS.json");
  if (ends_with(out_path, ".h5") || ends_with(out_path, ".hdf5")) {
    throw mgn::Unsupported("mgn-cli pj: HDF5 output is not built into mgn-cli; use --out " +
                           out_path.substr(0, out_path.find_last_of('.')) +
                           ".json (or `mgn pj label` from Python for textured.obj.hdf5)");
  }
  if (!ends_with(out_path, ".json")) {
    throw mgn::InvalidArgument("mgn-cli pj: --out must end in .json, got '" + out_path + "'");
  }
  if (points < 1) throw mgn::InvalidArgument("mgn-cli pj: --points must be >= 1");
  if (seed < 0) throw mgn::InvalidArgument("mgn-cli pj: --seed must be >= 0");
  if (!(scale > 0.0) || !std::isfinite(scale)) {
    throw mgn::InvalidArgument("mgn-cli pj: --scale must be a finite number > 0");
  }

  const mgn::ParallelJawGripper gripper =
      gripper_path.empty() ? mgn::ParallelJawGripper{} : read_gripper(gripper_path);
  mgn::LoadOptions load;
  load.scale = scale;
  mgn::Mesh mesh = mgn::load_mesh(mesh_path, load);
  warn_implausible_size("mgn-cli pj", mesh_path, mesh);
  // A closed mesh wound inward (e.g. a mirrored export) would give inward surface normals and no
  // grasp at all: use the same geometry wound outward (as mgn's user-object path does).
  const mgn::MeshReport report = mesh.validate();
  if (report.is_watertight && report.is_winding_consistent && report.signed_volume < 0)
    mesh = mesh.flipped();
  mgn::MassOptions mass_options;
  mass_options.density = density;
  mass_options.open_mesh = mgn::OpenMeshPolicy::Error;
  const mgn::AntipodalSampler sampler(mesh, gripper);
  const mgn::MassProperties props = mgn::compute_mass_properties(mesh, mass_options);
  mgn::SampleOptions sample_options;
  sample_options.method = mgn::SampleMethod::Even;
  sample_options.seed = static_cast<std::uint64_t>(seed);
  const mgn::SurfaceSamples s = mgn::sample_surface(mesh, points, sample_options);
  mgn::AntipodalOptions o;
  o.seed = static_cast<std::uint64_t>(seed);
  o.num_threads = threads;
  const mgn::AntipodalResult r =
      sampler.sample(s.points.cast<double>(), s.normals.cast<double>(), o);
  std::vector<mgn::ParallelJawGrasp> grasps;
  grasps.reserve(r.grasps.size());
  for (const auto& g : r.grasps) grasps.push_back(g.grasp);
  const std::vector<float> wrench =
      mgn::pj_wrench_scores(grasps, props.mass, props.center_of_mass, mgn::Vec3d(0, 0, -1));

  std::ostringstream js;
  js << std::setprecision(8);
  js << "{\n  \"mesh\": " << json_string(mesh_path)
     << ",\n  \"gripper\": " << json_string(gripper.name)
     << ",\n  \"units\": \"m\",\n  \"columns\": [\"ax\", \"ay\", \"az\", \"vx\", \"vy\", \"vz\", "
        "\"p1x\", \"p1y\", \"p1z\", \"w\"],\n"
     << "  \"seed\": " << seed << ",\n  \"num_points\": " << points
     << ",\n  \"mass\": " << props.mass << ",\n  \"num_accepted_probes\": " << r.num_accepted_probes
     << ",\n  \"num_colliding\": " << r.num_colliding << ",\n  \"pregrasp_transform\": [";
  for (std::size_t i = 0; i < grasps.size(); ++i) {
    const auto& g = grasps[i];
    js << (i ? ",\n    [" : "\n    [") << g.approach.x() << ", " << g.approach.y() << ", "
       << g.approach.z() << ", " << g.closing.x() << ", " << g.closing.y() << ", " << g.closing.z()
       << ", " << g.p1.x() << ", " << g.p1.y() << ", " << g.p1.z() << ", " << g.width << "]";
  }
  js << "\n  ],\n  \"quality_score\": [";
  for (std::size_t i = 0; i < grasps.size(); ++i) js << (i ? ", " : "") << r.grasps[i].score;
  js << "],\n  \"score_wrench\": [";
  for (std::size_t i = 0; i < grasps.size(); ++i) js << (i ? ", " : "") << wrench[i];
  js << "]\n}\n";

  write_atomically(out_path, js.str(), "mgn-cli pj");
  std::size_t good = 0;
  for (float sc : r.point_score) good += sc >= 1.0f;
  std::cout << "{\"out\": " << json_string(out_path) << ", \"num_grasps\": " << grasps.size()
            << ", \"num_points\": " << points << ", \"points_score_1\": " << good << "}\n";
  return 0;
}

}  // namespace mgn_cli
