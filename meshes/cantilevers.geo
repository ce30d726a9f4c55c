// cantilevers.geo -- after the report's 6.2: three stacked cantilever strips
// 10 m x 1 m: bottom y in [0,1], middle y in [1,2], top y in [2,3].
// Two conforming interfaces: "interface1" (y = 1) and "interface2" (y = 2),
// each ONE geometric line shared by the two neighbouring strips.
Mesh.MshFileVersion = 4.1;
Mesh.ElementOrder = 1;
Mesh.RecombineAll = 0;

L = 10.0;
t = 1.0;
h = 0.2;

For i In {0:3}
  Point(2*i + 1) = {0, i*t, 0, h};
  Point(2*i + 2) = {L, i*t, 0, h};
EndFor
// points: 1 (0,0) 2 (L,0) 3 (0,1) 4 (L,1) 5 (0,2) 6 (L,2) 7 (0,3) 8 (L,3)

Line(1) = {1, 2};    // bottom of bottom strip (free)
Line(2) = {2, 4};    // right end of bottom strip (free)
Line(3) = {4, 3};    // interface1
Line(4) = {3, 1};    // left end of bottom strip (clamped)
Line(5) = {4, 6};    // right end of middle strip (clamped)
Line(6) = {6, 5};    // interface2
Line(7) = {5, 3};    // left end of middle strip (free)
Line(8) = {6, 8};    // right end of top strip (free)
Line(9) = {8, 7};    // top of top strip (loaded)
Line(10) = {7, 5};   // left end of top strip (clamped)

Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Curve Loop(2) = {-3, 5, 6, 7};
Plane Surface(2) = {2};
Curve Loop(3) = {-6, 8, 9, 10};
Plane Surface(3) = {3};

Physical Surface("strip_bottom") = {1};
Physical Surface("strip_middle") = {2};
Physical Surface("strip_top") = {3};
Physical Curve("clamp_bottom") = {4};
Physical Curve("clamp_middle") = {5};
Physical Curve("clamp_top") = {10};
Physical Curve("interface1") = {3};
Physical Curve("interface2") = {6};
Physical Curve("top") = {9};
Physical Curve("bottom") = {1};
