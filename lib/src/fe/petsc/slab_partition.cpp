#include "slab_partition.hpp"

#include <algorithm>
#include <string>

#include "softhd/error.hpp"

namespace softhd::fe::petsc_detail {

namespace {

// Grid extents (nodes or cells) of a box, 1 along missing axes.
struct Grid {
  int n[3] = {1, 1, 1};
  int id(const int g[3]) const { return g[0] + n[0] * (g[1] + n[1] * g[2]); }
  void index(int id, int g[3]) const {
    g[0] = id % n[0];
    g[1] = (id / n[0]) % n[1];
    g[2] = id / (n[0] * n[1]);
  }
};

// Maps the ids of a slab grid (extent `local` along the axis) to the global grid's.
std::vector<int> to_global(const Grid& global, const Grid& local, int axis, int offset) {
  const int count = local.n[0] * local.n[1] * local.n[2];
  std::vector<int> out(count);
  int g[3];
  for (int id = 0; id < count; ++id) {
    local.index(id, g);
    g[axis] += offset;
    out[id] = global.id(g);
  }
  return out;
}

// The face's axis and side ("y1": axis 1, side 1).
void face_axis(const std::string& face, int* axis, int* side) {
  *axis = face.size() == 2 ? face[0] - 'x' : -1;
  *side = face.size() == 2 ? face[1] - '0' : -1;
}

}  // namespace

SlabPartition make_slab_partition(const Scene& scene, int rank, int size) {
  if (!scene.is_box())
    throw InvalidArgument("the PETSc state backends partition box bodies only; the mesh of " +
                          scene.mesh_file + " is solved with --state-backend cholmod");
  const int dim = scene.dim(), p = scene.order;
  SlabPartition s;
  s.rank = rank;
  s.size = size;
  for (int d = 1; d < dim; ++d)
    if (scene.cells[d] > scene.cells[s.axis]) s.axis = d;
  const int a = s.axis, nc = scene.cells[a];
  if (nc < size) {
    throw InvalidArgument("PETSc state: the mesh has " + std::to_string(nc) +
                          " cells along its longest axis, fewer than the " + std::to_string(size) +
                          " ranks");
  }
  s.c0 = static_cast<int>(static_cast<std::int64_t>(nc) * rank / size);
  s.c1 = static_cast<int>(static_cast<std::int64_t>(nc) * (rank + 1) / size);
  Eigen::VectorXd lo = scene.lower, hi = scene.upper;
  Eigen::VectorXi cells = scene.cells;
  const double len = scene.upper[a] - scene.lower[a];
  lo[a] = scene.lower[a] + len * s.c0 / nc;
  hi[a] = scene.lower[a] + len * s.c1 / nc;
  cells[a] = s.c1 - s.c0;
  s.mesh = make_box_mesh(lo, hi, cells, p);
  Grid gn, ln, gc, lc, gv, lv;
  for (int d = 0; d < dim; ++d) {
    gn.n[d] = p * scene.cells[d] + 1;
    ln.n[d] = p * cells[d] + 1;
    gc.n[d] = scene.cells[d];
    lc.n[d] = cells[d];
    gv.n[d] = scene.cells[d] + 1;
    lv.n[d] = cells[d] + 1;
  }
  s.global_node = to_global(gn, ln, a, p * s.c0);
  s.global_element = to_global(gc, lc, a, s.c0);
  s.global_vertex = to_global(gv, lv, a, s.c0);
  s.num_global_nodes = static_cast<Eigen::Index>(gn.n[0]) * gn.n[1] * gn.n[2];
  s.num_global_elements = static_cast<Eigen::Index>(gc.n[0]) * gc.n[1] * gc.n[2];
  s.num_global_vertices = static_cast<Eigen::Index>(gv.n[0]) * gv.n[1] * gv.n[2];
  // The global mesh's coordinates, bit for bit (make_box_mesh's formula on the global grid).
  for (Eigen::Index n = 0; n < s.mesh.num_nodes(); ++n) {
    int g[3];
    gn.index(s.global_node[n], g);
    for (int d = 0; d < dim; ++d)
      s.mesh.nodes(n, d) = scene.lower[d] + (scene.upper[d] - scene.lower[d]) *
                                                static_cast<double>(g[d]) / (gn.n[d] - 1);
  }
  // A constraint on a face across the slab axis applies only where that face is global.
  for (const DirichletConstraint& c : scene.constraints) {
    int axis, side;
    face_axis(c.face, &axis, &side);
    if (axis == a && ((side == 0 && s.c0 != 0) || (side == 1 && s.c1 != nc))) continue;
    s.constraints.push_back(c);
  }
  return s;
}

FreeNumbering number_free_dofs(const Scene& scene, const SlabPartition& slab,
                               const DofMap& slab_dofs) {
  const int dim = scene.dim(), p = scene.order, a = slab.axis;
  Grid gn;
  for (int d = 0; d < dim; ++d) gn.n[d] = p * scene.cells[d] + 1;
  // The two other axes, lower first (the in-plane order).
  int b = -1, c = -1;
  for (int d = 0; d < 3; ++d)
    if (d != a) (b < 0 ? b : c) = d;
  auto fixed = [&](const int g[3], int comp) {
    for (const DirichletConstraint& con : scene.constraints) {
      int axis, side;
      face_axis(con.face, &axis, &side);
      if (axis < 0 || axis > 2) continue;  // the scene's faces are checked when it is parsed
      if (g[axis] != (side == 0 ? 0 : gn.n[axis] - 1)) continue;
      if (con.components.empty() ||
          std::find(con.components.begin(), con.components.end(), comp) != con.components.end())
        return true;
    }
    return false;
  };
  // Free dofs of plane ia along the slab axis: all interior planes are alike.
  auto plane_free = [&](int ia) {
    std::int64_t count = 0;
    int g[3];
    g[a] = ia;
    for (g[c] = 0; g[c] < gn.n[c]; ++g[c])
      for (g[b] = 0; g[b] < gn.n[b]; ++g[b])
        for (int k = 0; k < dim; ++k) count += fixed(g, k) ? 0 : 1;
    return count;
  };
  const int last = gn.n[a] - 1;
  const std::int64_t first_free = plane_free(0), last_free = plane_free(last),
                     inner_free = last > 1 ? plane_free(1) : 0;
  auto offset = [&](int ia) { return ia == 0 ? 0 : first_free + (ia - 1) * inner_free; };
  FreeNumbering f;
  f.num_global = offset(last) + last_free;
  f.owned_begin = offset(p * slab.c0);
  f.owned_end = slab.rank == slab.size - 1 ? f.num_global : offset(p * slab.c1);
  f.local_to_global.assign(slab_dofs.num_free, -1);
  Grid ln;
  for (int d = 0; d < dim; ++d) ln.n[d] = slab.mesh.dim > d ? gn.n[d] : 1;
  ln.n[a] = p * (slab.c1 - slab.c0) + 1;
  for (int il = 0; il < ln.n[a]; ++il) {
    const int ia = il + p * slab.c0;
    const bool owned = ia < p * slab.c1 || slab.rank == slab.size - 1;
    std::int64_t next = offset(ia);
    int g[3], l[3];
    g[a] = ia;
    l[a] = il;
    for (g[c] = 0; g[c] < gn.n[c]; ++g[c])
      for (g[b] = 0; g[b] < gn.n[b]; ++g[b]) {
        l[b] = g[b];
        l[c] = g[c];
        int free_components = 0;
        for (int k = 0; k < dim; ++k) {
          const int fi = slab_dofs.free_index[static_cast<Eigen::Index>(ln.id(l)) * dim + k];
          if (fixed(g, k) != (fi < 0))
            throw Error("PETSc state: the slab's constraints differ from the mesh's (a bug)");
          if (fi < 0) continue;
          ++free_components;
          f.local_to_global[fi] = next;
          if (owned) {
            f.owned_local.push_back(fi);
            f.owned_global_dof.push_back(static_cast<std::int64_t>(gn.id(g)) * dim + k);
          }
          ++next;
        }
        if (free_components != 0 && free_components != dim) f.whole_nodes = false;
      }
  }
  if (static_cast<std::int64_t>(f.owned_local.size()) != f.owned_end - f.owned_begin)
    throw Error("PETSc state: inconsistent free-dof numbering (a bug)");
  return f;
}

}  // namespace softhd::fe::petsc_detail
