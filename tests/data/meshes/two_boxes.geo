// Two unit boxes side by side (x in [0, 1] and [1, 2]), volumes "left" and "right", meshed
// WITHOUT BooleanFragments: they touch at x = 1 but each has nodes of its own there, so
// nothing joins them (a non-conforming mesh, refused); "base" is the face x = 0.
// scripts/make_test_meshes.sh meshes it (two_boxes_nonconforming.msh).
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 1};
Box(2) = {1, 0, 0, 1, 1, 1};
Physical Volume("left", 1) = {1};
Physical Volume("right", 2) = {2};
Physical Surface("base", 11) = Surface In BoundingBox{-1e-6, -1e-6, -1e-6, 1e-6, 1 + 1e-6, 1 + 1e-6};
Mesh.MeshSizeMin = 1;
Mesh.MeshSizeMax = 1;
