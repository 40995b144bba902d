#include "cmd_seal.hpp"

#include <mgn/mgn.hpp>

#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "cli_util.hpp"
#include "flat_yaml.hpp"

namespace mgn_cli {

const char* kSealUsage =
    "  seal --mesh MESH --points PTS.csv [--cup CUP.yaml] [--model spring|strain|smoothness]\n"
    "       [--out OUT.csv|OUT.json] [--scale S] [--trials T | --nominal] [--seed S] [--threads "
    "T]\n"
    "      Seal scores of suction points (docs/models.md 1-2). PTS.csv rows: x,y,z,nx,ny,nz in\n"
    "      the mesh frame (metres after --scale; outward normals; a header line is allowed).\n"
    "      CUP is a cup YAML as written by mgn.hardware.SuctionCup (default: MetaGraspNet cup).\n"
    "      Prints (or writes) per point: index, score in [0,1] (fraction of T perturbed trials,\n"
    "      default 10; --nominal: one trial exactly at the given pose), failure reason, quality.\n";

namespace {

/// The cup of a YAML file written by mgn.hardware.SuctionCup.to_yaml().
mgn::Cup read_cup(const std::string& path) {
  const FlatYaml y = FlatYaml::load(path);
  y.require_known({"name", "radius", "num_points", "youngs_modulus", "pressure_difference",
                   "compensable_height", "approach_height", "c1", "c2", "outer_radius",
                   "body_height", "hole_rays"});
  mgn::Cup c;
  c.name = y.string_or("name", c.name);
  c.radius = y.number_or("radius", c.radius);
  c.num_points = whole_number(path + ": num_points", y.number_or("num_points", c.num_points));
  c.youngs_modulus = y.number_or("youngs_modulus", c.youngs_modulus);
  c.pressure_difference = y.number_or("pressure_difference", c.pressure_difference);
  c.compensable_height = y.number_or("compensable_height", c.compensable_height);
  c.approach_height = y.number_or("approach_height", c.approach_height);
  c.c1 = y.number_or("c1", c.c1);
  c.c2 = y.number_or("c2", c.c2);
  c.outer_radius = y.number_or("outer_radius", c.outer_radius);
  c.body_height = y.number_or("body_height", c.body_height);
  c.hole_rays = whole_number(path + ": hole_rays", y.number_or("hole_rays", c.hole_rays));
  c.validate();
  return c;
}

/// Points and normals of a CSV file with rows x,y,z,nx,ny,nz (an optional non-numeric header).
void read_points(const std::string& path, double scale, mgn::Points3f& points,
                 mgn::Points3f& normals) {
  std::ifstream in(path);
  if (!in) throw mgn::IoError("mgn-cli seal: cannot read points file '" + path + "'");
  std::vector<std::array<double, 6>> rows;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.find_first_not_of(" \t\r") == std::string::npos || line[0] == '#') continue;
    std::array<double, 6> r{};
    std::stringstream ss(line);
    std::string cell;
    int k = 0;
    bool numeric = true;
    while (std::getline(ss, cell, ',')) {
      if (k >= 6) {
        k = 7;
        break;
      }
      char* end = nullptr;
      r[k] = std::strtod(cell.c_str(), &end);
      while (end && (*end == ' ' || *end == '\t' || *end == '\r')) ++end;
      if (end == cell.c_str() || (end && *end != '\0')) numeric = false;
      ++k;
    }
    if (!numeric && rows.empty() && line_no == 1) continue;  // header line
    if (!numeric || k != 6) {
      mgn::throw_error<mgn::InvalidArgument>("mgn-cli seal: ", path, ":", line_no,
                                             ": expected 6 numbers x,y,z,nx,ny,nz, got '", line,
                                             "'");
    }
    rows.push_back(r);
  }
  if (rows.empty()) throw mgn::InvalidArgument("mgn-cli seal: no points in '" + path + "'");
  points.resize(static_cast<Eigen::Index>(rows.size()), 3);
  normals.resize(static_cast<Eigen::Index>(rows.size()), 3);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    for (int a = 0; a < 3; ++a) {
      points(static_cast<Eigen::Index>(i), a) = static_cast<float>(rows[i][a] * scale);
      normals(static_cast<Eigen::Index>(i), a) = static_cast<float>(rows[i][3 + a]);
    }
  }
}

mgn::SealModelKind model_kind(const std::string& name) {
  if (name == "spring") return mgn::SealModelKind::Spring;
  if (name == "strain") return mgn::SealModelKind::Strain;
  if (name == "smoothness") return mgn::SealModelKind::Smoothness;
  throw mgn::InvalidArgument("mgn-cli seal: --model must be spring, strain or smoothness, got '" +
                             name + "'");
}

}  // namespace

