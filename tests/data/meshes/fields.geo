// fields_bin.msh: fields.msh (hand-written: a 2-tet mesh with sparse node tags, a
// 3-component $NodeData "fibres" and an $ElementData "stiffness") saved by Gmsh as MSH 4.1
// binary with its views.
Merge "fields.msh";
Mesh.Binary = 1;
Mesh.MshFileVersion = 4.1;
PostProcessing.SaveMesh = 1;
Save View[0] "fields_bin_0.msh";
