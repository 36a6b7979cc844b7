// A cylinder (OpenCASCADE) of radius 0.5 and length 2 along x: volume "body", surfaces
// "base" (x = 0) and "tip" (x = 2), a coarse tetrahedral mesh. Meshed at order 2 the
// midside nodes on the mantle lie on the circle: curved (isoparametric) elements, some of
// whose nodes are outside the straight-sided mesh on the vertices.
SetFactory("OpenCASCADE");
Cylinder(1) = {0, 0, 0, 2, 0, 0, 0.5};
Physical Volume("body", 1) = {1};
Physical Surface("base", 11) = Surface In BoundingBox{-1e-6, -1, -1, 1e-6, 1, 1};
Physical Surface("tip", 12) = Surface In BoundingBox{2 - 1e-6, -1, -1, 2 + 1e-6, 1, 1};
Mesh.MeshSizeMin = 0.5;
Mesh.MeshSizeMax = 0.5;
