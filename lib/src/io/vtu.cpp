#include "softhd/io/vtu.hpp"

#include <cstdio>
#include <fstream>
#include <sstream>

#include "softhd/error.hpp"

namespace softhd {

namespace {

void check_rows(const std::vector<VtuField>& fields, Eigen::Index rows, const char* what) {
  for (const VtuField& f : fields)
    if (f.values.rows() != rows)
      throw InvalidArgument("VTU field '" + f.name + "' has " + std::to_string(f.values.rows()) +
                            " rows for " + std::to_string(rows) + " " + what);
}

void write_fields(std::ostringstream& s, const char* tag, const std::vector<VtuField>& fields) {
  s << "      <" << tag << ">\n";
  for (const VtuField& f : fields) {
    s << "        <DataArray type=\"Float64\" Name=\"" << f.name << "\" NumberOfComponents=\""
      << f.values.cols() << "\" format=\"ascii\">\n";
    for (Eigen::Index i = 0; i < f.values.rows(); ++i) {
      for (Eigen::Index c = 0; c < f.values.cols(); ++c) s << ' ' << f.values(i, c);
      s << '\n';
    }
    s << "        </DataArray>\n";
  }
  s << "      </" << tag << ">\n";
}

void write_points(std::ostringstream& s, const Eigen::MatrixXd& x) {
  s << "      <Points>\n        <DataArray type=\"Float64\" NumberOfComponents=\"3\" "
       "format=\"ascii\">\n";
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    s << ' ' << x(i, 0) << ' ' << x(i, 1) << ' ' << (x.cols() == 3 ? x(i, 2) : 0.0) << '\n';
  s << "        </DataArray>\n      </Points>\n";
}

void write_cells(std::ostringstream& s, const std::vector<std::vector<int>>& cells, int type) {
  s << "      <Cells>\n        <DataArray type=\"Int64\" Name=\"connectivity\" "
       "format=\"ascii\">\n";
  for (const auto& c : cells) {
    for (int n : c) s << ' ' << n;
    s << '\n';
  }
  s << "        </DataArray>\n        <DataArray type=\"Int64\" Name=\"offsets\" "
       "format=\"ascii\">\n";
  long offset = 0;
  for (const auto& c : cells) s << ' ' << (offset += static_cast<long>(c.size()));
  s << "\n        </DataArray>\n        <DataArray type=\"UInt8\" Name=\"types\" "
       "format=\"ascii\">\n";
  for (size_t k = 0; k < cells.size(); ++k) s << ' ' << type;
  s << "\n        </DataArray>\n      </Cells>\n";
}

const char* kHeader =
    "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
    "byte_order=\"LittleEndian\" header_type=\"UInt64\">\n  <UnstructuredGrid>\n";
const char* kFooter = "    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n";

}  // namespace

void write_vtu_mesh(const std::string& path, const fe::Mesh& mesh, const Eigen::VectorXd& u,
                    const std::vector<VtuField>& point_fields,
                    const std::vector<VtuField>& cell_fields) {
  const int d = mesh.dim;
  if (u.size() != mesh.num_nodes() * d)
    throw InvalidArgument("VTU: displacement has " + std::to_string(u.size()) +
                          " entries, expected " + std::to_string(mesh.num_nodes() * d));
  check_rows(point_fields, mesh.num_nodes(), "nodes");
  check_rows(cell_fields, mesh.num_elements(), "elements");
  const Eigen::MatrixXd x =
      mesh.nodes + Eigen::Map<const Eigen::MatrixXd>(u.data(), d, mesh.num_nodes()).transpose();
  // One VTK cell per element, of the cell type's VTK type, nodes in VTK's order
  // (reference_element(cell).vtk_order: VTK 29 and 24 for hex27 and tet10, 28 and 22 in 2D).
  const fe::ReferenceElement& ref = fe::reference_element(mesh.cell);
  std::vector<std::vector<int>> cells(static_cast<std::size_t>(mesh.num_elements()));
  for (Eigen::Index e = 0; e < mesh.num_elements(); ++e)
    for (int a : ref.vtk_order) cells[static_cast<std::size_t>(e)].push_back(mesh.elements(e, a));
  std::vector<VtuField> cf = cell_fields;
  if (mesh.region_names.size() > 1)  // region ids (mesh.region_names order)
    cf.push_back({"region", mesh.element_region.cast<double>()});
  std::ostringstream s;
  s.precision(12);
  s << kHeader << "    <Piece NumberOfPoints=\"" << x.rows() << "\" NumberOfCells=\""
    << cells.size() << "\">\n";
  write_points(s, x);
  write_cells(s, cells, ref.vtk_type);
  std::vector<VtuField> pf = point_fields;
  Eigen::MatrixXd u3 = Eigen::MatrixXd::Zero(mesh.num_nodes(), 3);
  u3.leftCols(d) = x - mesh.nodes;
  pf.insert(pf.begin(), VtuField{"displacement", u3});
  write_fields(s, "PointData", pf);
  write_fields(s, "CellData", cf);
  s << kFooter;
  write_file_atomically(path, s.str());
}

void write_vtu_cloud(const std::string& path, const PointCloud& cloud,
                     const std::vector<VtuField>& point_fields) {
  check_rows(point_fields, cloud.size(), "points");
  std::vector<std::vector<int>> cells(static_cast<size_t>(cloud.size()));
  for (Eigen::Index i = 0; i < cloud.size(); ++i)
    cells[static_cast<size_t>(i)] = {static_cast<int>(i)};
  std::ostringstream s;
  s.precision(12);
  s << kHeader << "    <Piece NumberOfPoints=\"" << cloud.size() << "\" NumberOfCells=\""
    << cloud.size() << "\">\n";
  write_points(s, cloud.points());
  write_cells(s, cells, 1);  // VTK_VERTEX
  std::vector<VtuField> pf = point_fields;
  pf.insert(pf.begin(), VtuField{"volume", cloud.volumes()});
  write_fields(s, "PointData", pf);
  s << kFooter;
  write_file_atomically(path, s.str());
}

void write_pvd(const std::string& path, const std::vector<std::pair<double, std::string>>& files) {
  std::ostringstream s;
  s << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"1.0\">\n  <Collection>\n";
  for (const auto& [t, f] : files)
    s << "    <DataSet timestep=\"" << t << "\" part=\"0\" file=\"" << f << "\"/>\n";
  s << "  </Collection>\n</VTKFile>\n";
  write_file_atomically(path, s.str());
}

}  // namespace softhd
