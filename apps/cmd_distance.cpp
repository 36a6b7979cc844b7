// softhd distance: ρ̃_H between two cloud files (docs/formulation.md §2, §6).

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "cli.hpp"
#include "commands.hpp"
#include "softhd/hausdorff.hpp"
#include "softhd/io/atomic_file.hpp"
#include "softhd/io/cloud_io.hpp"
#include "softhd/io/mask_io.hpp"
#include "softhd/parallel.hpp"
#include "softhd/scan/cleanup.hpp"
#include "softhd/scan/surface_weights.hpp"
#include "softhd/work_share.hpp"

namespace softhd::cli {

namespace {

const char* kUsage = R"(usage: softhd distance MOVING TARGET [options]

Regularised Hausdorff distance rho between two point clouds
(docs/formulation.md section 2).
MOVING and TARGET are text files (x y [z] [V] per line, whitespace or commas,
'#' comments, V = 1 when absent), PLY files (ascii or binary little-endian) or
PCD files (.pcd: ascii, binary or binary_compressed; fields x y z, volumes from
a volume, weight or area field). Skipped fields (colours, normals) are named on
stderr.

options:
  --alpha A        kernel exponent alpha > 0 (default 4)
  --beta B         mean exponent beta > 0 (default 4)
  --gamma G        combining exponent gamma > 0 (default 2)
  --eps E          kernel offset epsilon > 0, a length (default 1e-3)
  --method M       exact | tree | nearest (default exact); nearest gives the exact
                   (unregularised) Hausdorff distance and the two directed ones
  --tol T          tree: relative error bound on every kernel sum, 0 < T < 1
                   (default 1e-6)
  --dim D          2 or 3: dimension of text clouds (default: from the columns:
                   2 -> x y, 3 -> x y z, 4 -> x y z V)
  --threads T      OpenMP threads (default: all)
  --distance F     symmetric | scan_to_body | visible (default symmetric;
                   docs/formulation.md section 8): scan_to_body is rho = A alone
                   (TARGET -> MOVING, for a partial scan; B is reported 0), visible
                   restricts B to the moving points the camera mask marks
  --camera-mask FILE
                   with --distance visible: N lines of 0 or 1, one per moving point
                   in the order of MOVING ('#' comments allowed), 1 = seen by the
                   camera (in B)
  --cap C          soft cap psi_c(d) = (d^-q + c^-q)^(-1/q) on every field value
                   before its beta-mean, C > 0 a length (default 0: no cap)
  --cap-q Q        sharpness q > 0 of the cap (default 4)
  --grad FILE      write d rho / d x_i and d rho / d V_i, one row per moving point

clean-up of TARGET as a scan (docs/formulation.md section 8), in this order; each
step prints how many points it removed on stderr:
  --crop M         keep the points in MOVING's bounding box inflated by M times
                   its diagonal (M >= 0)
  --plane DIST     remove the dominant plane (RANSAC, inlier distance DIST > 0)
  --outliers K,R   statistical outlier removal: mean distance to the K nearest
                   neighbours at most mean + R std over the cloud
  --weights W      file (default: as read) | knn | delaunay: replace TARGET's
                   volumes by estimated surface areas (12 neighbours)
  --json           print one JSON object: rho, A, B, N, M, method, distance,
                   cap, seconds, ...
  --help           this text

MPI builds: under 'mpirun -np K softhd distance ...' every rank reads both clouds
and the pair sums (and nearest queries) are split across the ranks; rank 0 prints
and writes --grad. The result equals the one-process result (docs/scaling.md).

exit status: 0 done; 1 numerical failure; 2 bad input or refused (one line on stderr
names the file, line or flag).
)";

void write_gradient(const std::string& path, const PointCloud& X, const HausdorffResult& r) {
  std::ostringstream out;
  const int d = X.dim();
  out << "# gradient of rho w.r.t. the moving cloud: " << (d == 3 ? "x y z" : "x y")
      << (d == 3 ? " drho/dx drho/dy drho/dz" : " drho/dx drho/dy") << " drho/dV\n";
  out.precision(17);
  for (Eigen::Index i = 0; i < X.size(); ++i) {
    for (int k = 0; k < d; ++k) out << X.points()(i, k) << ' ';
    for (int k = 0; k < d; ++k) out << r.gradient_points(i, k) << ' ';
    out << r.gradient_volumes[i] << '\n';
  }
  write_file_atomically(path, out.str());
}

// "K,R" of --outliers.
scan::ScanCleanup::Outliers parse_outliers(const std::string& text) {
  scan::ScanCleanup::Outliers o;
  const std::size_t comma = text.find(',');
  std::size_t used_k = 0, used_r = 0;
  try {
    if (comma == std::string::npos) throw std::invalid_argument("no comma");
    o.k = std::stoi(text.substr(0, comma), &used_k);
    o.ratio = std::stod(text.substr(comma + 1), &used_r);
  } catch (const std::exception&) {
    used_k = 0;
  }
  if (used_k == 0 || used_k != comma || used_r != text.size() - comma - 1)
    throw UsageError("--outliers must be K,R (an integer and a number), got '" + text + "'");
  return o;
}

// TARGET cleaned (crop to MOVING's bounding box) and re-weighted; each step a note.
PointCloud clean_target(const PointCloud& X, const PointCloud& Y, const std::string& file,
                        const scan::ScanCleanup& clean, const std::string& weights,
                        std::vector<std::string>& notes) {
  std::vector<scan::CleanupStep> steps;
  PointCloud out = Y;
  try {
    out = scan::clean_scan(Y, X.points().colwise().minCoeff().transpose(),
                           X.points().colwise().maxCoeff().transpose(), clean, &steps);
    if (weights != "file")
      out = scan::with_area_weights(out, scan::area_estimate_from_string(weights));
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(file + ": " + e.what());
  }
  if (!steps.empty()) notes.push_back(file + ": " + scan::describe(steps, Y.size()));
  if (weights != "file") notes.push_back(file + ": weights " + weights);
  return out;
}

}  // namespace

