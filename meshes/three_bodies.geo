// three_bodies.geo -- after the report's test 1 (methods.md 6.1):
// rectangle 1000 m x 800 m cut by two inclined faults into three bodies.
// fault1: (350, 800) -> (450, 0);  fault2: (650, 800) -> (550, 0).
// The middle body is a "keystone" wedge, 300 m wide at the top and 100 m at
// the bottom, held sideways only by contact on the two faults.
// Each fault is ONE geometric line used by the two neighbouring surfaces.
Mesh.MshFileVersion = 4.1;
Mesh.ElementOrder = 1;
Mesh.RecombineAll = 0;

h = 25.0;

Point(1) = {0, 0, 0, h};
Point(2) = {450, 0, 0, h};
Point(3) = {550, 0, 0, h};
Point(4) = {1000, 0, 0, h};
Point(5) = {1000, 800, 0, h};
Point(6) = {650, 800, 0, h};
Point(7) = {350, 800, 0, h};
Point(8) = {0, 800, 0, h};

Line(1) = {1, 2};    // bottom, left body
Line(2) = {2, 3};    // bottom, wedge
Line(3) = {3, 4};    // bottom, right body
Line(4) = {4, 5};    // right side
Line(5) = {5, 6};    // top, right body
Line(6) = {6, 7};    // top, wedge
Line(7) = {7, 8};    // top, left body
Line(8) = {8, 1};    // left side
Line(9) = {2, 7};    // fault1 (bottom -> top)
Line(10) = {3, 6};   // fault2 (bottom -> top)

Curve Loop(1) = {1, 9, 7, 8};
Plane Surface(1) = {1};      // left body
Curve Loop(2) = {2, 10, 6, -9};
Plane Surface(2) = {2};      // wedge
Curve Loop(3) = {3, 4, 5, -10};
Plane Surface(3) = {3};      // right body

// probe points A, B, C as mesh nodes
Point(21) = {250, 400, 0, h};
Point(22) = {500, 400, 0, h};
Point(23) = {750, 120, 0, h};
Point{21} In Surface{1};
Point{22} In Surface{2};
Point{23} In Surface{3};

Physical Surface("rock_left") = {1};
Physical Surface("rock_wedge") = {2};
Physical Surface("rock_right") = {3};
Physical Curve("left") = {8};
Physical Curve("right") = {4};
Physical Curve("top") = {5, 6, 7};
Physical Curve("bottom") = {1, 2, 3};
Physical Curve("fault1") = {9};
Physical Curve("fault2") = {10};
