#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "softhd/error.hpp"
#include "softhd/fe/scene.hpp"

using namespace softhd::fe;

namespace {

std::string read(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

const std::string kBending = std::string(SOFTHD_SOURCE_DIR) + "/data/scenes/bending.json";
const std::string kTorsion = std::string(SOFTHD_SOURCE_DIR) + "/data/scenes/torsion.json";

// Expects FileError whose message contains every needle.
void expect_error(const std::string& text, const std::vector<std::string>& needles) {
  try {
    parse_scene(text, "test.json");
    ADD_FAILURE() << "no error for " << text;
  } catch (const softhd::FileError& e) {
    for (const auto& n : needles)
      EXPECT_NE(std::string(e.what()).find(n), std::string::npos) << e.what() << " lacks " << n;
  }
}

std::string replace(std::string s, const std::string& from, const std::string& to) {
  const size_t p = s.find(from);
  EXPECT_NE(p, std::string::npos) << from;
  return s.replace(p, from.size(), to);
}

}  // namespace

TEST(Scene, ReferenceScenesMatchSpec) {
  const Scene b = load_scene(kBending);
  EXPECT_EQ(b.name, "bending");
  EXPECT_EQ(b.dim(), 3);
  EXPECT_EQ(b.order, 2);
  EXPECT_EQ(b.make_mesh().num_nodes(), 5555);
  EXPECT_EQ(b.material_model, "mooney_rivlin");
  EXPECT_DOUBLE_EQ(b.material->a(), 1e5);
  EXPECT_DOUBLE_EQ(b.control_lower, -1e5);
  EXPECT_DOUBLE_EQ(b.control_upper, 0.0);
  EXPECT_EQ(b.constraints.size(), 1u);
  EXPECT_EQ(b.constraints[0].face, "x0");
  EXPECT_FALSE(b.target_json.empty());
  const Scene t = load_scene(kTorsion);
  EXPECT_EQ(t.material_model, "transversely_isotropic");
  EXPECT_DOUBLE_EQ(t.control_lower, -1.5e6);
  EXPECT_DOUBLE_EQ(t.upper[0], 50.0);
  EXPECT_TRUE(t.fibers.isApprox(Eigen::Vector3d::UnitX()));
}

TEST(Scene, InvalidFilesNameTheKey) {
  const std::string good = read(kBending);
  expect_error("{", {"not valid JSON"});
  expect_error(replace(good, "\"order\": 2", "\"order\": 3"), {"mesh.order", "1 or 2"});
  expect_error(replace(good, "\"cells\": [50, 5, 2]", "\"cells\": [50, 5]"), {"mesh.cells", "3"});
  expect_error(replace(good, "\"a\": 1e5", "\"a\": \"big\""), {"material.a", "number"});
  expect_error(replace(good, "\"b\": 2e4, ", ""), {"material.b", "missing"});
  expect_error(replace(good, "mooney_rivlin", "neo_hooke"), {"material.model"});
  expect_error(replace(good, "\"clamp\": [\"x0\"]", "\"clamp\": [\"q0\"]"), {"clamp", "q0"});
  expect_error(replace(good, "\"upper\": 0", "\"upper\": 3e5"), {"control.upper", "2a"});
  expect_error(replace(good, "\"space\": \"vertex\"", "\"space\": \"nodal\""), {"control.space"});
  EXPECT_THROW(load_scene("/nonexistent/scene.json"), softhd::FileError);
}
