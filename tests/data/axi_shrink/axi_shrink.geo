// Meridian section (x = r, y = z) of a shrink fit: a tube (r 1 .. 2,
// z 0 .. 1) and two sleeves around it (r 1.998 .. 3; z 0 .. 0.45 and
// 0.55 .. 1), each overlapping the tube by 2 mm radially (interference).
// Different mesh sizes: the interfaces are non-matching.
d = 0.002;
// tube
Point(1) = {1, 0, 0, 0.1}; Point(2) = {2, 0, 0, 0.1}; Point(3) = {2, 1, 0, 0.1}; Point(4) = {1, 1, 0, 0.1};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
// lower sleeve
Point(11) = {2 - d, 0, 0, 0.075}; Point(12) = {3, 0, 0, 0.12}; Point(13) = {3, 0.45, 0, 0.12}; Point(14) = {2 - d, 0.45, 0, 0.075};
Line(11) = {11, 12}; Line(12) = {12, 13}; Line(13) = {13, 14}; Line(14) = {14, 11};
Curve Loop(2) = {11, 12, 13, 14}; Plane Surface(2) = {2};
// upper sleeve
Point(21) = {2 - d, 0.55, 0, 0.07}; Point(22) = {3, 0.55, 0, 0.12}; Point(23) = {3, 1, 0, 0.12}; Point(24) = {2 - d, 1, 0, 0.07};
Line(21) = {21, 22}; Line(22) = {22, 23}; Line(23) = {23, 24}; Line(24) = {24, 21};
Curve Loop(3) = {21, 22, 23, 24}; Plane Surface(3) = {3};
Physical Surface("tube") = {1};
Physical Surface("sleeve_lo") = {2};
Physical Surface("sleeve_hi") = {3};
Physical Curve("tube_bottom") = {1};
Physical Curve("tube_outer") = {2};
Physical Curve("lo_bottom") = {11};
Physical Curve("lo_inner") = {14};
Physical Curve("hi_inner") = {24};
Physical Point("hi_pin") = {22};
