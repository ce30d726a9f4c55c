// Rubber gasket in a steel groove, pressed by a steel plate that slides on two slip lines.
hb = 0.05; hg = 0.03; hp = 0.07;
// base (U shape)
Point(1) = {0, 0, 0, hb}; Point(2) = {4, 0, 0, hb}; Point(3) = {4, 1, 0, hb};
Point(4) = {3, 1, 0, hb}; Point(5) = {3, 0.6, 0, hb}; Point(6) = {1, 0.6, 0, hb};
Point(7) = {1, 1, 0, hb}; Point(8) = {0, 1, 0, hb};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 5};
Line(5) = {5, 6}; Line(6) = {6, 7}; Line(7) = {7, 8}; Line(8) = {8, 1};
Curve Loop(1) = {1, 2, 3, 4, 5, 6, 7, 8}; Plane Surface(1) = {1};
// gasket
Point(11) = {1, 0.6, 0, hg}; Point(12) = {3, 0.6, 0, hg}; Point(13) = {3, 1.1, 0, hg}; Point(14) = {1, 1.1, 0, hg};
Line(11) = {11, 12}; Line(12) = {12, 13}; Line(13) = {13, 14}; Line(14) = {14, 11};
Curve Loop(2) = {11, 12, 13, 14}; Plane Surface(2) = {2};
// plate
Point(21) = {0.5, 1.1, 0, hp}; Point(22) = {3.5, 1.1, 0, hp}; Point(23) = {3.5, 1.5, 0, hp};
Point(24) = {2.0, 1.5, 0, hp}; Point(25) = {0.5, 1.5, 0, hp};
Line(21) = {21, 22}; Line(22) = {22, 23}; Line(23) = {23, 24}; Line(24) = {24, 25}; Line(25) = {25, 21};
Curve Loop(3) = {21, 22, 23, 24, 25}; Plane Surface(3) = {3};
Physical Surface("base") = {1};
Physical Surface("gasket") = {2};
Physical Surface("plate") = {3};
Physical Curve("base_bottom") = {1};
Physical Curve("groove_floor") = {5};
Physical Curve("groove_left") = {6};
Physical Curve("groove_right") = {4};
Physical Curve("gasket_bottom") = {11};
Physical Curve("gasket_left") = {14};
Physical Curve("gasket_right") = {12};
Physical Curve("gasket_top") = {13};
Physical Curve("plate_bottom") = {21};
Physical Curve("plate_sides") = {22, 25};
Physical Curve("plate_top_right") = {23};
Physical Curve("plate_top_left") = {24};
Physical Point("plate_mid") = {24};
Physical Point("gasket_corner") = {14};
