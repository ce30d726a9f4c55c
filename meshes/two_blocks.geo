// two_blocks.geo -- two stacked blocks W x 0.5 m with a conforming interface.
// lower block: x in [0,1], y in [0,0.5];  upper block: x in [0,1], y in [0.5,1].
// The interface line is ONE geometric curve used by both surfaces, so the
// mesh has one set of nodes on it (shared by the triangles of both blocks).
Mesh.MshFileVersion = 4.1;
Mesh.ElementOrder = 1;
Mesh.RecombineAll = 0;

W = 1.0;
Hb = 0.5;   // height of each block
h = 0.05;

Point(1) = {0, 0, 0, h};
Point(2) = {W, 0, 0, h};
Point(3) = {W, Hb, 0, h};
Point(4) = {0, Hb, 0, h};
Point(5) = {W, 2*Hb, 0, h};
Point(6) = {0, 2*Hb, 0, h};

Line(1) = {1, 2};  // bottom of lower block
Line(2) = {2, 3};  // right side, lower block
Line(3) = {3, 4};  // interface
Line(4) = {4, 1};  // left side, lower block
Line(5) = {3, 5};  // right side, upper block
Line(6) = {5, 6};  // top of upper block
Line(7) = {6, 4};  // left side, upper block

Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Curve Loop(2) = {-3, 5, 6, 7};
Plane Surface(2) = {2};

Physical Surface("lower") = {1};
Physical Surface("upper") = {2};
Physical Curve("bottom") = {1};
Physical Curve("right_lower") = {2};
Physical Curve("left_lower") = {4};
Physical Curve("right_upper") = {5};
Physical Curve("left_upper") = {7};
Physical Curve("interface") = {3};
Physical Curve("top") = {6};
