// A steel block on a rubber slope (25 deg), held against a rubber stop by gravity alone.
th = 25*Pi/180; hf = 0.06; hb = 0.035;
Point(1) = {0, 0, 0, hf}; Point(2) = {4, 0, 0, hf}; Point(3) = {4, 0.5, 0, hf};
Point(4) = {0.4, 0.5, 0, 0.02}; Point(5) = {0.4, 1.0, 0, hf}; Point(6) = {0, 1.0, 0, hf};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 5}; Line(5) = {5, 6}; Line(6) = {6, 1};
Curve Loop(1) = {1, 2, 3, 4, 5, 6}; Plane Surface(1) = {1};
Point(11) = {0.4, 0.5, 0, hb}; Point(12) = {1.6, 0.5, 0, hb}; Point(13) = {1.6, 1.1, 0, hb}; Point(14) = {0.4, 1.1, 0, hb};
Line(11) = {11, 12}; Line(12) = {12, 13}; Line(13) = {13, 14}; Line(14) = {14, 11};
Curve Loop(2) = {11, 12, 13, 14}; Plane Surface(2) = {2};
Rotate {{0, 0, 1}, {0, 0, 0}, th} { Surface{1, 2}; }
Physical Surface("pad") = {1};
Physical Surface("block") = {2};
Physical Curve("pad_bottom") = {1};
Physical Curve("slope") = {3};
Physical Curve("stop") = {4};
Physical Curve("block_bottom") = {11};
Physical Curve("block_left") = {14};
Physical Point("block_top_left") = {14};
Physical Point("block_bottom_right") = {12};
