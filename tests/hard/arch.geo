// arch.geo -- semicircular arch of 5 voussoirs with joggled (stepped) joints.
// Centre (0, 0); intrados radius R1, extrados R2; each block spans 36 deg.
// Joint k (k = 1..4) at angle t_k = 36 k deg is a stepped polyline: a radial
// segment from the intrados to the mid radius Rm at t_k + s d, an arc of
// radius Rm from t_k + s d to t_k - s d (the joggle), and a radial segment
// from Rm to the extrados at t_k - s d, with s = +1 for t_k < 90 deg and
// s = -1 above. So the block nearer the crown always overhangs the tongue of
// the block nearer its springer: the joggle carries radial force (one way).
// Each joint is ONE physical curve shared by both blocks (conforming contact).
// The springers (blocks 1 and 5) stand on y = 0: curves "springer_right"
// (x in [R1, R2]) and "springer_left" (x in [-R2, -R1]).
// The extrados of block 2 is split at 60 deg: physical point "load_point".
Mesh.MshFileVersion = 4.1;
Mesh.ElementOrder = 1;
Mesh.RecombineAll = 0;

R1 = 4.0;      // intrados
R2 = 5.0;      // extrados
Rm = 4.5;      // radius of the joggle
d = 3 * Pi / 180;   // half width of the joggle (angle)
h = 0.15;

Point(1) = {0, 0, 0, h};   // centre (used by the circle arcs only)

Point(2) = {R1, 0, 0, h};
Point(3) = {R2, 0, 0, h};
Point(4) = {-R1, 0, 0, h};
Point(5) = {-R2, 0, 0, h};
Point(6) = {R2*Cos(Pi/3), R2*Sin(Pi/3), 0, h};   // load_point (60 deg, extrados of block 2)
// joint 1 at 36 deg
Point(11) = {R1*Cos(36*Pi/180 + d), R1*Sin(36*Pi/180 + d), 0, h};
Point(12) = {Rm*Cos(36*Pi/180 + d), Rm*Sin(36*Pi/180 + d), 0, h};
Point(13) = {Rm*Cos(36*Pi/180 - d), Rm*Sin(36*Pi/180 - d), 0, h};
Point(14) = {R2*Cos(36*Pi/180 - d), R2*Sin(36*Pi/180 - d), 0, h};
Line(11) = {11, 12};
Circle(12) = {12, 1, 13};
Line(13) = {13, 14};
// joint 2 at 72 deg
Point(21) = {R1*Cos(72*Pi/180 + d), R1*Sin(72*Pi/180 + d), 0, h};
Point(22) = {Rm*Cos(72*Pi/180 + d), Rm*Sin(72*Pi/180 + d), 0, h};
Point(23) = {Rm*Cos(72*Pi/180 - d), Rm*Sin(72*Pi/180 - d), 0, h};
Point(24) = {R2*Cos(72*Pi/180 - d), R2*Sin(72*Pi/180 - d), 0, h};
Line(21) = {21, 22};
Circle(22) = {22, 1, 23};
Line(23) = {23, 24};
// joint 3 at 108 deg
Point(31) = {R1*Cos(108*Pi/180 - d), R1*Sin(108*Pi/180 - d), 0, h};
Point(32) = {Rm*Cos(108*Pi/180 - d), Rm*Sin(108*Pi/180 - d), 0, h};
Point(33) = {Rm*Cos(108*Pi/180 + d), Rm*Sin(108*Pi/180 + d), 0, h};
Point(34) = {R2*Cos(108*Pi/180 + d), R2*Sin(108*Pi/180 + d), 0, h};
Line(31) = {31, 32};
Circle(32) = {32, 1, 33};
Line(33) = {33, 34};
// joint 4 at 144 deg
Point(41) = {R1*Cos(144*Pi/180 - d), R1*Sin(144*Pi/180 - d), 0, h};
Point(42) = {Rm*Cos(144*Pi/180 - d), Rm*Sin(144*Pi/180 - d), 0, h};
Point(43) = {Rm*Cos(144*Pi/180 + d), Rm*Sin(144*Pi/180 + d), 0, h};
Point(44) = {R2*Cos(144*Pi/180 + d), R2*Sin(144*Pi/180 + d), 0, h};
Line(41) = {41, 42};
Circle(42) = {42, 1, 43};
Line(43) = {43, 44};
// intrados and extrados arcs of block b (b = 1..5, from the right springer)
Circle(101) = {2, 1, 11};
Circle(201) = {3, 1, 14};
Circle(102) = {11, 1, 21};
Circle(202) = {14, 1, 6};
Circle(212) = {6, 1, 24};
Circle(103) = {21, 1, 31};
Circle(203) = {24, 1, 34};
Circle(104) = {31, 1, 41};
Circle(204) = {34, 1, 44};
Circle(105) = {41, 1, 4};
Circle(205) = {44, 1, 5};
Line(301) = {2, 3};   // right springer base
Line(305) = {5, 4};   // left springer base
Curve Loop(1) = {301, 201, -13, -12, -11, -101};
Plane Surface(1) = {1};
Curve Loop(2) = {11, 12, 13, 202, 212, -23, -22, -21, -102};
Plane Surface(2) = {2};
Curve Loop(3) = {21, 22, 23, 203, -33, -32, -31, -103};
Plane Surface(3) = {3};
Curve Loop(4) = {31, 32, 33, 204, -43, -42, -41, -104};
Plane Surface(4) = {4};
Curve Loop(5) = {41, 42, 43, 205, 305, -105};
Plane Surface(5) = {5};

Physical Surface("masonry") = {1, 2, 3, 4, 5};
Physical Curve("joint1") = {11, 12, 13};
Physical Curve("joint2") = {21, 22, 23};
Physical Curve("joint3") = {31, 32, 33};
Physical Curve("joint4") = {41, 42, 43};
Physical Curve("springer_right") = {301};
Physical Curve("springer_left") = {305};
Physical Curve("intrados") = {101, 102, 103, 104, 105};
Physical Curve("extrados") = {201, 202, 212, 203, 204, 205};
Physical Point("load_point") = {6};
