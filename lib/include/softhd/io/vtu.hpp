#pragma once
/// \file vtu.hpp
/// ParaView output (docs/formulation.md §6.2): VTK XML unstructured grids (.vtu, ascii) of a
/// grid of cells (fe::write_vtu_mesh makes one of a deformed mesh) or a point cloud, and .pvd
/// collections that make a series of them a time line. Knows no FE types.

#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

#include "softhd/io/atomic_file.hpp"
#include "softhd/point_cloud.hpp"

namespace softhd {

/// A named field: one row per point (or per cell), one column per component.
struct VtuField {
  std::string name;        ///< the field's name in ParaView
  Eigen::MatrixXd values;  ///< rows: points or cells; columns: components
};

/// An unstructured grid of one VTK cell type: points (N by 2 or 3; z = 0 in 2D) and cells as
/// lists of point indices in VTK's node order.
struct VtuGrid {
  Eigen::MatrixXd points;               ///< N by 2 or 3
  std::vector<std::vector<int>> cells;  ///< point indices per cell, VTK's order
  int vtk_type = 1;                     ///< the VTK cell type of every cell (1: vertex)
};

/// The grid with point fields (N rows) and cell fields (one row per cell). Throws FileError
/// if the file cannot be written, InvalidArgument for mis-sized fields.
void write_vtu_grid(const std::string& path, const VtuGrid& grid,
                    const std::vector<VtuField>& point_fields,
                    const std::vector<VtuField>& cell_fields = {});

/// A point cloud as vertex cells, with its volumes and the given point fields.
void write_vtu_cloud(const std::string& path, const PointCloud& cloud,
                     const std::vector<VtuField>& point_fields = {});

/// A ParaView collection: (time, file name relative to the .pvd) pairs.
void write_pvd(const std::string& path, const std::vector<std::pair<double, std::string>>& files);

}  // namespace softhd
