// A 2 x 1 x 1 box of 4 x 2 x 2 transfinite, recombined hexahedra (built-in kernel,
// extruded with layers); meshed at order 2 with complete elements: 27-node hexahedra.
Point(1) = {0, 0, 0};
Point(2) = {2, 0, 0};
Line(1) = {1, 2};
Transfinite Line{1} = 5;
e[] = Extrude{0, 1, 0}{ Line{1}; Layers{2}; Recombine; };
v[] = Extrude{0, 0, 1}{ Surface{e[1]}; Layers{2}; Recombine; };
Physical Volume("body") = {v[1]};
Physical Surface("x0") = {v[5]};
Mesh.ElementOrder = 2;
Mesh.SecondOrderIncomplete = 0;