namespace {

/// What `softhd distance` was asked for.
struct DistanceArgs {
  HausdorffOptions options;
  DistanceForm form;
  long dim = 0;
  std::optional<std::string> mask_path, grad_path;
  bool json = false;
  scan::ScanCleanup clean;
  std::string weights;
  std::vector<std::string> files;  // MOVING TARGET
};

DistanceArgs parse_distance(Args& args) {
  DistanceArgs a;
  HausdorffOptions& opt = a.options;
  opt.params.alpha = args.number("--alpha", opt.params.alpha);
  opt.params.beta = args.number("--beta", opt.params.beta);
  opt.params.gamma = args.number("--gamma", opt.params.gamma);
  opt.params.epsilon = args.number("--eps", opt.params.epsilon);
  opt.method = method_from_string(args.value("--method").value_or("exact"));
  opt.tolerance = args.number("--tol", opt.tolerance);
  opt.threads = static_cast<int>(args.integer("--threads", 0, 0, kMaxThreads));
  a.dim = args.integer("--dim", 0);
  if (a.dim != 0 && a.dim != 2 && a.dim != 3) throw UsageError("--dim must be 2 or 3");
  a.form.sides = sides_from_string(args.value("--distance").value_or("symmetric"));
  a.form.cap.c = args.number("--cap", a.form.cap.c);
  a.form.cap.q = args.number("--cap-q", a.form.cap.q);
  try {
    DistanceForm{Sides::symmetric, a.form.cap, {}}.validate(0);
  } catch (const InvalidArgument& e) {
    throw UsageError(std::string("--cap/--cap-q: ") + e.what());
  }
  args.retired("--visible", "--camera-mask");
  a.mask_path = args.value("--camera-mask");
  if (a.mask_path.has_value() != (a.form.sides == Sides::visible))
    throw UsageError(a.mask_path ? "--camera-mask needs --distance visible"
                                 : "--distance visible needs --camera-mask FILE");
  a.grad_path = args.value("--grad");
  a.json = args.flag("--json");
  if (const auto crop = args.value("--crop")) a.clean.crop = parse_number(*crop, "--crop");
  if (const auto plane = args.value("--plane")) a.clean.plane = parse_number(*plane, "--plane");
  if (const auto o = args.value("--outliers")) a.clean.outliers = parse_outliers(*o);
  a.weights = args.value("--weights").value_or("file");
  if (a.weights != "file" && a.weights != "knn" && a.weights != "delaunay")
    throw UsageError("--weights must be file, knn or delaunay, got '" + a.weights + "'");
  try {
    a.clean.validate();
  } catch (const InvalidArgument& e) {  // "clean.crop must be ..." for the flag --crop
    throw UsageError(std::string("--") + (e.what() + 6));
  }
  a.files = args.finish();
  if (a.files.size() != 2) {
    throw UsageError("expected two cloud files (MOVING TARGET), got " +
                     std::to_string(a.files.size()) + " (see --help)");
  }
  return a;
}

void print_json(const DistanceArgs& a, const PointCloud& X, const PointCloud& Y,
                const HausdorffResult& r) {
  const HausdorffOptions& opt = a.options;
  nlohmann::json j;
  j["rho"] = r.rho;
  j["A"] = r.A;
  j["B"] = r.B;
  j["N"] = X.size();
  j["M"] = Y.size();
  j["dim"] = X.dim();
  j["method"] = to_string(opt.method);
  j["alpha"] = opt.params.alpha;
  j["beta"] = opt.params.beta;
  j["gamma"] = opt.params.gamma;
  j["eps"] = opt.params.epsilon;
  if (opt.method == Method::tree) j["tolerance"] = opt.tolerance;
  j["distance"] = to_string(a.form.sides);
  j["cap"] = a.form.cap.c;
  j["cap_q"] = a.form.cap.q;
  j["kernel_evaluations"] = r.kernel_evaluations;
  j["ranks"] = opt.share ? opt.share->size() : 1;
  j["seconds"] = r.seconds;
  std::cout << j.dump(2) << '\n';
}

void print_text(const DistanceArgs& a, const PointCloud& X, const PointCloud& Y,
                const HausdorffResult& r) {
  const bool nn = a.options.method == Method::nearest;
  std::printf("%s = %.10g\n", nn ? "Hausdorff distance" : "rho", r.rho);
  std::printf("%s = %.10g\n", nn ? "max_j dist(y_j, X)" : "A  ", r.A);
  std::printf("%s = %.10g\n", nn ? "max_i dist(x_i, Y)" : "B  ", r.B);
  std::printf("N = %ld moving, M = %ld target points, %dD, method %s, distance %s, %.3g s\n",
              static_cast<long>(X.size()), static_cast<long>(Y.size()), X.dim(),
              to_string(a.options.method).c_str(), to_string(a.form.sides).c_str(), r.seconds);
  if (a.form.cap.c > 0.0) std::printf("cap c = %.10g, q = %.10g\n", a.form.cap.c, a.form.cap.q);
}

}  // namespace

