// Two unit cubes stacked along z, meshed apart (issue 45,
// tests/solid_contact.rs): non-matching triangulations on the touching
// faces, "lower_top" (master, h1) and "upper_bottom" (slave, h2); slip on
// x = 0, y = 0 (both cubes) and z = 0, a pressure on "top" (z = 2).
// "upper_top" is the upper cube's far face (a wrong-facing slave).
SetFactory("OpenCASCADE");
DefineConstant[ h1 = 0.3, h2 = 0.22 ];
Box(1) = {0, 0, 0, 1, 1, 1};
Box(2) = {0, 0, 1, 1, 1, 1};
MeshSize{ PointsOf{ Volume{1}; } } = h1;
MeshSize{ PointsOf{ Volume{2}; } } = h2;
// Points inside the upper cube's bottom face, so that its triangulation
// differs from the lower cube's top face's.
Point(101) = {0.37, 0.61, 1, h2 / 2};
Point(102) = {0.71, 0.23, 1, h2 / 2};
Point{101, 102} In Surface{11};
e = 1e-6;
Physical Volume("lower") = {1};
Physical Volume("upper") = {2};
// OpenCASCADE numbers a box's faces x-, x+, y-, y+, z-, z+.
Physical Surface("lower_top") = {6};
Physical Surface("upper_bottom") = {11};
Physical Surface("x0") = {1, 7};
Physical Surface("y0") = {3, 9};
Physical Surface("bottom") = {5};
Physical Surface("top") = {12};
Physical Surface("lower_x0") = {1};
Physical Surface("lower_y0") = {3};
