// floating_punch.geo -- a floating punch held by friction alone (issue 36):
// a steel punch [1.5, 2.5] x [1, 1.5] pressed onto a softer foundation
// [0, 4] x [0, 1] and pushed sideways; no Dirichlet condition touches the
// punch, so friction alone holds it tangentially. Separate geometry
// touching along y = 1: non-matching pair, slave = "punch_bottom", master =
// "found_top". Uniform size h (about 2 k nodes at -clscale 1; nodes grow
// like clscale^-2: 0.45 -> 10 k, 0.2 -> 50 k).
Mesh.MshFileVersion = 4.1;
h = 0.05;
Point(1) = {0, 0, 0, h}; Point(2) = {4, 0, 0, h}; Point(3) = {4, 1, 0, h};
Point(4) = {2.5, 1, 0, h}; Point(5) = {1.5, 1, 0, h}; Point(6) = {0, 1, 0, h};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 5};
Line(5) = {5, 6}; Line(6) = {6, 1};
Curve Loop(1) = {1, 2, 3, 4, 5, 6}; Plane Surface(1) = {1};
Point(11) = {1.5, 1, 0, h}; Point(12) = {2.5, 1, 0, h};
Point(13) = {2.5, 1.5, 0, h}; Point(14) = {1.5, 1.5, 0, h};
Line(11) = {11, 12}; Line(12) = {12, 13}; Line(13) = {13, 14}; Line(14) = {14, 11};
Curve Loop(2) = {11, 12, 13, 14}; Plane Surface(2) = {2};
Physical Surface("foundation") = {1};
Physical Surface("punch") = {2};
Physical Curve("found_bottom") = {1};
Physical Curve("found_sides") = {2, 6};
Physical Curve("found_top") = {3, 4, 5};
Physical Curve("punch_bottom") = {11};
Physical Curve("punch_right") = {12};
Physical Curve("punch_top") = {13};
Physical Curve("punch_left") = {14};
