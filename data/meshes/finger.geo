// A soft finger actuator (lengths in mm): a 60 x 12 x 10 elastomer bar with rounded long
// edges, an air chamber inside (a 50 x 6 x 5 cavity), and a 1.5 mm strain-limiting layer of
// a stiffer material under it. Clamped at its base (x = 0). OpenCASCADE kernel.
// Physical groups: volumes "body" and "layer"; surfaces "base" (x = 0) and "cavity".
// scripts/make_test_meshes.sh meshes it (data/meshes/finger.msh, first-order tetrahedra).
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 1.5, 60, 12, 10};
Fillet{1}{5, 7}{3}             // round the two upper long edges (radius 3 mm)
Box(2) = {5, 3, 3.5, 50, 6, 5};  // the air chamber
BooleanDifference(3) = { Volume{1}; Delete; }{ Volume{2}; Delete; };
Box(4) = {0, 0, 0, 60, 12, 1.5};  // the strain-limiting layer
BooleanFragments{ Volume{3, 4}; Delete; }{}
Physical Volume("body", 1) = {3};
Physical Volume("layer", 2) = {4};
Physical Surface("base", 11) = Surface In BoundingBox{-0.01, -0.01, -0.01, 0.01, 12.01, 12.01};
Physical Surface("cavity", 12) = Surface In BoundingBox{4.99, 2.99, 3.49, 55.01, 9.01, 8.51};
Mesh.MeshSizeMax = 3;
Mesh.MeshSizeMin = 1.5;
