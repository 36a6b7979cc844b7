#pragma once
// softhd._core.Mesh: a body's mesh and its volume, for Python (read_mesh, Scene.mesh).

#include "common.hpp"
#include "softhd/fe/assembly.hpp"
#include "softhd/fe/mesh.hpp"

namespace softhd::python {

/// A mesh and |Ω₀| by softhd's quadrature.
struct PyMesh {
  fe::Mesh mesh;
  double volume = 0.0;
};

/// The mesh of an assembler, with its quadrature volume.
PyMesh mesh_of(const fe::Assembler& assembler);

}  // namespace softhd::python