int cmd_seal(const std::vector<std::string>& args) {
  std::string mesh_path, points_path, cup_path, out_path, model = "spring";
  double scale = 1.0;
  int trials = 10, threads = 0;
  long long seed = 0;
  bool nominal = false;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--nominal") {
      nominal = true;
      continue;
    }
    if (i + 1 >= args.size()) throw mgn::InvalidArgument("mgn-cli seal: " + a + " needs a value");
    const std::string& v = args[++i];
    if (a == "--mesh") {
      mesh_path = v;
    } else if (a == "--points") {
      points_path = v;
    } else if (a == "--cup") {
      cup_path = v;
    } else if (a == "--out") {
      out_path = v;
    } else if (a == "--model") {
      model = v;
    } else if (a == "--scale") {
      scale = to_double("mgn-cli seal: " + a, v);
    } else if (a == "--trials") {
      trials = to_int("mgn-cli seal: " + a, v);
    } else if (a == "--seed") {
      seed = to_int("mgn-cli seal: " + a, v);
    } else if (a == "--threads") {
      threads = to_int("mgn-cli seal: " + a, v);
    } else {
      throw mgn::InvalidArgument("mgn-cli seal: unknown option '" + a + "' (see mgn-cli --help)");
    }
  }
  if (mesh_path.empty()) throw mgn::InvalidArgument("mgn-cli seal: missing --mesh MESH");
  if (points_path.empty()) throw mgn::InvalidArgument("mgn-cli seal: missing --points PTS.csv");
  if (!(scale > 0.0)) throw mgn::InvalidArgument("mgn-cli seal: --scale must be > 0");
  if (trials < 1) throw mgn::InvalidArgument("mgn-cli seal: --trials must be >= 1");
  if (seed < 0) throw mgn::InvalidArgument("mgn-cli seal: --seed must be >= 0");
  const bool json = ends_with(out_path, ".json");
  if (!out_path.empty() && !json && !ends_with(out_path, ".csv")) {
    throw mgn::InvalidArgument("mgn-cli seal: --out must end in .csv or .json, got '" + out_path +
                               "'");
  }
  const mgn::SealModelKind kind = model_kind(model);
  const mgn::Cup cup = cup_path.empty() ? mgn::Cup{} : read_cup(cup_path);
  mgn::LoadOptions load;
  load.scale = scale;
  const mgn::Mesh mesh = mgn::load_mesh(mesh_path, load);
  warn_implausible_size("mgn-cli seal", mesh_path, mesh);
  mgn::Points3f points, normals;
  read_points(points_path, scale, points, normals);

  const mgn::SealModel seal(mesh, cup, kind);
  mgn::SealOptions o;
  o.num_trials = nominal ? 1 : trials;
  o.perturb = !nominal;
  o.seed = static_cast<std::uint64_t>(seed);
  o.num_threads = threads;
  const mgn::SealResult r = seal.evaluate(points, normals, o);

  std::ostringstream os;
  os << std::setprecision(6);
  const std::size_t n = r.score.size();
  if (json) {
    os << "{\n  \"mesh\": " << json_string(mesh_path) << ",\n  \"cup\": " << json_string(cup.name)
       << ",\n  \"model\": " << json_string(model) << ",\n  \"trials\": " << o.num_trials
       << ",\n  \"nominal\": " << (nominal ? "true" : "false") << ",\n  \"seed\": " << seed
       << ",\n  \"score\": [";
    for (std::size_t i = 0; i < n; ++i) os << (i ? ", " : "") << r.score[i];
    os << "],\n  \"reason\": [";
    for (std::size_t i = 0; i < n; ++i) {
      os << (i ? ", " : "")
         << json_string(mgn::failure_name(static_cast<mgn::SealFailure>(r.reason[i])));
    }
    os << "],\n  \"quality\": [";
    for (std::size_t i = 0; i < n; ++i) os << (i ? ", " : "") << r.quality[i];
    os << "]\n}\n";
  } else {
    os << "index,score,reason,quality\n";
    for (std::size_t i = 0; i < n; ++i) {
      os << i << ',' << r.score[i] << ','
         << mgn::failure_name(static_cast<mgn::SealFailure>(r.reason[i])) << ',' << r.quality[i]
         << '\n';
    }
  }
  if (out_path.empty()) {
    std::cout << os.str();
  } else {
    write_atomically(out_path, os.str(), "mgn-cli seal");
    std::size_t sealed = 0;
    for (float s : r.score) sealed += s >= 0.5f;
    std::cout << "mgn-cli seal: " << n << " points, " << sealed << " with score >= 0.5 -> "
              << out_path << "\n";
  }
  return 0;
}

}  // namespace mgn_cli
