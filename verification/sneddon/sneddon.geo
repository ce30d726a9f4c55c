// sneddon.geo -- rigid flat-ended cylindrical punch on an elastic
// half-space (Sneddon 1946), AXISYMMETRIC: x = r, y = z, axis x = 0.
// Units m. Punch: radius a = 0.1, height 0.1 ([0, a] x [0, 0.1]), a very
// stiff elastic body (1000 x the block's modulus) standing in for a rigid
// one. Block: the cylinder r <= R, -H <= z <= 0 with R = H = 20 m = 200 a,
// standing in for the half-space, its base fixed.
// The punch base z = 0, 0 <= r <= a, is ONE curve shared by both bodies: a
// conforming contact interface ("punch_base"), so there is no
// node-to-segment ripple. A mesh node sits at r = a/2 (Point 3) so that the
// force on the central disk r < a/2 can be summed node by node.
// hc: element size along the punch base (set by scripts/verify); the
// element size grows linearly with the distance d from the punch base,
// hc + k d (k = 0.05: a gentler growth than 0.1 or 0.2, which cost 1 % and
// 2 % of delta on the coarse mesh; docs/verification.md §7). k can be set
// with -setnumber k: the 3D comparison (sneddon_3d.geo, §7e) uses 0.1.
DefineConstant[ hc = {0.005, Name "hc"} ];
Mesh.MshFileVersion = 4.1;
Mesh.ElementOrder = 1;
DefineConstant[ k = {0.05, Name "k"} ];
a = 0.1; hp = 0.1; R = 20.0; H = 20.0;

Point(1) = {0, 0, 0};
Point(3) = {a/2, 0, 0};
Point(2) = {a, 0, 0};
Point(4) = {a, hp, 0};
Point(5) = {0, hp, 0};
Point(6) = {R, 0, 0};
Point(7) = {R, -H, 0};
Point(8) = {0, -H, 0};
Line(1) = {1, 3};      // punch_base (conforming contact)
Line(2) = {3, 2};      // punch_base
Line(3) = {2, 4};      // punch_side
Line(4) = {4, 5};      // punch_top (loaded)
Line(5) = {5, 1};      // punch_axis
Line(6) = {2, 6};      // block_top (free)
Line(7) = {6, 7};      // block_side (free)
Line(8) = {7, 8};      // block_bottom (fixed)
Line(9) = {8, 1};      // block_axis
Curve Loop(1) = {1, 2, 3, 4, 5};
Plane Surface(1) = {1};
Curve Loop(2) = {-2, -1, -9, -8, -7, -6};
Plane Surface(2) = {2};

Field[1] = Distance;
Field[1].CurvesList = {1, 2};
Field[1].NumPointsPerCurve = 200;
Field[2] = MathEval;
Field[2].F = Sprintf("%g + %g*F1", hc, k);
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;

Physical Surface("punch") = {1};
Physical Surface("block") = {2};
Physical Curve("punch_base") = {1, 2};
Physical Curve("punch_side") = {3};
Physical Curve("punch_top") = {4};
Physical Curve("punch_axis") = {5};
Physical Curve("block_top") = {6};
Physical Curve("block_side") = {7};
Physical Curve("block_bottom") = {8};
Physical Curve("block_axis") = {9};
