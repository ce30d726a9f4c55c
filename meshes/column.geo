// column.geo -- gravity column (oedometric test), one body.
// Width W = 1 m, height H = 10 m, x in [0, W], y in [0, H].
Mesh.MshFileVersion = 4.1;
Mesh.ElementOrder = 1;
Mesh.RecombineAll = 0;

W = 1.0;
H = 10.0;
h = 0.1;   // element size

Point(1) = {0, 0, 0, h};
Point(2) = {W, 0, 0, h};
Point(3) = {W, H, 0, h};
Point(4) = {0, H, 0, h};

Line(1) = {1, 2};  // bottom
Line(2) = {2, 3};  // right
Line(3) = {3, 4};  // top
Line(4) = {4, 1};  // left

Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};

// node at the mid-height probe point (0.5, 5)
Point(5) = {W/2, H/2, 0, h};
Point{5} In Surface{1};

Physical Surface("soil") = {1};
Physical Curve("bottom") = {1};
Physical Curve("right") = {2};
Physical Curve("top") = {3};
Physical Curve("left") = {4};
