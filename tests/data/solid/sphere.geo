// An octant of a thick sphere, inner radius 1, outer 2 (issue 45): the
// Lamé problem under internal pressure of docs/verification.md. Slip on the
// three symmetry planes; pressure on "inner".
SetFactory("OpenCASCADE");
DefineConstant[ h = 0.3 ];
Sphere(1) = {0, 0, 0, 2};
Sphere(2) = {0, 0, 0, 1};
Box(3) = {0, 0, 0, 2, 2, 2};
BooleanDifference(4) = { Volume{1}; Delete; }{ Volume{2}; Delete; };
BooleanIntersection(5) = { Volume{4}; Delete; }{ Volume{3}; Delete; };
e = 1e-6;
Physical Volume("shell") = {5};
Physical Surface("inner") = Surface In BoundingBox{-e, -e, -e, 1 + e, 1 + e, 1 + e};
Physical Surface("sym_x") = Surface In BoundingBox{-e, -e, -e, e, 2 + e, 2 + e};
Physical Surface("sym_y") = Surface In BoundingBox{-e, -e, -e, 2 + e, e, 2 + e};
Physical Surface("sym_z") = Surface In BoundingBox{-e, -e, -e, 2 + e, 2 + e, e};
Mesh.MeshSizeMax = h;
Mesh.MeshSizeMin = h / 2;
