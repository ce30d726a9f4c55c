// patch.geo -- contact patch test: two blocks with a NON-MATCHING flat
// interface under a uniform pressure. Plane strain, units m.
// Lower block [0,1] x [-0.5,0] ("lower"), upper block [0,1] x [0,0.5]
// ("upper"); they touch along y = 0 (zero initial gap) and are separate
// geometry, so the interface is a non-matching pair: upper_bottom (slave)
// on lower_top (master). Unstructured triangles of different sizes on each
// side (hu and hl, set by scripts/verify with -setnumber), so no slave node
// lines up with a master node except at the two ends.
DefineConstant[ hu = {0.14, Name "hu"}, hl = {0.1, Name "hl"} ];
Mesh.MshFileVersion = 4.1;
Mesh.ElementOrder = 1;

Point(1) = {0, -0.5, 0, hl};
Point(2) = {1, -0.5, 0, hl};
Point(3) = {1, 0, 0, hl};
Point(4) = {0, 0, 0, hl};
Line(1) = {1, 2};   // lower_bottom
Line(2) = {2, 3};   // lower_right
Line(3) = {3, 4};   // lower_top (master)
Line(4) = {4, 1};   // lower_left
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};

Point(11) = {0, 0, 0, hu};
Point(12) = {1, 0, 0, hu};
Point(13) = {1, 0.5, 0, hu};
Point(14) = {0, 0.5, 0, hu};
Line(11) = {11, 12};  // upper_bottom (slave)
Line(12) = {12, 13};  // upper_right
Line(13) = {13, 14};  // upper_top (loaded)
Line(14) = {14, 11};  // upper_left
Curve Loop(2) = {11, 12, 13, 14};
Plane Surface(2) = {2};

Physical Surface("lower") = {1};
Physical Surface("upper") = {2};
Physical Curve("lower_bottom") = {1};
Physical Curve("lower_right") = {2};
Physical Curve("lower_top") = {3};
Physical Curve("lower_left") = {4};
Physical Curve("upper_bottom") = {11};
Physical Curve("upper_right") = {12};
Physical Curve("upper_top") = {13};
Physical Curve("upper_left") = {14};
