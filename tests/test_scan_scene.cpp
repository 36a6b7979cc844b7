// A scan as a scene's target (docs/guide.md, target block): clean and weights applied in the
// order read → crop → plane → outliers → weights, the same as the library's calls, with the
// counts in the description; bad keys and an emptied scan refused.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <random>
#include <string>

#include "expect_error.hpp"
#include "softhd/control/pose_file.hpp"
#include "softhd/control/scene.hpp"
#include "softhd/control/scene_target.hpp"
#include "softhd/io/cloud_io.hpp"
#include "softhd/scan/cleanup.hpp"
#include "softhd/scan/surface_weights.hpp"

namespace softhd::test {
namespace {

// A body [0,2]×[0,1]×[0,0.2]: its top face sampled (800 points), a table z = 0 around it
// (3000 points over [−1,3]×[−1,2], not under the body), 60 uniform outliers.
std::string write_scan() {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Eigen::MatrixXd p(3860, 3);
  Eigen::Index r = 0;
  for (int i = 0; i < 800; ++i) p.row(r++) << 2 * u(rng), u(rng), 0.2;
  while (r < 3800) {
    const double x = -1 + 4 * u(rng), y = -1 + 3 * u(rng);
    if (x > 0 && x < 2 && y > 0 && y < 1) continue;
    p.row(r++) << x, y, 0.0;
  }
  while (r < 3860) p.row(r++) << -1 + 4 * u(rng), -1 + 3 * u(rng), u(rng);
  const std::string path = testing::TempDir() + "/scan_scene.ply";
  write_ply_cloud(path, PointCloud(p));
  return path;
}

softhd::Scene scene_with(const std::string& target) {
  return softhd::parse_scene(R"({
    "mesh": { "type": "box", "lower": [0, 0, 0], "upper": [2, 1, 0.2], "cells": [2, 1, 1], "order": 1 },
    "material": { "model": "mooney_rivlin", "a": 1e5, "b": 2e4, "c": 3e5 },
    "fibers": [1, 0, 0], "clamp": ["x0"],
    "control": { "space": "vertex", "lower": -1e5, "upper": 0, "initial": 0 },
    "target": )" + target + "}",
                             testing::TempDir() + "/scan_scene.json");
}

// "fixture" (docs/formulation.md §8.12): the table in the body's frame; the scan's table is the
// plane of "clean": {"plane": D}, found as the clean-up's plane step finds it; the objective's
// inner pose keeps the table (pose_table_normal). Bad values refused naming the key.
TEST(ScanScene, FixtureKeys) {
  const std::string file = write_scan();
  const std::string head =
      R"({"kind": "cloud", "file": "scan_scene.ply", "frame": "camera", "clean": {"plane": 0.01}, )";
  const softhd::Scene s = scene_with(head + R"("fixture": {"normal": [0, 0, 2], "offset": -0.1}})");
  const SceneTarget t = scene_target(s, s.body.make_mesh());
  ASSERT_TRUE(t.fixture && t.table);
  EXPECT_EQ(t.fixture->normal, Eigen::Vector3d(0, 0, 2));
  EXPECT_EQ(t.fixture->offset, -0.1);
  scan::PlaneRemoval plane;
  plane.distance = 0.01;
  const scan::Plane expected = scan::find_dominant_plane(read_cloud(file), plane);
  EXPECT_EQ(t.table->normal, expected.normal);
  EXPECT_EQ(t.table->offset, expected.offset);
  EXPECT_EQ(t.cloud.size(), 3860 - expected.inliers);  // that plane's points removed
  EXPECT_GE(expected.inliers, 3000);                   // the table's
  ShapeObjectiveOptions o;
  apply_target_settings(t, &o);
  ASSERT_TRUE(o.pose_table_normal);
  EXPECT_EQ(*o.pose_table_normal, Eigen::Vector3d(0, 0, 2));
  auto refuses = [&](const std::string& rest, const std::string& message) {
    const softhd::Scene bad = scene_with(rest + "}");
    expect_error<Error>([&] { scene_target(bad, bad.body.make_mesh()); }, message);
  };
  refuses(head + R"("fixture": {"normal": [0, 0, 0], "offset": 0})",
          "target.fixture.normal has zero length");
  refuses(head + R"("fixture": {"normal": [0, 0, "NaN"], "offset": 0})",
          "target.fixture.normal must be 3 numbers");
  refuses(head + R"("fixture": {"normal": [0, 0, 1], "offset": "NaN"})",
          "target.fixture.offset must be a number");
  refuses(head + R"("fixture": {"normal": [0, 0, 1], "offset": 0, "side": 1})",
          "unknown key 'side'");
  refuses(head + R"("align": "similarity", "fixture": {"normal": [0, 0, 1], "offset": 0})",
          "target.fixture needs \"align\": \"rigid\"");
  refuses(R"({"kind": "cloud", "file": "scan_scene.ply", "frame": "camera",
              "fixture": {"normal": [0, 0, 1], "offset": 0})",
          "target.fixture needs the table found in the scan");
  refuses(R"({"kind": "cloud", "file": "scan_scene.ply",
              "fixture": {"normal": [0, 0, 1], "offset": 0})",
          "target.fixture is for a cloud in the camera's frame");
  // No table: 40 scattered points, of which no plane holds 10 % (4) within 1e-9.
  Eigen::MatrixXd scattered(40, 3);
  for (int i = 0; i < 40; ++i)
    scattered.row(i) << std::sin(1.3 * i), std::cos(2.1 * i + 0.4), std::sin(0.7 * i * i);
  write_ply_cloud(testing::TempDir() + "/scan_scene_scattered.ply", PointCloud(scattered));
  refuses(R"({"kind": "cloud", "file": "scan_scene_scattered.ply", "frame": "camera",
              "clean": {"plane": 1e-9}, "fixture": {"normal": [0, 0, 1], "offset": 0})",
          "target.fixture: no table plane in");
}

