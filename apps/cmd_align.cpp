// softhd align: the pose of a scan found by the distance (docs/formulation.md §8.5).

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli.hpp"
#include "commands.hpp"
#include "softhd/control/pose_file.hpp"
#include "softhd/control/scene.hpp"
#include "softhd/fe/boundary.hpp"
#include "softhd/fe/cloud.hpp"
#include "softhd/io/atomic_file.hpp"
#include "softhd/io/cloud_io.hpp"
#include "softhd/parallel.hpp"
#include "softhd/scan/align.hpp"
#include "softhd/scan/cleanup.hpp"

namespace softhd::cli {

namespace {

const char* kUsage = R"(usage: softhd align SCENE_OR_CLOUD SCAN --out DIR [options]

Finds the pose P (y -> s R y + t) that takes the scan's points (camera frame) onto the
body (its frame) by minimising rho over a twist (docs/formulation.md section 8): a global
start over a grid of rotations on subsampled clouds with a large epsilon, a refinement at
epsilon = L/100 and at --eps, then a nearest-point (ICP) finish. The best starts are
ranked, and the refined candidates compared, by the coverage score (--score).
SCENE_OR_CLOUD: a scene file (.json: the body is its mesh's nodes in the reference
configuration, with their volumes) or a 3D cloud file (text or PLY, as softhd distance).
SCAN: a 3D cloud file.

options:
  --out DIR         write DIR/pose.txt (4x4 matrix), DIR/pose.json (matrix, twist,
                    scale, rho, overlap, rmse, the global start's starts and the
                    candidates refined, the refinement's points of body and scan, the
                    table and the fixture if given, ...),
                    DIR/aligned.ply (the moved scan) and
                    DIR/residuals.csv (each scan point's true nearest distance to the body)
  --similarity      also find a scale s (default: a rigid motion, s = 1)
  --scale-min S     similarity: lower bound on s, 0 < S <= 1 (default 0.5)
  --scale-max S     similarity: upper bound on s, S >= 1 (default 2)
  --distance D      symmetric | scan_to_body (default symmetric); scan_to_body (rho = A)
                    does not punish the parts of the body a partial view does not show
  --cap C           soft cap on every field value (a length; default 0: none)
  --eps E           epsilon of the final refinement, a length (default: L/1000, L the
                    diagonal of the body's bounding box)
  --alpha A, --beta B, --gamma G
                    the functional's exponents (defaults 4, 4, 2)
  --no-global       no global start: refine from --initial (default the identity)
  --initial FILE    a starting pose, a 4x4 matrix file as pose.txt: with --no-global the
                    only start; else one more candidate, refined and compared with the
                    global start's (rigid, scale 1, unless --similarity)
  --rotations K     global start: grid rotations (default 48, plus 4 principal-axis ones;
                    0: those 4 only)
  --refine-points N points of each cloud in the refinement, 0: all (default 1000)
  --keep K          global start: distinct candidates refined and compared (default 4)
  --score S         coverage | rho (default coverage): how the global start's poses are
                    ranked and its refined candidates compared. coverage: the camera at the
                    scan frame's origin (a depth view in its camera's frame), each candidate
                    fitted by nearest points, then the mean truncated distance of the scan
                    to the body and of the body points the pose shows the camera (over the
                    scan's image) to the scan; it tells a flipped one-sided view from the
                    true one. rho: rho itself (for a scan not in its camera's frame)
  --score-cap F     coverage score: nearest distances capped at F L (default 0.05)
  --table T         find the table in the scan (the dominant plane within T, a length:
                    RANSAC as a scene's "clean": {"plane": T}) and remove its points
                    before aligning; nothing is removed if it holds under 10 % of them
  --fixture N1,N2,N3,D
                    the table's plane n.x = D in the body's frame (n pointing towards the
                    body; need not be a unit vector): the pose keeps the table found by
                    --table (required) on this one, so only the rotation about the table's
                    normal (--rotations angles in the global start) and the shift along it
                    are searched and refined; rigid only (docs/formulation.md section 8.12)
  --clamp B1,B2,B3,S1,S2,S3
                    with --fixture, the clamp's side: B the direction from the body's centre
                    to its clamped end (body frame), S the direction that end is seen in
                    (scan frame, e.g. -1,0,0: the image's left); poses that turn B more than
                    90 degrees from S (on the table) are not tried
  --surface         the body's surface is the scene mesh's boundary (a scene body only):
                    the nearest-point fits pair each scan point with its closest point of
                    the surface (not the nearest node), the finish fits the pose
                    point-to-plane to convergence, and the residuals are distances to the
                    surface; a scan sampled anywhere on it, rigidly moved, is recovered to
                    rounding (without it, only to the nodes' spacing)
  --inlier F        overlap threshold as a fraction of L, 0 < F < 1 (default 0.01)
  --threads T       OpenMP threads (default: all)
  --json            print pose.json's object instead of the one-line summary
  --help            this text

exit status: 0 done; 1 numerical failure; 2 bad input or refused (one line on stderr
names the file, line or flag): a pose file that is not a 4x4 scaled rotation, NaN
coordinates, scale bounds that exclude 1, a 2D cloud, a body or scan whose points do not
span a plane (a single point, coincident or collinear points fix no pose), a --fixture
that is not 4 finite numbers or has a zero normal, --fixture without --table or with
--similarity, a scan with no table plane for --fixture.
)";

bool is_scene(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".json";
}

/// The body: a scene's mesh nodes with their reference volumes, or a cloud file. With
/// `triangles` (not null; a scene only): the mesh's boundary triangles over its node ids.
PointCloud read_body(const std::string& path, Eigen::Matrix<int, Eigen::Dynamic, 3>* triangles) {
  if (!is_scene(path)) {
    if (triangles != nullptr)
      throw UsageError("--surface needs a scene file as the body (its mesh's boundary), got '" +
                       path + "'");
    return read_cloud(path);
  }
  const softhd::Scene scene = softhd::load_scene(path);
  const fe::Assembler assembler = scene.body.make_assembler();
  if (triangles != nullptr) {  // surface point ids → node ids
    const fe::BoundaryFacets b = fe::boundary_facets(assembler.mesh());
    *triangles = b.triangles;
    for (Eigen::Index t = 0; t < triangles->rows(); ++t)
      for (int c = 0; c < 3; ++c)
        (*triangles)(t, c) = b.nodes[static_cast<size_t>(b.triangles(t, c))];
  }
  return fe::deformed_cloud(assembler, Eigen::VectorXd::Zero(assembler.dofs().num_dofs),
                            fe::CloudPoints::kNodes, fe::CloudVolumes::kReference);
}

void require_3d(const PointCloud& c, const std::string& path) {
  if (c.dim() != 3)
    throw InvalidArgument("'" + path + "' is a " + std::to_string(c.dim()) +
                          "D cloud; align takes 3D clouds");
}

nlohmann::json summary_json(const scan::AlignSummary& s, const scan::AlignOptions& o, double L) {
  nlohmann::json j;
  const Eigen::Matrix4d m = s.pose.matrix();
  const Eigen::Matrix<double, 7, 1> x = s.pose.twist();
  j["matrix"] = nlohmann::json::array();
  for (int r = 0; r < 4; ++r) j["matrix"].push_back({m(r, 0), m(r, 1), m(r, 2), m(r, 3)});
  j["twist"] = {x[0], x[1], x[2], x[3], x[4], x[5], x[6]};
  j["rotation_deg"] = x.head<3>().norm() * 180.0 / M_PI;
  j["scale"] = s.pose.s;
  j["rho"] = s.rho;
  j["overlap"] = s.overlap;
  j["inlier_distance"] = s.inlier_distance;
  j["rmse"] = s.rmse;
  j["status"] = scan::to_string(s.status);
  j["iterations"] = s.iterations;
  j["seconds"] = s.seconds;
  j["kind"] = scan::to_string(o.kind);
  j["distance"] = to_string(o.form.sides);
  j["cap"] = o.form.cap.c;
  j["eps"] = o.distance.params.epsilon;
  j["body_size"] = L;
  j["scan_points"] = s.residuals.size();
  j["starts"] = s.starts;
  j["candidates"] = s.candidates;
  j["refine_points"] = {s.refine_body_points, s.refine_scan_points};
  j["surface_triangles"] = o.body_triangles.rows();  // --surface: the body's boundary (0: none)
  if (o.table)  // --table: the plane removed from the scan (its frame)
    j["table"] = {{"normal", {o.table->normal[0], o.table->normal[1], o.table->normal[2]}},
                  {"offset", o.table->offset},
                  {"inliers", o.table->inliers}};
  if (o.fixture) {
    const scan::Fixture& f = *o.fixture;
    j["fixture"] = {{"normal", {f.normal[0], f.normal[1], f.normal[2]}}, {"offset", f.offset}};
    if (f.has_clamp())
      j["fixture"]["clamp"] = {f.clamp[0],      f.clamp[1],      f.clamp[2],
                               f.clamp_seen[0], f.clamp_seen[1], f.clamp_seen[2]};
  }
  return j;
}

/// The fixture of --fixture N1,N2,N3,D (UsageError naming the flag).
scan::Fixture parse_fixture(const std::string& text) {
  std::vector<double> v;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) v.push_back(parse_number(item, "--fixture"));
  if (v.size() != 4 || text.empty() || text.back() == ',')
    throw UsageError(
        "--fixture must be 4 numbers N1,N2,N3,D (the table's plane n.x = D in the "
        "body's frame), got '" +
        text + "'");
  scan::Fixture f{Eigen::Vector3d(v[0], v[1], v[2]), v[3]};
  if (!(f.normal.norm() > 0.0)) throw UsageError("--fixture: the normal has zero length");
  return f;
}

/// --table: the scan's dominant plane within `distance`, removed from *scan; into o->table
/// when it holds at least 10 % of the points, else (with a fixture) refused naming the file.
void remove_table(PointCloud* scan, double distance, const std::string& path,
                  scan::AlignOptions* o) {
  scan::PlaneRemoval removal;
  removal.distance = distance;
  const scan::Plane plane = scan::find_dominant_plane(*scan, removal);
  const Eigen::Index n = scan->size();
  if (static_cast<double>(plane.inliers) < removal.min_fraction * static_cast<double>(n)) {
    if (o->fixture)
      throw InvalidArgument(path +
                            ": no table plane for --fixture: the largest plane within --table " +
                            std::to_string(distance) + " holds " + std::to_string(plane.inliers) +
                            " of " + std::to_string(n) + " points (fewer than 10 %)");
    return;
  }
  o->table = plane;
  *scan = scan::select(*scan, scan::remove_dominant_plane(*scan, removal));
}

void write_residuals(const std::string& path, const PointCloud& moved, const Eigen::VectorXd& r) {
  std::ostringstream out;
  out.precision(17);
  out << "x,y,z,distance\n";
  for (Eigen::Index j = 0; j < moved.size(); ++j)
    out << moved.points()(j, 0) << ',' << moved.points()(j, 1) << ',' << moved.points()(j, 2) << ','
        << r[j] << '\n';
  write_file_atomically(path, out.str());
}

}  // namespace

int run_align(const std::vector<std::string>& tokens) {
  Args args(tokens);
  if (args.flag("--help")) {
    std::cout << kUsage;
    return 0;
  }
  scan::AlignOptions o;
  const std::optional<std::string> out_dir = args.value("--out");
  if (args.flag("--similarity")) o.kind = scan::PoseKind::similarity;
  o.scale_min = args.number("--scale-min", o.scale_min);
  o.scale_max = args.number("--scale-max", o.scale_max);
  o.form.sides = sides_from_string(args.value("--distance").value_or("symmetric"));
  o.form.cap.c = args.number("--cap", 0.0);
  const std::optional<std::string> eps = args.value("--eps");
  o.distance.params.alpha = args.number("--alpha", o.distance.params.alpha);
  o.distance.params.beta = args.number("--beta", o.distance.params.beta);
  o.distance.params.gamma = args.number("--gamma", o.distance.params.gamma);
  o.global_start = !args.flag("--no-global");
  const std::optional<std::string> initial = args.value("--initial");
  o.rotations = static_cast<int>(args.integer("--rotations", o.rotations, 0, 100000));
  o.refine_points = static_cast<int>(args.integer("--refine-points", o.refine_points, 0, 1L << 30));
  o.keep = static_cast<int>(args.integer("--keep", o.keep, 1, 100000));
  const std::string score = args.value("--score").value_or("coverage");
  if (score == "visible") throw UsageError("--score visible is now --score coverage");
  if (score != "coverage" && score != "rho")
    throw UsageError("--score must be coverage or rho, got '" + score + "'");
  o.score = scan::candidate_score_from_string(score);
  o.score_truncation = args.number("--score-cap", o.score_truncation);
  if (!(o.score_truncation > 0.0))
    throw UsageError("--score-cap must be > 0, got " + std::to_string(o.score_truncation));
  const std::optional<std::string> fixture = args.value("--fixture");
  if (fixture) o.fixture = parse_fixture(*fixture);
  if (const std::optional<std::string> clamp = args.value("--clamp")) {
    if (!fixture) throw UsageError("--clamp is the fixture's clamp side: give --fixture");
    std::vector<double> v;
    std::stringstream in(*clamp);
    for (std::string item; std::getline(in, item, ',');) v.push_back(parse_number(item, "--clamp"));
    if (v.size() != 6)
      throw UsageError("--clamp must be 6 numbers B1,B2,B3,S1,S2,S3, got '" + *clamp + "'");
    o.fixture->clamp = Eigen::Vector3d(v[0], v[1], v[2]);
    o.fixture->clamp_seen = Eigen::Vector3d(v[3], v[4], v[5]);
    try {
      o.fixture->validate();
    } catch (const InvalidArgument& e) {
      throw UsageError(std::string("--clamp: ") + e.what());
    }
  }
  const std::optional<std::string> table = args.value("--table");
  const double table_distance = table ? parse_number(*table, "--table") : 0.0;
  if (table && !(table_distance > 0.0))
    throw UsageError("--table must be > 0 (a length), got " + *table);
  if (fixture && !table)
    throw UsageError("--fixture needs --table T (the table is found in the scan within T)");
  if (fixture && o.kind == scan::PoseKind::similarity)
    throw UsageError("--fixture needs a rigid alignment (a scale would change the table's height)");
  o.inlier_distance = args.number("--inlier", o.inlier_distance);
  if (!(o.inlier_distance > 0.0 && o.inlier_distance < 1.0))
    throw UsageError("--inlier must be in (0, 1) (a fraction of the body size L), got " +
                     std::to_string(o.inlier_distance));
  o.threads = static_cast<int>(args.integer("--threads", 0, 0, kMaxThreads));
  const bool json = args.flag("--json");
  const bool surface = args.flag("--surface");
  const std::vector<std::string> files = args.finish();
  if (files.size() != 2)
    throw UsageError("expected SCENE_OR_CLOUD and SCAN, got " + std::to_string(files.size()) +
                     " files (see --help)");
  if (!out_dir) throw UsageError("--out DIR is required (see --help)");
  if (o.form.sides == Sides::visible)
    throw UsageError(
        "--distance visible is not supported by align (it has no camera model); use "
        "scan_to_body for a partial view");
  if (initial) {
    o.initial = read_pose(*initial);
    if (o.kind == scan::PoseKind::rigid && !o.initial->rigid()) {
      std::ostringstream msg;
      msg.precision(10);
      msg << *initial << ": the pose has scale " << o.initial->s
          << "; a rigid alignment keeps scale 1 (give --similarity, or a rigid pose)";
      throw InvalidArgument(msg.str());
    }
  }
  if (o.scale_min <= 0.0 || o.scale_min > 1.0)
    throw UsageError("--scale-min must be in (0, 1] (the bounds must include 1), got " +
                     std::to_string(o.scale_min));
  if (o.scale_max < 1.0)
    throw UsageError("--scale-max must be >= 1 (the bounds must include 1), got " +
                     std::to_string(o.scale_max));

  const PointCloud body = read_body(files[0], surface ? &o.body_triangles : nullptr);
  PointCloud scan = read_cloud(files[1]);
  require_3d(body, files[0]);
  require_3d(scan, files[1]);
  check_coordinates(body, files[0]);
  check_coordinates(scan, files[1]);
  if (table) remove_table(&scan, table_distance, files[1], &o);
  scan::check_fixes_pose(body, files[0]);
  scan::check_fixes_pose(scan, files[1]);
  const double L = scan::body_size(body);
  o.distance.params.epsilon = eps ? parse_number(*eps, "--eps") : 1e-3 * L;
  o.validate();
  const scan::AlignSummary s = scan::align(body, scan, o);
  if (s.status == scan::AlignStatus::failed)
    throw NumericalError("align failed: " + s.BriefReport());

  std::filesystem::create_directories(*out_dir);
  const std::filesystem::path dir(*out_dir);
  write_pose((dir / "pose.txt").string(), s.pose);
  const nlohmann::json j = summary_json(s, o, L);
  write_file_atomically((dir / "pose.json").string(), j.dump(2) + "\n");
  const PointCloud moved = s.pose.apply(scan, false);
  write_cloud((dir / "aligned.ply").string(), moved);
  write_residuals((dir / "residuals.csv").string(), moved, s.residuals);
  if (json)
    std::cout << j.dump(2) << '\n';
  else
    std::cout << s.BriefReport() << "\nwrote " << (dir / "pose.txt").string() << ", pose.json, "
              << "aligned.ply, residuals.csv\n";
  return 0;
}

}  // namespace softhd::cli
