// Two unit boxes meshed apart (not fragmented), their coincident nodes merged by
// Coherence Mesh: the file's node tags have gaps (252 nodes, tags 1..312 in Gmsh 4.8).
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 1};
Box(2) = {1, 0, 0, 1, 1, 1};
Physical Volume("left") = {1};
Physical Volume("right") = {2};
Mesh.MeshSizeMax = 1;
Mesh 3;
Coherence Mesh;
Save "sparse.msh";
