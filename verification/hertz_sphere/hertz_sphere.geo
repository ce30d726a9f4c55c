// hertz_sphere.geo -- Hertz contact of two SPHERES, axisymmetric (x = r,
// y = z; the axis is x = 0). Units m. The same section as ../hertz/hertz2.geo.
// Upper sphere (was: cylinder): radius R1 = 1, the lower-right quarter of the disk of
// centre (0, R1), loaded on its horizontal diameter y = R1.
// Lower sphere (was: cylinder): radius R2 = 2, the upper-right quarter of the disk of
// centre (0, -R2), held on its horizontal diameter y = -R2.
// They touch at the origin. Slave: upper arc 0..30 deg; master: lower arc
// 0..20 deg. Element size hc (set by scripts/verify) within r1 of the
// contact point, growing to hmax.
DefineConstant[ hc = {0.005, Name "hc"} ];
Mesh.MshFileVersion = 4.1;
Mesh.ElementOrder = 1;
R1 = 1.0; R2 = 2.0;
hmax = 0.15; r1 = 0.08; r2 = 1.5;
t1 = 30*Pi/180; t2 = 20*Pi/180;

// upper cylinder (quarter disk)
Point(1) = {0, 0, 0};
Point(2) = {R1*Sin(t1), R1 - R1*Cos(t1), 0};
Point(3) = {R1, R1, 0};
Point(4) = {0, R1, 0};
Circle(1) = {1, 4, 2};     // upper_contact (slave)
Circle(2) = {2, 4, 3};     // upper_free
Line(3) = {3, 4};          // upper_top (loaded)
Line(4) = {4, 1};          // upper_axis
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};

// lower cylinder (quarter disk)
Point(11) = {0, 0, 0};
Point(12) = {R2*Sin(t2), -R2 + R2*Cos(t2), 0};
Point(13) = {R2, -R2, 0};
Point(14) = {0, -R2, 0};
Circle(11) = {11, 14, 12}; // lower_contact (master)
Circle(12) = {12, 14, 13}; // lower_free
Line(13) = {13, 14};       // lower_bottom (fixed)
Line(14) = {14, 11};       // lower_axis
Curve Loop(2) = {-14, -13, -12, -11};
Plane Surface(2) = {2};

Field[1] = Distance;
Field[1].PointsList = {1, 11};
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

Physical Surface("upper") = {1};
Physical Surface("lower") = {2};
Physical Curve("upper_contact") = {1};
Physical Curve("upper_free") = {2};
Physical Curve("upper_top") = {3};
Physical Curve("upper_axis") = {4};
Physical Curve("lower_contact") = {11};
Physical Curve("lower_free") = {12};
Physical Curve("lower_bottom") = {13};
Physical Curve("lower_axis") = {14};
