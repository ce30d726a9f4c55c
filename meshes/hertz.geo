// hertz.geo -- Hertz contact of a cylinder (radius R) on an elastic block,
// plane strain, HALF model by symmetry about x = 0.
//
// Cylinder: the lower-right QUARTER of the disk with centre C = (0, R):
//   bounded by the axis x = 0 (from (0,0) to C), the flat top y = R
//   (the horizontal diameter, from C to (R, R)) and the arc from (R, R)
//   down to the bottom point (0, 0). The arc is split at 60 deg from the
//   bottom: "cyl_contact" (0..60 deg, slave curve) and "cyl_arc_free".
// Block: x in [0, Bw], y in [-Bd, 0]; "block_top" (master curve) is its whole top.
// The two bodies are SEPARATE geometry (no shared points): they touch at the
// origin only (zero initial gap there, gap ~ x^2/(2R) away from it).
// Mesh: size hmin ~ a/15 within distance r1 of the contact point, growing
// linearly to hmax at distance r2 (Distance + Threshold size field).
Mesh.MshFileVersion = 4.1;
Mesh.ElementOrder = 1;
Mesh.RecombineAll = 0;

R  = 1.0;        // cylinder radius
Bw = 4.0;        // block half-width
Bd = 4.0;        // block depth
a  = 0.1;        // expected half contact width (see hertz.toml)
hmin = a / 15;   // element size at the contact
hmax = 0.3;      // element size far away
r1 = 0.15;       // radius of the finely meshed zone (1.5 a)
r2 = 3.0;        // distance where hmax is reached

// --- cylinder (quarter disk) ---
Point(1) = {0, 0, 0};                           // bottom point of the cylinder
Point(2) = {R*Sin(Pi/3), R - R*Cos(Pi/3), 0};   // 60 deg from the bottom
Point(3) = {R, R, 0};                           // end of the horizontal diameter
Point(4) = {0, R, 0};                           // centre C (corner of the quarter disk)
Circle(1) = {1, 4, 2};   // cyl_contact (slave)
Circle(2) = {2, 4, 3};   // cyl_arc_free
Line(3) = {3, 4};        // cyl_top (loaded)
Line(4) = {4, 1};        // cyl_axis (slip)
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};

// --- block ---
Point(11) = {0, 0, 0};   // same location as Point(1), but a distinct point
Point(12) = {Bw, 0, 0};
Point(13) = {Bw, -Bd, 0};
Point(14) = {0, -Bd, 0};
Line(11) = {11, 12};     // block_top (master)
Line(12) = {12, 13};     // block_right (free)
Line(13) = {13, 14};     // block_bottom (fixed)
Line(14) = {14, 11};     // block_axis (slip)
Curve Loop(2) = {-14, -13, -12, -11};   // counter-clockwise
Plane Surface(2) = {2};

// --- mesh size: fine around the initial contact point (0, 0) ---
Field[1] = Distance;
Field[1].PointsList = {1, 11};
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

Physical Surface("cylinder") = {1};
Physical Surface("block") = {2};
Physical Curve("cyl_contact") = {1};
Physical Curve("cyl_arc_free") = {2};
Physical Curve("cyl_top") = {3};
Physical Curve("cyl_axis") = {4};
Physical Curve("block_top") = {11};
Physical Curve("block_right") = {12};
Physical Curve("block_bottom") = {13};
Physical Curve("block_axis") = {14};
