// blocks54.geo -- two blocks pressed together along a flat NON-MATCHING
// interface whose segments are in the ratio 5:4, structured meshes.
// Plane strain, units mm. Lower block [0,10] x [-4,0] ("lower", the
// master: 4k segments on its top, h_m = 2.5/k mm), upper block
// [0,10] x [0,4] ("upper", the slave: 5k segments on its bottom,
// h_s = 2/k mm). They touch along y = 0 and are separate geometry, so every
// fifth slave node lands on a master node (x = 10 j / k) and the others
// between two. k is set by scripts/verify with -setnumber (k = 5, 10, 20, 40:
// h_m = 0.5, 0.25, 0.125, 0.0625 mm); k must be a multiple of 5 (the lower
// block's 1.6 k rows). See docs/verification.md, section 3.
DefineConstant[ k = {5, Name "k"} ];
Mesh.MshFileVersion = 4.1;
Mesh.ElementOrder = 1;

Point(1) = {0, -4, 0};
Point(2) = {10, -4, 0};
Point(3) = {10, 0, 0};
Point(4) = {0, 0, 0};
Line(1) = {1, 2};   // lower_bottom
Line(2) = {2, 3};   // lower_right
Line(3) = {3, 4};   // lower_top (master)
Line(4) = {4, 1};   // lower_left
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Transfinite Curve {1, 3} = 4 * k + 1;
Transfinite Curve {2, 4} = 8 * k / 5 + 1;
Transfinite Surface {1} Alternate;

Point(11) = {0, 0, 0};
Point(12) = {10, 0, 0};
Point(13) = {10, 4, 0};
Point(14) = {0, 4, 0};
Line(11) = {11, 12};  // upper_bottom (slave)
Line(12) = {12, 13};  // upper_right
Line(13) = {13, 14};  // upper_top (loaded)
Line(14) = {14, 11};  // upper_left
Curve Loop(2) = {11, 12, 13, 14};
Plane Surface(2) = {2};
Transfinite Curve {11, 13} = 5 * k + 1;
Transfinite Curve {12, 14} = 2 * k + 1;
Transfinite Surface {2} Alternate;

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
