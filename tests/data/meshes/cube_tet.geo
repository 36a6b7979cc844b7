// Unit cube of two boxes (OpenCASCADE): volume "body" (z < 0.6) and "layer" (z > 0.6),
// surfaces "base" (x = 0) and "tip" (x = 1), a coarse tetrahedral mesh.
// scripts/make_test_meshes.sh meshes it at order 1 (cube_tet4_*) and 2 (cube_tet10_*).
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 0.6};
Box(2) = {0, 0, 0.6, 1, 1, 0.4};
BooleanFragments{ Volume{1, 2}; Delete; }{}
Physical Volume("body", 1) = {1};
Physical Volume("layer", 2) = {2};
Physical Surface("base", 11) = Surface In BoundingBox{-1e-6, -1e-6, -1e-6, 1e-6, 1 + 1e-6, 1 + 1e-6};
Physical Surface("tip", 12) = Surface In BoundingBox{1 - 1e-6, -1e-6, -1e-6, 1 + 1e-6, 1 + 1e-6, 1 + 1e-6};
Mesh.MeshSizeFactor = 1.5;
