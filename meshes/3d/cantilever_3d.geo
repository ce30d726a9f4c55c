// A steel cantilever of P1 tetrahedra (issue 45; docs/guide.md "A 3D
// model"): 2 m long, a 0.2 m x 0.2 m square section, clamped at x = 0
// ("root"), a downward traction on its end face x = 2 ("tip"). Physical
// Volume "beam" is the material. `signorini mesh` meshes it in 3D
// (it declares a Physical Volume).
SetFactory("OpenCASCADE");
DefineConstant[ h = 0.05 ];
Box(1) = {0, 0, 0, 2, 0.2, 0.2};
e = 1e-6;
Physical Volume("beam") = {1};
Physical Surface("root") = Surface In BoundingBox{-e, -e, -e, e, 0.2 + e, 0.2 + e};
Physical Surface("tip") = Surface In BoundingBox{2 - e, -e, -e, 2 + e, 0.2 + e, 0.2 + e};
Mesh.MeshSizeMax = h;
Mesh.MeshSizeMin = h / 2;
