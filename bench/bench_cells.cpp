// What `make bench` reports in its quadrature section ("cells"): the distance integrated over cells
// against the paper's collocation (docs/formulation.md §2.8; ε = 1e-3, α = β = 4, γ = 2).
//
//   bench_cells [--quick] [--threads T] [--repeats R (default 1)] [--section cube|plate|loop]
//               --csv FILE
//
// One CSV row per measurement (section, case, pair, quadrature, rho, reference, seconds,
// points):
//   cube   the unit cube of n_X³ hexahedra against a second cube of n_Y³: itself, translated by
//          0.0025 … 0.02 and by one spacing 1/16, and the concentric cube of side 0.875 (the
//          ranking), each with its continuum value (formulation §2.8, by an independent
//          high-order quadrature); quadratures: cells, and collocation (exact sums) at the grids'
//          nodes with lumped volumes and at their cell centres;
//   plate  the paper's plate 10 × 2 × 0.1 of hexahedra against itself at two resolutions and
//          mixed (continuum 0.149702598);
//   loop   the bending scene (data/scenes/bending.json) at the bent control m = −2.6e4 X₃/0.1
//          against its arc target's cells at the scene's resolution and at the body's: seconds
//          of the distance in one objective evaluation, value alone and value with gradient, with
//          each quadrature (the tree at the loop's τ = 1e-2), interleaved, the median of R.
// --quick: the cube at 4 × 4 against itself and the smaller cube, nothing else (a smoke run).
// --section: that section alone (default: all three).
// The loop's body: 4 000 hexahedra (Q2 50 × 5 × 2 split in 8); the arc target: 32 000 (the
// scene's) or 4 000.

#include <Eigen/Core>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hausdorff/cell_distance.hpp"
#include "softhd/control/scene.hpp"
#include "softhd/control/scene_target.hpp"
#include "softhd/control/shape_objective.hpp"
#include "softhd/error.hpp"
#include "softhd/hausdorff.hpp"

using namespace softhd;
using detail::HexCells;

namespace {

class Timer {
 public:
  void reset() { t0_ = std::chrono::steady_clock::now(); }
  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
  }

 private:
  std::chrono::steady_clock::time_point t0_ = std::chrono::steady_clock::now();
};

struct Settings {
  bool quick = false;
  int threads = 0, repeats = 1;
  std::string csv, section;  // section: empty for all
};

class Csv {
 public:
  explicit Csv(const std::string& path) : f_(path) {
    if (!f_) throw FileError("bench_cells: cannot write " + path);
    f_ << "section,case,pair,quadrature,rho,reference,seconds,points\n";
  }
  void row(const std::string& section, const std::string& name, const std::string& pair,
           const std::string& quadrature, double rho, double reference, double seconds,
           long points) {
    char line[512];
    std::snprintf(line, sizeof line, "%s,%s,%s,%s,%.12g,%.12g,%.6g,%ld\n", section.c_str(),
                  name.c_str(), pair.c_str(), quadrature.c_str(), rho, reference, seconds, points);
    f_ << line << std::flush;
    std::printf("%-6s %-16s %-20s %-14s %.9f  ref %.9f  %+9.4f %%  %8.3f s\n", section.c_str(),
                name.c_str(), pair.c_str(), quadrature.c_str(), rho, reference,
                reference > 0 ? 100.0 * (rho / reference - 1.0) : 0.0, seconds);
    std::fflush(stdout);
  }

 private:
  std::ofstream f_;
};

// The nodes of a hexahedral body of boxes with lumped volumes (an eighth of each cell's), or
// its cell centres with the cells' volumes.
PointCloud collocation_cloud(const HexCells& b, bool nodes) {
  const Eigen::Index n = nodes ? b.nodes.rows() : b.cells.rows();
  Eigen::MatrixXd p = Eigen::MatrixXd::Zero(n, 3);
  Eigen::VectorXd v = Eigen::VectorXd::Zero(n);
  for (Eigen::Index c = 0; c < b.cells.rows(); ++c) {
    const Eigen::RowVector3d d = b.nodes.row(b.cells(c, 6)) - b.nodes.row(b.cells(c, 0));
    if (!nodes) {
      p.row(c) = b.nodes.row(b.cells(c, 0)) + 0.5 * d;
      v[c] = d.prod();
      continue;
    }
    for (int i = 0; i < 8; ++i) v[b.cells(c, i)] += d.prod() / 8.0;
  }
  if (nodes) p = b.nodes;
  return PointCloud(p, v);
}

