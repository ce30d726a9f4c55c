// shrinkfit.geo -- shrink fit of two thick tubes, AXISYMMETRIC (x = r,
// y = z). Units m. Inner tube a <= r <= c + delta, outer tube c <= r <= b,
// both of length L (0 <= z <= L): the inner tube's outer radius exceeds
// the outer tube's bore by the radial interference delta, an intended
// overlap (`interference = true` in the problem file).
// Structured meshes: n elements through each wall, n (inner) and n + 1
// (outer) along the length, so the interface is non-matching; each
// quadrilateral is cut into two triangles along alternating diagonals.
// n: set by scripts/verify (coarse 8, fine 24).
DefineConstant[ n = {8, Name "n"} ];
Mesh.MshFileVersion = 4.1;
Mesh.ElementOrder = 1;
a = 0.5; c = 1.0; b = 1.5; L = 0.5; delta = 1.0e-3;

// inner tube
Point(1) = {a, 0, 0};
Point(2) = {c + delta, 0, 0};
Point(3) = {c + delta, L, 0};
Point(4) = {a, L, 0};
Line(1) = {1, 2};   // inner_bottom
Line(2) = {2, 3};   // inner_contact (slave)
Line(3) = {3, 4};   // inner_top
Line(4) = {4, 1};   // inner_bore
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Transfinite Curve {1, 3} = n + 1;
Transfinite Curve {2, 4} = n + 1;
Transfinite Surface {1} Alternate;

// outer tube
Point(11) = {c, 0, 0};
Point(12) = {b, 0, 0};
Point(13) = {b, L, 0};
Point(14) = {c, L, 0};
Line(11) = {11, 12};  // outer_bottom
Line(12) = {12, 13};  // outer_surface
Line(13) = {13, 14};  // outer_top
Line(14) = {14, 11};  // outer_contact (master)
Curve Loop(2) = {11, 12, 13, 14};
Plane Surface(2) = {2};
Transfinite Curve {11, 13} = n + 1;
Transfinite Curve {12, 14} = n + 2;
Transfinite Surface {2} Alternate;

Physical Surface("inner") = {1};
Physical Surface("outer") = {2};
Physical Curve("inner_bottom") = {1};
Physical Curve("inner_contact") = {2};
Physical Curve("inner_top") = {3};
Physical Curve("inner_bore") = {4};
Physical Curve("outer_bottom") = {11};
Physical Curve("outer_surface") = {12};
Physical Curve("outer_top") = {13};
Physical Curve("outer_contact") = {14};
