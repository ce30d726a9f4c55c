// Two unit cubes stacked along z (issue 45, tests/solid_contact.rs): a
// conforming contact surface "interface" at z = 1 (the cubes fragmented,
// so the interface nodes are shared and the model cuts them), slip on
// x = 0, y = 0 (both cubes) and z = 0, a pressure on "top" (z = 2).
SetFactory("OpenCASCADE");
DefineConstant[ h = 0.35 ];
Box(1) = {0, 0, 0, 1, 1, 1};
Box(2) = {0, 0, 1, 1, 1, 1};
BooleanFragments{ Volume{1, 2}; Delete; }{}
e = 1e-6;
Physical Volume("lower") = Volume In BoundingBox{-e, -e, -e, 1 + e, 1 + e, 1 + e};
Physical Volume("upper") = Volume In BoundingBox{-e, -e, 1 - e, 1 + e, 1 + e, 2 + e};
Physical Surface("interface") = Surface In BoundingBox{-e, -e, 1 - e, 1 + e, 1 + e, 1 + e};
Physical Surface("x0") = Surface In BoundingBox{-e, -e, -e, e, 1 + e, 2 + e};
Physical Surface("y0") = Surface In BoundingBox{-e, -e, -e, 1 + e, e, 2 + e};
Physical Surface("bottom") = Surface In BoundingBox{-e, -e, -e, 1 + e, 1 + e, e};
Physical Surface("top") = Surface In BoundingBox{-e, -e, 2 - e, 1 + e, 1 + e, 2 + e};
Mesh.MeshSizeMax = h;
Mesh.MeshSizeMin = h / 2;
