#include "softhd/fe/dofs.hpp"

#include "softhd/error.hpp"

namespace softhd::fe {

Eigen::VectorXd DofMap::expand(const Eigen::VectorXd& free_values) const {
  Eigen::VectorXd full = Eigen::VectorXd::Zero(num_dofs);
  for (Eigen::Index i = 0; i < num_free; ++i) full[free_dofs[i]] = free_values[i];
  return full;
}

Eigen::VectorXd DofMap::restrict(const Eigen::VectorXd& full_values) const {
  Eigen::VectorXd r(num_free);
  for (Eigen::Index i = 0; i < num_free; ++i) r[i] = full_values[free_dofs[i]];
  return r;
}

DofMap make_dof_map(const Mesh& mesh, const std::vector<DirichletConstraint>& constraints) {
  DofMap map;
  map.dim = mesh.dim;
  map.num_dofs = mesh.num_nodes() * mesh.dim;
  std::vector<char> fixed(map.num_dofs, 0);
  for (const DirichletConstraint& c : constraints) {
    const std::vector<int>& nodes = mesh.face(c.face);
    std::vector<int> comps = c.components;
    if (comps.empty())
      for (int k = 0; k < mesh.dim; ++k) comps.push_back(k);
    for (int k : comps) {
      if (k < 0 || k >= mesh.dim) {
        throw InvalidArgument("constraint on face '" + c.face + "': component " +
                              std::to_string(k) + " is not in 0.." + std::to_string(mesh.dim - 1));
      }
      for (int n : nodes) fixed[static_cast<size_t>(n) * mesh.dim + k] = 1;
    }
  }
  map.free_index = Eigen::VectorXi::Constant(map.num_dofs, -1);
  std::vector<int> free;
  for (Eigen::Index d = 0; d < map.num_dofs; ++d) {
    if (!fixed[d]) {
      map.free_index[d] = static_cast<int>(free.size());
      free.push_back(static_cast<int>(d));
    }
  }
  map.num_free = static_cast<Eigen::Index>(free.size());
  map.free_dofs = Eigen::Map<Eigen::VectorXi>(free.data(), map.num_free);
  return map;
}

}  // namespace softhd::fe
