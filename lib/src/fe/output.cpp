#include "softhd/fe/output.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>

#include "softhd/error.hpp"
#include "softhd/fe/interpolation.hpp"
#include "softhd/fe/reference_element.hpp"
#include "softhd/io/atomic_file.hpp"
#include "softhd/io/vtu.hpp"

namespace softhd::fe {

Eigen::VectorXd probe_displacement(const Assembler& assembler, const Eigen::VectorXd& u,
                                   const Eigen::VectorXd& X) {
  return probe_displacement(assembler.mesh(), u, X);
}

Eigen::VectorXd probe_displacement(const Mesh& mesh, const Eigen::VectorXd& u,
                                   const Eigen::VectorXd& X) {
  // u(X) = Σ_a N_a(ξ) u_a in the element containing X
  std::vector<int> outside;
  const Eigen::MatrixXd v =
      X.size() != mesh.dim ? Eigen::MatrixXd()
                           : interpolate_nodal(mesh, PointLocator(mesh),
                                               u.reshaped(mesh.dim, mesh.num_nodes()).transpose(),
                                               X.transpose(), &outside);
  if (X.size() != mesh.dim || !outside.empty()) {
    std::ostringstream os;
    os << "probe (" << X.transpose() << ") is outside the body";
    throw InvalidArgument(os.str());
  }
  return v.row(0).transpose();
}

void write_vtu_mesh(const std::string& path, const Mesh& mesh, const Eigen::VectorXd& u,
                    const std::vector<VtuField>& point_fields,
                    const std::vector<VtuField>& cell_fields) {
  const int d = mesh.dim;
  if (u.size() != mesh.num_nodes() * d)
    throw InvalidArgument("VTU: displacement has " + std::to_string(u.size()) +
                          " entries, expected " + std::to_string(mesh.num_nodes() * d));
  // One VTK cell per element, of the cell type's VTK type, nodes in VTK's order
  // (reference_element(cell).vtk_order: VTK 29 and 24 for hex27 and tet10, 28 and 22 in 2D).
  const ReferenceElement& ref = reference_element(mesh.cell);
  VtuGrid grid;
  grid.points =
      mesh.nodes + Eigen::Map<const Eigen::MatrixXd>(u.data(), d, mesh.num_nodes()).transpose();
  grid.vtk_type = ref.vtk_type;
  grid.cells.resize(static_cast<std::size_t>(mesh.num_elements()));
  for (Eigen::Index e = 0; e < mesh.num_elements(); ++e)
    for (int a : ref.vtk_order)
      grid.cells[static_cast<std::size_t>(e)].push_back(mesh.elements(e, a));
  std::vector<VtuField> pf = point_fields, cf = cell_fields;
  Eigen::MatrixXd u3 = Eigen::MatrixXd::Zero(mesh.num_nodes(), 3);
  u3.leftCols(d) = grid.points - mesh.nodes;
  pf.insert(pf.begin(), VtuField{"displacement", u3});
  if (mesh.region_names.size() > 1)  // region ids (mesh.region_names order)
    cf.push_back({"region", mesh.element_region.cast<double>()});
  write_vtu_grid(path, grid, pf, cf);
}

void write_vtu(const std::string& path, const Mesh& mesh, const Eigen::VectorXd& u,
               const Eigen::MatrixXd& m_qp, const Eigen::MatrixXd& J_qp) {
  // Element means of m and J as cell data.
  write_vtu_mesh(path, mesh, u, {}, {{"m", m_qp.rowwise().mean()}, {"J", J_qp.rowwise().mean()}});
}

Eigen::VectorXd read_control_file(const std::string& path, const Eigen::MatrixXd& positions) {
  std::ifstream in(path);
  if (!in) throw FileError("control file " + path + ": cannot open");
  const int dim = static_cast<int>(positions.cols());
  // Tolerance: 1 % of the smallest gap between distinct control coordinates along an axis,
  // so rows written with ~6 significant digits still match their node.
  double gap = std::numeric_limits<double>::infinity();
  for (int d = 0; d < dim; ++d) {
    std::vector<double> c(positions.col(d).data(), positions.col(d).data() + positions.rows());
    std::sort(c.begin(), c.end());
    for (size_t i = 1; i < c.size(); ++i)
      if (c[i] - c[i - 1] > 1e-12 * (std::abs(c[i]) + 1.0)) gap = std::min(gap, c[i] - c[i - 1]);
  }
  const double tol = std::isfinite(gap) ? 0.01 * gap : 1e-9;
  std::vector<Eigen::VectorXd> rows;
  std::vector<int> row_lines;  // the file line of each row
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const size_t hash = line.find('#');
    if (hash != std::string::npos) line.erase(hash);
    for (char& ch : line)
      if (ch == ',') ch = ' ';
    std::istringstream ls(line);
    std::vector<double> v;
    double x;
    while (ls >> x) v.push_back(x);
    if (!ls.eof()) {
      throw FileError("control file " + path + ": line " + std::to_string(line_no) +
                      " has a non-numeric entry");
    }
    if (v.empty()) continue;
    if (static_cast<int>(v.size()) != dim + 1) {
      throw FileError("control file " + path + ": line " + std::to_string(line_no) + " has " +
                      std::to_string(v.size()) + " numbers, expected " + std::to_string(dim + 1) +
                      " (X1 X2" + (dim == 3 ? " X3" : "") + " m)");
    }
    rows.push_back(Eigen::Map<Eigen::VectorXd>(v.data(), dim + 1));
    row_lines.push_back(line_no);
  }
  // Linear search per control node: O(N rows), fine for the control meshes of the scenes.
  std::vector<char> used(rows.size(), 0);
  Eigen::VectorXd m(positions.rows());
  for (Eigen::Index k = 0; k < positions.rows(); ++k) {
    bool found = false;
    std::size_t first = 0;
    for (size_t r = 0; r < rows.size(); ++r) {
      if ((rows[r].head(dim) - positions.row(k).transpose()).norm() > tol) continue;
      if (!found) {
        m[k] = rows[r][dim];
        found = true;
        first = r;
      } else if (rows[r][dim] != m[k]) {  // two values for one node: which one was meant?
        throw FileError("control file " + path + ": lines " + std::to_string(row_lines[first]) +
                        " and " + std::to_string(row_lines[r]) +
                        " give different values for the same control node");
      }
    }
    if (!found) {
      std::ostringstream os;
      os << "control file " << path << ": no row for control node " << k << " at ("
         << positions.row(k) << ")";
      throw FileError(os.str());
    }
  }
  return m;
}

void write_control_file(const std::string& path, const Eigen::MatrixXd& positions,
                        const Eigen::VectorXd& values) {
  std::ostringstream out;
  out << "# control nodes: X1 X2" << (positions.cols() == 3 ? " X3" : "") << " m\n";
  out.precision(17);
  for (Eigen::Index k = 0; k < positions.rows(); ++k) {
    for (Eigen::Index d = 0; d < positions.cols(); ++d) out << positions(k, d) << ' ';
    out << values[k] << '\n';
  }
  write_file_atomically(path, out.str());
}

}  // namespace softhd::fe
