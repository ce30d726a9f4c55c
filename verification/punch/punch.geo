// punch.geo -- flat rigid punch on an elastic half-space, plane strain,
// HALF model by symmetry about x = 0. Units m.
// Punch: [0, a] x [0, 0.1], a = 0.1, a very stiff elastic body (1000 x the
// block's modulus) standing in for a rigid one. Block: [0, W] x [-D, 0],
// W = D = 4 m = 40 a, standing in for the half-space.
// The punch base y = 0, 0 <= x <= a, is ONE curve shared by both bodies: a
// conforming contact interface ("punch_base"), so there is no node-to-segment
// ripple. A mesh node sits at x = a/2 (Point 3) so that the force on the
// central half of the punch can be summed exactly node by node.
// hc: element size along the punch base (set by scripts/verify).
DefineConstant[ hc = {0.005, Name "hc"} ];
Mesh.MshFileVersion = 4.1;
Mesh.ElementOrder = 1;
a = 0.1; hp = 0.1; W = 4.0; D = 4.0; hmax = 0.4;

Point(1) = {0, 0, 0};
Point(3) = {a/2, 0, 0};
Point(2) = {a, 0, 0};
Point(4) = {a, hp, 0};
Point(5) = {0, hp, 0};
Point(6) = {W, 0, 0};
Point(7) = {W, -D, 0};
Point(8) = {0, -D, 0};
Line(1) = {1, 3};      // punch_base (conforming contact)
Line(2) = {3, 2};      // punch_base
Line(3) = {2, 4};      // punch_side
Line(4) = {4, 5};      // punch_top (loaded)
Line(5) = {5, 1};      // punch_axis
Line(6) = {2, 6};      // block_top (free)
Line(7) = {6, 7};      // block_right
Line(8) = {7, 8};      // block_bottom (fixed)
Line(9) = {8, 1};      // block_axis
Curve Loop(1) = {1, 2, 3, 4, 5};
Plane Surface(1) = {1};
Curve Loop(2) = {-2, -1, -9, -8, -7, -6};
Plane Surface(2) = {2};

Field[1] = Distance;
Field[1].CurvesList = {1, 2};
Field[1].NumPointsPerCurve = 200;
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = hc;
Field[2].SizeMax = hmax;
Field[2].DistMin = 0.0;
Field[2].DistMax = 2.0;
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
Physical Curve("block_right") = {7};
Physical Curve("block_bottom") = {8};
Physical Curve("block_axis") = {9};
