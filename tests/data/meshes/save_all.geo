// The unit cube of cube_tet.geo, coarser, with a physical group on the lower volume only,
// saved with Mesh.SaveAll (as `gmsh -save_all`): the upper volume's tetrahedra are in the
// file, in no physical group. softhd refuses it naming the entity (tests/fe/test_gmsh_mesh).
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 0.6};
Box(2) = {0, 0, 0.6, 1, 1, 0.4};
BooleanFragments{ Volume{1, 2}; Delete; }{}
Physical Volume("body", 1) = {1};
Physical Surface("base", 11) = Surface In BoundingBox{-1e-6, -1e-6, -1e-6, 1e-6, 1 + 1e-6, 1 + 1e-6};
Mesh.MeshSizeMin = 0.5;
Mesh.MeshSizeMax = 0.5;
Mesh.SaveAll = 1;
