// wedge.geo -- a keystone wedge between two closed faults (conforming
// contact), for the slide-only kernel models (wedge_slip.toml, wedge_point.toml).
// Rectangle x in [0, 3], y in [0, 2], cut by "fault_left" (1.0,2)-(1.3,0) and
// "fault_right" (2.0,2)-(1.7,0) into a left block, the wedge (1.0 m wide at
// the top, 0.4 m at the bottom) and a right block. The wedge bottom
// y = 0, x in [1.3, 1.7] is split at its mid point (1.5, 0) = "wedge_bottom_mid".
Mesh.MshFileVersion = 4.1;
Mesh.ElementOrder = 1;
Mesh.RecombineAll = 0;

h = 0.07;

Point(1) = {0, 0, 0, h};
Point(2) = {1.3, 0, 0, h};
Point(3) = {1.5, 0, 0, h};
Point(4) = {1.7, 0, 0, h};
Point(5) = {3, 0, 0, h};
Point(6) = {3, 2, 0, h};
Point(7) = {2.0, 2, 0, h};
Point(8) = {1.0, 2, 0, h};
Point(9) = {0, 2, 0, h};

Line(1) = {1, 2};    // left block bottom
Line(2) = {2, 3};    // wedge bottom, left half
Line(3) = {3, 4};    // wedge bottom, right half
Line(4) = {4, 5};    // right block bottom
Line(5) = {5, 6};    // right side
Line(6) = {6, 7};    // right block top
Line(7) = {7, 8};    // wedge top
Line(8) = {8, 9};    // left block top
Line(9) = {9, 1};    // left side
Line(10) = {2, 8};   // fault_left
Line(11) = {4, 7};   // fault_right

Curve Loop(1) = {1, 10, 8, 9};
Plane Surface(1) = {1};
Curve Loop(2) = {2, 3, 11, 7, -10};
Plane Surface(2) = {2};
Curve Loop(3) = {4, 5, 6, -11};
Plane Surface(3) = {3};

Physical Surface("rock_left") = {1};
Physical Surface("rock_wedge") = {2};
Physical Surface("rock_right") = {3};
Physical Curve("left_bottom") = {1};
Physical Curve("wedge_bottom") = {2, 3};
Physical Curve("right_bottom") = {4};
Physical Curve("left") = {9};
Physical Curve("right") = {5};
Physical Curve("left_top") = {8};
Physical Curve("wedge_top") = {7};
Physical Curve("right_top") = {6};
Physical Curve("fault_left") = {10};
Physical Curve("fault_right") = {11};
Physical Point("wedge_bottom_mid") = {3};
