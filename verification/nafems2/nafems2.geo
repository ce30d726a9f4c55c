// nafems2.geo -- NAFEMS contact benchmark 2: a punch with rounded edges on
// a cylindrical foundation, AXISYMMETRIC (x = r, y = z; axis x = 0).
// Units mm. Geometry of NAFEMS R0094 benchmark 2 as modelled by Code_Aster
// SSNA122 (astest/ssna122a.comm; the dimensions as in the solids4foam
// tutorial `punch` that reproduces SSNA122): punch radius 50, height 100,
// edge fillet radius 10; foundation radius 100, height 200.
// Foundation: [0, 100] x [-200, 0], its top y = 0 the master curve; M is
// its point on the axis, (0, 0). Punch: [0, 50] x [0, 100], its base flat
// for r <= 40, then the fillet (centre (40, 10), radius 10) up to the side
// r = 50 at y = 10; base + fillet are the slave curve. P is the punch's
// point on the axis, (0, 0).
// hc: element size on the contact zone (set by scripts/verify), growing
// linearly with the distance from it.
DefineConstant[ hc = {2.0, Name "hc"} ];
Mesh.MshFileVersion = 4.1;
Mesh.ElementOrder = 1;
Rp = 50; Hp = 100; rf = 10; Rf = 100; Hf = 200; k = 0.15;

// punch
Point(1) = {0, 0, 0};            // P
Point(2) = {Rp - rf, 0, 0};      // start of the fillet
Point(3) = {Rp - rf, rf, 0};     // centre of the fillet
Point(4) = {Rp, rf, 0};          // end of the fillet
Point(5) = {Rp, Hp, 0};
Point(6) = {0, Hp, 0};
Line(1) = {1, 2};                // punch_contact: flat base
Circle(2) = {2, 3, 4};           // punch_contact: fillet
Line(3) = {4, 5};                // punch_side
Line(4) = {5, 6};                // punch_top (loaded)
Line(5) = {6, 1};                // punch_axis
Curve Loop(1) = {1, 2, 3, 4, 5};
Plane Surface(1) = {1};

// foundation
Point(11) = {0, 0, 0};           // M (a distinct point at P)
Point(12) = {Rf, 0, 0};
Point(13) = {Rf, -Hf, 0};
Point(14) = {0, -Hf, 0};
Line(11) = {11, 12};             // found_top (master)
Line(12) = {12, 13};             // found_side
Line(13) = {13, 14};             // found_bottom (fixed)
Line(14) = {14, 11};             // found_axis
Curve Loop(2) = {-14, -13, -12, -11};
Plane Surface(2) = {2};

// size: hc + k d, d the distance from the punch's base and fillet
Field[1] = Distance;
Field[1].CurvesList = {1, 2};
Field[1].NumPointsPerCurve = 400;
Field[2] = MathEval;
Field[2].F = Sprintf("%g + %g*F1", hc, k);
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;

Physical Surface("punch") = {1};
Physical Surface("foundation") = {2};
Physical Curve("punch_contact") = {1, 2};
Physical Curve("punch_side") = {3};
Physical Curve("punch_top") = {4};
Physical Curve("punch_axis") = {5};
Physical Curve("found_top") = {11};
Physical Curve("found_side") = {12};
Physical Curve("found_bottom") = {13};
Physical Curve("found_axis") = {14};
