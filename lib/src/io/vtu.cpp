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

void write_vtu_grid(const std::string& path, const VtuGrid& grid,
                    const std::vector<VtuField>& point_fields,
                    const std::vector<VtuField>& cell_fields) {
  check_rows(point_fields, grid.points.rows(), "points");
  check_rows(cell_fields, static_cast<Eigen::Index>(grid.cells.size()), "cells");
  std::ostringstream s;
  s.precision(12);
  s << kHeader << "    <Piece NumberOfPoints=\"" << grid.points.rows() << "\" NumberOfCells=\""
    << grid.cells.size() << "\">\n";
  write_points(s, grid.points);
  write_cells(s, grid.cells, grid.vtk_type);
  write_fields(s, "PointData", point_fields);
  write_fields(s, "CellData", cell_fields);
  s << kFooter;
  write_file_atomically(path, s.str());
}

void write_vtu_cloud(const std::string& path, const PointCloud& cloud,
                     const std::vector<VtuField>& point_fields) {
  VtuGrid grid{cloud.points(), std::vector<std::vector<int>>(static_cast<size_t>(cloud.size())),
               1};  // VTK_VERTEX
  for (Eigen::Index i = 0; i < cloud.size(); ++i)
    grid.cells[static_cast<size_t>(i)] = {static_cast<int>(i)};
  std::vector<VtuField> pf = point_fields;
  pf.insert(pf.begin(), VtuField{"volume", cloud.volumes()});
  write_vtu_grid(path, grid, pf);
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
