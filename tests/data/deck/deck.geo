// A steel deck on two rubber bearings (tests/data/deck/deck.toml; gmsh -2 deck.geo).
h = 0.05;
// deck
Point(1) = {0, 1.0, 0, h}; Point(2) = {10, 1.0, 0, h}; Point(3) = {10, 1.5, 0, h}; Point(4) = {0, 1.5, 0, h};
Point(5) = {6, 1.5, 0, h}; Point(6) = {8, 1.5, 0, h};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 6}; Line(4) = {6, 5}; Line(5) = {5, 4}; Line(6) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4, 5, 6}; Plane Surface(1) = {1};
// left bearing
Point(11) = {1.0, 0, 0, h}; Point(12) = {1.4, 0, 0, h}; Point(13) = {1.4, 1.0, 0, h}; Point(14) = {1.0, 1.0, 0, h};
Line(11) = {11, 12}; Line(12) = {12, 13}; Line(13) = {13, 14}; Line(14) = {14, 11};
Curve Loop(2) = {11, 12, 13, 14}; Plane Surface(2) = {2};
// right bearing
Point(21) = {8.6, 0, 0, h}; Point(22) = {9.0, 0, 0, h}; Point(23) = {9.0, 1.0, 0, h}; Point(24) = {8.6, 1.0, 0, h};
Line(21) = {21, 22}; Line(22) = {22, 23}; Line(23) = {23, 24}; Line(24) = {24, 21};
Curve Loop(3) = {21, 22, 23, 24}; Plane Surface(3) = {3};
Physical Surface("deck") = {1};
Physical Surface("bearing_l") = {2};
Physical Surface("bearing_r") = {3};
Physical Curve("deck_bottom") = {1};
Physical Curve("deck_left") = {6};
Physical Curve("load") = {4};
Physical Curve("bear_l_top") = {13};
Physical Curve("bear_r_top") = {23};
Physical Curve("ground") = {11, 21};
