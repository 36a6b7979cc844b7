#pragma once
/// \file vtu.hpp
/// ParaView output (docs/formulation.md §6.2): VTK XML unstructured grids (.vtu, ascii) of a
/// deformed mesh or a point cloud, and .pvd collections that make a series of them a time line. Q2
/// elements are written as 2^dim linear sub-cells through their nodes, so nodal data are shown
/// exactly.

#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

#include "softhd/fe/mesh.hpp"
#include "softhd/io/atomic_file.hpp"
#include "softhd/point_cloud.hpp"

namespace softhd {

/// A named field: one row per point (or per cell), one column per component.
struct VtuField {
  std::string name;        ///< the field's name in ParaView
  Eigen::MatrixXd values;  ///< rows: points or cells; columns: components
};

/// The mesh moved by the displacement u (num_nodes · dim entries, node-major), with
/// point fields (num_nodes rows) and cell fields (num_elements rows). Throws
/// FileError if the file cannot be written, InvalidArgument for mis-sized fields.
void write_vtu_mesh(const std::string& path, const fe::Mesh& mesh, const Eigen::VectorXd& u,
                    const std::vector<VtuField>& point_fields,
                    const std::vector<VtuField>& cell_fields = {});

/// A point cloud as vertex cells, with its volumes and the given point fields.
void write_vtu_cloud(const std::string& path, const PointCloud& cloud,
                     const std::vector<VtuField>& point_fields = {});

/// A ParaView collection: (time, file name relative to the .pvd) pairs.
void write_pvd(const std::string& path, const std::vector<std::pair<double, std::string>>& files);

}  // namespace softhd
