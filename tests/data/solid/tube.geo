// A thick tube about the z axis (the turn tests, tests/solid_turn.rs):
// bore radius 0.5, outer radius 1, length 1; coarse P1 tetrahedra.
// gmsh -3 -order 1 -format msh22 tube.geo -o tube.msh
SetFactory("OpenCASCADE");
DefineConstant[ h = 0.25 ];
Cylinder(1) = {0, 0, 0, 0, 0, 1, 1.0};
Cylinder(2) = {0, 0, 0, 0, 0, 1, 0.5};
BooleanDifference(3) = { Volume{1}; Delete; }{ Volume{2}; Delete; };
e = 1e-6;
bore[] = Surface In BoundingBox{-0.5 - e, -0.5 - e, -e, 0.5 + e, 0.5 + e, 1 + e};
end0[] = Surface In BoundingBox{-1 - e, -1 - e, -e, 1 + e, 1 + e, e};
end1[] = Surface In BoundingBox{-1 - e, -1 - e, 1 - e, 1 + e, 1 + e, 1 + e};
outer[] = Boundary{ Volume{3}; };
outer[] -= bore[];
outer[] -= end0[];
outer[] -= end1[];
Physical Volume("tube") = {3};
Physical Surface("bore") = {bore[]};
Physical Surface("outer") = {outer[]};
Physical Surface("end0") = {end0[]};
Physical Surface("end1") = {end1[]};
Mesh.MeshSizeMax = h;
Mesh.MeshSizeMin = h / 2;