TEST(ScanScene, CleansAndWeighsInTheDocumentedOrder) {
  const std::string file = write_scan();
  const softhd::Scene s = scene_with(
      R"({"kind": "cloud", "file": "scan_scene.ply", "weights": "knn",
          "clean": {"crop": 0.5, "plane": 0.01, "outliers": {"k": 10, "ratio": 2}}})");
  const SceneTarget t = scene_target(s, s.body.make_mesh());
  // The same steps by the library's calls.
  const PointCloud read = read_cloud(file);
  const PointCloud cropped =
      scan::select(read, scan::crop_to_box(read, s.body.lower, s.body.upper, 0.5));
  scan::PlaneRemoval plane;
  plane.distance = 0.01;
  const PointCloud flat = scan::select(cropped, scan::remove_dominant_plane(cropped, plane));
  const PointCloud clean = scan::select(flat, scan::remove_statistical_outliers(flat, 10, 2.0));
  const PointCloud expected = scan::with_area_weights(clean, scan::AreaEstimate::knn);
  ASSERT_EQ(t.cloud.size(), expected.size());
  EXPECT_EQ(t.cloud.points(), expected.points());
  EXPECT_EQ(t.cloud.volumes(), expected.volumes());
  // The table went with the plane, the body's top stayed (a few outliers near it too).
  EXPECT_EQ((t.cloud.points().col(2).array() == 0.0).count(), 0);
  EXPECT_GE((t.cloud.points().col(2).array() == 0.2).count(), 790);
  const std::string counts = "crop removed " + std::to_string(read.size() - cropped.size()) +
                             ", plane removed " + std::to_string(cropped.size() - flat.size()) +
                             ", outliers removed " + std::to_string(flat.size() - clean.size()) +
                             " of 3860 points; weights knn";
  EXPECT_NE(t.description.find(counts), std::string::npos) << t.description;
  EXPECT_FALSE(t.map_displacement);
}

TEST(ScanScene, RefusesBadKeysAndAnEmptiedScan) {
  write_scan();
  const std::string head = R"({"kind": "cloud", "file": "scan_scene.ply", )";
  auto refuses = [&](const std::string& rest, const std::string& message) {
    const softhd::Scene s = scene_with(head + rest + "}");
    expect_error<Error>([&] { scene_target(s, s.body.make_mesh()); }, message);
  };
  refuses(R"("weights": "area")", "target.weights must be \"file\", \"knn\" or \"delaunay\"");
  refuses(R"("clean": {"crop": -1})", "target.clean.crop must be a finite margin >= 0");
  refuses(R"("clean": {"plain": 0.1})", "unknown key 'plain'");
  refuses(R"("clean": {"outliers": {"k": 0}})", "target.clean.outliers.k must be an integer");
  refuses(R"("clean": {"outliers": 3})", "target.clean.outliers must be an object");
  refuses(R"("clean": {"plane": 0})", "target.clean.plane must be a finite distance > 0");
  // Crop to the body's box with no margin, then a plane as thick as the scene: nothing left.
  refuses(R"("clean": {"crop": 0, "plane": 5})",
          "no points left after the clean-up (plane removed the last");
  // "file" weights are the file's (here 1s).
  const softhd::Scene s = scene_with(head + R"("weights": "file"})");
  EXPECT_EQ(scene_target(s, s.body.make_mesh()).cloud.volumes(), Eigen::VectorXd::Ones(3860));
}

