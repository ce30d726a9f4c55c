// ssnv104_3d.geo -- Code_Aster SSNV104 (validation manual V6.04.104): two
// elastic hemispheres of radius R = 50 mm pressed together by a crush of
// 2 mm on each equatorial face; here in 3D, a quarter of each hemisphere
// (slip planes x = 0 and y = 0). Units mm (and MPa, N). z is the axis.
// Lower hemisphere: centre (0, 0, -R), its cap touches the origin, held on
// its equatorial face z = -R. Upper hemisphere: centre (0, 0, R), its cap
// touches the origin, crushed on its equatorial face z = R. The two volumes
// are meshed apart (no fragment): non-matching caps, mortar rows.
// Element size hc (set by scripts/verify) within r1 of the contact point,
// growing to hmax = min(10, 8 hc) at r2 (the bulk refined with the contact).
SetFactory("OpenCASCADE");
DefineConstant[ hc = {2.0, Name "hc"} ];
R = 50.0;
hmax = Min(10.0, 8 * hc); r1 = 12.0; r2 = 45.0;
// OCC Sphere {xc, yc, zc, r, latitude from, latitude to, longitude span}
Sphere(1) = {0, 0, -R, R, 0, Pi/2, Pi/2};     // lower: the northern quarter-hemisphere
Sphere(2) = {0, 0,  R, R, -Pi/2, 0, Pi/2};    // upper: the southern one
e = 1e-6;
// The faces of each volume, found by their boxes.
lx() = Surface In BoundingBox{-e, -e, -R-e, e, R+e, e};
ly() = Surface In BoundingBox{-e, -e, -R-e, R+e, e, e};
lb() = Surface In BoundingBox{-e, -e, -R-e, R+e, R+e, -R+e};
lc() = Surface In BoundingBox{-e, -e, -R-e, R+e, R+e, e};
lc() -= {lx(), ly(), lb()};
ux() = Surface In BoundingBox{-e, -e, -e, e, R+e, R+e};
uy() = Surface In BoundingBox{-e, -e, -e, R+e, e, R+e};
ut() = Surface In BoundingBox{-e, -e, R-e, R+e, R+e, R+e};
uc() = Surface In BoundingBox{-e, -e, -e, R+e, R+e, R+e};
uc() -= {ux(), uy(), ut()};
poles() = Point In BoundingBox{-e, -e, -e, e, e, e};

Field[1] = Distance;
Field[1].PointsList = {poles()};
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

Physical Volume("lower") = {1};
Physical Volume("upper") = {2};
Physical Surface("lower_cap") = {lc()};
Physical Surface("upper_cap") = {uc()};
Physical Surface("lower_base") = {lb()};
Physical Surface("upper_top") = {ut()};
Physical Surface("sym_x") = {lx(), ux()};
Physical Surface("sym_y") = {ly(), uy()};
