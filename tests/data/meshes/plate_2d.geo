// A 2 x 1 plate (built-in kernel): left half triangles, right half recombined quadrangles
// (transfinite); at order 2 (complete): 6-node triangles and 9-node quadrangles.
Point(1) = {0, 0, 0}; Point(2) = {1, 0, 0}; Point(3) = {2, 0, 0};
Point(4) = {2, 1, 0}; Point(5) = {1, 1, 0}; Point(6) = {0, 1, 0};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 5};
Line(5) = {5, 6}; Line(6) = {6, 1}; Line(7) = {2, 5};
Curve Loop(1) = {1, 7, 5, 6}; Plane Surface(1) = {1};
Curve Loop(2) = {2, 3, 4, -7}; Plane Surface(2) = {2};
Transfinite Curve{2, 3, 4, 7} = 3;
Transfinite Surface{2};
Recombine Surface{2};
Physical Surface("tris") = {1};
Physical Surface("quads") = {2};
Physical Curve("left") = {6};
Mesh.MeshSizeMax = 0.5;
Mesh.ElementOrder = 2;
Mesh.SecondOrderIncomplete = 0;