// A scan in the camera's frame (docs/formulation.md §8.10): "frame", "align", "pose" read; the
// pose file's matrix is the start; bad values refused naming the key.
TEST(ScanScene, CameraFrameKeys) {
  write_scan();
  Eigen::Matrix<double, 7, 1> tw;
  tw << 0.1, -0.2, 0.3, 1.0, 2.0, -0.5, 0.0;
  const scan::Pose P = scan::Pose::from_twist(tw);
  write_pose(testing::TempDir() + "/scan_scene_pose.txt", P);
  const std::string head = R"({"kind": "cloud", "file": "scan_scene.ply", )";
  const softhd::Scene s =
      scene_with(head + R"("frame": "camera", "align": "similarity", "pose": "scan_scene_pose.txt",
                 "distance": "visible"})");
  const SceneTarget t = scene_target(s, s.body.make_mesh());
  EXPECT_EQ(t.frame, TargetFrame::camera);
  EXPECT_EQ(t.align, scan::PoseKind::similarity);
  ASSERT_TRUE(t.pose);
  EXPECT_LT((t.pose->matrix() - P.matrix()).norm(), 1e-14);
  EXPECT_EQ(t.distance.sides, Sides::visible);  // its camera is the pose's
  EXPECT_FALSE(t.camera);
  ShapeObjectiveOptions o;
  apply_target_settings(t, &o);
  EXPECT_EQ(o.pose_kind, scan::PoseKind::similarity);
  const softhd::Scene body = scene_with(head + R"("frame": "body"})");
  EXPECT_EQ(scene_target(body, body.body.make_mesh()).frame, TargetFrame::body);

  auto refuses = [&](const std::string& rest, const std::string& message) {
    const softhd::Scene bad = scene_with(head + rest + "}");
    expect_error<Error>([&] { scene_target(bad, bad.body.make_mesh()); }, message);
  };
  refuses(R"("frame": "world")", "target.frame must be \"body\" or \"camera\", got \"world\"");
  refuses(R"("frame": "camera", "align": "affine")",
          "target.align must be \"rigid\" or \"similarity\"");
  refuses(R"("align": "rigid")", "target.align is for a cloud in the camera's frame");
  refuses(R"("pose": "scan_scene_pose.txt")", "target.pose is for a cloud in the camera's frame");
  refuses(R"("frame": "camera", "pose": "missing_pose.txt")", "cannot open the pose file");
  refuses(R"("frame": "camera", "pose": 3)", "target.pose must be a pose file path string");
  refuses(R"("frame": "camera", "camera": [0, 0, 5])", "the camera is the pose's");
  refuses(R"("frame": "camera", "clean": {"crop": 0.5})", "target.clean.crop crops to the body's");
  std::ofstream(testing::TempDir() + "/scan_scene_bad_pose.txt") << "1 0 0 0\n0 1 0 0\n0 0 1\n";
  refuses(R"("frame": "camera", "pose": "scan_scene_bad_pose.txt")",
          "scan_scene_bad_pose.txt:3: expected 4 numbers, got 3");
  // A rigid start pose has scale 1; a similarity's lies in [0.5, 2] (PoseBounds): refused naming
  // the pose file, the scale in decimals.
  std::ofstream(testing::TempDir() + "/scan_scene_tiny_pose.txt")
      << "1e-100 0 0 0\n0 1e-100 0 0\n0 0 1e-100 0\n0 0 0 1\n";
  refuses(R"("frame": "camera", "pose": "scan_scene_tiny_pose.txt")",
          "scan_scene_tiny_pose.txt' has scale 1e-100, but a rigid pose");
  refuses(R"("frame": "camera", "align": "similarity", "pose": "scan_scene_tiny_pose.txt")",
          "scan_scene_tiny_pose.txt' has scale 1e-100, outside the similarity's scale bounds "
          "[0.5, 2]");
  // "pose_uncertainty" of the pose file: the projection's bound (degrees to radians); bad values
  // refused naming the key, a pose file with a non-rotation block naming the file.
  const softhd::Scene calibrated =
      scene_with(head + R"("frame": "camera", "pose": "scan_scene_pose.txt",
                 "pose_uncertainty": {"degrees": 2, "length": 0.5}})");
  const SceneTarget ct = scene_target(calibrated, calibrated.body.make_mesh());
  ASSERT_TRUE(ct.pose_uncertainty);
  EXPECT_DOUBLE_EQ(ct.pose_uncertainty->rotation, 2 * M_PI / 180);
  EXPECT_EQ(ct.pose_uncertainty->translation, 0.5);
  ShapeObjectiveOptions co;
  apply_target_settings(ct, &co);
  ASSERT_TRUE(co.pose_bound);
  EXPECT_EQ(co.pose_bound->translation, 0.5);
  const std::string pose = R"("frame": "camera", "pose": "scan_scene_pose.txt", )";
  refuses(pose + R"("pose_uncertainty": {"degrees": -1, "length": 0.5})",
          "target.pose_uncertainty.degrees must be a number > 0, got -1");
  refuses(pose + R"("pose_uncertainty": {"degrees": "NaN", "length": 0.5})",
          "target.pose_uncertainty.degrees must be a number > 0, got \"NaN\"");
  refuses(pose + R"("pose_uncertainty": {"degrees": 1, "length": 0})",
          "target.pose_uncertainty.length must be a number > 0, got 0");
  refuses(pose + R"("pose_uncertainty": {"degrees": 1})",
          "target.pose_uncertainty.length must be a number > 0, got null");
  refuses(pose + R"("pose_uncertainty": {"degrees": 1, "length": 1, "scale": 1})",
          "unknown key 'scale'");
  refuses(pose + R"("pose_uncertainty": [1, 1])", "target.pose_uncertainty must be {");
  refuses(R"("frame": "camera", "pose_uncertainty": {"degrees": 1, "length": 1})",
          "target.pose_uncertainty is the uncertainty of target.pose");
  refuses(R"("pose_uncertainty": {"degrees": 1, "length": 1})",
          "target.pose_uncertainty is for a cloud in the camera's frame");
  std::ofstream(testing::TempDir() + "/scan_scene_shear_pose.txt")
      << "1 0.3 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n";
  refuses(R"("frame": "camera", "pose": "scan_scene_shear_pose.txt",
             "pose_uncertainty": {"degrees": 1, "length": 1})",
          "scan_scene_shear_pose.txt: pose matrix: the 3x3 block is not a scaled rotation");
  const softhd::Scene arc = softhd::parse_scene(R"({
    "mesh": { "type": "box", "lower": [0, 0, 0], "upper": [2, 1, 0.2], "cells": [2, 1, 1], "order": 1 },
    "material": { "model": "mooney_rivlin", "a": 1e5, "b": 2e4, "c": 3e5 },
    "fibers": [1, 0, 0], "clamp": ["x0"],
    "control": { "space": "vertex", "lower": -1e5, "upper": 0, "initial": 0 },
    "target": {"kind": "arc", "frame": "camera"}})",
                                                testing::TempDir() + "/scan_scene_arc.json");
  expect_error<Error>([&] { scene_target(arc, arc.body.make_mesh()); }, "unknown key 'frame'");
}

