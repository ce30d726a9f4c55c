// cattaneo.geo -- a cylinder pressed on a block, then sheared
// (Cattaneo-Mindlin in plane strain). FULL model (the shear breaks the
// symmetry). Units m.
// Cylinder: the lower half of the disk of radius R = 1 and centre (0, R),
// loaded on its horizontal diameter y = R ("cyl_top"). Block: [-2, 2] x
// [-2, 0]. They touch at the origin. Slave: the cylinder arc within 25 deg
// of the bottom; master: the block top.
// hc: element size at the contact (set by scripts/verify).
DefineConstant[ hc = {0.006, Name "hc"} ];
Mesh.MshFileVersion = 4.1;
Mesh.ElementOrder = 1;
R = 1.0; W = 2.0; D = 2.0;
hmax = 0.25; r1 = 0.15; r2 = 1.5;
th = 25*Pi/180;

Point(1) = {0, 0, 0};
Point(2) = {R*Sin(th), R - R*Cos(th), 0};
Point(3) = {R, R, 0};
Point(4) = {-R, R, 0};
Point(5) = {-R*Sin(th), R - R*Cos(th), 0};
Point(6) = {0, R, 0};
Circle(1) = {5, 6, 1};
Circle(2) = {1, 6, 2};   // cyl_contact = {1, 2}
Circle(3) = {2, 6, 3};   // cyl_free
Line(4) = {3, 4};        // cyl_top
Circle(5) = {4, 6, 5};   // cyl_free
Curve Loop(1) = {1, 2, 3, 4, 5};
Plane Surface(1) = {1};

Point(11) = {-W, 0, 0};
Point(12) = {W, 0, 0};
Point(13) = {W, -D, 0};
Point(14) = {-W, -D, 0};
Point(15) = {0, 0, 0};
Line(11) = {11, 15};
Line(12) = {15, 12};     // block_top = {11, 12}
Line(13) = {12, 13};
Line(14) = {13, 14};     // block_bottom
Line(15) = {14, 11};
Curve Loop(2) = {11, 12, 13, 14, 15};
Plane Surface(2) = {2};

Field[1] = Distance;
Field[1].PointsList = {1, 15};
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

Physical Surface("cylinder") = {1};
Physical Surface("block") = {2};
Physical Curve("cyl_contact") = {1, 2};
Physical Curve("cyl_free") = {3, 5};
Physical Curve("cyl_top") = {4};
Physical Curve("block_top") = {11, 12};
Physical Curve("block_sides") = {13, 15};
Physical Curve("block_bottom") = {14};
