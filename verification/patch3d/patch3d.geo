// patch3d.geo -- the 3D contact patch test (docs/verification_3d.md §7f): two
// unit cubes stacked along z, meshed apart, so the touching faces have
// non-matching triangulations: "lower_top" (size h1) and "upper_bottom"
// (size h2, with two extra points inside so that it differs from the
// lower face however h1 and h2 relate). Slip on x = 0, y = 0 (both cubes)
// and z = 0; a pressure on "top" (z = 2). tests/data/solid_contact/
// stack_nm.geo with the sizes as parameters (set by scripts/verify).
SetFactory("OpenCASCADE");
DefineConstant[ h1 = {0.3, Name "h1"}, h2 = {0.22, Name "h2"} ];
Box(1) = {0, 0, 0, 1, 1, 1};
Box(2) = {0, 0, 1, 1, 1, 1};
MeshSize{ PointsOf{ Volume{1}; } } = h1;
MeshSize{ PointsOf{ Volume{2}; } } = h2;
Point(101) = {0.37, 0.61, 1, h2 / 2};
Point(102) = {0.71, 0.23, 1, h2 / 2};
Point{101, 102} In Surface{11};
Physical Volume("lower") = {1};
Physical Volume("upper") = {2};
// OpenCASCADE numbers a box's faces x-, x+, y-, y+, z-, z+.
Physical Surface("lower_top") = {6};
Physical Surface("upper_bottom") = {11};
Physical Surface("x0") = {1, 7};
Physical Surface("y0") = {3, 9};
Physical Surface("bottom") = {5};
Physical Surface("top") = {12};