// Without "pose" the start is align against the body at rest: for the rest nodes seen from a
// camera (moved by a rigid motion) it puts every scan point on a node (to 1e-6 of the body's
// size; which of the box's symmetric poses is not asked).
TEST(ScanScene, CameraFrameWithoutAPoseStartsFromAlign) {
  const softhd::Scene s0 = scene_with(R"({"kind": "arc"})");
  const fe::Assembler A = s0.body.make_assembler();
  const Eigen::MatrixXd& nodes = A.mesh().nodes;
  Eigen::Matrix<double, 7, 1> tw;
  tw << 0.7, -0.4, 1.1, 3.0, -1.0, 2.0, 0.0;
  const scan::Pose G = scan::Pose::from_twist(tw);
  write_ply_cloud(testing::TempDir() + "/scan_scene_rest.ply", G.apply(PointCloud(nodes), false));
  const softhd::Scene s = scene_with(R"({"kind": "cloud", "file": "scan_scene_rest.ply",
                                      "frame": "camera"})");
  const SceneTarget t = scene_target(s, s.body.make_mesh());
  EXPECT_FALSE(t.pose);
  EXPECT_NE(t.description.find("start pose by align"), std::string::npos) << t.description;
  ShapeObjectiveOptions o;
  apply_target_settings(t, &o);
  const Eigen::MatrixXd moved = scan::apply_points(start_pose(t, A, o), t.cloud.points());
  double worst = 0.0;
  for (Eigen::Index i = 0; i < moved.rows(); ++i)
    worst = std::max(worst, (nodes.rowwise() - moved.row(i)).rowwise().norm().minCoeff());
  EXPECT_LT(worst, 1e-6 * std::sqrt(2.0 * 2.0 + 1.0 + 0.04));
  const softhd::Scene body = scene_with(R"({"kind": "cloud", "file": "scan_scene_rest.ply"})");
  expect_error<InvalidArgument>(
      [&] { start_pose(scene_target(body, body.body.make_mesh()), A, o); }, "body's frame");
}

}  // namespace
}  // namespace softhd::test
