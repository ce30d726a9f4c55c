// Meridian section (x = r, y = z) of a steel half-ball (radius 1, centre
// (0, 1), touching at the origin) on an aluminium cylinder block (radius 3,
// height 2, top at z = 0). The two bodies have distinct nodes at the origin.
hc = 0.02; hb = 0.2;
// ball
Point(1) = {0, 0, 0, hc}; Point(2) = {0, 1, 0, hb}; Point(3) = {1, 1, 0, hb};
Circle(1) = {1, 2, 3}; Line(2) = {3, 2}; Line(3) = {2, 1};
Curve Loop(1) = {1, 2, 3}; Plane Surface(1) = {1};
// block
Point(11) = {0, 0, 0, hc}; Point(12) = {0, -2, 0, 0.4}; Point(13) = {3, -2, 0, 0.4}; Point(14) = {3, 0, 0, 0.3};
Line(11) = {11, 12}; Line(12) = {12, 13}; Line(13) = {13, 14}; Line(14) = {14, 11};
Curve Loop(2) = {11, 12, 13, 14}; Plane Surface(2) = {2};
Field[1] = Distance; Field[1].PointsList = {1, 11};
Field[2] = Threshold; Field[2].InField = 1; Field[2].SizeMin = hc; Field[2].SizeMax = 0.4;
Field[2].DistMin = 0.25; Field[2].DistMax = 1.5;
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0;
Physical Surface("ball") = {1};
Physical Surface("block") = {2};
Physical Curve("ball_surface") = {1};
Physical Curve("ball_top") = {2};
Physical Curve("block_top") = {14};
Physical Curve("block_bottom") = {12};