// The box `lower` + [0, size] meshed by n[0] · n[1] · n[2] hexahedra.
HexCells box_cells(const Eigen::Vector3d& lower, const Eigen::Vector3d& size, const int n[3]) {
  return detail::hex_box(lower, size, Eigen::Vector3i(n[0], n[1], n[2]));
}

// One pair of bodies: the cell ρ̃ and both collocations.
void compare(Csv& csv, const Settings& s, const std::string& section, const std::string& name,
             const std::string& pair, const HexCells& x, const HexCells& y, double reference,
             double tolerance) {
  detail::CellDistanceOptions co;
  co.threads = s.threads;
  co.tolerance = tolerance;
  if (tolerance > 0) co.j_near_ratio = 2.0, co.j_angle_points = 8;  // as the objective's loop
  Timer t;
  const detail::CellRho r = detail::cell_rho(x, y, co);
  csv.row(section, name, pair, "cells", r.rho, reference, t.seconds(),
          r.a.near_points + r.b.near_points);
  HausdorffOptions h;
  h.threads = s.threads;
  h.method = tolerance > 0 ? Method::tree : Method::exact;
  h.tolerance = tolerance > 0 ? tolerance : h.tolerance;
  for (bool nodes : {true, false}) {
    const PointCloud cx = collocation_cloud(x, nodes), cy = collocation_cloud(y, nodes);
    t.reset();
    const double rho = hausdorff(cx, cy, h).rho;
    csv.row(section, name, pair, nodes ? "nodes" : "centres", rho, reference, t.seconds(),
            cx.size() + cy.size());
  }
}

void cube_section(Csv& csv, const Settings& s) {
  struct Case {
    const char* name;
    Eigen::Vector3d lower;
    double side, reference;  // the continuum value (formulation §2.8)
    bool all_pairs;          // every pair, else 8 × 8 and 12 × 16 only
  };
  const Case cases[] = {{"self", {0, 0, 0}, 1.0, 0.124155377, true},
                        {"shift 0.0025", {0.0025, 0, 0}, 1.0, 0.124321471, false},
                        {"shift 0.005", {0.005, 0, 0}, 1.0, 0.124778817, false},
                        {"shift 0.01", {0.01, 0, 0}, 1.0, 0.126529335, false},
                        {"shift 0.02", {0.02, 0, 0}, 1.0, 0.133060278, false},
                        {"shift 1/16", {0.0625, 0, 0}, 1.0, 0.181797402, true},
                        {"side 0.875", {0.0625, 0.0625, 0.0625}, 0.875, 0.201406692, true}};
  std::vector<std::pair<int, int>> pairs = {{4, 4}, {6, 8}, {8, 8}, {12, 16}, {16, 16}};
  if (s.quick) pairs = {{4, 4}};
  for (const Case& c : cases)
    for (const auto& [nx, ny] : pairs) {
      if (s.quick && c.side == 1.0 && c.lower.norm() > 0) continue;
      if (!c.all_pairs && !(nx == 8 && ny == 8) && !(nx == 12 && ny == 16) && !s.quick) continue;
      const int a[3] = {nx, nx, nx}, b[3] = {ny, ny, ny};
      compare(csv, s, "cube", c.name, std::to_string(nx) + "x" + std::to_string(ny),
              box_cells({0, 0, 0}, {1, 1, 1}, a), box_cells(c.lower, {c.side, c.side, c.side}, b),
              c.reference, 0.0);
    }
}

void plate_section(Csv& csv, const Settings& s) {
  const Eigen::Vector3d size(10, 2, 0.1);
  const int coarse[3] = {50, 5, 2}, fine[3] = {100, 10, 4};
  const HexCells c = box_cells({0, 0, 0}, size, coarse);
  compare(csv, s, "plate", "self", "50x5x2 x 50x5x2", c, c, 0.149702598, 1e-2);
  const HexCells f = box_cells({0, 0, 0}, size, fine);
  compare(csv, s, "plate", "self", "100x10x4 x 100x10x4", f, f, 0.149702598, 1e-2);
  compare(csv, s, "plate", "self", "50x5x2 x 100x10x4", c, f, 0.149702598, 1e-2);
}

