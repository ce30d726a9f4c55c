// rollers.geo -- four rigidly driven rollers of different radii pressed into
// one elastic foundation (plane strain, full model). The third benchmark
// family (issue 15): the contact zones are not given by the geometry, they
// grow with the load, four at once, and together span many contact rows.
//
// Roller k (k = 1..4): the LOWER half of the disk of radius R_k and centre
// (X_k, R_k); its flat top (the horizontal diameter) is driven down by a
// rigid platen (rollers 1 and 3, "roller_top_driven": u = [0, -delta]) or
// loaded by a pressure with u_x = 0 (rollers 2 and 4, "roller_top_loaded":
// their vertical translation and rotation are held only by contact, so C is
// singular). The arc is split
// into the contact arc (60 deg either side of the bottom point, slave
// curves, physical groups "roller1_contact" .. "roller4_contact") and two
// free arcs.
// Foundation: x in [-W, W], y in [-D, 0]; its top is the master curve.
// Each roller touches the foundation at its bottom point (X_k, 0) only; the
// bodies are separate geometry (non-matching pair, zero gap at the touching
// points, gap ~ x^2 / (2 R_k) away from them).
// Mesh: size hmin within r1 of every touching point, growing to hmax at r2.
Mesh.MshFileVersion = 4.1;
Mesh.ElementOrder = 1;
Mesh.RecombineAll = 0;

W = 8.0;  D = 4.0;
hmin = 0.03;  hmax = 0.5;  r1 = 0.3;  r2 = 3.0;
X[] = {-6, -2, 2, 6};
Rk[] = {0.6, 0.8, 1.0, 1.2};

For k In {0:3}
  x = X[k];  r = Rk[k];  p = 100 * (k + 1);
  Point(p + 1) = {x, 0, 0};                              // bottom (touching) point
  Point(p + 2) = {x + r * Sin(Pi/3), r - r * Cos(Pi/3), 0};
  Point(p + 3) = {x + r, r, 0};
  Point(p + 4) = {x, r, 0};                              // centre
  Point(p + 5) = {x - r, r, 0};
  Point(p + 6) = {x - r * Sin(Pi/3), r - r * Cos(Pi/3), 0};
  Circle(p + 1) = {p + 6, p + 4, p + 1};   // contact arc, left half
  Circle(p + 2) = {p + 1, p + 4, p + 2};   // contact arc, right half
  Circle(p + 3) = {p + 2, p + 4, p + 3};   // free arc, right
  Line(p + 4) = {p + 3, p + 4};            // top, right half
  Line(p + 6) = {p + 4, p + 5};            // top, left half (the centre is a node: probe)
  Circle(p + 5) = {p + 5, p + 4, p + 6};   // free arc, left
  Curve Loop(p) = {p + 1, p + 2, p + 3, p + 4, p + 6, p + 5};
  Plane Surface(p) = {p};
EndFor

Point(1) = {-W, 0, 0};  Point(2) = {W, 0, 0};
Point(3) = {W, -D, 0};  Point(4) = {-W, -D, 0};
// the foundation top passes through points under the touching points, so
// the master curve has nodes there (as in hertz.geo)
For k In {0:3}
  Point(10 + k) = {X[k], 0, 0};
EndFor
Line(1) = {1, 10};  Line(2) = {10, 11};  Line(3) = {11, 12};  Line(4) = {12, 13};
Line(5) = {13, 2};                       // foundation top (master), 5 pieces
Line(6) = {2, 3};  Line(7) = {3, 4};  Line(8) = {4, 1};
Curve Loop(1) = {-8, -7, -6, -5, -4, -3, -2, -1};   // counter-clockwise
Plane Surface(1) = {1};
Point(20) = {2, -1, 0};                  // probe below roller 3
Point{20} In Surface{1};

Field[1] = Distance;
Field[1].PointsList = {101, 201, 301, 401, 10, 11, 12, 13};
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = hmin;
Field[2].SizeMax = hmax;
Field[2].DistMin = r1;
Field[2].DistMax = r2;
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;

Physical Surface("roller1") = {100};
Physical Surface("roller2") = {200};
Physical Surface("roller3") = {300};
Physical Surface("roller4") = {400};
Physical Surface("foundation") = {1};
Physical Curve("roller1_contact") = {101, 102};
Physical Curve("roller2_contact") = {201, 202};
Physical Curve("roller3_contact") = {301, 302};
Physical Curve("roller4_contact") = {401, 402};
Physical Curve("roller_free") = {103, 105, 203, 205, 303, 305, 403, 405};
Physical Curve("roller_top_driven") = {104, 106, 304, 306};
Physical Curve("roller_top_loaded") = {204, 206, 404, 406};
Physical Curve("foundation_top") = {1, 2, 3, 4, 5};
Physical Curve("foundation_sides") = {6, 8};
Physical Curve("foundation_bottom") = {7};
