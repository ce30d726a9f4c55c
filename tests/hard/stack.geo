// stack.geo -- two stacked blocks 1 m x 0.5 m on one conforming interface
// (y = 0.5), for the stiffness-contrast sweep (stack_*.toml: only E, the load
// and the supports change). Lower block x in [0,1], y in [0,0.5]; upper block
// x in [0,1], y in [0.5,1]. The top is split at its mid point (0.5, 1) so that
// "top_mid" is a mesh node (the floating variants hold ux = 0 there).
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
Point(6) = {W/2, 2*Hb, 0, h};
Point(7) = {0, 2*Hb, 0, h};

Line(1) = {1, 2};  // bottom of the lower block
Line(2) = {2, 3};  // right side, lower block
Line(3) = {3, 4};  // interface (shared by both blocks: conforming)
Line(4) = {4, 1};  // left side, lower block
Line(5) = {3, 5};  // right side, upper block
Line(6) = {5, 6};  // top, right half
Line(7) = {6, 7};  // top, left half
Line(8) = {7, 4};  // left side, upper block

Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Curve Loop(2) = {-3, 5, 6, 7, 8};
Plane Surface(2) = {2};

Physical Surface("lower") = {1};
Physical Surface("upper") = {2};
Physical Curve("bottom") = {1};
Physical Curve("right_lower") = {2};
Physical Curve("left_lower") = {4};
Physical Curve("right_upper") = {5};
Physical Curve("left_upper") = {8};
Physical Curve("interface") = {3};
Physical Curve("top") = {6, 7};
Physical Point("top_mid") = {6};
