// cattaneo3d.geo -- Cattaneo-Mindlin in 3D (issue 46, docs/verification_3d.md
// §7g): an elastic sphere pressed on an elastic block, then sheared. Units m.
// Sphere: the lower hemisphere of radius R = 1 centred at (0, 0, R), so its
// pole touches the origin; its flat face z = R ("ball_top") is where it is
// held. Block: a cylinder of radius 1 and height 1 below z = 0 (its top
// "block_top" flat, its bottom "block_bottom" held). The two volumes are
// meshed apart (non-matching surfaces). Element size hc (set by
// scripts/verify: coarse a/7, fine a/13 with a ~ 0.1) within r1 = 0.12 of
// the origin, growing to hmax = 0.25 at 0.8.
SetFactory("OpenCASCADE");
DefineConstant[ hc = {0.015, Name "hc"} ];
R = 1.0;
r1 = 0.12; r2 = 0.8; hmax = 0.25;
Sphere(1) = {0, 0, R, R, -Pi/2, 0, 2*Pi};
Cylinder(2) = {0, 0, -1, 0, 0, 1, 1, 2*Pi};
e = 1e-6;
btop() = Surface In BoundingBox{-R-e, -R-e, R-e, R+e, R+e, R+e};
ball() = Surface In BoundingBox{-R-e, -R-e, -e, R+e, R+e, R+e};
ktop() = Surface In BoundingBox{-1-e, -1-e, -e, 1+e, 1+e, e};
ball() -= {btop(), ktop()};
kbot() = Surface In BoundingBox{-1-e, -1-e, -1-e, 1+e, 1+e, -1+e};
pole() = Point In BoundingBox{-e, -e, -e, e, e, e};

Field[1] = Distance;
Field[1].PointsList = {pole()};
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = hc;
Field[2].SizeMax = hmax;
Field[2].DistMin = r1;
Field[2].DistMax = r2;
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;

Physical Volume("ball") = {1};
Physical Volume("block") = {2};
Physical Surface("ball_top") = {btop()};
Physical Surface("ball_surface") = {ball()};
Physical Surface("block_top") = {ktop()};
Physical Surface("block_bottom") = {kbot()};
