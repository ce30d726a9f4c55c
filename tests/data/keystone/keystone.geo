// Flat arch (tests/trust.rs): two steel abutments fixed at their feet and a
// soft keystone, wider at the top, held only by the two inclined joints
// (conforming). Loaded on the left part of its top: the joint ends carry
// small multipliers, weakly active rows.
h = 0.12;
Point(1) = {0, 0, 0, h};
Point(2) = {2.0, 0, 0, h};
Point(3) = {2.6, 1.5, 0, h/2};
Point(4) = {0, 1.5, 0, h};
Point(5) = {5.0, 0, 0, h};
Point(6) = {7.2, 0, 0, h};
Point(7) = {7.2, 1.5, 0, h};
Point(8) = {4.8, 1.5, 0, h/2};
Point(9) = {3.4, 1.5, 0, h/2};
// keystone: joint1 3-2? keystone bottom narrower: uses points 2..? 
Point(10) = {2.9, 0.4, 0, h/2};
Point(11) = {4.5, 0.4, 0, h/2};
Line(1) = {1, 2};
Line(2) = {2, 10};
Line(3) = {10, 3};
Line(4) = {3, 4};
Line(5) = {4, 1};
Line(6) = {5, 6};
Line(7) = {6, 7};
Line(8) = {7, 8};
Line(9) = {8, 11};
Line(10) = {11, 5};
Line(11) = {10, 11};
Line(12) = {3, 9};
Line(13) = {9, 8};
Curve Loop(1) = {1, 2, 3, 4, 5};
Plane Surface(1) = {1};
Curve Loop(2) = {6, 7, 8, 9, 10};
Plane Surface(2) = {2};
Curve Loop(3) = {11, -9, -13, -12, -3};
Plane Surface(3) = {3};
Physical Surface("left") = {1};
Physical Surface("right") = {2};
Physical Surface("keystone") = {3};
Physical Curve("feet") = {1, 6};
Physical Curve("joint1") = {3};
Physical Curve("joint2") = {9};
Physical Curve("load") = {12};
Physical Curve("ends") = {5, 7};
