// bumps.geo -- a soft pad with two flat-topped bumps under it on a stiff
// foundation (tests/forces.rs, tests/plot.rs): pressed down and pushed
// sideways, the contact is two zones with stick and slip, and rows on the
// bumps' slopes close initial gaps. Non-matching pair: slave = "pad_bottom",
// master = "found_top". gmsh -2 bumps.geo (or signorini mesh bumps.geo).
Mesh.MshFileVersion = 4.1;
h = 0.04; H = 0.25;
// pad: bottom polyline with two flats at y = 0, slopes rising to 0.04
Point(1) = {-1.5, 0.04, 0, h}; Point(2) = {-0.9, 0.0, 0, h}; Point(3) = {-0.6, 0.0, 0, h};
Point(4) = {0.0, 0.04, 0, h}; Point(5) = {0.6, 0.0, 0, h}; Point(6) = {0.9, 0.0, 0, h};
Point(7) = {1.5, 0.04, 0, h}; Point(8) = {1.5, 0.8, 0, H}; Point(9) = {-1.5, 0.8, 0, H};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 5}; Line(5) = {5, 6};
Line(6) = {6, 7}; Line(7) = {7, 8}; Line(8) = {8, 9}; Line(9) = {9, 1};
Curve Loop(1) = {1, 2, 3, 4, 5, 6, 7, 8, 9}; Plane Surface(1) = {1};
// foundation
Point(11) = {-2, -1, 0, H}; Point(12) = {2, -1, 0, H}; Point(13) = {2, 0, 0, h}; Point(14) = {-2, 0, 0, h};
Line(11) = {11, 12}; Line(12) = {12, 13}; Line(13) = {13, 14}; Line(14) = {14, 11};
Curve Loop(2) = {11, 12, 13, 14}; Plane Surface(2) = {2};
Physical Surface("pad") = {1};
Physical Surface("foundation") = {2};
Physical Curve("pad_bottom") = {1, 2, 3, 4, 5, 6};
Physical Curve("pad_top") = {8};
Physical Curve("found_top") = {13};
Physical Curve("found_bottom") = {11};