int run_distance(const std::vector<std::string>& tokens) {
  Args args(tokens);
  if (args.flag("--help")) {
    std::cout << kUsage;
    return 0;
  }
  DistanceArgs a = parse_distance(args);
  a.options.share = world_share();  // null unless started by mpirun with K > 1 ranks
  const bool speaker = world_rank() == 0;
  a.options.validate();

  std::vector<std::string> notes;
  const std::vector<std::string>& files = a.files;
  const PointCloud X = read_cloud(files[0], static_cast<int>(a.dim), &notes);
  PointCloud Y = read_cloud(files[1], static_cast<int>(a.dim), &notes);
  check_coordinates(X, files[0]);  // the limit's message names the file
  check_coordinates(Y, files[1]);
  if (X.dim() != Y.dim()) {
    throw InvalidArgument("mixed dimensions: '" + files[0] + "' is " + std::to_string(X.dim()) +
                          "D but '" + files[1] + "' is " + std::to_string(Y.dim()) + "D");
  }
  Y = clean_target(X, Y, files[1], a.clean, a.weights, notes);
  try {
    check_cap_length(a.form.cap, X, Y);
  } catch (const InvalidArgument& e) {
    throw UsageError(std::string("--cap: ") + e.what());
  }
  if (speaker)
    for (const std::string& n : notes) std::cerr << "softhd distance: " << n << '\n';
  if (a.mask_path) {
    a.form.camera_mask = read_mask(*a.mask_path);
    if (a.form.camera_mask.size() != X.size())
      throw FileError(*a.mask_path + ": " + std::to_string(a.form.camera_mask.size()) +
                      " entries for the " + std::to_string(X.size()) + " points of '" + files[0] +
                      "'");
  }
  HausdorffRequest req;
  req.form = a.form;
  req.gradient_points = req.gradient_volumes = a.grad_path.has_value();
  const HausdorffTarget target(Y, a.options);
  const HausdorffResult r = target.evaluate(X, req);
  // Clouds within kMaxCoordinate give finite results; anything else is a bug, not input.
  if (!std::isfinite(r.rho) || !std::isfinite(r.A) || !std::isfinite(r.B))
    throw InternalError("non-finite result (rho " + std::to_string(r.rho) + ")");
  if (!speaker) return 0;
  if (a.grad_path) write_gradient(*a.grad_path, X, r);
  if (a.json)
    print_json(a, X, Y, r);
  else
    print_text(a, X, Y, r);
  return 0;
}

}  // namespace softhd::cli
