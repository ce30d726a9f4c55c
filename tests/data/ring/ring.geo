// A rubber ring (E = 1e7) pressed between two steel plates (tests/trust.rs): the
// ring is held only by contact at its top and bottom, and nothing fixes where
// along the plates it sits (a free horizontal translation, no load working on it).
// The top plate is held horizontally on its lid (ux = 0) and pressed down.
h = 0.05; hr = 0.01;
R = 0.5; r = 0.35;
// bottom plate
Point(1) = {-1, -0.8, 0, h}; Point(2) = {1, -0.8, 0, h}; Point(3) = {1, -0.5, 0, h}; Point(4) = {-1, -0.5, 0, h};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
// top plate
Point(5) = {-1, 0.5, 0, h}; Point(6) = {1, 0.5, 0, h}; Point(7) = {1, 0.8, 0, h}; Point(8) = {-1, 0.8, 0, h};
Line(5) = {5, 6}; Line(6) = {6, 7}; Line(7) = {7, 8}; Line(8) = {8, 5};
Curve Loop(2) = {5, 6, 7, 8}; Plane Surface(2) = {2};
// ring
Point(10) = {0, 0, 0, hr};
Point(11) = {R, 0, 0, hr}; Point(12) = {0, R, 0, hr}; Point(13) = {-R, 0, 0, hr}; Point(14) = {0, -R, 0, hr};
Point(21) = {r, 0, 0, hr}; Point(22) = {0, r, 0, hr}; Point(23) = {-r, 0, 0, hr}; Point(24) = {0, -r, 0, hr};
Circle(11) = {11, 10, 12}; Circle(12) = {12, 10, 13}; Circle(13) = {13, 10, 14}; Circle(14) = {14, 10, 11};
Circle(21) = {21, 10, 22}; Circle(22) = {22, 10, 23}; Circle(23) = {23, 10, 24}; Circle(24) = {24, 10, 21};
Curve Loop(3) = {11, 12, 13, 14}; Curve Loop(4) = {21, 22, 23, 24};
Plane Surface(3) = {3, 4};
Physical Surface("bottom") = {1};
Physical Surface("top") = {2};
Physical Surface("ring") = {3};
Physical Curve("base") = {1};
Physical Curve("lid") = {7};
Physical Curve("bottom_face") = {3};
Physical Curve("top_face") = {5};
Physical Curve("ring_out") = {11, 12, 13, 14};
