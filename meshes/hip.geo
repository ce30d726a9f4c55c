// hip.geo -- simplified hip-joint-like model (after the report's 6.3), plane stress.
// Units: metres. Picture drawn with the socket BELOW the head (see README).
//
// socket ("pelvis"): block x in [-Ls, Ls], y in [-Ds, 0] with a half-circular
//   cavity of radius R centred at the origin (the lower half disk removed).
// femur-like body: disk of radius R centred at the origin, capped by a shaft
//   of half-width w going up to y = Ht ("disk-capped shaft").
// The lower half circle (two quarter arcs) is used by BOTH surfaces: it is the
// conforming contact curve "joint" (same radius, one set of nodes).
Mesh.MshFileVersion = 4.1;
Mesh.ElementOrder = 1;
Mesh.RecombineAll = 0;

R  = 0.025;   // head radius
w  = 0.012;   // shaft half-width
Ht = 0.10;    // shaft top
Yt = 0.05;    // height of the "trochanter" vertex (point force) on the right side
Ys = 0.06;    // slip line on the left side of the shaft: y in [Ys, Ht]
Ls = 0.06;    // socket half-width
Ds = 0.06;    // socket depth
hj = 0.0015;  // size along the joint
hf = 0.004;   // size elsewhere

Yw = Sqrt(R*R - w*w);   // where the shaft meets the head

Point(1) = {0, 0, 0, hj};      // centre of the head (embedded node)
Point(2) = {-R, 0, 0, hj};
Point(3) = {0, -R, 0, hj};
Point(4) = {R, 0, 0, hj};
Point(5) = {w, Yw, 0, hj};
Point(6) = {w, Yt, 0, hf};
Point(7) = {w, Ht, 0, hf};
Point(8) = {-w, Ht, 0, hf};
Point(9) = {-w, Ys, 0, hf};
Point(10) = {-w, Yw, 0, hj};
// socket outer corners
Point(11) = {-Ls, -Ds, 0, hf};
Point(12) = {Ls, -Ds, 0, hf};
Point(13) = {Ls, 0, 0, hf};
Point(14) = {-Ls, 0, 0, hf};

Circle(1) = {2, 1, 3};   // joint, left quarter
Circle(2) = {3, 1, 4};   // joint, right quarter
Circle(3) = {4, 1, 5};   // head, free upper-right arc
Line(4) = {5, 6};        // shaft right side, lower part
Line(5) = {6, 7};        // shaft right side, upper part
Line(6) = {7, 8};        // shaft top (body-weight load)
Line(7) = {8, 9};        // shaft left side, upper part (slip line)
Line(8) = {9, 10};       // shaft left side, lower part (free)
Circle(9) = {10, 1, 2};  // head, free upper-left arc
Line(11) = {11, 12};     // socket bottom (clamped)
Line(12) = {12, 13};     // socket right side (free)
Line(13) = {13, 4};      // socket top right (free)
Line(14) = {2, 14};      // socket top left (free)
Line(15) = {14, 11};     // socket left side (free)

Curve Loop(1) = {1, 2, 3, 4, 5, 6, 7, 8, 9};
Plane Surface(1) = {1};   // femur-like body
Curve Loop(2) = {11, 12, 13, -2, -1, 14, 15};
Plane Surface(2) = {2};   // socket
Point{1} In Surface{1};

Physical Surface("femur") = {1};
Physical Surface("pelvis") = {2};
Physical Curve("joint") = {1, 2};
Physical Curve("femur_top") = {6};
Physical Curve("femur_slip") = {7};
Physical Curve("femur_free") = {3, 4, 5, 8, 9};
Physical Curve("socket_base") = {11};
Physical Curve("socket_free") = {12, 13, 14, 15};
Physical Point("trochanter") = {6};