// The bending loop at the bent control m = −2.6e4 X₃/0.1 against the arc target's cells at
// `counts` (its point cloud: their centres): the distance's seconds in one evaluation (value;
// value and gradient) with each quadrature, interleaved, the median of the repeats.
void loop_case(Csv& csv, const Settings& s, const Eigen::Vector3i& counts) {
  Scene scene = load_scene(std::string(SOFTHD_SOURCE_DIR) + "/data/scenes/bending.json");
  nlohmann::json t = nlohmann::json::parse(scene.target_json);
  t["cells"] = {counts[0], counts[1], counts[2]};
  scene.target_json = t.dump();
  fe::Assembler assembler = scene.body.make_assembler();
  const fe::ControlSpace space(assembler.mesh(), assembler.geometry(), scene.body.control_kind);
  const SceneTarget target = scene_target(scene, assembler.mesh());
  if (!target.cells) throw InternalError("bench_cells: the bending target has no cells");
  ShapeObjectiveOptions o;
  o.hausdorff.method = Method::tree;
  o.hausdorff.tolerance = 1e-2;
  o.hausdorff.threads = s.threads;
  ShapeObjective colloc(assembler, space, HausdorffTarget(target.cloud, o.hausdorff), o);
  o.hausdorff.quadrature = Quadrature::cells;
  o.target_cells = std::make_shared<const fe::Mesh>(*target.cells);
  HausdorffOptions h = o.hausdorff;  // the point cloud's trees: collocation options
  h.quadrature = Quadrature::collocation;
  ShapeObjective cells(assembler, space, HausdorffTarget(target.cloud, h), o);
  const Eigen::MatrixXd p = space.positions(assembler.mesh());
  const Eigen::VectorXd m = -2.6e4 * p.col(2) / 0.1;
  const std::string name = "target " + std::to_string(counts[0]) + "x" + std::to_string(counts[1]) +
                           "x" + std::to_string(counts[2]);
  for (bool gradient : {false, true}) {
    std::vector<double> tc, tk;
    double rc = 0, rk = 0;
    for (int r = 0; r < s.repeats; ++r) {
      const ShapeEvaluation a = colloc.evaluate(m, gradient);
      const ShapeEvaluation b = cells.evaluate(m, gradient);
      if (a.status != EvaluationStatus::ok || b.status != EvaluationStatus::ok)
        throw NumericalError("bench_cells: the state solve failed (" + name + ")");
      tc.push_back(a.seconds_distance), tk.push_back(b.seconds_distance);
      rc = a.rho, rk = b.rho;
    }
    std::sort(tc.begin(), tc.end()), std::sort(tk.begin(), tk.end());
    const std::string what = gradient ? "value+gradient" : "value";
    csv.row("loop", name, what, "nodes", rc, 0.0, tc[tc.size() / 2], 0);
    csv.row("loop", name, what, "cells", rk, 0.0, tk[tk.size() / 2], 0);
  }
}

// The scene's own arc target (2 · order cells per element and axis: 32 000 hexahedra) and one
// at the body's hexahedra (Q2 50 × 5 × 2 split in 8: 4 000).
void loop_section(Csv& csv, const Settings& s) {
  loop_case(csv, s, Eigen::Vector3i(200, 20, 8));
  loop_case(csv, s, Eigen::Vector3i(100, 10, 4));
}

Settings parse(int argc, char** argv) {
  Settings s;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&](const char* flag) -> std::string {
      if (i + 1 >= argc) throw InvalidArgument(std::string(flag) + ": needs a value");
      return argv[++i];
    };
    if (a == "--quick")
      s.quick = true;
    else if (a == "--threads")
      s.threads = std::stoi(value("--threads"));
    else if (a == "--repeats")
      s.repeats = std::stoi(value("--repeats"));
    else if (a == "--csv")
      s.csv = value("--csv");
    else if (a == "--section")
      s.section = value("--section");
    else
      throw InvalidArgument("unknown flag " + a);
  }
  if (s.csv.empty()) throw InvalidArgument("--csv: required");
  if (s.repeats < 1) throw InvalidArgument("--repeats: must be >= 1");
  if (s.quick) s.repeats = 1;
  if (!s.section.empty() && s.section != "cube" && s.section != "plate" && s.section != "loop")
    throw InvalidArgument("--section: cube, plate or loop (not " + s.section + ")");
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const Settings s = parse(argc, argv);
    Csv csv(s.csv);
    auto run = [&](const char* name) { return s.section.empty() || s.section == name; };
    if (run("cube")) cube_section(csv, s);
    if (s.quick) return 0;
    if (run("plate")) plate_section(csv, s);
    if (run("loop")) loop_section(csv, s);
  } catch (const InvalidArgument& e) {
    std::fprintf(stderr, "bench_cells: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_cells: %s\n", e.what());
    return 1;
  }
  return 0;
}
