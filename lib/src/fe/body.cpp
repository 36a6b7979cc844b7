#include "softhd/fe/body.hpp"

#include <algorithm>

#include "softhd/error.hpp"
#include "softhd/fe/dofs.hpp"
#include "softhd/fe/newton.hpp"

namespace softhd::fe {

Mesh Body::make_mesh() const {
  return file_mesh ? *file_mesh : make_box_mesh(lower, upper, cells, order);
}

Assembler Body::make_assembler() const {
  return Assembler(make_mesh(), materials, fiber_field, constraints, AssemblerStorage::kFull,
                   quadrature_degree);
}

double Body::residual_floor() const {
  double stiffness = 0.0;
  for (const auto& m : materials) stiffness = std::max(stiffness, m->stiffness_scale());
  return fe::residual_floor(stiffness, volume, dim());
}

Body box_body(const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
              const Eigen::VectorXi& cells, int order, std::shared_ptr<const Material> material,
              const std::vector<std::string>& clamp, double control_lower, double control_upper) {
  const Eigen::Index d = lower.size();
  if ((d != 2 && d != 3) || upper.size() != d || cells.size() != d)
    throw InvalidArgument("box_body: lower, upper and cells must have 2 or 3 entries each");
  if (!((upper - lower).array() > 0.0).all())
    throw InvalidArgument("box_body: upper must be > lower on every axis");
  if ((cells.array() < 1).any()) throw InvalidArgument("box_body: cells must be >= 1");
  if (order != 1 && order != 2) throw InvalidArgument("box_body: order must be 1 or 2");
  if (!material) throw InvalidArgument("box_body: material is null");
  if (clamp.empty()) throw InvalidArgument("box_body: clamp names no boundary set");
  if (!(control_lower <= 0.0 && 0.0 <= control_upper))
    throw InvalidArgument("box_body: the bounds [control_lower, control_upper] must hold 0");
  Body b;
  b.source = "box_body";
  b.lower = lower;
  b.upper = upper;
  b.cells = cells;
  b.order = order;
  b.materials.assign(1, std::move(material));  // a box has one region, "body"
  for (const std::string& name : clamp) b.constraints.push_back({name, {}});
  b.control_lower = control_lower;
  b.control_upper = control_upper;
  b.volume = (upper - lower).prod();           // |Ω₀| = Π (upper_i − lower_i)
  make_dof_map(b.make_mesh(), b.constraints);  // throws for a name that is no face
  return b;
}

}  // namespace softhd::fe
