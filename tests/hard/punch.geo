// punch.geo -- a stiff punch on a soft foundation, meshed independently
// (non-matching contact pair).
// Punch: x in [-1, 1], y in [0, 1], bottom corners rounded with r = 0.2 m
// (quarter circles centred at (+-0.8, 0.2)). Its flat bottom lies on the
// foundation top (zero initial gap there); the rounded corners rise above it.
// Slave curve "punch_bottom" = the flat bottom and both rounded corners.
// Foundation: x in [-3, 3], y in [-3, 0]; master curve "found_top" = its top.
// The top of the punch is split at (0, 1), the physical point "top_mid".
// The two bodies share no geometric point, so Gmsh meshes them separately:
// punch edge ~ 0.05 m at its bottom, foundation ~ 0.07 m at its top.
Mesh.MshFileVersion = 4.1;
Mesh.ElementOrder = 1;
Mesh.RecombineAll = 0;

r = 0.2;
hp = 0.05;   // punch bottom
hp2 = 0.12;  // punch top
hf = 0.07;   // foundation top near the punch
hf2 = 0.5;   // foundation bottom

// --- punch ---
Point(1) = {-1 + r, 0, 0, hp};
Point(2) = {1 - r, 0, 0, hp};
Point(3) = {1 - r, r, 0, hp};      // centre of the right corner
Point(4) = {1, r, 0, hp};
Point(5) = {1, 1, 0, hp2};
Point(6) = {0, 1, 0, hp2};
Point(7) = {-1, 1, 0, hp2};
Point(8) = {-1, r, 0, hp};
Point(9) = {-1 + r, r, 0, hp};     // centre of the left corner
Line(1) = {1, 2};          // flat bottom
Circle(2) = {2, 3, 4};     // right rounded corner
Line(3) = {4, 5};          // right side
Line(4) = {5, 6};          // top, right half
Line(5) = {6, 7};          // top, left half
Line(6) = {7, 8};          // left side
Circle(7) = {8, 9, 1};     // left rounded corner
Curve Loop(1) = {1, 2, 3, 4, 5, 6, 7};
Plane Surface(1) = {1};

// --- foundation ---
Point(11) = {-3, 0, 0, hf2};
Point(12) = {-1.5, 0, 0, hf};
Point(13) = {1.5, 0, 0, hf};
Point(14) = {3, 0, 0, hf2};
Point(15) = {3, -3, 0, hf2};
Point(16) = {-3, -3, 0, hf2};
Line(11) = {11, 12};
Line(12) = {12, 13};
Line(13) = {13, 14};
Line(14) = {14, 15};       // right side
Line(15) = {15, 16};       // bottom
Line(16) = {16, 11};       // left side
Curve Loop(2) = {-16, -15, -14, -13, -12, -11};   // counter-clockwise
Plane Surface(2) = {2};

Physical Surface("punch") = {1};
Physical Surface("foundation") = {2};
Physical Curve("punch_bottom") = {7, 1, 2};
Physical Curve("punch_sides") = {3, 6};
Physical Curve("punch_top") = {4, 5};
Physical Point("top_mid") = {6};
Physical Curve("found_top") = {11, 12, 13};
Physical Curve("found_sides") = {14, 16};
Physical Curve("found_bottom") = {15};
