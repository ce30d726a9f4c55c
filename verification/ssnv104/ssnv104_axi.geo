// ssnv104_axi.geo -- Code_Aster SSNV104 (V6.04.104), axisymmetric (x = r,
// y = z; the axis is x = 0): the section of ssnv104_3d.geo. Units mm.
// Upper hemisphere: the lower-right quarter of the disc of centre (0, R);
// lower hemisphere: the upper-right quarter of the disc of centre (0, -R);
// they touch at the origin. Contact arcs: 0..20 degrees from the axis on
// the upper one (slave, r <= 17 mm; the contact radius is about 10 mm),
// 0..35 degrees on the lower one (master: the slave normals from 20 degrees
// meet it at 23 degrees; from 30 degrees on they would miss it). Element size hc
// (set by scripts/verify) within r1 of the contact point, growing to hmax
// at r2 -- the sizes of the 3D model.
DefineConstant[ hc = {2.0, Name "hc"} ];
Mesh.MshFileVersion = 4.1;
Mesh.ElementOrder = 1;
R = 50.0;
hmax = Min(10.0, 8 * hc); r1 = 12.0; r2 = 45.0;
t = 20*Pi/180; tm = 35*Pi/180;

// upper hemisphere
Point(1) = {0, 0, 0};
Point(2) = {R*Sin(t), R - R*Cos(t), 0};
Point(3) = {R, R, 0};
Point(4) = {0, R, 0};
Circle(1) = {1, 4, 2};     // upper_cap (slave)
Circle(2) = {2, 4, 3};     // upper_free
Line(3) = {3, 4};          // upper_top (crushed)
Line(4) = {4, 1};          // upper_axis
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};

// lower hemisphere
Point(11) = {0, 0, 0};
Point(12) = {R*Sin(tm), -R + R*Cos(tm), 0};
Point(13) = {R, -R, 0};
Point(14) = {0, -R, 0};
Circle(11) = {11, 14, 12}; // lower_cap (master)
Circle(12) = {12, 14, 13}; // lower_free
Line(13) = {13, 14};       // lower_base (crushed)
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
Physical Curve("upper_cap") = {1};
Physical Curve("upper_free") = {2};
Physical Curve("upper_top") = {3};
Physical Curve("upper_axis") = {4};
Physical Curve("lower_cap") = {11};
Physical Curve("lower_free") = {12};
Physical Curve("lower_base") = {13};
Physical Curve("lower_axis") = {14};
