// nafems1.geo -- NAFEMS contact benchmark 1 (cylindrical roller on a block),
// plane strain, HALF model by symmetry about x = 0. Units: mm.
// Geometry after NAFEMS R0094 benchmark 1 as used by Code_Aster SSNP154:
// roller diameter 100 mm on a block 200 mm wide x 200 mm high; the half model
// keeps x >= 0 (block half-width 100 mm). The roller is the right half disk
// of centre (0, 50); it touches the block at B = (0, 0).
// hc: element size at the contact (set by scripts/verify with -setnumber).
DefineConstant[ hc = {0.6, Name "hc"} ];
Mesh.MshFileVersion = 4.1;
Mesh.ElementOrder = 1;
R = 50; W = 100; H = 200;
hmax = 8; r1 = 10; r2 = 80;
th = 30*Pi/180;                 // end of the slave arc, 30 deg from the bottom

// roller (right half disk)
Point(1) = {0, 0, 0};                          // C, bottom of the roller
Point(2) = {R*Sin(th), R - R*Cos(th), 0};
Point(3) = {R, R, 0};
Point(4) = {0, 2*R, 0};                        // load point (top)
Point(5) = {0, R, 0};                          // centre
Circle(1) = {1, 5, 2};                         // roller_contact (slave)
Circle(2) = {2, 5, 3};
Circle(3) = {3, 5, 4};
Line(4) = {4, 5};
Line(5) = {5, 1};
Curve Loop(1) = {1, 2, 3, 4, 5};
Plane Surface(1) = {1};

// block
Point(11) = {0, 0, 0};                         // B (a distinct point at C)
Point(12) = {W, 0, 0};
Point(13) = {W, -H, 0};
Point(14) = {0, -H, 0};
Line(11) = {11, 12};                           // block_top (master)
Line(12) = {12, 13};
Line(13) = {13, 14};                           // block_bottom (fixed)
Line(14) = {14, 11};                           // block_axis (symmetry)
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

Physical Surface("roller") = {1};
Physical Surface("block") = {2};
Physical Curve("roller_contact") = {1};
Physical Curve("roller_free") = {2, 3};
Physical Curve("roller_axis") = {4, 5};
Physical Point("load") = {4};
Physical Curve("block_top") = {11};
Physical Curve("block_right") = {12};
Physical Curve("block_bottom") = {13};
Physical Curve("block_axis") = {14};
