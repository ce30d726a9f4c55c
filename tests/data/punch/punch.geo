// Steel punch (2 m wide, 1 m high, rounded bottom corners r = 0.2) on a soft foundation (6 x 3).
r = 0.2; h = 0.08; hf = 0.12;
// punch: bottom at y = 0.0
Point(1) = {-1+r, 0, 0, h}; Point(2) = {1-r, 0, 0, h};
Point(3) = {1, r, 0, h}; Point(4) = {1, 1, 0, h}; Point(5) = {0, 1, 0, h}; Point(6) = {-1, 1, 0, h}; Point(7) = {-1, r, 0, h};
Point(8) = {1-r, r, 0, h}; Point(9) = {-1+r, r, 0, h};
Line(1) = {1, 2}; Circle(2) = {2, 8, 3}; Line(3) = {3, 4}; Line(4) = {4, 5}; Line(5) = {5, 6}; Line(6) = {6, 7}; Circle(7) = {7, 9, 1};
Curve Loop(1) = {1,2,3,4,5,6,7}; Plane Surface(1) = {1};
// foundation: top at y = 0
Point(11) = {-3, -3, 0, 0.3}; Point(12) = {3, -3, 0, 0.3}; Point(13) = {3, 0, 0, hf}; Point(14) = {-3, 0, 0, hf};
Line(11) = {11, 12}; Line(12) = {12, 13}; Line(13) = {13, 14}; Line(14) = {14, 11};
Curve Loop(2) = {11,12,13,14}; Plane Surface(2) = {2};
Physical Surface("punch") = {1};
Physical Surface("foundation") = {2};
Physical Curve("punch_bottom") = {7, 1, 2};
Physical Curve("punch_top") = {4, 5};
Physical Point("punch_mid") = {5};
Physical Curve("found_top") = {13};
Physical Curve("found_bottom") = {11};
