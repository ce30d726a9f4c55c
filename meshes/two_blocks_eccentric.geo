// two_blocks_eccentric.geo -- the two stacked blocks of two_blocks.geo with
// the top of the upper block split at its midpoint (0.5, 1) into "top_left"
// and "top_right"; the midpoint is the physical point "top_mid".
Mesh.MshFileVersion = 4.1;
Mesh.ElementOrder = 1;
Mesh.RecombineAll = 0;

W = 1.0;
Hb = 0.5;
h = 0.05;

Point(1) = {0, 0, 0, h};
Point(2) = {W, 0, 0, h};
Point(3) = {W, Hb, 0, h};
Point(4) = {0, Hb, 0, h};
Point(5) = {W, 2*Hb, 0, h};
Point(6) = {0, 2*Hb, 0, h};
Point(7) = {W/2, 2*Hb, 0, h};

Line(1) = {1, 2};  // bottom of lower block
Line(2) = {2, 3};  // right side, lower block
Line(3) = {3, 4};  // interface
Line(4) = {4, 1};  // left side, lower block
Line(5) = {3, 5};  // right side, upper block
Line(6) = {5, 7};  // top, right half
Line(8) = {7, 6};  // top, left half
Line(7) = {6, 4};  // left side, upper block

Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Curve Loop(2) = {-3, 5, 6, 8, 7};
Plane Surface(2) = {2};

Physical Surface("lower") = {1};
Physical Surface("upper") = {2};
Physical Curve("bottom") = {1};
Physical Curve("right_lower") = {2};
Physical Curve("left_lower") = {4};
Physical Curve("right_upper") = {5};
Physical Curve("left_upper") = {7};
Physical Curve("interface") = {3};
Physical Curve("top_right") = {6};
Physical Curve("top_left") = {8};
Physical Point("top_mid") = {7};
