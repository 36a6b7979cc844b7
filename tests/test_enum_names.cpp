// The enum name tables (softhd/enum_names.hpp) and the parsers built on them.

#include <gtest/gtest.h>

#include "expect_error.hpp"
#include "softhd/control/bounded_optimizer.hpp"
#include "softhd/control/shape_objective.hpp"
#include "softhd/enum_names.hpp"
#include "softhd/fe/control.hpp"
#include "softhd/fe/reference_element.hpp"

namespace softhd {
namespace {

using test::expect_error;

enum class Colour { red, green, blue };
constexpr EnumNames<Colour, 3> kColours{
    {{Colour::red, "red"}, {Colour::green, "green"}, {Colour::blue, "blue"}}};

TEST(EnumNames, BothDirections) {
  for (Colour c : {Colour::red, Colour::green, Colour::blue})
    EXPECT_EQ(enum_from_name(kColours, enum_name(kColours, c), "colour"), c);
  EXPECT_EQ(enum_name(kColours, Colour::green), "green");
  EXPECT_EQ(enum_choices(kColours), "red, green or blue");
  expect_error<InvalidArgument>([] { enum_from_name(kColours, "Red", "colour"); },
                                "unknown colour 'Red' (expected red, green or blue)");
}

TEST(EnumNames, ASequenceIsTheTableOfItsValuesInOrder) {
  constexpr auto seq = enum_sequence<Colour::blue>({"red", "green", "blue"});
  static_assert(seq.size() == 3);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(seq[k].first, kColours[k].first);
    EXPECT_STREQ(seq[k].second, kColours[k].second);
  }
  // The library's sequences name each value, the last included, in declaration order.
  EXPECT_EQ(to_string(Algorithm::newton), "newton");
  EXPECT_EQ(to_string(OptimizerStatus::iteration_limit), "iteration_limit");
  EXPECT_EQ(to_string(OptimizerStatus::hessian_failed), "hessian_failed");
  EXPECT_EQ(fe::to_string(fe::CellType::kHex27), "hex27");
  EXPECT_EQ(fe::parse_cell_type("tet10"), fe::CellType::kTet10);
}

TEST(EnumNames, LibraryParsers) {
  EXPECT_EQ(particles_from_string("quadrature"), Particles::quadrature);
  EXPECT_EQ(particles_from_string("boundary"), Particles::boundary);
  EXPECT_EQ(to_string(ParticleVolumes::deformed), "deformed");
  EXPECT_EQ(fe::parse_control_kind("element"), fe::ControlKind::kElement);
  expect_error<InvalidArgument>([] { particle_volumes_from_string("moving"); },
                                "unknown volumes 'moving' (expected reference or deformed)");
  expect_error<InvalidArgument>([] { fe::parse_control_kind("node"); },
                                "unknown control space 'node' (expected vertex or element)");
}

}  // namespace
}  // namespace softhd
