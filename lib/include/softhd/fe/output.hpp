#pragma once
/// \file output.hpp
/// Results of a state solve for people and tools: displacement probes by FE
/// interpolation, VTU files for ParaView, and control files (text rows `X1 X2 [X3] m`).

#include <Eigen/Core>
#include <string>
#include <vector>

#include "softhd/fe/assembly.hpp"
#include "softhd/io/vtu.hpp"

namespace softhd::fe {

/// u(X) = Σ_a N_a(ξ) u_a in the element containing the reference point X (size dim).
/// Throws InvalidArgument if X is outside the body.
Eigen::VectorXd probe_displacement(const Assembler& assembler, const Eigen::VectorXd& u,
                                   const Eigen::VectorXd& X);
/// The same on a mesh alone (u: num_nodes · dim entries).
Eigen::VectorXd probe_displacement(const Mesh& mesh, const Eigen::VectorXd& u,
                                   const Eigen::VectorXd& X);

/// The mesh moved by the displacement u (num_nodes · dim entries, node-major) as an ASCII VTU:
/// one VTK cell per element (quadratic cells as VTK's quadratic types), point data
/// "displacement" then `point_fields` (num_nodes rows), cell data `cell_fields` (num_elements
/// rows) then "region" when the mesh has several. Throws FileError if the file cannot be
/// written, InvalidArgument for mis-sized u or fields.
void write_vtu_mesh(const std::string& path, const Mesh& mesh, const Eigen::VectorXd& u,
                    const std::vector<VtuField>& point_fields,
                    const std::vector<VtuField>& cell_fields = {});

/// Writes an ASCII VTU (VTK unstructured grid) of the deformed mesh: points at X + u,
/// point data "displacement", cell data "m" and "J" (element means, E by nq inputs). Q2
/// elements as VTK's quadratic cells. Throws FileError if it cannot write.
void write_vtu(const std::string& path, const Mesh& mesh, const Eigen::VectorXd& u,
               const Eigen::MatrixXd& m_qp, const Eigen::MatrixXd& J_qp);

/// Reads rows `X1 X2 [X3] m` ('#' comments, commas allowed) and matches them to
/// `positions` (size by dim) within 1 % of the smallest spacing of the control grid. Throws
/// FileError naming the first position without a row, or a malformed line.
Eigen::VectorXd read_control_file(const std::string& path, const Eigen::MatrixXd& positions);

/// Writes one row `X1 X2 [X3] m` per position. Throws FileError if it cannot write.
void write_control_file(const std::string& path, const Eigen::MatrixXd& positions,
                        const Eigen::VectorXd& values);

}  // namespace softhd::fe
