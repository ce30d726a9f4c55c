// A 1 x 0.5 x 0.3 block of P1 tetrahedra (issue 45): uniaxial tension,
// the 3D patch test of docs/verification.md. Slip on x = 0, y = 0, z = 0;
// a traction on x = 1.
SetFactory("OpenCASCADE");
DefineConstant[ h = 0.15 ];
Box(1) = {0, 0, 0, 1, 0.5, 0.3};
e = 1e-6;
Physical Volume("block") = {1};
Physical Surface("x0") = Surface In BoundingBox{-e, -e, -e, e, 0.5 + e, 0.3 + e};
Physical Surface("x1") = Surface In BoundingBox{1 - e, -e, -e, 1 + e, 0.5 + e, 0.3 + e};
Physical Surface("y0") = Surface In BoundingBox{-e, -e, -e, 1 + e, e, 0.3 + e};
Physical Surface("z0") = Surface In BoundingBox{-e, -e, -e, 1 + e, 0.5 + e, e};
Mesh.MeshSizeMax = h;
Mesh.MeshSizeMin = h / 2;
