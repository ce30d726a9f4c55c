// cattaneo.geo -- Cattaneo-Mindlin partial slip (tests/friction.rs):
// a cylinder (lower half disk, radius R, centre (0, R)) on a block
// [-B, B] x [-B, 0], plane strain, full model (the tangential load breaks
// the symmetry). The two bodies are separate geometry touching at the
// origin: non-matching pair, slave = "cyl_contact" (the arc +-30 deg from
// the bottom), master = "block_top". Element size hmin ~ a/30 within r1 of
// the contact point (a ~ 0.1 for the loads of the test), growing to hmax.
Mesh.MshFileVersion = 4.1;
R = 1.0; B = 2.0;
hmin = 0.1 / 60; hmax = 0.25; r1 = 0.14; r2 = 1.5;
Point(1) = {0, 0, 0};
Point(2) = {R*Sin(Pi/6), R - R*Cos(Pi/6), 0};
Point(3) = {-R*Sin(Pi/6), R - R*Cos(Pi/6), 0};
Point(4) = {R, R, 0};
Point(5) = {-R, R, 0};
Point(6) = {0, R, 0};
Circle(1) = {3, 6, 1};
Circle(2) = {1, 6, 2};
Circle(3) = {2, 6, 4};
Line(4) = {4, 5};
Circle(5) = {5, 6, 3};
Curve Loop(1) = {1, 2, 3, 4, 5};
Plane Surface(1) = {1};
Point(11) = {-B, 0, 0};
Point(12) = {B, 0, 0};
Point(13) = {B, -B, 0};
Point(14) = {-B, -B, 0};
Point(15) = {0, 0, 0};
Line(11) = {11, 15};
Line(16) = {15, 12};
Line(12) = {12, 13};
Line(13) = {13, 14};
Line(14) = {14, 11};
Curve Loop(2) = {-14, -13, -12, -16, -11};
Plane Surface(2) = {2};
Field[1] = Distance; Field[1].PointsList = {1, 15};
Field[2] = Threshold; Field[2].InField = 1; Field[2].SizeMin = hmin; Field[2].SizeMax = hmax;
Field[2].DistMin = r1; Field[2].DistMax = r2;
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0; Mesh.MeshSizeFromPoints = 0; Mesh.MeshSizeFromCurvature = 0;
Physical Surface("cylinder") = {1};
Physical Surface("block") = {2};
Physical Curve("cyl_contact") = {1, 2};
Physical Curve("cyl_free") = {3, 5};
Physical Curve("cyl_top") = {4};
Physical Curve("block_top") = {11, 16};
Physical Curve("block_side") = {12, 14};
Physical Curve("block_bottom") = {13};
